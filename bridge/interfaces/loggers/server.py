"""The loggers' UDP endpoints: one thread, every socket (a PST port per rotator, an N1MM port
per address shared by the rotators named on it), and the N1MM position reports. What each
datagram does, once read and parsed, is commands.py's.

Rules (numbered as before commands.py was split off, so that citations hold):
1. 2. 4. 5. What a datagram commands and how a query is answered: commands.py rules 1 to 4.
3. Sockets are served in turn: on every wake-up each ready socket gives PER_WAKEUP datagrams
   at most, so a flood on one port delays a stop on another by that many datagrams, not by the
   flood. Each datagram is parsed on its own: a malformed or ambiguous one (datagrams.py rules
   1, 2 and 4) is dropped and counted, logged at debug level at most once per JUNK_LOG_S with
   the count since. Nothing of it reaches the rotator; the serial line is served by another
   thread and never waits for this one.
6. N1MM position reports go to the configured destination from the N1MM port's own socket, so
   from the configured bind address (no socket of ours listens anywhere else); one that cannot
   be sent is said once at warning level. The heading is looked at every REPORT_MOVING_S and
   reported when it has moved REPORT_MOVE_DEG since the last report (while the rotor turns,
   and where it came to rest), else every REPORT_IDLE_S. A name several rotators share is
   reported for one of them, the one its last turn chose by band (commands.py rule 6), at once
   when that changes; none before a turn has chosen one. The destination is an address in
   digits when a report goes: this thread never looks a name up (rules 3 and 8; resolver.py
   rule 1). A name (``n1mm-pc.lan:13010``) is looked up on a thread of its own, and a report
   goes to the last address that found; while it has found none, the reports are dropped,
   said once at warning level (an attack pass: with the name server silent, each report's
   lookup inside ``sendto`` held this thread 5 s, and a PstRotator STOP reached the rotor 5 s
   late, 50 degrees on).
7. Nothing ends the thread but stop(): a fault behind a datagram (a bug in what it reaches) is
   logged with its traceback at most once per FAULT_LOG_S and the next datagram is served; a
   fault in the loop itself gets a fresh selector (and a pause if it comes again at once). A
   socket that cannot be read any more (EBADF, ENOTSOCK) is reported once and dropped: the
   selector is made anew without it, so it can never wake the thread again.
8. A flood cannot starve a stop (docs/architecture.md rule 12), nor hide one it reads (a flood
   faster than the reads overflows the system's buffer, and the system drops datagrams, a stop
   among them: an attack pass, 175,000 a second on loopback; docs/loggers.md): the thread never
   sleeps while a datagram waits (a sleeping reader lets the system's buffer fill with the
   flood, and a stop sent then is dropped or queued behind it), so every wake-up reads what
   waits, PER_WAKEUP a socket (rule 3), and comes straight back for more. Each datagram is
   first searched for a stop (datagrams.py rule 6, one byte search); one that may be a stop is
   parsed and carried out at once, whatever any budget says, on the N1MM port if it may also
   name a rotor there (a tag whose whole text is one of its names, or ``*``: ``_may_name``;
   an attack pass flooded 2 KiB datagrams of stops for a name nobody has, each parsed whole,
   and an operator's stop waited up to 1.3 s behind them). Everything else is parsed and
   carried out only within its sender's budget (ratelimit.SourceBudgets, per address and port:
   RATE_DATAGRAMS_S a second each, a second's worth at once, each datagram costing 1 + its size
   in KiB, at most MAX_SOURCES senders remembered; RATE_ALL_S for all of them together); a
   stop is charged to it too, never refused. Each port has budgets of its own, the cap for all
   senders together among them (the ports are the configuration's, so the work is still
   bounded: RATE_ALL_S a port): one budget set served every socket, and an attack pass (11)
   flooded the PstRotator port with junk from six local sockets, each within its own budget,
   spent the cap for all, and N1MM's turns for another rotator on its own port were dropped
   while it lasted. A flood on a port now drops what comes to that port alone (an N1MM port's
   rotators share it, as they share the port). Over budget a datagram is dropped unparsed and
   counted (``over_budget``), said at warning level at most once per FLOOD_LOG_S with the
   count since and the last sender. A flood so costs a read and a search a datagram, and
   each socket asks the system for a receive buffer of RECV_BUFFER bytes to ride out bursts.
   Nor may what a datagram is handed to hold the reads: the remote's rotator answers a
   command only once its broker acknowledged it, so the remote hands the PstRotator ports a
   rotator whose moves go to a sender thread of their own, a newer one replacing an unsent
   older one, a stop dropping those unsent (remote/courier.py; attack 29: a burst of 190
   targets held the operator's STOP one broker round trip per target, up to 10 s).
9. Each datagram is read with the time the system took it (``SO_TIMESTAMPNS``, where the
   system has it: Linux), on the wall clock, made monotonic by its age when read (never
   below 0: a wall clock set back meanwhile makes it as new as its read). What a datagram
   that reached the system before its rotator's last STOP or lock ON would move is not
   carried out (commands.py rule 8): a flood this thread is behind with no longer carries a
   logger's turn past a stop from another interface. A wall clock stepped forward between
   the arrival and the read ages the datagram: refused, the safe side, and said. The
   monotonic clock is read on both sides of the wall clock (commands.py ``Arrival``): the
   thread may lose the interpreter between any two readings, to the very thread that
   carries out a STOP, and one reading after the wall clock's dated a turn read as the STOP
   landed after it. Where the system does not stamp (Windows, macOS: where the remote runs),
   the thread dates a datagram itself for the seen time a rotator that stamps its commands
   takes (front.py rule 3; the remote's, a review: a logger's turn read late went out stamped
   when sent, across a STOP from Home Assistant): each wake-up first looks at what already
   waits (a select that does not wait); a datagram on a socket that held nothing then came
   after that look, one already waiting after the socket was last found empty. Every check
   proves that of each socket it finds with nothing waiting, not only the read that got
   nothing (an attack pass: after a quiet spell, its waits timed out many times, a turn was
   dated from the read after the turn before it, hours back, and refused as expired): a
   check that waits for nothing, the clock read before it, notes each socket it finds empty
   as empty since that reading (``_look``: empty at some moment after it, so never dated
   late); the wait itself is followed by one such check, since the time its return saw is
   only known after it. A datagram that ends a wait is dated from the look before it, so no
   wait lasts longer than UNSTAMPED_WAIT_S there (review 26: a wait of up to REPORT_IDLE_S
   dated a turn after an idle spell 10 s back, refused as expired; one sent half a second
   after a STOP, before it): early by a quarter second at most, four wake-ups a second. These
   bounds do not order two sockets' datagrams (review 33: a serve dates every datagram it reads
   by the bound its wake-up began with, though they came while it carried out the first, and
   another socket was found empty after that: a STOP so read was dated before a turn that came
   before it on another port, read at the next wake-up, and the turn went out dated after the
   STOP). So a datagram that may be a stop (rule 8's search) is noted with the time after its
   read, an upper bound, and one that is no stop, read later from another socket for one of
   the same rotators (a PST port's; on an N1MM port those the datagram names, ``_rotator_ids``:
   every one there for ``*`` or for a name several share, a turn to it being chosen by band,
   and every one named on the port for a datagram not understood, the safe side) with a bound
   before that time (it may have come before the stop), is dated BEFORE_HALT_S before the
   stop's date: the remote refuses it as seen before the STOP (remote.py rule 8). A stop for
   other rotators only says nothing of it: the remote orders a move against its own rotator's
   halts alone (review 34: rotator X's STOP, read first in a wake-up, dated rotator Y's turn,
   read after Y's own STOP on Y's port, before Y's STOP too, and the remote refused the
   operator's turn; review 36: the same through one N1MM port for a tower X and a yagi Y, as
   N1MM is usually set up, beside X's PstRotator port, while an N1MM port's rotators were
   every one named on it: the yagi's turn after the yagi's STOP was dated before X's STOP).
   A stop keeps its own bound (dated later, a turn its own sender sent after it would be lifted
   with it past a STOP from Home Assistant: remote.py rule 8's floor), and a datagram read
   after a stop from the same socket, whichever rotator that stop was for, is never dated
   before it (its bound is the later of its own and that stop's date): one socket's datagrams
   are read in the order they came (``AZIMUTH 300``, ``STOP``, ``AZIMUTH 200`` ends at 200).
   Only a stop for the same rotator from another socket, read after that bound, dates it
   earlier (it may have come after the turn: the safe side).
   What comes to a socket the loop found empty after the stop was read is dated as before:
   PstRotator tracks on after a STOP.
   Across interfaces (a rotctld ``S``, a logger's turn) the remote orders them itself: a
   move goes after another reader's stop only if seen after that stop was read (remote.py
   rule 8; a stop's ``read_s``, front.py rule 3).
   Each socket's stops are kept HALTS_KEPT at most, the oldest two then one: the later read,
   the earlier date, the rotators of both (the safe side: more is dated before it). With the
   system's stamps none of this is needed. The stale check above is the system's stamp's alone.
   The stamps are live before a port is bound (``_stamping_on``): Linux turns its stamping on
   for the first socket that asks a moment later, on a worker thread (milliseconds; longer on a
   loaded host), and a datagram that comes meanwhile is stamped when it is read, not when it
   came, with nothing to tell the two apart. A turn sent before a STOP from another interface,
   come in that moment and read after the STOP, was dated after it and carried out (a flaky
   test on a loaded 2-core CI machine, a real hole at every start). So a socket of its own asks
   first and sends itself datagrams until one comes back stamped before it was read; the ports
   asked while it holds the stamping on are stamped at once. Not live within STAMPS_LIVE_S:
   said, and the ports listen all the same.
10. Every port is the bridge's alone: no socket option lets another program bind it too, so
   one that tries is told the address is in use (and a bridge that finds it taken says so at
   its start). N1MM advises programs to share its ports (SO_REUSEADDR), but on Linux a
   datagram sent to one address goes to the socket bound there last: an attack pass bound the
   N1MM port as another user (``nobody``), with SO_REUSEADDR, and took every STOP sent to it,
   5 of 5, without a word; a second bridge on the same port took them from the first. Two
   programs that both obey one port's rotor commands are a conflict all the same.
"""

from __future__ import annotations

import contextlib
import errno
import logging
import os
import platform
import re
import selectors
import socket
import struct
import sys
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

from bridge.core.ratelimit import SourceBudgets
from bridge.interfaces.fdwait import readable
from bridge.interfaces.loggers.commands import (
    JUNK_LOG_S,
    Arrival,
    Commands,
    N1mmEndpoint,
    N1mmRotor,
    PstEndpoint,
    Rarely,
    Rotator,
)
from bridge.interfaces.loggers.datagrams import (
    MAX_DATAGRAM,
    Malformed,
    N1mmRequest,
    ascii_text,
    may_stop_n1mm,
    may_stop_pst,
    n1mm_report,
    parse_n1mm,
    parse_pst,
)
from bridge.interfaces.loggers.resolver import Lookup, ReportAddress, lookup_ipv4
from bridge.pointing import angle_between

log = logging.getLogger(__name__)

FAULT_LOG_S = 10.0  # a fault behind a datagram or in the loop: logged at most this often
PER_WAKEUP = 16  # datagrams read from one socket before the next ready one is served
RATE_DATAGRAMS_S = 200.0  # rule 8: a sender's budget, a second
RATE_ALL_S = 1000.0  # rule 8: every sender's together, a second
MAX_SOURCES = 256  # rule 8: senders whose budget is remembered
RECV_BUFFER = 1 << 20  # rule 8: asked of the system (which may give less: net.core.rmem_max)
FLOOD_LOG_S = 30.0  # rule 8
STAMPS_LIVE_S = 2.0  # rule 9: the most listen() waits for the system's stamps to come on
REPORT_LOOK_S = 0.1  # a flood's wake-ups look at the reports no more often than this
REPORT_MOVING_S = 1.5
REPORT_IDLE_S = 15.0
# rule 9, where the system does not stamp datagrams: the longest wait, so a datagram that ends
# one is dated at most this much before it came (a review: dated from the start of a 15 s wait,
# a turn after an idle spell was refused as expired, one 0.5 s after a STOP as before it)
UNSTAMPED_WAIT_S = 0.25
# rule 9, where the system does not stamp datagrams: how far before a stop read on another
# socket a datagram not proven to have come after it is dated (one stamp's millisecond)
BEFORE_HALT_S = 0.001
HALTS_KEPT = 8  # rule 9: the stops read on one socket remembered for that, at most
REPORT_MOVE_DEG = 1.0  # a heading this far from the last report is reported at the next look

_BIND_HINTS = {
    errno.EADDRINUSE: " (another program, PstRotator or a second bridge, has it)",
    errno.EACCES: " (ports below 1024 need privileges)",
    errno.EADDRNOTAVAIL: " (the bind address is not an address of this host)",
}


@dataclass
class N1mmReporter:
    rotator: Rotator
    name: str
    endpoint: N1mmEndpoint  # its socket sends the reports (from the configured address)
    to: ReportAddress  # rule 6: where they go, never looked up here
    next_s: float = 0.0
    last_deg: float | None = None  # the heading last reported
    failed: bool = False  # a report could not be sent (said once at warning level)
    unknown: bool = False  # rule 6: a report dropped, its name not found yet (said once)


class LoggerEndpoints:
    def __init__(
        self, clock: Callable[[], float] = time.monotonic, lookup: Lookup = lookup_ipv4
    ) -> None:
        self._clock = clock
        self._lookup = lookup  # rule 6: a report address's name, on a thread of its own
        self._report_addresses: dict[tuple[str, int], ReportAddress] = {}
        self.pst: list[PstEndpoint] = []
        self.n1mm: dict[tuple[str, int], N1mmEndpoint] = {}
        self._reporters: list[N1mmReporter] = []
        self._commands = Commands(clock, self._fault)
        self.counts = self._commands.counts
        self._sockets: dict[socket.socket, PstEndpoint | N1mmEndpoint] = {}
        self._addresses: dict[socket.socket, tuple[str, int]] = {}  # where each really listens
        self._dropped: set[socket.socket] = set()  # went bad: no longer selected (rule 7)
        # rule 9, where the system does not stamp datagrams: when each socket was last found
        # empty (monotonic), and a time before any could be (for one not read yet)
        self._drained_s: dict[socket.socket, float] = {}
        # ... and the stops read on each: (the time after the read, the date given, the ids of
        # the rotators they were for), oldest first
        self._halts_read: dict[socket.socket, deque[tuple[float, float, frozenset[str]]]] = {}
        self._started_s = time.monotonic()
        self._selector: selectors.BaseSelector | None = None
        self._thread: threading.Thread | None = None
        self._wake_r, self._wake_w = -1, -1
        self._junk_log = Rarely(JUNK_LOG_S)
        self._fault_log = Rarely(FAULT_LOG_S)
        self._flood_log = Rarely(FLOOD_LOG_S)
        self._budgets: dict[socket.socket, SourceBudgets] = {}  # rule 8: each port's own
        self._looked_s = -REPORT_LOOK_S
        self.over_budget = 0  # rule 8: datagrams dropped unparsed

    # -- configuration --------------------------------------------------------------------
    def add_pst(self, rotator: Rotator, port: int, bind: str = "127.0.0.1") -> None:
        self.pst.append(PstEndpoint(rotator, bind, port))

    def add_n1mm(
        self,
        rotator: Rotator,
        name: str,
        port: int = 12040,
        bind: str = "127.0.0.1",
        report_to: tuple[str, int] = ("127.0.0.1", 13010),
        bands: tuple[str, ...] = (),
    ) -> None:
        """``bands``: what a turn to a shared name or ``*`` is chosen by (commands.py rule 5)."""
        endpoint = self.n1mm.setdefault((bind, port), N1mmEndpoint(bind, port))
        endpoint.rotors.append(N1mmRotor(name, rotator, bands))
        to = self._report_addresses.get(report_to)
        if to is None:  # rule 6: one lookup thread a name, however many report there
            to = self._report_addresses[report_to] = ReportAddress(*report_to, self._lookup)
        self._reporters.append(N1mmReporter(rotator, name, endpoint, to))

    def __bool__(self) -> bool:
        return bool(self.pst or self.n1mm)

    # -- life -----------------------------------------------------------------------------
    def listen(self) -> None:
        """Take every address (OSError naming the endpoint and the reason if one cannot be
        had, and none kept)."""
        if self._sockets:
            return
        # rule 10: every port has one owner (a PstRotator or another bridge still running must
        # show as "in use"), N1MM's too
        wanted: list[tuple[PstEndpoint | N1mmEndpoint, str]] = [
            (e, f"PstRotator UDP for rotator {e.rotator.id!r}") for e in self.pst
        ]
        wanted += [(e, f"N1MM rotor UDP for {_named(e)}") for e in self.n1mm.values()]
        holder = _stamping_on()  # rule 9: live before the first datagram can come
        try:
            for endpoint, what in wanted:
                sock = _bound(endpoint.bind, endpoint.port, what)
                self._sockets[sock] = endpoint
                self._budgets[sock] = SourceBudgets(
                    RATE_DATAGRAMS_S, RATE_ALL_S, MAX_SOURCES, self._clock()
                )
                host, port = sock.getsockname()[:2]
                self._addresses[sock] = host, port
        except OSError:
            self._close_sockets()
            raise
        finally:
            if holder is not None:  # (the ports hold the stamping on now)
                holder.close()

    def start(self) -> None:
        self.listen()
        for endpoint in self._sockets.values():
            where = f"{endpoint.bind}:{endpoint.port}"
            if endpoint.bind not in ("127.0.0.1", "localhost"):
                log.warning(
                    "logger UDP port %s is not on loopback: neither PstRotator's nor N1MM's "
                    "protocol has authentication, anyone who can reach it can turn the antenna",
                    where,
                )
            log.info("logger UDP port %s (%s) listening", where, _kind(endpoint))
        for to in self._report_addresses.values():  # rule 6: names looked up beside it
            to.start()
        self._wake_r, self._wake_w = os.pipe()
        self._thread = threading.Thread(target=self._loop, name="loggers", daemon=True)
        self._thread.start()

    def stop(self, timeout_s: float = 3.0) -> None:
        for to in self._report_addresses.values():  # (never waited for: resolver.py rule 4)
            to.stop()
        if self._thread is not None:
            os.write(self._wake_w, b"x")
            self._thread.join(timeout_s)
            self._thread = None
            os.close(self._wake_r)
            os.close(self._wake_w)
        self._close_sockets()

    def address(self, endpoint: PstEndpoint | N1mmEndpoint) -> tuple[str, int]:
        """Where ``endpoint`` really listens (port 0 in tests: the one the system gave)."""
        for sock, e in self._sockets.items():
            if e is endpoint:
                return self._addresses[sock]
        return endpoint.bind, endpoint.port

    def _socket_of(self, endpoint: PstEndpoint | N1mmEndpoint) -> socket.socket | None:
        for sock, e in self._sockets.items():
            if e is endpoint and sock not in self._dropped:
                return sock
        return None

    def _close_sockets(self) -> None:
        for sock in self._sockets:
            sock.close()
        self._sockets.clear()
        self._addresses.clear()
        self._budgets.clear()
        self._dropped.clear()
        self._halts_read.clear()

    # -- the thread -----------------------------------------------------------------------
    def _loop(self) -> None:
        """Rule 7: nothing that goes wrong in here ends the thread."""
        failed_before = False
        try:
            while True:
                try:
                    if self._selector is None:
                        self._selector = self._new_selector()
                    if not self._turn(self._selector):
                        return
                    failed_before = False
                except Exception as exc:
                    self._fault("the loggers' loop", exc)
                    self._close_selector()  # a fresh one next time round
                    if failed_before:  # the same again: not at 100 % of a core
                        readable((self._wake_r,), 0.1)
                    failed_before = True
        finally:
            self._close_selector()

    def _new_selector(self) -> selectors.BaseSelector:
        sel = selectors.DefaultSelector()
        for sock in self._sockets:
            if sock not in self._dropped:
                try:
                    sel.register(sock, selectors.EVENT_READ)
                except (OSError, ValueError) as exc:  # closed under us
                    self._drop(sock, OSError(str(exc)))
        sel.register(self._wake_r, selectors.EVENT_READ)
        return sel

    def _close_selector(self) -> None:
        if self._selector is not None:
            self._selector.close()
            self._selector = None

    def _turn(self, sel: selectors.BaseSelector) -> bool:
        """One wake-up: every ready socket served PER_WAKEUP datagrams at most (rule 3), the
        reports looked at; False once stop() asks. Never a sleep while a datagram waits (rule
        8): a socket with more comes back ready at once."""
        now = self._clock()
        due = min((r.next_s for r in self._reporters), default=now + REPORT_IDLE_S)
        if self._reporters:  # look at the rotors often enough to see a move begin or end
            due = min(due, now + REPORT_MOVING_S)
        ready: list[socket.socket] = []
        waiting: set[object] | None = None  # rule 9: no stamps: what waits before the wait
        polled = time.monotonic()
        if not (_STAMPS and _STAMP_SPACE):
            waiting = self._look(sel)
        wait_s = max(0.0, due - now)
        if waiting is not None:  # rule 9: a datagram that ends the wait is dated from before it
            wait_s = min(wait_s, UNSTAMPED_WAIT_S)
        for key, _mask in sel.select(wait_s):
            if key.fileobj == self._wake_r:
                return False
            assert isinstance(key.fileobj, socket.socket)
            ready.append(key.fileobj)
        if waiting is not None:  # rule 9: and what the wait left empty, found so again now
            self._look(sel, ready)
        for sock in ready:
            if waiting is None:
                self._serve(sock)
            elif sock in waiting:  # rule 9: it came after the socket was last found empty
                self._serve(sock, self._drained_s.get(sock, self._started_s))
            else:  # it came during the wait: after the look before it
                self._serve(sock, polled)
        if any(sock in self._dropped for sock in ready):
            self._close_selector()  # rule 7: a selector that never hears of it again
        now = self._clock()
        if not ready or now - self._looked_s >= REPORT_LOOK_S:
            self._looked_s = now
            self._report(now)
        return True

    def _look(
        self, sel: selectors.BaseSelector, ready: list[socket.socket] | None = None
    ) -> set[object]:
        """Rule 9, where the system does not stamp datagrams: a check that waits for nothing,
        the clock read before it; every socket it finds with nothing waiting (and not in
        ``ready``, which the caller reads) was empty at some moment after that reading, so is
        noted empty since then. What waits is returned."""
        before = time.monotonic()
        waiting: set[object] = {key.fileobj for key, _mask in sel.select(0)}
        for sock in self._sockets:
            if sock not in waiting and sock not in self._dropped:
                if ready is None or sock not in ready:
                    self._drained_s[sock] = max(before, self._drained_s.get(sock, before))
        return waiting

    def _serve(self, sock: socket.socket, since_s: float | None = None) -> None:
        """Rule 3: PER_WAKEUP datagrams at most, each on its own; rule 8: a stop first; rule
        9: ``since_s``, where the system does not stamp datagrams, a time none that waits
        came before."""
        endpoint, budgets = self._sockets[sock], self._budgets[sock]
        named = endpoint if isinstance(endpoint, N1mmEndpoint) else None  # (rule 8's names)
        may_stop = may_stop_pst if named is None else may_stop_n1mm
        for _ in range(PER_WAKEUP):
            before = time.monotonic()  # rule 9: found empty from then on, if so
            try:
                data, peer, arrived = _received(sock)
                read_s = time.monotonic()  # rule 9: what was read came before this
            except (BlockingIOError, InterruptedError):
                self._drained_s[sock] = before
                return
            except OSError as exc:
                if exc.errno in (errno.EBADF, errno.ENOTSOCK):
                    self._drop(sock, exc)
                    return
                log.debug("logger UDP %s:%d: %s", *self._addresses[sock], exc)
                continue
            now = self._clock()
            source = peer[0], peer[1]
            stop = may_stop(data) and (named is None or _may_name(named, data))
            if not stop and not budgets.allow(source, now):
                self._flooded(now, source)
                continue
            seen_s = since_s
            parsed: N1mmRequest | Malformed | None = None  # (an N1MM datagram's, parsed once)
            if since_s is not None and arrived is None:  # rule 9: no stamp, a bound
                if named is not None:
                    parsed = _parse_n1mm(data)
                ids = self._rotator_ids(sock, parsed)
                if stop:
                    self._halt_read(sock, read_s, since_s, ids)
                else:
                    seen_s = self._before_halts(sock, since_s, ids)
            self._carry_out(sock, endpoint, data, peer, arrived, seen_s, parsed)
            budgets.spend(source, 1 + len(data) / 1024, now)

    def _halt_read(
        self, sock: socket.socket, read_s: float, since_s: float, ids: frozenset[str]
    ) -> None:
        """Rule 9, where the system does not stamp datagrams: a datagram that may be a stop for
        the rotators ``ids``, dated ``since_s``, read before ``read_s``: noted, for what another
        socket gives after it. The stops one serve reads share a date: one entry, the last
        read's time, every rotator they were for; past HALTS_KEPT the oldest two become one,
        the later time, the earlier date and both's rotators (the safe side: more is dated
        before them)."""
        halts = self._halts_read.setdefault(sock, deque())
        if halts and halts[-1][1] == since_s:
            halts[-1] = read_s, since_s, halts[-1][2] | ids
            return
        halts.append((read_s, since_s, ids))
        if len(halts) > HALTS_KEPT:
            (_, first, some), (last_s, second, more) = halts.popleft(), halts.popleft()
            halts.appendleft((last_s, min(first, second), some | more))

    def _before_halts(self, sock: socket.socket, since_s: float, ids: frozenset[str]) -> float:
        """Rule 9, where the system does not stamp datagrams: the date of a datagram that is
        no stop, read from ``sock``, come after ``since_s`` and for the rotators ``ids``: that,
        or the latest date of a stop ``sock`` gave before it if later (it came after that stop,
        whichever rotator the stop was for); unless a stop for one of the same rotators another
        socket gave was read after that bound (it may then have come after that stop): just
        before that stop's date, then (the safe side, even before its own port's stop)."""
        own = self._halts_read.get(sock, ())
        seen_s = bound_s = max([since_s, *(dated_s for _, dated_s, _ in own)])
        for other, halts in self._halts_read.items():
            if other is not sock:
                for read_s, dated_s, stopped in halts:
                    if read_s > bound_s and not ids.isdisjoint(stopped):
                        seen_s = min(seen_s, dated_s - BEFORE_HALT_S)
        return seen_s

    def _rotator_ids(
        self, sock: socket.socket, parsed: N1mmRequest | Malformed | None = None
    ) -> frozenset[str]:
        """Rule 9: the rotators a datagram on ``sock`` may stop or turn: a PST port's one; on
        an N1MM port those the datagram (``parsed``) names, every one on the port for ``*``
        and every one that shares a name (a turn to it is chosen by band: commands.py rule 5),
        none for a name nobody there has (the datagram moves and stops nothing); every one
        named on the port when the datagram is not understood (the safe side)."""
        endpoint = self._sockets.get(sock)
        if isinstance(endpoint, PstEndpoint):
            return frozenset((endpoint.rotator.id,))
        if not isinstance(endpoint, N1mmEndpoint):
            return frozenset()
        rotors = endpoint.rotors
        if isinstance(parsed, N1mmRequest):
            names = {parsed.rotor, *parsed.also} if parsed.stop else {parsed.rotor}
            if "*" not in names:
                rotors = [r for r in rotors if r.name in names]
        return frozenset(r.rotator.id for r in rotors)

    def _carry_out(
        self,
        sock: socket.socket,
        endpoint: PstEndpoint | N1mmEndpoint,
        data: bytes,
        peer: tuple[str, int],
        arrived: Arrival | None = None,
        seen_s: float | None = None,
        parsed: N1mmRequest | Malformed | None = None,
    ) -> None:
        """``parsed``: an N1MM datagram's parse, if rule 9 took it already."""
        try:
            if isinstance(endpoint, PstEndpoint):
                port = self._addresses[sock][1]
                req = parse_pst(data)
                self._commands.pst(endpoint, sock, port, req, peer, data, arrived, seen_s)
            else:
                n1mm = parse_n1mm(data) if parsed is None else parsed
                if isinstance(n1mm, Malformed):
                    raise n1mm
                self._commands.n1mm(endpoint, n1mm, data, peer[0], arrived, seen_s)
        except Malformed as exc:
            self._junk(_kind(endpoint), peer, exc)
        except Exception as exc:
            self._fault(f"{_kind(endpoint)} datagram from {peer[0]}", exc)

    def _drop(self, sock: socket.socket, exc: OSError) -> None:
        """Rule 7: a socket that cannot be read any more is said once and never selected."""
        self._dropped.add(sock)
        log.error(
            "logger UDP port %s:%d (%s) stopped listening: %s; restart the bridge to listen again",
            *self._addresses[sock],
            _kind(self._sockets[sock]),
            exc,
        )

    def _flooded(self, now: float, source: tuple[str, int]) -> None:
        """Rule 8: a datagram over its sender's budget, dropped unparsed."""
        self.over_budget += 1
        count = self._flood_log.due(now)
        if count is not None:
            log.warning(
                "logger UDP: %d datagram(s) dropped unread, over the budget of their sender "
                "(%g a second each, %g in all on a port), the last from %s:%d; stops are still "
                "obeyed",
                count,
                RATE_DATAGRAMS_S,
                RATE_ALL_S,
                *source,
            )

    def _fault(self, where: str, exc: Exception) -> None:
        """Rule 7: a bug behind a datagram or in the loop is logged (rarely) and survived."""
        count = self._fault_log.due(self._clock())
        if count is not None:
            log.error("loggers: %s failed (%d since the last report)", where, count, exc_info=exc)

    def _junk(self, kind: str, peer: tuple[str, int], exc: Malformed) -> None:
        """Rule 3."""
        self.counts[kind].malformed += 1
        count = self._junk_log.due(self._clock())
        if count is not None:
            log.debug(
                "%s UDP: dropped %d malformed datagram(s), the last from %s: %s",
                kind,
                count,
                peer[0],
                exc,
            )

    # -- N1MM reports ---------------------------------------------------------------------
    def _report(self, now: float) -> None:
        """Rule 6 (the loop comes here at least every REPORT_MOVING_S)."""
        for r in self._reporters:
            try:
                self._report_one(r, now)
            except Exception as exc:  # rule 7
                self._fault(f"the N1MM report of rotator {r.rotator.id!r}", exc)

    def _report_one(self, r: N1mmReporter, now: float) -> None:
        status = r.rotator.status
        bearing = status.bearing_deg
        sock = self._socket_of(r.endpoint)
        if bearing is None or not status.available or sock is None:
            return
        e = r.endpoint
        if e.shared(r.name) and e.current.get(r.name) is not r.rotator:  # rule 6
            r.last_deg = None  # reported at once when a turn chooses it
            return
        moved = r.last_deg is None or angle_between(bearing, r.last_deg) >= REPORT_MOVE_DEG
        if now < r.next_s and not moved:
            return
        to = r.to.current()  # rule 6: an address in digits, or none yet; never a lookup here
        if to is None:  # (looked at again in REPORT_MOVING_S, not at once: no busy wake-ups)
            r.next_s = now + REPORT_MOVING_S
            if not r.unknown:
                r.unknown = True
                log.warning(
                    "N1MM reports of rotator %r to %s:%d are dropped until the name is found "
                    "(looked up beside the logger ports, never in their way)",
                    r.rotator.id,
                    r.to.host,
                    r.to.port,
                )
            return
        r.next_s, r.last_deg = now + REPORT_IDLE_S, bearing
        try:
            sock.sendto(n1mm_report(r.name, bearing), to)
        except OSError as exc:  # e.g. from 127.0.0.1 to another host: said once
            level = logging.DEBUG if r.failed else logging.WARNING
            r.failed = True
            log.log(level, "N1MM report from %s to %s:%d: %s", r.endpoint.bind, *to, exc)


def _named(e: N1mmEndpoint) -> str:
    """``rotator 'tower' (N1MM's "Yagi")``, for every rotator on the endpoint."""
    return ", ".join(f"rotator {r.rotator.id!r} (N1MM's {r.name!r})" for r in e.rotors)


def _may_name(endpoint: N1mmEndpoint, data: bytes) -> bool:
    """Rule 8: whether a stop-like N1MM datagram may name a rotor of ``endpoint`` (or every
    rotor, ``*``): a tag's whole text, spaces around it aside, is one of them (parse_n1mm
    reads a name so, datagrams.py rule 4; a cold review: any ``*`` byte anywhere let a flood
    of stops for nobody past the budget). A name not all ASCII is not looked for: the datagram
    is parsed."""
    names = [rotor.name for rotor in endpoint.rotors]
    if not all(name.isascii() for name in names):
        return True
    text = data if data.isascii() else ascii_text(data).encode("ascii")
    alternatives = b"|".join(re.escape(name.encode("ascii")) for name in [*names, "*"])
    return re.search(rb">\s*(?:" + alternatives + rb")\s*<", text) is not None


def _parse_n1mm(data: bytes) -> N1mmRequest | Malformed:
    """Rule 9: an N1MM datagram parsed, or why it is not understood (said when carried out)."""
    try:
        return parse_n1mm(data)
    except Malformed as exc:
        return exc


def _kind(endpoint: PstEndpoint | N1mmEndpoint) -> str:
    return "pst" if isinstance(endpoint, PstEndpoint) else "n1mm"


def _bound(host: str, port: int, what: str) -> socket.socket:
    """Rule 10: ``host``:``port`` for this socket alone (no SO_REUSEADDR, no SO_REUSEPORT)."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        sock.bind((host, port))
        sock.setblocking(False)
        with contextlib.suppress(OSError):  # rule 8: the system may give less, or refuse
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, RECV_BUFFER)
        if _STAMPS:  # rule 9
            with contextlib.suppress(OSError):
                sock.setsockopt(socket.SOL_SOCKET, _STAMPS, 1)
    except OSError as exc:
        sock.close()
        code = exc.errno or 0
        reason = os.strerror(code) if code > 0 else exc.strerror or str(exc)
        raise OSError(
            exc.errno,
            f"{what}: cannot listen on {host}:{port}: {reason}{_BIND_HINTS.get(code, '')}",
        ) from None
    return sock


# rule 9: Linux's SO_TIMESTAMPNS (SO_TIMESTAMPNS_OLD, its cmsg type the same number), which
# Python does not name: 35 in asm-generic and on x86, the machines below; others, none
_STAMP_MACHINES = ("x86_64", "amd64", "i386", "i686", "aarch64", "arm64", "riscv64", "ppc64le")
_STAMPS = (
    35
    if sys.platform == "linux"
    and platform.machine().lower().startswith(_STAMP_MACHINES + ("armv",))
    else 0
)
_STAMP = struct.Struct("@ll")  # the old struct timespec: a long's seconds, a long's nanoseconds
_STAMP_SPACE = socket.CMSG_SPACE(_STAMP.size) if hasattr(socket, "CMSG_SPACE") else 0


def _stamping_on(wait_s: float = STAMPS_LIVE_S) -> socket.socket | None:
    """Rule 9: a socket that holds the system's datagram stamps on, returned once they are
    live (a datagram it sent itself came back stamped before it was read); None where the
    system gives none, or when they did not come on within ``wait_s`` (said)."""
    if not (_STAMPS and _STAMP_SPACE):
        return None
    holder = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        holder.bind(("127.0.0.1", 0))
        holder.setblocking(False)
        holder.setsockopt(socket.SOL_SOCKET, _STAMPS, 1)
        deadline = time.monotonic() + wait_s
        while True:
            holder.sendto(b"", holder.getsockname())
            if readable((holder.fileno(),), max(0.0, deadline - time.monotonic())):
                before = time.time()
                _data, ancillary, _flags, _peer = holder.recvmsg(1, _STAMP_SPACE)
                for level, kind, payload in ancillary:
                    if level == socket.SOL_SOCKET and kind == _STAMPS:
                        seconds, nanoseconds = _STAMP.unpack_from(payload)
                        if seconds + nanoseconds * 1e-9 < before:  # stamped as it came
                            return holder
            if time.monotonic() >= deadline:
                break
            time.sleep(0.001)  # (the system's worker turns them on: let it run)
    except OSError as exc:
        log.warning("logger UDP: the system's datagram stamps could not be checked: %s", exc)
        holder.close()
        return None
    log.warning(
        "logger UDP: the system's datagram stamps did not come on within %g s: a datagram "
        "that comes in the first moments may be judged by when it is read (server.py rule 9)",
        wait_s,
    )
    holder.close()
    return None


def _received(sock: socket.socket) -> tuple[bytes, tuple[str, int], Arrival | None]:
    """One datagram, its sender, and (rule 9) when the system took it, on the monotonic
    clock, between two bounds: None where the system does not say."""
    if not (_STAMPS and _STAMP_SPACE):
        data, peer = sock.recvfrom(MAX_DATAGRAM + 1)
        return data, peer, None
    data, ancillary, _flags, peer = sock.recvmsg(MAX_DATAGRAM + 1, _STAMP_SPACE)
    for level, kind, payload in ancillary:
        if level == socket.SOL_SOCKET and kind == _STAMPS and len(payload) >= _STAMP.size:
            seconds, nanoseconds = _STAMP.unpack_from(payload)
            before = time.monotonic()  # rule 9: on both sides of the wall clock's reading
            wall = time.time()
            after = time.monotonic()
            age = max(0.0, wall - (seconds + nanoseconds * 1e-9))
            return data, peer, Arrival(before - age, after - age)
    return data, peer, None
