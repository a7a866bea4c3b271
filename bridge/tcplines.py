"""The TCP side shared by the text front ends (rotctld, GS-232, Easycomm): one listener per
rotator and protocol, one thread per client, every reply in one send, and a budget per client so
that no client, nor all of them together, can starve the serial-lines thread of the GIL.

What a client's bytes mean is not decided here: each client gets a fresh ``LineSession`` from the
front end (its parser and its commands onto the judge); this module owns the sockets.

Rules:
1. Each reply the session returns goes out in one ``sendall`` (Gpredict reads ``p`` with a single
   recv(); a GS-232 client reads one line).
2. A connection that speaks HTTP is closed at once with a warning and nothing it sent runs: its
   first line is held until complete and may not be an HTTP request line, and no line may be an
   HTTP header (``Host: ...``). A text protocol parses any bytes as commands, so a web page open
   on the shack PC could otherwise turn the antenna through a loopback port.
3. A client is disconnected when it sends nothing for the idle timeout (300 s by default), or
   leaves a command unfinished for 60 s (one byte a second would hold a slot for ever);
   connections turned away because every slot is taken are logged once per 10 s, with a count.
4. ``listen`` takes the address before anything else starts, and its OSError names the front end,
   the rotator, the address and the setting to change.
5. Nothing a client sends can starve a stop (docs/architecture.md rule 12), by construction:
   at most ``max_clients`` threads a port, ACCEPTS_S connections a second (the rest wait in the
   kernel's backlog); a wake-up reads at most READ_BYTES (so runs at most that many commands);
   each client has a budget (ratelimit.Budget) of bytes a second, each reply costing
   REPLY_COST more: over it, its thread sleeps in the kernel (an Event) and its bytes wait in
   TCP's buffers, said once (at most once per LOG_S a port). A client that sends MAX_UNFINISHED
   bytes without finishing a command (no command is near that long) is dropped and logged (at
   most once per LOG_S, with a count); the bytes are counted from the last command finished
   (a read that finishes one counts its own bytes at most), so commands sent back to back,
   however the reads cut them, never add up. A well-behaved client's stop is read at its first
   wake-up: its budget is its own.
"""

from __future__ import annotations

import errno
import logging
import math
import os
import re
import select
import selectors
import socket
import threading
import time
from collections.abc import Callable, Sequence
from typing import Protocol

from bridge.ratelimit import Budget

log = logging.getLogger(__name__)

USEFUL_WITHIN_S = 60.0  # bytes trickling in without a complete command: dropped after this
REFUSAL_LOG_S = 10.0  # connections turned away are logged at most this often, with a count
# rule 5: a tracker sending 20 targets and 20 readings a second spends about 3 KB/s of this
READ_BYTES = 64  # at most this much read, and so at most this many commands run, a wake-up
RATE_BYTES_S = 8192.0  # a client's budget: this many bytes a second, a burst of as many
REPLY_COST = 64  # each reply (each command answered) costs this many bytes of the budget
MAX_UNFINISHED = 4096  # bytes without a complete command: the client is dropped
LOG_S = 10.0  # rule 5's log lines, at most this often a port
ACCEPTS_S = 20.0  # rule 5: connections accepted a second, at most


class RareLog:
    """One warning at most once per ``every_s``, with how many since the last said."""

    def __init__(self, every_s: float = LOG_S) -> None:
        self._every_s = every_s
        self._said_s = -math.inf
        self._since = 0
        self._lock = threading.Lock()

    def warn(self, now: float, msg: str, *args: object) -> None:
        with self._lock:
            self._since += 1
            if now - self._said_s < self._every_s:
                return
            count, self._since, self._said_s = self._since, 0, now
        log.warning(msg + " (%d time(s) since last said)", *args, count)


class Close:
    """A session's answer that ends the connection (rotctld's ``q``)."""


CLOSE = Close()


class LineSession(Protocol):
    """One client's conversation: bytes in, replies out (each reply is sent in one write)."""

    @property
    def idle(self) -> bool:
        """True when no command is half received."""
        ...

    def feed(self, data: bytes) -> Sequence[bytes | Close]: ...


def _bind_hints(key: str) -> dict[int, str]:
    return {
        errno.EADDRINUSE: f" (another program on this port? give this rotator another {key}_port)",
        errno.EACCES: " (ports below 1024 need privileges: use 4533 or above)",
        errno.EADDRNOTAVAIL: f" ({key}_bind is not an address of this host)",
    }


class LineServer:
    """One TCP listener for one rotator; one thread per client, each with its own session.
    ``label`` names the front end in logs and errors; ``key`` is its settings prefix."""

    def __init__(
        self,
        rotator_id: str,
        port: int,
        bind: str,
        session: Callable[[], LineSession],
        *,
        label: str,
        key: str,
        max_clients: int = 16,
        idle_timeout_s: float = 300.0,
        useful_within_s: float = USEFUL_WITHIN_S,
        clock: Callable[[], float] = time.monotonic,
        peer_session: Callable[[str], LineSession] | None = None,
        rate_bytes_s: float = RATE_BYTES_S,
        read_bytes: int = READ_BYTES,
        max_unfinished: int = MAX_UNFINISHED,
    ) -> None:
        """``peer_session``, if given, makes each client's session knowing its address (who
        sent a command: model.Origin) instead of ``session``. The last three: rule 5."""
        self._rate_bytes_s = rate_bytes_s
        self._read_bytes = read_bytes
        self._max_unfinished = max_unfinished
        self._paused_log = RareLog()
        self._dropped_log = RareLog()
        self._ended = threading.Event()  # stop(): a paused client's thread wakes at once
        self.paused = 0  # rule 5: times a client was over its budget, for the tests
        self._peer_session = peer_session
        self.rotator_id = rotator_id
        self.label = label
        self._key = key
        self._session = session
        self._bind = bind
        self._requested_port = port
        self._max_clients = max_clients
        self._idle_timeout_s = idle_timeout_s
        self._useful_within_s = max(useful_within_s, 0.0)
        self._clock = clock
        self._refused_logged_s = -REFUSAL_LOG_S
        self._refused_since = 0
        self._listener: socket.socket | None = None
        self._wake_r, self._wake_w = -1, -1
        self._accept_thread: threading.Thread | None = None
        self._lock = threading.Lock()
        self._clients: dict[socket.socket, threading.Thread] = {}
        self._stopping = False

    @property
    def address(self) -> tuple[str, int]:
        if self._listener is None:
            return self._bind, self._requested_port
        host, port = self._listener.getsockname()[:2]
        return host, port

    @property
    def port(self) -> int:
        return self.address[1]

    @property
    def client_count(self) -> int:
        with self._lock:
            return len(self._clients)

    def listen(self) -> None:
        """Rule 4: take the address; OSError whose strerror is one line naming the rotator, the
        address and the reason if it cannot be had. ``start`` does this too."""
        if self._listener is not None:
            return
        host, port = self._bind, self._requested_port
        try:
            family = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)[0][0]
            self._listener = socket.create_server((host, port), family=family)
        except OSError as exc:
            # create_server's strerror repeats the address; the plain reason is enough
            code = exc.errno or 0
            reason = os.strerror(code) if code > 0 else exc.strerror or str(exc)
            raise OSError(
                exc.errno,
                f"{self.label} for rotator {self.rotator_id!r}: cannot listen on {host}:{port}: "
                f"{reason}{_bind_hints(self._key).get(code, '')}",
            ) from None

    def start(self) -> None:
        """Listen (OSError if the address cannot be had) and accept clients in a thread."""
        self.listen()
        host = self._bind
        if host not in ("127.0.0.1", "::1", "localhost"):
            log.warning(
                "%s for %s listens on %s:%d: %s has no authentication, anyone who "
                "can reach this address can turn the antenna",
                self.label,
                self.rotator_id,
                host,
                self.port,
                self.label,
            )
        self._wake_r, self._wake_w = os.pipe()
        self._stopping = False
        self._ended.clear()
        self._accept_thread = threading.Thread(
            target=self._accept_loop, name=f"{self._key}-{self.rotator_id}", daemon=True
        )
        self._accept_thread.start()
        log.info("%s for %s listening on %s:%d", self.label, self.rotator_id, *self.address)

    def stop(self, timeout_s: float = 3.0) -> None:
        """Stop listening, close every client; commands already queued stay queued."""
        if self._listener is None:
            return
        if self._accept_thread is None:  # listening, never started: nothing else to end
            self._listener.close()
            self._listener = None
            return
        with self._lock:
            self._stopping = True
            clients = list(self._clients.items())
        self._ended.set()
        os.write(self._wake_w, b"x")
        self._accept_thread.join(timeout_s)
        for conn, _thread in clients:
            try:
                conn.shutdown(socket.SHUT_RDWR)  # wakes the client thread's recv()
            except OSError:
                pass
        for _conn, thread in clients:
            thread.join(timeout_s)
        self._listener.close()
        self._listener = None
        self._accept_thread = None
        os.close(self._wake_r)
        os.close(self._wake_w)

    def _accept_loop(self) -> None:
        listener = self._listener
        assert listener is not None
        listener.setblocking(False)  # a client that gave up between select and accept
        budget = Budget(ACCEPTS_S, self._clock())
        with selectors.DefaultSelector() as sel:
            sel.register(listener, selectors.EVENT_READ)
            sel.register(self._wake_r, selectors.EVENT_READ)
            while True:
                pause_s = budget.wait_s(self._clock())
                if pause_s > 0:  # rule 5: the next ones wait in the backlog
                    if select.select([self._wake_r], [], [], pause_s)[0]:
                        return
                    continue
                events = sel.select()
                if any(key.fileobj == self._wake_r for key, _ in events):
                    return
                try:
                    conn, peer = listener.accept()
                except BlockingIOError:
                    continue
                except OSError as exc:
                    log.warning("%s for %s: accept failed: %s", self.label, self.rotator_id, exc)
                    continue
                conn.setblocking(True)
                budget.spend(1, self._clock())
                self._admit(conn, peer)

    def _admit(self, conn: socket.socket, peer: tuple[str, int]) -> None:
        with self._lock:
            if self._stopping or len(self._clients) >= self._max_clients:
                conn.close()
                self._refused_since += 1
                now = self._clock()
                if now - self._refused_logged_s >= REFUSAL_LOG_S:  # rule 3: one line, a count
                    log.warning(
                        "%s for %s: turned away %d connection(s), the last from %s:%d "
                        "(%d clients connected, the most it takes)",
                        self.label,
                        self.rotator_id,
                        self._refused_since,
                        peer[0],
                        peer[1],
                        len(self._clients),
                    )
                    self._refused_logged_s, self._refused_since = now, 0
                return
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            thread = threading.Thread(
                target=self._serve,
                args=(conn, peer),
                name=f"{self._key}-{self.rotator_id}-{peer[1]}",
                daemon=True,
            )
            self._clients[conn] = thread
        thread.start()

    def _serve(self, conn: socket.socket, peer: tuple[str, int]) -> None:
        who = f"{self.label} for {self.rotator_id}: client {peer[0]}:{peer[1]}"
        log.info("%s connected", who)
        session = self._session() if self._peer_session is None else self._peer_session(peer[0])
        guard = HttpGuard()
        budget = Budget(self._rate_bytes_s, self._clock())
        unfinished = 0  # rule 5: bytes since the client last finished a command
        over = False  # rule 5: over its budget now (said once each time)
        last_bytes = self._clock()
        pending_since: float | None = None  # the first byte of a command not yet complete
        try:
            while True:
                pause_s = budget.wait_s(self._clock())
                if pause_s > 0:  # rule 5: in the kernel, unread, until back in credit
                    if not over:
                        over = True
                        self.paused += 1
                        self._paused_log.warn(
                            self._clock(), "%s sends faster than a client may: paused", who
                        )
                    if self._ended.wait(pause_s):
                        return
                    continue
                over = False
                # rule 3: silent for the idle timeout, or a command left unfinished for a while
                now = self._clock()
                deadline = last_bytes + self._idle_timeout_s
                if pending_since is not None:
                    deadline = min(deadline, pending_since + self._useful_within_s)
                if now >= deadline:
                    idle = now >= last_bytes + self._idle_timeout_s
                    log.info("%s dropped: %s", who, "idle" if idle else "no command")
                    return
                conn.settimeout(deadline - now)
                try:
                    data = conn.recv(self._read_bytes)
                except TimeoutError:
                    continue
                if not data:
                    break
                last_bytes, raw = self._clock(), len(data)
                data = guard.feed(data)
                if guard.http:
                    log.warning(
                        "%s sent %s: connection closed, nothing executed "
                        "(a web page may try to reach %s on this host)",
                        who,
                        guard.http,
                        self.label,
                    )
                    return
                replies = session.feed(data) if data else ()
                for reply in replies:
                    if isinstance(reply, Close):
                        return
                    if reply:
                        conn.sendall(reply)
                budget.spend(raw + REPLY_COST * len(replies), self._clock())
                finished = any(not isinstance(r, Close) for r in replies)
                if session.idle and not guard.holding:
                    pending_since, unfinished = None, 0
                elif finished:  # rule 5: counted from the last command finished, not read
                    pending_since, unfinished = last_bytes, raw  # its tail: within this read
                else:
                    unfinished += raw
                    if pending_since is None:
                        pending_since = last_bytes
                if unfinished > self._max_unfinished:  # rule 5: a line with no end
                    self._dropped_log.warn(
                        self._clock(),
                        "%s dropped: %d bytes and no command finished",
                        who,
                        unfinished,
                    )
                    return
        except OSError as exc:
            log.debug("%s: %s", who, exc)
        finally:
            with self._lock:
                self._clients.pop(conn, None)
            conn.close()
            dropped = "" if session.idle else " (an unfinished command was dropped)"
            log.info("%s gone%s", who, dropped)


_REQUEST_LINE = re.compile(rb"^[A-Za-z]{3,10} \S* ?HTTP/\d(\.\d)?\s*$")
_HEADER = re.compile(rb"^[A-Za-z][A-Za-z0-9-]{1,40}:[ \t]")
HTTP_FIRST_LINE_MAX = 8192


class HttpGuard:
    """Rule 2: what a client sends is held until its first line is complete; a connection whose
    first line is an HTTP request line, or that sends a header line (``Host: ...``) at any
    point, is HTTP and nothing of it may run (a web page cross-talking to a loopback port:
    ``KHTML`` in a User-Agent would park the rotor). ``feed`` returns the bytes the parser may
    have now; ``http`` names what was seen."""

    def __init__(self) -> None:
        self.http: str | None = None
        self._head: bytes | None = b""  # the first line while it is incomplete; None after
        self._line = b""  # the current line's start, for the header check

    @property
    def holding(self) -> bool:
        """True while the first line is held (incomplete)."""
        return self._head is not None

    def feed(self, data: bytes) -> bytes:
        if self._head is not None:
            self._head += data
            # a GS-232 client ends its lines with CR alone; an HTTP request line ends in CR LF
            ended = b"\n" in data or b"\r" in data  # not in what came before: it was held
            if not ended and len(self._head) < HTTP_FIRST_LINE_MAX:
                return b""
            data, self._head = self._head, None
            if _REQUEST_LINE.match(re.split(rb"[\r\n]", data, maxsplit=1)[0]):
                self.http = "an HTTP request line"
                return b""
        lines = (self._line + data).split(b"\n")
        self._line = lines[-1][-64:]  # enough of a partial line to see "Name: " at its start
        for line in lines:
            if _HEADER.match(line):
                self.http = f"an HTTP header ({line.split(b':')[0].decode('ascii', 'replace')})"
                return b""
        return data
