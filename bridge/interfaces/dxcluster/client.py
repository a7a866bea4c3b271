"""The DX cluster client: a telnet session to one node on a thread of its own, its spots kept
(book.py) and published (``B/spots``); and a second thread that turns a rotator to a call
(``R/target`` ``{"call": ...}``), so that no cty lookup runs on paho's or the lines thread.

Rules:
1. Off unless ``[dxcluster] enabled``. Connect, wait for the login prompt (``login:``, or a
   line asking for "your call"; at most LOGIN_WAIT_S, a slow node is waited for), send the
   call sign and CRLF, then read lines (spots.py) until the node closes or fails. The wait
   for the prompt ends at LOGIN_WAIT_S whether the node is silent or talks without asking
   (unless what it sends unasked are spots).
2. On any failure (refused, dropped, no prompt in time, a dead peer found by TCP keepalive)
   it connects again after a back-off: ``backoff_s`` (1 s) doubling to MAX_BACKOFF_S (60 s);
   a session that logged in and then brought a spot or lasted MAX_BACKOFF_S resets it (a node
   that refuses the call sign after the prompt and hangs up is not tried every second).
   Failures and logins are logged at most once per LOG_EVERY_S, with how many since (a node
   that sends a spot and hangs up is logged in to every second); a fault behind a
   line (a bug) likewise, with its traceback: the session goes on (house rule 8). Nothing
   ends the thread but stop() (which waits for a connect under way at most 5 s).
3. ``B/spots`` is published (retained) when the kept spots change: a new spot, or one aged
   out (checked every TICK_S); at most once per PUBLISH_EVERY_S (a busy node with skimmers
   sends several spots a second, and the list is up to tens of kilobytes), the newest list
   at the latest PUBLISH_EVERY_S + TICK_S after its spot; while the node is down, after each
   attempt to connect (the aged spots leave within a back-off and a connect timeout).
   ``on_calls`` (Home Assistant's select) gets the calls of the newest spots when they
   changed, at most once per CALLS_EVERY_S (the first at once). Spots the book does not take
   for their own time (older than ``max_age_min``: a node's replay at a login, or this host's
   wall clock wrong; book.py rule 2) are said in the log at most once per LOG_EVERY_S, with
   how many, the last one's time and the host's.
4. ``aim`` only queues (paho's thread returns at once; a full queue is a refusal). The aim
   thread takes the newest kept spot of the call, else its cty entity, and asks the rotator
   through its one judge (a ``Toward`` command: limits, keep-out, lock, lease), with the source
   ``dxcluster`` and the asker's origin kept for the audit. An unknown call, or no station,
   is a refusal on ``R/error``. A STOP or lock ON put in after the call was asked overtakes
   it: the call is refused, never turned to after the stop (docs/architecture.md rule 11). The
   rotator's halt count read when it was asked (by the MQTT service, before it asked its fence
   for another interface's halt: a stop put between the two is after the call, an attack
   pass: read here, it was not) goes with it to the judge (``submit``'s
   ``since``), which drops it at the put if a halt came since, however long the look-up took
   (a clock compared before the look-up let a stop that came during it be overtaken); so is
   its place in the order of the rotator's commands (``ticket``): a target sent after the
   call was asked is the later word, and the call is refused (an attack pass: a target of 200
   sent while the call's look-up ran was overtaken by it, the rotor turned back to the call).
   The lock, the wind and the lease are judged when it is asked too (``check_motion``), and
   again when it is put: a call asked while another held the lease, or the lock was ON, is
   refused then, not turned to once the lease was released (an attack pass: it was); a lock
   OFF takes a place in the order as well (mailbox.py rule 10a). A stamped call's expiry
   (interfaces/mqtt/service.py rule 9, ``not_after_s``) goes with the ``Toward`` it makes, as
   a stamped target's does: one that waits for the order of a STOP or lock past it is
   dropped (session.py rule 13).
5. The node cannot starve a stop (docs/architecture.md rule 12): a read takes at most
   READ_BYTES, every line is parsed in time linear in its length (spots.py rule 5), and the
   session has a budget of RATE_BYTES_S (ratelimit.Budget; each line charged LINE_COST more,
   each read READ_COST more: a node sending every byte in a segment of its own, paced just
   under the budget, woke the thread some 30,000 times a second, a fifth of a core of Python
   for a few KB): a node sending faster is not read until the budget allows (the thread sleeps
   in the kernel, the node's bytes wait in TCP's buffers), counted in ``paused``.
"""

from __future__ import annotations

import logging
import math
import queue
import socket
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

from bridge.core.errors import Refused
from bridge.core.model import Origin, Source, Toward
from bridge.core.ratelimit import Budget
from bridge.interfaces.dxcluster.book import Book
from bridge.interfaces.dxcluster.spots import Lines, parse_spot
from bridge.interfaces.mqtt.ports import RotatorPort

log = logging.getLogger(__name__)

CONNECT_TIMEOUT_S = 10.0
LOGIN_WAIT_S = 30.0  # rule 1
TICK_S = 1.0  # how often a quiet session looks at the spots' ages and at stop()
MAX_BACKOFF_S = 60.0
LOG_EVERY_S = 60.0
CALLS_EVERY_S = 60.0
PUBLISH_EVERY_S = 1.0
AIM_QUEUE = 16
READ_BYTES = 4096  # rule 5
RATE_BYTES_S = 32768.0  # rule 5: some 400 spot lines a second, far more than a busy node's
LINE_COST = 64  # rule 5: each line costs as many bytes more (its parse, its place)
READ_COST = 64  # rule 5: each read costs as many bytes more (a wake-up, the spots' ages)
_PROMPTS = (b"login:", b"your call", b"callsign:")


@dataclass
class Counts:
    """Read from any thread (tests, logs); written by the client's thread alone."""

    connects: int = 0  # sessions logged in
    spots: int = 0
    other_lines: int = 0  # greetings, announcements, junk, bytes that are not UTF-8
    long_lines: int = 0
    failures: int = 0
    faults: int = 0  # a bug behind a line, a publish that raised: logged, the session goes on
    quiet_reads: int = 0  # reads that timed out (TICK_S without a byte): a quiet node
    paused: int = 0  # rule 5: times the node sent faster than its budget


class SpotSelect(Protocol):
    """Home Assistant's publisher as the spot select's options need it (homeassistant/)."""

    def set_spot_calls(self, calls: tuple[str, ...]) -> None: ...


@dataclass(frozen=True)
class _Aim:
    rotator: RotatorPort
    call: str
    long_path: bool
    described: str
    origin: Origin
    halts: int  # rule 4: the rotator's halt count when it was asked
    ticket: int  # rule 4: its place in the order of the rotator's commands, taken then
    not_after_s: float | None = None  # rule 4: its stamp's expiry, for the Toward it makes


@dataclass
class DxCluster:
    host: str
    port: int
    login: str
    book: Book
    publish: Callable[[str], None]  # B/spots, retained
    on_calls: Callable[[tuple[str, ...]], None] | None = None
    backoff_s: float = 1.0
    clock: Callable[[], float] = time.monotonic
    counts: Counts = field(default_factory=Counts)

    def __post_init__(self) -> None:
        self._stop = threading.Event()
        self._sock: socket.socket | None = None
        self._sock_lock = threading.Lock()
        self._threads: list[threading.Thread] = []
        self._aims: queue.Queue[_Aim | None] = queue.Queue(AIM_QUEUE)
        self._logged_s = -math.inf
        self._since = 0
        self._login_said_s = -math.inf  # rule 2: when a login was last said
        self._logins_since = 0
        self._published: str | None = None
        self._published_s = -math.inf
        self._calls: tuple[str, ...] | None = None
        self._calls_s = -math.inf
        self._old_said_s = -math.inf  # rule 3: when spots too old were last said
        self._old_since = 0

    # -- life ---------------------------------------------------------------------------------
    def start(self) -> None:
        self._publish()  # an empty list at first: no stale spots from a run before
        for target, name in ((self._run, "dxcluster"), (self._aim_loop, "dxcluster-aim")):
            thread = threading.Thread(target=target, name=name, daemon=True)
            thread.start()
            self._threads.append(thread)
        log.info("DX cluster: connecting to %s:%d as %s", self.host, self.port, self.login)

    def stop(self) -> None:
        self._stop.set()
        with self._sock_lock:
            if self._sock is not None:
                try:
                    self._sock.shutdown(socket.SHUT_RDWR)  # its recv returns now
                except OSError:
                    pass
        try:
            self._aims.put_nowait(None)
        except queue.Full:
            pass  # the aim thread looks at the event after each request anyway
        for thread in self._threads:
            thread.join(timeout=5.0)
        self._threads.clear()

    def with_discovery(self, publisher: SpotSelect) -> None:
        """Home Assistant's spot select follows the newest calls (rule 3's ``on_calls``)."""
        self.on_calls = publisher.set_spot_calls

    # -- the telnet session (its own thread) ---------------------------------------------------
    def _run(self) -> None:
        delay = self.backoff_s
        while not self._stop.is_set():
            began_s, spots, connects = self.clock(), self.counts.spots, self.counts.connects
            try:
                self._session()
            except Exception as exc:  # rule 2: refused, dropped, timed out, or a bug
                if not self._stop.is_set():
                    self.counts.failures += 1
                    self._rarely(exc)
            lasted = self.clock() - began_s >= MAX_BACKOFF_S or self.counts.spots > spots
            if self.counts.connects > connects and lasted:
                delay = self.backoff_s
            if self._stop.is_set():
                break  # nothing published once stopping (the MQTT side is going too)
            try:
                self._tick()  # rule 3: spots age out while the node is down too (book rule 2)
            except Exception as exc:  # rule 2: a bug here must not end the thread
                self.counts.faults += 1
                self._rarely(exc)
            if self._stop.wait(delay):
                break
            delay = min(delay * 2, MAX_BACKOFF_S)

    def _session(self) -> None:
        """One connection, to its end (an exception says why)."""
        sock = socket.create_connection((self.host, self.port), timeout=CONNECT_TIMEOUT_S)
        with self._sock_lock:
            if self._stop.is_set():
                sock.close()
                return
            self._sock = sock
        lines = Lines()
        budget = Budget(RATE_BYTES_S, self.clock())
        logged_in, spots = False, self.counts.spots
        deadline = self.clock() + LOGIN_WAIT_S
        try:
            _keepalive(sock)
            sock.settimeout(TICK_S)
            while not self._stop.is_set():
                pause_s = budget.wait_s(self.clock())
                if pause_s > 0:  # rule 5: unread, in the kernel, until the budget allows
                    self.counts.paused += 1
                    self._stop.wait(min(pause_s, TICK_S))
                    self._tick()
                    continue
                try:
                    data = sock.recv(READ_BYTES)
                except TimeoutError:
                    self.counts.quiet_reads += 1
                    if not logged_in and self.counts.spots == spots and self.clock() > deadline:
                        raise TimeoutError(f"no login prompt in {LOGIN_WAIT_S:g} s") from None
                    self._tick()
                    continue
                if not data:
                    if self._stop.is_set():
                        return
                    raise ConnectionError("the node closed the connection")
                before = lines.long_lines
                complete = lines.feed(data)
                cost = READ_COST + len(data) + LINE_COST * len(complete)
                budget.spend(cost, self.clock())
                self.counts.long_lines += lines.long_lines - before
                if not logged_in and any(
                    p in line.lower() for line in [*complete, lines.pending] for p in _PROMPTS
                ):
                    sock.sendall(self.login.encode("ascii") + b"\r\n")
                    lines.reset()  # the prompt is no part of the next line
                    logged_in = True
                    self.counts.connects += 1
                    self._logged_in()
                    continue  # the prompt's own line is no spot
                quiet = self.counts.spots == spots  # a node that sends spots unasked is kept
                if not logged_in and quiet and self.clock() > deadline:  # rule 1: it talks and
                    raise TimeoutError(f"no login prompt in {LOGIN_WAIT_S:g} s")  # never asks
                for line in complete:
                    try:
                        self._line(line)
                    except Exception as exc:  # rule 2: a bug behind one line
                        self.counts.faults += 1
                        self._rarely(exc)
                self._tick()
        finally:
            with self._sock_lock:
                self._sock = None
            sock.close()

    def _logged_in(self) -> None:
        """Rule 2: said at most once per LOG_EVERY_S, with how many since (a node that sends a
        spot and hangs up is logged in to again every second)."""
        self._logins_since += 1
        now = self.clock()
        if now - self._login_said_s < LOG_EVERY_S:
            return
        count, self._logins_since, self._login_said_s = self._logins_since, 0, now
        again = f" ({count} times since last said)" if count > 1 else ""
        log.info("DX cluster: logged in to %s:%d%s", self.host, self.port, again)

    def _line(self, line: bytes) -> None:
        spot = parse_spot(line)
        if spot is None:
            self.counts.other_lines += 1
            return
        self.counts.spots += 1
        before = self.book.too_old
        self.book.add(spot)  # the cty lookup: here, on this thread
        if self.book.too_old != before:
            self._too_old()

    def _too_old(self) -> None:
        """Rule 3: spots older than max_age_min by their own time, said now and then."""
        self._old_since += 1
        now = self.clock()
        last = self.book.last_too_old
        if now - self._old_said_s < LOG_EVERY_S or last is None:
            return
        count, self._old_since, self._old_said_s = self._old_since, 0, now
        hhmm, wall = last
        here = time.strftime("%H%MZ", time.gmtime(wall))
        log.info(
            "DX cluster: %d spot(s) older than max_age_min by their own time not taken (the "
            "last of %sZ, at %s by this host's clock): a node's replay at login; if every "
            "spot is, this host's clock is wrong",
            count,
            hhmm,
            here,
        )

    def _tick(self) -> None:
        """Rule 3: the aged spots dropped; B/spots and the select's calls when they changed."""
        self.book.prune()
        now = self.clock()
        if now - self._published_s >= PUBLISH_EVERY_S:
            try:
                if self._publish():
                    self._published_s = now
            except Exception as exc:  # rule 2: the broker's side fails alone
                self.counts.faults += 1
                self._rarely(exc)
        if self.on_calls is None:
            return
        calls = self.book.calls()
        if calls != self._calls and now - self._calls_s >= CALLS_EVERY_S:
            self._calls, self._calls_s = calls, now
            try:
                self.on_calls(calls)
            except Exception as exc:  # rule 2: Home Assistant's part fails alone
                self._rarely(exc)

    def _publish(self) -> bool:
        """B/spots if the list changed; whether it was published."""
        payload = self.book.as_json()
        if payload == self._published:
            return False
        self._published = payload
        self.publish(payload)
        return True

    def _rarely(self, exc: BaseException) -> None:
        self._since += 1
        now = self.clock()
        if now - self._logged_s < LOG_EVERY_S:
            return
        count, self._since, self._logged_s = self._since, 0, now
        where = f"{self.host}:{self.port}"
        if isinstance(exc, OSError):
            log.warning("DX cluster %s: %s (%d failure(s) since last said)", where, exc, count)
        else:
            log.error("DX cluster %s: fault (%d since last said)", where, count, exc_info=exc)

    # -- turning to a call (rule 4) ------------------------------------------------------------
    def aim(
        self,
        rotator: RotatorPort,
        call: str,
        long_path: bool,
        described: str,
        origin: Origin,
        since: int | None = None,
        not_after_s: float | None = None,
    ) -> None:
        """From paho's thread: queued for the aim thread; a full queue is refused at once, and
        so is a call the lock, the wind or the lease refuses now (rule 4). ``since``: the halt
        count the asker read before it asked the MQTT fence (interfaces/mqtt/service.py rule
        11); read here when not given. ``not_after_s``: the asker's stamp's expiry on the
        steady clock (service.py rule 9), handed on with the ``Toward``."""
        try:
            rotator.check_motion(origin)
        except Refused as exc:
            rotator.report_refusal(exc.message, described, origin=origin)
            return
        try:
            halts = rotator.halts if since is None else since
            ticket = rotator.ticket()
            aim = _Aim(rotator, call, long_path, described, origin, halts, ticket, not_after_s)
            self._aims.put_nowait(aim)
        except queue.Full:
            rotator.report_refusal(
                "too many calls asked at once: send it again", described, origin=origin
            )

    def _aim_loop(self) -> None:
        while not self._stop.is_set():
            aim = self._aims.get()
            if aim is None:
                continue
            try:
                self._turn(aim)
            except Refused:
                pass  # the rotator has reported it on R/error
            except Exception as exc:  # rule 2
                self._rarely(exc)

    def _turn(self, aim: _Aim) -> None:
        if aim.rotator.halts != aim.halts:  # rule 4 (no look-up for it)
            aim.rotator.report_refusal(
                f"{aim.call}: a stop came after it was asked: not turned",
                aim.described,
                origin=aim.origin,
            )
            return
        kept = self.book.newest(aim.call)
        place = kept.place if kept is not None else self.book.entity_place(aim.call)
        if place is None:
            why = "not spotted and" if kept is None else "spotted without a locator, and"
            aim.rotator.report_refusal(
                f"{aim.call}: {why} in no entity of the cty file", aim.described, origin=aim.origin
            )
            return
        toward = Toward(
            place.latitude_deg,
            place.longitude_deg,
            place.locator,
            aim.long_path,
            source=Source.DXCLUSTER,
            origin=aim.origin,
            not_after_s=aim.not_after_s,
        )
        aim.rotator.submit(toward, aim.described, since=aim.halts, ticket=aim.ticket)  # rule 4


def _keepalive(sock: socket.socket) -> None:
    """Rule 2: a node that vanished without a word (a router's reboot) is noticed in about two
    minutes, not the system's two hours: a quiet node is normal, so no read timeout says it."""
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_KEEPALIVE, 1)
    for name, value in (("TCP_KEEPIDLE", 60), ("TCP_KEEPINTVL", 20), ("TCP_KEEPCNT", 3)):
        option = getattr(socket, name, None)
        if option is not None:
            sock.setsockopt(socket.IPPROTO_TCP, option, value)
