"""The loggers' UDP endpoints: one thread, every socket (a PST port per rotator, an N1MM port
per address shared by the rotators named on it), the N1MM position reports.

Rules:
1. Every command goes through the Rotator like MQTT's and rotctld's (Source.PST, Source.N1MM):
   the lock, limits, keep-out sectors and offsets are judged there, and a refusal is published
   on ``R/error`` naming the protocol. The sender gets no reply to a command: neither protocol
   has one.
2. ``AZ?``/``EL?`` are answered at once from the rotator's status, to the sender's address at
   the listen port + 1, in integer degrees with a CR: one reply per kind per datagram however
   often it asks, and no more than limiter.py lets go to that address (a sender's address can
   be anybody's: a burst, then a few a second); a reply beyond is dropped, counted
   (``replies_dropped``) and logged at most once per JUNK_LOG_S. No position, no answer (never
   a made-up one); an azimuth-only rotator does not answer ``EL?``.
3. Sockets are served in turn: on every wake-up each ready socket gives PER_WAKEUP datagrams
   at most, so a flood on one port delays a stop on another by that many datagrams, not by the
   flood. Each datagram is parsed on its own: a malformed or ambiguous one (datagrams.py rules
   1, 2 and 4) is dropped and counted, logged at debug level at most once per JUNK_LOG_S with
   the count since. Nothing of it reaches the rotator; the serial line is served by another
   thread and never waits for this one.
4. An azimuth outside 0..360 but inside Hamlib's -180..450 is folded into 0..360 (the
   rotator's own rules pick the way round); one beyond that is refused (a mis-scaled value,
   99999, must not become 279). An elevation sent to an azimuth-only rotator is ignored.
5. N1MM: a datagram for another rotor name is ignored; ``*`` is taken only when one rotator
   listens on that port, except a stop, which stops every rotator on it; a stop naming several
   rotors stops each of them on the port. ``bidirectional`` 1 turns to the heading or its
   reciprocal, whichever is nearer the bearing. A non-zero ``offset`` is logged once and not
   applied (its meaning is not documented).
6. N1MM position reports go to the configured destination from the N1MM port's own socket, so
   from the configured bind address (no socket of ours listens anywhere else); one that cannot
   be sent is said once at warning level. The heading is looked at every REPORT_MOVING_S and
   reported when it has moved REPORT_MOVE_DEG since the last report (while the rotor turns,
   and where it came to rest), else every REPORT_IDLE_S.
7. Nothing ends the thread but stop(): a fault behind a datagram (a bug in what it reaches) is
   logged with its traceback at most once per FAULT_LOG_S and the next datagram is served; a
   fault in the loop itself gets a fresh selector (and a pause if it comes again at once). A
   socket that cannot be read any more (EBADF, ENOTSOCK) is reported once and dropped: the
   selector is made anew without it, so it can never wake the thread again.
"""

from __future__ import annotations

import errno
import logging
import math
import os
import select
import selectors
import socket
import threading
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from bridge import geo
from bridge.errors import Refused
from bridge.loggers.datagrams import (
    MAX_DATAGRAM,
    Malformed,
    N1mmRequest,
    PstRequest,
    n1mm_report,
    parse_n1mm,
    parse_pst,
    pst_reply,
)
from bridge.loggers.limiter import ReplyLimiter
from bridge.model import Source, Stop, Target
from bridge.pointing import angle_between, norm360

if TYPE_CHECKING:
    from bridge.engine.rotator import Rotator

log = logging.getLogger(__name__)

JUNK_LOG_S = 10.0  # malformed datagrams, replies dropped: logged at most this often, a count
FAULT_LOG_S = 10.0  # a fault behind a datagram or in the loop: logged at most this often
PER_WAKEUP = 16  # datagrams read from one socket before the next ready one is served
AZ_FOLDED = (-180.0, 450.0)  # Hamlib's azimuth range: folded into 0..360; beyond, refused
REPORT_MOVING_S = 1.5
REPORT_IDLE_S = 15.0
REPORT_MOVE_DEG = 1.0  # a heading this far from the last report is reported at the next look

_BIND_HINTS = {
    errno.EADDRINUSE: " (another program, PstRotator or a second bridge, has it)",
    errno.EACCES: " (ports below 1024 need privileges)",
    errno.EADDRNOTAVAIL: " (the bind address is not an address of this host)",
}


@dataclass
class PstEndpoint:
    rotator: Rotator
    bind: str
    port: int


@dataclass
class N1mmEndpoint:
    """One N1MM address; the rotators that answer to a name on it."""

    bind: str
    port: int
    rotators: dict[str, Rotator] = field(default_factory=dict)  # name -> rotator


@dataclass
class N1mmReporter:
    rotator: Rotator
    name: str
    endpoint: N1mmEndpoint  # its socket sends the reports (from the configured address)
    to: tuple[str, int]
    next_s: float = 0.0
    last_deg: float | None = None  # the heading last reported
    failed: bool = False  # a report could not be sent (said once at warning level)


@dataclass
class Counts:
    """What came in, per protocol (the benchmark and the tests read them)."""

    commands: int = 0
    queries: int = 0
    malformed: int = 0
    ignored: int = 0
    replies_dropped: int = 0  # over the rate limit of the address they would go to


@dataclass
class _Rarely:
    """What can come in floods is logged at most once per ``every_s``, with the count since."""

    every_s: float
    logged_s: float = -math.inf
    since: int = 0

    def due(self, now: float) -> int | None:
        """One more; how many to report now, or None (not yet)."""
        self.since += 1
        if now - self.logged_s < self.every_s:
            return None
        count, self.since, self.logged_s = self.since, 0, now
        return count


class LoggerEndpoints:
    def __init__(self, clock: Callable[[], float] = time.monotonic) -> None:
        self._clock = clock
        self.pst: list[PstEndpoint] = []
        self.n1mm: dict[tuple[str, int], N1mmEndpoint] = {}
        self._reporters: list[N1mmReporter] = []
        self.counts = {"pst": Counts(), "n1mm": Counts()}
        self._sockets: dict[socket.socket, PstEndpoint | N1mmEndpoint] = {}
        self._addresses: dict[socket.socket, tuple[str, int]] = {}  # where each really listens
        self._dropped: set[socket.socket] = set()  # went bad: no longer selected (rule 7)
        self._selector: selectors.BaseSelector | None = None
        self._thread: threading.Thread | None = None
        self._wake_r, self._wake_w = -1, -1
        self._replies = ReplyLimiter(clock)
        self._junk_log = _Rarely(JUNK_LOG_S)
        self._limited_log = _Rarely(JUNK_LOG_S)
        self._fault_log = _Rarely(FAULT_LOG_S)
        self._offset_warned: set[str] = set()

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
    ) -> None:
        endpoint = self.n1mm.setdefault((bind, port), N1mmEndpoint(bind, port))
        endpoint.rotators[name] = rotator
        self._reporters.append(N1mmReporter(rotator, name, endpoint, report_to))

    def __bool__(self) -> bool:
        return bool(self.pst or self.n1mm)

    # -- life -----------------------------------------------------------------------------
    def listen(self) -> None:
        """Take every address (OSError naming the endpoint and the reason if one cannot be
        had, and none kept)."""
        if self._sockets:
            return
        # a PST port has one owner (a PstRotator still running must show as "in use"); N1MM's
        # advice is to share its port (SO_REUSEADDR), as its loggers and rotor programs do
        wanted: list[tuple[PstEndpoint | N1mmEndpoint, str, bool]] = [
            (e, f"PstRotator UDP for rotator {e.rotator.id!r}", False) for e in self.pst
        ]
        wanted += [(e, f"N1MM rotor UDP for {_named(e)}", True) for e in self.n1mm.values()]
        try:
            for endpoint, what, shared in wanted:
                sock = _bound(endpoint.bind, endpoint.port, what, shared)
                self._sockets[sock] = endpoint
                host, port = sock.getsockname()[:2]
                self._addresses[sock] = host, port
        except OSError:
            self._close_sockets()
            raise

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
        self._wake_r, self._wake_w = os.pipe()
        self._thread = threading.Thread(target=self._loop, name="loggers", daemon=True)
        self._thread.start()

    def stop(self, timeout_s: float = 3.0) -> None:
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
        self._dropped.clear()

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
                        select.select([self._wake_r], [], [], 0.1)
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
        reports looked at; False once stop() asks."""
        now = self._clock()
        due = min((r.next_s for r in self._reporters), default=now + REPORT_IDLE_S)
        if self._reporters:  # look at the rotors often enough to see a move begin or end
            due = min(due, now + REPORT_MOVING_S)
        ready: list[socket.socket] = []
        for key, _mask in sel.select(max(0.0, due - now)):
            if key.fileobj == self._wake_r:
                return False
            assert isinstance(key.fileobj, socket.socket)
            ready.append(key.fileobj)
        for sock in ready:
            self._serve(sock)
        if any(sock in self._dropped for sock in ready):
            self._close_selector()  # rule 7: a selector that never hears of it again
        self._report(self._clock())
        return True

    def _serve(self, sock: socket.socket) -> None:
        """Rule 3: PER_WAKEUP datagrams at most, each on its own."""
        endpoint = self._sockets[sock]
        for _ in range(PER_WAKEUP):
            try:
                data, peer = sock.recvfrom(MAX_DATAGRAM + 1)
            except (BlockingIOError, InterruptedError):
                return
            except OSError as exc:
                if exc.errno in (errno.EBADF, errno.ENOTSOCK):
                    self._drop(sock, exc)
                    return
                log.debug("logger UDP %s:%d: %s", *self._addresses[sock], exc)
                continue
            try:
                if isinstance(endpoint, PstEndpoint):
                    self._pst(endpoint, sock, parse_pst(data), peer, data)
                else:
                    self._n1mm(endpoint, parse_n1mm(data), data)
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

    # -- PstRotator -----------------------------------------------------------------------
    def _pst(
        self,
        e: PstEndpoint,
        sock: socket.socket,
        req: PstRequest,
        peer: tuple[str, int],
        data: bytes,
    ) -> None:
        counts, rot = self.counts["pst"], e.rotator
        port = self._addresses[sock][1]
        for query in req.queries:  # rule 2, before the command: the position it had
            status = rot.status
            value = status.bearing_deg if query == "AZ" else status.elevation_deg
            counts.queries += 1
            if not status.available or value is None:
                continue
            if not self._replies.allow(peer[0]):
                self._limited(counts, peer[0])
                continue
            try:
                sock.sendto(pst_reply(query, value), (peer[0], port + 1))
            except OSError as exc:
                log.debug("PST reply to %s:%d: %s", peer[0], port + 1, exc)
        counts.ignored += len(req.ignored)
        described = "pst " + data.decode("ascii").strip()[:120]
        has_el = rot.spec.has_elevation
        el = req.elevation if has_el else None
        try:
            if req.stop:
                rot.submit(Stop(Source.PST), described)
            elif req.park:
                rot.park(Source.PST, described)
            elif req.locator is not None:
                try:
                    lat, lon = geo.parse_locator(req.locator)
                except geo.LocatorError as exc:
                    rot.report_refusal(f"pst: locator {req.locator!r}: {exc}", described)
                    return
                rot.go_toward(lat, lon, Source.PST, described, locator=req.locator)
            elif req.azimuth is not None and not AZ_FOLDED[0] <= req.azimuth <= AZ_FOLDED[1]:
                rot.report_refusal(
                    f"pst: azimuth {req.azimuth:g} outside {AZ_FOLDED[0]:g}..{AZ_FOLDED[1]:g}",
                    described,
                )
                return
            elif req.azimuth is not None or el is not None:
                az = None if req.azimuth is None else norm360(req.azimuth)  # rule 4
                rot.submit(Target(az, el, Source.PST), described)
            else:
                return
            counts.commands += 1
        except Refused:
            pass  # the rotator has published it on R/error

    def _limited(self, counts: Counts, address: str) -> None:
        """Rule 2: a reply over the address's rate is dropped, counted, logged rarely."""
        counts.replies_dropped += 1
        count = self._limited_log.due(self._clock())
        if count is not None:
            log.info(
                "PST UDP: %d repl(ies) dropped over the rate limit, the last to %s (a client "
                "polling too fast, or queries sent in its name)",
                count,
                address,
            )

    # -- N1MM -----------------------------------------------------------------------------
    def _n1mm(self, e: N1mmEndpoint, req: N1mmRequest, data: bytes) -> None:
        counts = self.counts["n1mm"]
        described = "n1mm " + data.decode("ascii").strip()[:160]
        if req.stop:  # a stop is never dropped: every rotor it names, every one for "*"
            names = {req.rotor, *req.also}
            stopped = [r for n, r in e.rotators.items() if n in names or "*" in names]
            if stopped:
                self._stop_each(stopped, described)
                counts.commands += 1
                return
        rot = e.rotators.get(req.rotor)
        if rot is None and req.rotor == "*" and len(e.rotators) == 1:
            rot = next(iter(e.rotators.values()))
        if rot is None:
            counts.ignored += 1
            log.debug("N1MM UDP %d: rotor %r is not ours", e.port, req.rotor)
            return
        assert req.azimuth is not None
        if req.offset and req.rotor not in self._offset_warned:
            self._offset_warned.add(req.rotor)
            log.warning("N1MM rotor %r sends offset %g: not applied", req.rotor, req.offset)
        az = req.azimuth
        bearing = rot.status.bearing_deg
        if req.bidirectional and bearing is not None:
            az = min((az, norm360(az + 180.0)), key=lambda a: angle_between(a, bearing))
        try:
            rot.submit(Target(norm360(az), None, Source.N1MM), described)
            counts.commands += 1
        except Refused:
            pass

    def _stop_each(self, rotators: Iterable[Rotator], described: str) -> None:
        """Rule 7: a fault behind one rotator's stop does not keep it from the next."""
        for rot in rotators:
            try:
                rot.submit(Stop(Source.N1MM), described)
            except Exception as exc:
                self._fault(f"the N1MM stop of rotator {rot.id!r}", exc)

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
        moved = r.last_deg is None or angle_between(bearing, r.last_deg) >= REPORT_MOVE_DEG
        if now < r.next_s and not moved:
            return
        r.next_s, r.last_deg = now + REPORT_IDLE_S, bearing
        try:
            sock.sendto(n1mm_report(r.name, bearing), r.to)
        except OSError as exc:  # e.g. from 127.0.0.1 to another host: said once
            level = logging.DEBUG if r.failed else logging.WARNING
            r.failed = True
            log.log(level, "N1MM report from %s to %s:%d: %s", r.endpoint.bind, *r.to, exc)


def _named(e: N1mmEndpoint) -> str:
    """``rotator 'tower' (N1MM's "Yagi")``, for every rotator on the endpoint."""
    return ", ".join(f"rotator {r.id!r} (N1MM's {n!r})" for n, r in e.rotators.items())


def _kind(endpoint: PstEndpoint | N1mmEndpoint) -> str:
    return "pst" if isinstance(endpoint, PstEndpoint) else "n1mm"


def _bound(host: str, port: int, what: str, shared: bool) -> socket.socket:
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        if shared:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind((host, port))
        sock.setblocking(False)
    except OSError as exc:
        sock.close()
        code = exc.errno or 0
        reason = os.strerror(code) if code > 0 else exc.strerror or str(exc)
        raise OSError(
            exc.errno,
            f"{what}: cannot listen on {host}:{port}: {reason}{_BIND_HINTS.get(code, '')}",
        ) from None
    return sock
