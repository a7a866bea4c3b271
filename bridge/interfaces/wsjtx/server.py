"""The WSJT-X (JTDX) listener: one UDP socket on a thread of its own; what WSJT-X says of the
QSO under way (its Status messages, decoded by messages.py) handed to every rotator as an input
(``Rotator.heard``). Whether a rotator turns is its follow part's decision (session/follow.py),
made on the serial-lines thread: nothing here judges or moves anything.

Rules:
1. Off unless ``[wsjtx] enabled``. Unicast: the socket is bound to ``bind:port`` alone (a
   second program on the port shows as "in use"). With ``multicast_group`` it is shared
   (SO_REUSEADDR, as GridTracker and JTAlert share it), bound to the group's address and the
   port, and joins the group on the interface of ``bind`` (0.0.0.0: the system's choice).
   It hears the group only where it joined it (IP_MULTICAST_ALL off: Linux otherwise hands it
   the group's datagrams from every interface another program joined the group on), and a
   listener bound to a loopback address takes datagrams from loopback sources alone (counted
   as ``foreign``): a forged Status from the LAN never reaches a rotator.
2. Each datagram is decoded on its own. A malformed one (messages.py rule 1) is dropped and
   counted, and logged at most once per JUNK_LOG_S with the count since: it reaches no
   rotator. Heartbeats and other message types are counted and ignored.
3. Nothing ends the thread but stop(): a fault behind a datagram (a bug in what it reaches) is
   logged at most once per JUNK_LOG_S with its traceback and the next datagram is served.
4. The thread never waits on a rotator: ``Rotator.heard`` only puts into the mailbox.
5. A flood cannot starve a stop (docs/architecture.md rule 12): the thread never sleeps while
   a datagram waits (a sleeping reader lets the system's buffer fill), it reads PER_WAKEUP at
   a wake-up and comes straight back for more; each datagram is decoded and handed on only
   within its sender's budget (ratelimit.SourceBudgets, per address and port: RATE_DATAGRAMS_S
   a second each, a second's worth at once, each one costing 1 + its size in KiB, MAX_SOURCES
   remembered, RATE_ALL_S for all together), far above WSJT-X's few a second. Over it a
   datagram is dropped undecoded and counted (``counts.over_budget``), said at most once per
   JUNK_LOG_S. Each datagram's decoding is linear in its size. WSJT-X's own socket is held
   to its own budget alone, not to what all senders together may spend: an attack pass
   flooded the port with well-formed heartbeats from eight local sockets, the cap for all
   together went to them, and 8 of WSJT-X's 10 statuses were dropped, the transmission's hold
   of the beam among them. That room is for the programs following listens to. No key names
   one: a rotator follows any program until its follow part has chosen one (session/follow.py
   rule 8: the first heard once it is switched on, or the first on an antenna's bands, the
   newest fresh one it starts with included), and its status names that one from then on
   (``Rotator.followed``, read at each wake-up, never waited on). So the room is the latest
   sender of each program (WSJT-X's Id) a rotator follows, and of each of the
   STATUS_INSTANCES others heard most recently that are programs (rule 6): one sender kept for
   each, so one program's statuses never push another's sender out (two radios, one WSJT-X
   each) and a restarted WSJT-X (a new socket, the same Id) keeps it: a status of a program
   followed from a sender outside the room (WSJT-X restarted during a flood, review 55: held to
   the spent cap for all, it was never heard again while the flood lasted) is let through
   within its sender's own budget and a program's pace (PROGRAM_STATUSES_S, for all such
   together), its header read to know whose it is. Statuses of any other
   instance, and every other message, share the cap for all. The room went first to the
   senders of the last two statuses (attack 11: three local sockets flooding statuses of
   another name took both places and WSJT-X's next statuses were dropped undecoded again),
   then to the first two instances heard since the start, for good (review 49: JTDX and a
   WSJT-X under a rig name heard once weeks ago, or two names forged before WSJT-X started,
   kept it, and today's WSJT-X was drowned by the same flood). (A program that sends
   statuses under the name of one followed, or as WSJT-X does, can be followed as it is: the
   port is the shack's.)
6. A program is an instance whose statuses come as a program's do: at a program's pace,
   PROGRAM_STATUSES_S a second, as many at once, its debt held to PROGRAM_DEBT_S of that pace
   (WSJT-X sends one on each change and at every decoding period, a few a second at most),
   and its latest sender within its own budget (rule 5's). Each status handed on is charged
   to its instance; one in debt (a flood of statuses under its name, as much as the cap for
   all let through), or whose sender floods the port, is no program until the debt is paid,
   and the room goes to the programs heard before it, which are remembered for that
   (PROGRAMS_KEPT, the least recently heard forgotten first, one in debt before any other, a
   program followed never). A name first heard while new names come faster than programs
   start (NEW_PROGRAMS at once, one more each NEW_PROGRAM_S) is handed on as any status but
   not remembered, unless a rotator follows it: a flood of a new name in every datagram takes
   no room and forgets no program. A program followed keeps its room whatever its pace. (What
   a forger on this computer can still do, while no rotator has chosen WSJT-X: send statuses
   under two names at a program's pace from sockets of their own, after WSJT-X's latest, and
   flood the port from others: those two are the programs heard last. At any time: send under
   WSJT-X's own name, its sender then WSJT-X's, or be heard first once following is on.)
"""

from __future__ import annotations

import logging
import math
import os
import selectors
import socket
import struct
import sys
import threading
import time
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from bridge.core.ratelimit import SourceBudgets, TokenBucket
from bridge.interfaces.wsjtx.messages import Malformed, Status, decode, status_instance
from bridge.session.follow import Heard

if TYPE_CHECKING:
    from bridge.runtime.rotator import Rotator

log = logging.getLogger(__name__)

JUNK_LOG_S = 30.0
RECV_BYTES = 65536  # a whole datagram, whatever its size: a longer one is junk (messages.py)
IP_MULTICAST_ALL = getattr(socket, "IP_MULTICAST_ALL", 49)  # Linux's number (rule 1)


def _loopback(address: str) -> bool:
    return address.startswith("127.")


RATE_DATAGRAMS_S = 200.0  # rule 5: a sender's budget, a second
RATE_ALL_S = 1000.0  # rule 5: every sender's together
MAX_SOURCES = 64  # rule 5
STATUS_INSTANCES = 2  # rule 5: the programs heard last, their senders held to their own budget
PROGRAM_STATUSES_S = 10.0  # rule 6: a program's pace of statuses, a second (as many at once)
PROGRAM_DEBT_S = 60.0  # rule 6: a flooded name's debt, held to this long at a program's pace
PROGRAMS_KEPT = 32  # rule 6: the programs remembered
NEW_PROGRAMS = 4  # rule 6: names first heard at once (as many programs as start together) ...
NEW_PROGRAM_S = 10.0  # ... then one more this often
PER_WAKEUP = 32  # rule 5: datagrams read at one wake-up


@dataclass
class Counts:
    """Read from any thread (tests, a status page); written by the listener's alone."""

    statuses: int = 0
    malformed: int = 0
    ignored: int = 0  # heartbeats and message types nobody here needs
    foreign: int = 0  # rule 1: from a source a loopback listener does not take
    faults: int = 0
    over_budget: int = 0  # rule 5: dropped undecoded


@dataclass
class _Rarely:
    every_s: float
    logged_s: float = -math.inf
    since: int = 0

    def due(self, now: float) -> int | None:
        self.since += 1
        if now - self.logged_s < self.every_s:
            return None
        count, self.since, self.logged_s = self.since, 0, now
        return count


@dataclass
class _Pace:
    """Rule 6: an instance's statuses against a program's pace; in debt, it is no program."""

    tokens: float
    t: float

    def _refill(self, now: float) -> None:
        gained = max(0.0, now - self.t) * PROGRAM_STATUSES_S
        self.tokens = min(PROGRAM_STATUSES_S, self.tokens + gained)
        self.t = max(self.t, now)

    def spend(self, now: float) -> None:
        self._refill(now)
        self.tokens = max(-PROGRAM_STATUSES_S * PROGRAM_DEBT_S, self.tokens - 1.0)

    def program(self, now: float) -> bool:
        self._refill(now)
        return self.tokens >= 0.0  # (as many at once: review 55, the last of them counted)


@dataclass
class _Program:
    """Rule 5: an instance heard (WSJT-X's Id): its latest sender and its pace (rule 6)."""

    sender: tuple[str, int]
    pace: _Pace


@dataclass
class WsjtxListener:
    port: int
    bind: str = "127.0.0.1"
    multicast_group: str | None = None
    clock: Callable[[], float] = time.monotonic
    rotators: list[Rotator] = field(default_factory=list)
    counts: Counts = field(default_factory=Counts)

    def __post_init__(self) -> None:
        self._sock: socket.socket | None = None
        self._thread: threading.Thread | None = None
        self._wake_r, self._wake_w = -1, -1
        self._junk_log = _Rarely(JUNK_LOG_S)
        self._fault_log = _Rarely(JUNK_LOG_S)
        self._foreign_log = _Rarely(JUNK_LOG_S)
        self._programs: OrderedDict[str, _Program] = OrderedDict()  # rules 5, 6: latest last
        self._new_names = TokenBucket.full(NEW_PROGRAMS, 1.0 / NEW_PROGRAM_S, self.clock())
        self._room: frozenset[tuple[str, int]] = frozenset()  # rule 5: the programs' senders
        self._followed: frozenset[str] = frozenset()  # rule 5: the programs rotators follow
        # rule 5: statuses of a program followed from a sender not (yet) its own, at its pace
        self._moved = TokenBucket.full(PROGRAM_STATUSES_S, PROGRAM_STATUSES_S, self.clock())
        self._flood_log = _Rarely(JUNK_LOG_S)

    def add(self, rotator: Rotator) -> None:
        self.rotators.append(rotator)

    @property
    def address(self) -> tuple[str, int]:
        """Where it really listens (port 0 in tests: the one the system gave)."""
        if self._sock is None:
            return self.bind, self.port
        host, port = self._sock.getsockname()[:2]
        return host, port

    def listen(self) -> None:
        """Rule 1; OSError naming the port and the reason if it cannot be had."""
        if self._sock is not None:
            return
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            if self.multicast_group is None:
                sock.bind((self.bind, self.port))
            else:
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
                sock.bind((self.multicast_group, self.port))
                membership = struct.pack(
                    "4s4s", socket.inet_aton(self.multicast_group), socket.inet_aton(self.bind)
                )
                sock.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP, membership)
                if sys.platform.startswith("linux"):  # (49 may mean something else elsewhere)
                    sock.setsockopt(socket.IPPROTO_IP, IP_MULTICAST_ALL, 0)
        except OSError as exc:
            sock.close()
            where = f"{self.multicast_group or self.bind}:{self.port}"
            raise OSError(exc.errno, f"WSJT-X UDP port {where}: {exc.strerror or exc}") from None
        sock.setblocking(False)  # rule 5: read until nothing waits
        self._sock = sock

    def start(self) -> None:
        self.listen()
        host, port = self.address
        group = f" (multicast group {self.multicast_group})" if self.multicast_group else ""
        log.info("WSJT-X UDP port %s:%d listening%s", host, port, group)
        self._wake_r, self._wake_w = os.pipe()
        self._thread = threading.Thread(target=self._loop, name="wsjtx", daemon=True)
        self._thread.start()

    def stop(self, timeout_s: float = 3.0) -> None:
        if self._thread is not None:
            os.write(self._wake_w, b"x")
            self._thread.join(timeout_s)
            self._thread = None
            os.close(self._wake_r)
            os.close(self._wake_w)
        if self._sock is not None:
            self._sock.close()
            self._sock = None

    def _loop(self) -> None:
        sock = self._sock
        assert sock is not None
        budgets = SourceBudgets(RATE_DATAGRAMS_S, RATE_ALL_S, MAX_SOURCES, self.clock())
        with selectors.DefaultSelector() as sel:
            sel.register(sock, selectors.EVENT_READ)
            sel.register(self._wake_r, selectors.EVENT_READ)
            while True:
                for key, _mask in sel.select():
                    if key.fileobj == self._wake_r:
                        return
                    self._serve(sock, budgets)

    def _serve(self, sock: socket.socket, budgets: SourceBudgets) -> None:
        """Rule 5: what waits, PER_WAKEUP at most, each within its sender's budget."""
        self._followed = self._followed_now()
        self._room = self._room_at(self.clock(), budgets)  # (debts paid meanwhile)
        for _ in range(PER_WAKEUP):
            try:
                datagram, source = sock.recvfrom(RECV_BYTES)
            except (BlockingIOError, InterruptedError):
                return
            except OSError as exc:  # a transient error (ICMP, ENOBUFS): the next one
                self._fault("reading the WSJT-X port", exc)
                continue
            now = self.clock()
            sender = source[0], source[1]
            own = sender in self._room  # rule 5: WSJT-X's, its room kept
            if not (
                budgets.allow_own(sender, now)
                if own
                else self._allow(datagram, sender, now, budgets)
            ):
                self._flooded(source[0])
                continue
            instance: str | None = None
            try:
                instance = self.datagram(datagram, source[0])
                if instance is not None:
                    self._program_heard(instance, sender, now)
            except Exception as exc:  # rule 3: a bug behind it, not the end
                self._fault("a WSJT-X datagram", exc)
            budgets.spend(sender, 1 + len(datagram) / 1024, now)
            if instance is not None:
                self._room = self._room_at(now, budgets)

    def _allow(
        self, datagram: bytes, sender: tuple[str, int], now: float, budgets: SourceBudgets
    ) -> bool:
        """Rule 5: a datagram from a sender outside the room, within the cap for all, or a
        status of a program followed (its header read) from a new sender of its own, at a
        program's pace (``_moved``)."""
        if budgets.allow(sender, now):
            return True
        if not self._followed or not budgets.allow_own(sender, now):
            return False
        return status_instance(datagram) in self._followed and self._moved.take(now)

    def _program_heard(self, instance: str, sender: tuple[str, int], now: float) -> None:
        """Rules 5, 6: a status of ``instance`` from ``sender``, handed on."""
        programs = self._programs
        program = programs.get(instance)
        if program is None:
            followed = self._followed
            if instance not in followed and not self._new_names.take(now):
                return  # rule 6: names come faster than programs start
            if len(programs) >= PROGRAMS_KEPT:
                others = [name for name in programs if name not in followed]
                gone = next(
                    (name for name in others if not programs[name].pace.program(now)),
                    others[0] if others else next(iter(programs)),
                )
                del programs[gone]
            program = programs[instance] = _Program(sender, _Pace(PROGRAM_STATUSES_S, now))
        else:
            programs.move_to_end(instance)
            program.sender = sender  # rule 5: its latest sender
        program.pace.spend(now)

    def _room_at(self, now: float, budgets: SourceBudgets) -> frozenset[tuple[str, int]]:
        """Rule 5: the senders of the programs followed and of the STATUS_INSTANCES programs
        heard last (rule 6)."""
        followed = self._followed
        room = {p.sender for name, p in self._programs.items() if name in followed}
        last = 0
        for name, program in reversed(self._programs.items()):
            if last == STATUS_INSTANCES:
                break
            if name in followed:
                continue
            if program.pace.program(now) and budgets.in_credit(program.sender, now):
                room.add(program.sender)
                last += 1
        return frozenset(room)

    def _followed_now(self) -> frozenset[str]:
        """Rule 5: the programs the rotators' follow parts listen to now, as their latest
        statuses say (``Rotator.followed``: read, never waited on)."""
        names: set[str] = set()
        for rotator in self.rotators:
            try:
                name = rotator.followed
            except Exception as exc:  # rule 3
                self._fault(f"asking {rotator.id} which program it follows", exc)
                continue
            if name is not None:
                names.add(name)
        return frozenset(names)

    def datagram(self, datagram: bytes, source: str = "127.0.0.1") -> str | None:
        """One datagram from the address ``source``, decoded and handed on (rules 1-4); the
        status's instance (WSJT-X's Id) if it was a status, handed on, else None."""
        if _loopback(self.bind) and not _loopback(source):  # rule 1
            self.counts.foreign += 1
            count = self._foreign_log.due(self.clock())
            if count is not None:
                log.warning(
                    "WSJT-X port: %d datagram(s) from outside this computer dropped (listening "
                    "on %s), the last from %s",
                    count,
                    self.bind,
                    source,
                )
            return None
        try:
            message = decode(datagram)
        except Malformed as exc:
            self.counts.malformed += 1
            count = self._junk_log.due(self.clock())
            if count is not None:
                log.info("WSJT-X port: %d malformed datagram(s) dropped, the last: %s", count, exc)
            return None
        if not isinstance(message, Status):
            self.counts.ignored += 1
            return None
        self.counts.statuses += 1
        heard = Heard(
            message.dx_call,
            message.dx_grid,
            message.transmitting,
            message.instance,
            message.dial_hz,
        )
        for rotator in self.rotators:
            try:
                rotator.heard(heard)
            except Exception as exc:  # rule 3
                self._fault(f"handing WSJT-X's status to {rotator.id}", exc)
        return message.instance

    def _flooded(self, source: str) -> None:
        """Rule 5."""
        self.counts.over_budget += 1
        count = self._flood_log.due(self.clock())
        if count is not None:
            log.warning(
                "WSJT-X port: %d datagram(s) dropped undecoded, over the budget of their "
                "sender (%g a second each), the last from %s",
                count,
                RATE_DATAGRAMS_S,
                source,
            )

    def _fault(self, what: str, exc: BaseException) -> None:
        self.counts.faults += 1
        if self._fault_log.due(self.clock()) is not None:
            log.error("%s failed: %s", what, exc, exc_info=exc)
