"""The console's look at what each of its connections has sent, right before each STOP or lock
ON is counted: the TCP ports' construction (interfaces/tcplines.py rule 9, its ``Looks``) on the
console's sockets, so that a command whose bytes reached the bridge before another front end's
halt is dated before it, however late the console's event loop reads it (docs/architecture.md
rule 11; an attack pass: a script's target posted 2 ms before a rotctld ``S``, read by a busy
loop after it, turned the rotor; its lock OFF sent before Home Assistant's lock ON unlocked it).

Rules:
1. The console's listening sockets and the connections they accept are this module's
   (``listeners``, ``Listener``, ``Conn``), handed to asyncio as they are: each accept and each
   read is one step with what it counts, under the queue's or the connection's lock, so a
   look never counts bytes as both read and unread, nor misses bytes between the kernel and
   the event loop (tcplines.py rule 9).
2. Each rotator's halt watchers (core/haltwatch.py) are told right before it counts a halt:
   every connection with bytes beyond the request being served (``low``, rule 3) is looked at
   then, at the count before it: what it has read plus what the kernel holds unread
   (FIONREAD), one entry of ``Looks`` per look that found something new. A connection accepted
   but not yet served (asyncio accepts, then hands it over a step later) is among them. One
   still in the kernel's queue is looked at when it is accepted, at the floor: the count when
   the queue was last found empty (by an accept, or by the look before each halt, then ahead
   of the count), which only rises (tcplines.py ``_queue_looked``).
3. A request is dated by its first byte, a lower bound (``low``): the bytes the connection had
   read when the request before it was answered, if any came after that; if none did (HTTP
   pipelining: it came with the one before), that one's own bound. The count of the first
   look that counted a byte past it is when it arrived (``arrived``); a halt counted after
   that, other than the connection's own or its page's own numbered before it
   (server.py ``_looked``), overtakes its command, refused as stale. A body its handler left
   unread only moves the bound earlier: toward refusing. The one case that errs the other way:
   a request whose first bytes came in one read with the request before it and the rest
   after that one was answered is dated from that answer (a client that sends half a request
   behind another one's, pipelined).
4. Only the console's event loop reads a connection; a look runs on the halting thread and
   takes only the connection's lock. What a halt's look costs is bounded and small, whatever
   the console holds (connections.py's MOST_HELD at most) and whatever another thread runs:
   one ``poll`` with no wait over every connection and the listeners (whose queue rule 2 asks
   about) says which have bytes unread in the kernel, and only those are asked how many
   (FIONREAD); the others are counted as what the loop has read. Both system calls keep the
   interpreter lock (``ready_held``, fdwait.py rule 3, and ``unread_held``: ctypes' PyDLL, on Linux;
   each a few microseconds to a tenth of a millisecond in the kernel, never a wait); elsewhere
   they are fdwait's and fcntl's, which let it go. The look used to ask each connection in
   turn, each ioctl letting the lock go: with 250 connections held half-way through a request
   (connections.py's caps) a rotctld STOP's round trip went from 0.1-2 ms to 6-35 ms, and
   beside a thread running Python (it takes the lock back for up to its switch interval,
   5 ms, each time) a look over 500 took 0.3 s at p95; a poll that let it go, once, still
   9-14 ms (docs/performance.md, "Operator console").
5. Where the kernel cannot say what waits unread (Windows, no FIONREAD: the remote runs there),
   or asyncio does not accept and read through these sockets (its proactor loop), nothing is
   looked at: commands.py rule 5's start of the request dates it, as before.
6. A connection keeps only the looks a request can still be dated by (rule 3): the first past
   the bound of the request being served (``low``), the first past the bytes read when the
   last request was answered (``fin``: the next request's bound), and those at bytes the loop
   has not read yet (any later request begins there or further); a look at bytes already read
   that is neither dates nothing any more. At most LOOKS_KEPT are kept: past that two
   neighbours at bytes not read yet become one, dated by the earlier (toward refusing; only a
   connection paused over its budget, connections.py rule 4, through that many halts gets
   there). A page's WebSocket or event stream is one request for hours: it kept up to the
   TCP ports' SEEN_KEPT (4,096) looks a rotator, one per halt that found it had sent more,
   before this rule (review 51: some 160 MB a rotator at the console's caps).
"""

from __future__ import annotations

import itertools
import socket
import threading
import time
import weakref
from collections.abc import Callable, Hashable, Iterable
from typing import Any

from bridge.core.haltwatch import HaltWatchers
from bridge.interfaces.fdwait import libc_holding, ready_held
from bridge.interfaces.tcplines import Looks, unread

__all__ = ["Conn", "HaltLooks", "Listener", "unread_held"]

BACKLOG = 100  # the kernel's queue of connections (asyncio's own default)
LOOKS_KEPT = 16  # rule 6: a connection's looks kept per rotator, at most


def _unread_holding() -> Callable[[int], int]:
    """Rule 4: FIONREAD by a call that keeps the interpreter lock (ctypes' PyDLL: the lock is
    not let go around it), on Linux; elsewhere ``unread``'s (fcntl), which lets it go (an
    ioctl takes variadic arguments, whose calling convention ctypes is trusted with on Linux
    alone here)."""
    try:
        import ctypes
        import termios  # (a POSIX module: the remote runs where it is missing)
    except ImportError:
        return unread
    ioctl = libc_holding("ioctl", ctypes.c_int, ctypes.c_ulong, ctypes.c_void_p)
    if ioctl is None:
        return unread
    request = termios.FIONREAD

    def held(fd: int) -> int:
        waiting = ctypes.c_int(0)
        if ioctl(fd, request, ctypes.byref(waiting)) < 0:
            code = ctypes.get_errno()
            raise OSError(code, "FIONREAD failed")
        return waiting.value

    return held


unread_held = _unread_holding()


class Conn(socket.socket):
    """One accepted connection (rule 1): its reads counted under its lock; its looks per
    rotator; the bounds of rule 3."""

    __slots__ = ("fin", "lock", "looks", "low")

    def _setup(self, rotators: Iterable[str]) -> None:
        self.lock = threading.Lock()
        self.looks: dict[str, Looks] = {}
        for rid in rotators:
            looks = self.looks[rid] = Looks()
            looks.lock = self.lock  # (one lock for the reads and every rotator's looks)
        self.low = 0  # rule 3: the first byte of the request being served (or next), at least
        self.fin: int | None = None  # rule 3: what was read when the last request was answered

    def _read(self) -> int:
        """(under ``lock``) What the event loop has read of it so far."""
        return next(iter(self.looks.values())).read if self.looks else 0

    def recv(self, bufsize: int, flags: int = 0, /) -> bytes:
        with self.lock:  # rule 1: the read and its count, one step
            data = super().recv(bufsize, flags)
            for looks in self.looks.values():
                looks.read += len(data)
        return data

    def recv_into(self, buffer: Any, nbytes: int = 0, flags: int = 0, /) -> int:
        with self.lock:
            got = super().recv_into(buffer, nbytes, flags)
            for looks in self.looks.values():
                looks.read += got
        return got

    def look(self, rotator_id: str, count: int, waiting: bool = True) -> None:
        """Rule 2: one look, at ``count``, if the connection holds bytes past ``low`` that no
        look has counted yet; ``waiting``: the kernel may hold bytes unread (False: a poll
        since ``count`` was read found none, rule 4: what the loop has read is all)."""
        with self.lock:
            looks = self.looks.get(rotator_id)
            fd = self.fileno()
            if looks is None or fd < 0:
                return
            sent, counted = looks.read, True
            if waiting:
                try:
                    sent += unread_held(fd)
                except OSError:  # (the kernel cannot say: rule 5)
                    counted = False
            if sent <= self.low or (looks.seen and looks.seen[-1][0] >= sent):
                return
            looks.record(sent, count, counted, time.monotonic())
            self._trim(looks)

    def _trim(self, looks: Looks) -> None:
        """(under ``lock``) Rule 6: the looks no request can be dated by any more forgotten,
        and at most LOOKS_KEPT kept."""
        seen = looks.seen
        if len(seen) <= 2:
            return
        fin, read = self.fin, looks.read
        kept = [seen[0]]
        before = seen[0][0]
        for entry in itertools.islice(seen, 1, None):
            if entry[0] > read or (fin is not None and before <= fin < entry[0]):
                kept.append(entry)
            before = entry[0]
        while len(kept) > LOOKS_KEPT:  # (the oldest two past the first become one, dated
            first, second = kept[1], kept[2]  # by the earlier: toward refusing)
            kept[1:3] = [(second[0], first[1], first[2])]
        if len(kept) < len(seen):
            seen.clear()
            seen.extend(kept)

    def begin(self) -> None:
        """Rule 3: a request begins (the event loop's): its ``low``, and the looks at bytes
        before it forgotten."""
        with self.lock:
            read = self._read()
            if self.fin is None:
                low = 0
            elif read > self.fin:
                low = self.fin
            else:  # (pipelined: it was read before the one before it was answered)
                low = self.low
            self.low = low
            for looks in self.looks.values():
                while looks.seen and looks.seen[0][0] <= low:
                    looks.seen.popleft()

    def end(self) -> None:
        """Rule 3: a request answered (the event loop's)."""
        with self.lock:
            self.fin = self._read()

    def arrived(self, rotator_id: str) -> int | None:
        """Rule 3: the halt count when the request being served was first looked at (None:
        after every look so far)."""
        with self.lock:
            looks = self.looks.get(rotator_id)
            if looks is None or not looks.seen:
                return None
            return looks.seen[0][1]


class Listener(socket.socket):
    """A listening socket whose accepts are counted (rules 1, 2)."""

    __slots__ = ("halt_looks",)
    halt_looks: HaltLooks

    def accept(self) -> tuple[socket.socket, Any]:
        looks: HaltLooks = self.halt_looks
        with looks.queue_lock:  # rule 2: the queue found empty at these counts (read first)
            counts = looks.counts()
            try:
                plain, peer = super().accept()
            except BlockingIOError:
                looks.found_empty(counts)
                raise
            floors = dict(looks.floors)
        conn = Conn(plain.family, plain.type, plain.proto, fileno=plain.detach())
        conn._setup(counts)
        looks.accepted(conn, floors)
        return conn, peer


class HaltLooks:
    """Rules 1 to 3 for one console: its rotators' counts and watchers, its listeners, its
    connections."""

    def __init__(self) -> None:
        self._counts: dict[str, Callable[[], int]] = {}
        self._watchers: dict[str, tuple[HaltWatchers, Callable[[], None]]] = {}
        self.floors: dict[str, int] = {}  # rule 2: under ``queue_lock``
        self.queue_lock = threading.Lock()
        # by descriptor, from the accept until asyncio lets the socket go
        self._conns: weakref.WeakValueDictionary[int, Conn] = weakref.WeakValueDictionary()
        self._conns_lock = threading.Lock()
        self._listeners: list[Listener] = []
        # server.py ``_looked``: the halts the console itself carried out here, by number
        self.own: dict[str, dict[int, tuple[Hashable, str | None, int | None]]] = {}

    def attach(self, rotator_id: str, count: Callable[[], int], watchers: HaltWatchers) -> None:
        """Before ``start``: a rotator whose halts are looked before (rule 2)."""
        self._counts[rotator_id] = count

        def coming() -> None:
            self._coming(rotator_id)

        self._watchers[rotator_id] = (watchers, coming)
        self.own[rotator_id] = {}

    def listeners(self, bind: str, port: int) -> list[Listener]:
        """The listening sockets for ``bind`` (every address when empty) and ``port``, bound
        and listening (OSError if not), as asyncio's ``create_server`` would make them."""
        made: list[Listener] = []
        try:
            infos = socket.getaddrinfo(
                bind or None, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE
            )
            for family, kind, proto, _name, address in dict.fromkeys(infos):
                try:
                    sock = Listener(family, kind, proto)
                except OSError:  # (a family this host has not: skipped, as asyncio does)
                    continue
                made.append(sock)
                sock.halt_looks = self
                if hasattr(socket, "SO_REUSEADDR") and not hasattr(socket, "SO_EXCLUSIVEADDRUSE"):
                    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
                if family == socket.AF_INET6 and hasattr(socket, "IPPROTO_IPV6"):
                    sock.setsockopt(socket.IPPROTO_IPV6, socket.IPV6_V6ONLY, 1)
                sock.bind(address)
                sock.listen(BACKLOG)
                sock.setblocking(False)
            if not made:
                raise OSError(f"no socket for {bind or '(every address)'}:{port}")
        except BaseException:
            for sock in made:
                sock.close()
            raise
        self._listeners = made
        return made

    def start(self) -> None:
        """Rule 2: told before each halt from now on."""
        for rid, (watchers, coming) in self._watchers.items():
            with self.queue_lock:
                self.floors[rid] = self._counts[rid]()
            watchers.add(coming)

    def stop(self) -> None:
        for watchers, coming in self._watchers.values():
            watchers.remove(coming)

    def counts(self) -> dict[str, int]:
        return {rid: count() for rid, count in self._counts.items()}

    def found_empty(self, counts: dict[str, int]) -> None:
        """(under ``queue_lock``) Rule 2: the queue empty, at ``counts`` read first."""
        for rid, count in counts.items():
            self.floors[rid] = max(self.floors.get(rid, count), count)

    def accepted(self, conn: Conn, floors: dict[str, int]) -> None:
        """Rule 2: looked at before each halt from now on, and now: at the count then, or the
        floor if lower (it came when the count was at least the floor)."""
        fd = conn.fileno()
        with self._conns_lock:
            self._conns[fd] = conn
        for rid, count in self.counts().items():
            conn.look(rid, min(count, floors.get(rid, count)))

    def of(self, transport: Any) -> Conn | None:
        """The connection a request came on (None: not one of these, rule 5)."""
        sock = transport.get_extra_info("socket") if transport is not None else None
        try:
            fd = sock.fileno() if sock is not None else -1
        except (OSError, ValueError):
            return None
        with self._conns_lock:
            return self._conns.get(fd)

    def _coming(self, rotator_id: str) -> None:
        """Rule 2 (the halting thread): every connection looked at, at the count before the
        halt, then the queue's floor raised past it if the queue is empty; rule 4: one poll
        says which connections hold bytes unread, and only those are asked how many."""
        count = self._counts[rotator_id]()
        with self._conns_lock:
            each = list(self._conns.values())
        fds = [_fd(conn) for conn in each]
        with self.queue_lock:  # (one poll for both, after both counts were read: rule 4)
            now = self._counts[rotator_id]()
            listening = [_fd(sock) for sock in self._listeners]
            waiting = ready_held(fds + listening)
            if not any(fd < 0 or fd in waiting for fd in listening):
                self.floors[rotator_id] = max(self.floors.get(rotator_id, now), now + 1)
        for conn, fd in zip(each, fds, strict=True):
            conn.look(rotator_id, count, waiting=fd in waiting)


def _fd(sock: socket.socket) -> int:
    """``sock``'s descriptor, -1 once closed (never polled: fdwait.py rule 2; a listener's:
    a connection may wait in its queue, rule 2 errs toward refusing)."""
    try:
        return sock.fileno()
    except (OSError, ValueError):
        return -1
