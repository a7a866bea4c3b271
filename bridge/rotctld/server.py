"""The TCP side: one listener per rotator, one thread per client, every reply in one send."""

from __future__ import annotations

import errno
import logging
import os
import selectors
import socket
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING

from bridge.rotctld.commands import RotctldCommands
from bridge.rotctld.parser import HttpGuard, Quit, RequestParser

if TYPE_CHECKING:
    from bridge.engine.rotator import Rotator

log = logging.getLogger(__name__)

USEFUL_WITHIN_S = 60.0  # bytes trickling in without a complete command: dropped after this
REFUSAL_LOG_S = 10.0  # connections turned away are logged at most this often, with a count

_BIND_HINTS = {
    errno.EADDRINUSE: " (another rotctld or rotor-bridge? give this rotator another rotctld_port)",
    errno.EACCES: " (ports below 1024 need privileges: use 4533 or above)",
    errno.EADDRNOTAVAIL: " (rotctld_bind is not an address of this host)",
}


class RotctldServer:
    """One TCP listener for one rotator; one thread per client."""

    def __init__(
        self,
        rotator: Rotator,
        port: int,
        bind: str = "127.0.0.1",
        *,
        max_clients: int = 16,
        idle_timeout_s: float = 300.0,
        useful_within_s: float = USEFUL_WITHIN_S,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.rotator = rotator
        self.rotator_id = rotator.id
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
        """Take the address; OSError whose strerror is one line naming the rotator, the address
        and the reason if it cannot be had. ``start`` does this too; the app calls it first so
        that a port in use stops the start before anything else runs."""
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
                f"rotctld for rotator {self.rotator_id!r}: cannot listen on {host}:{port}: "
                f"{reason}{_BIND_HINTS.get(code, '')}",
            ) from None

    def start(self) -> None:
        """Listen (OSError if the address cannot be had) and accept clients in a thread."""
        self.listen()
        host = self._bind
        if host not in ("127.0.0.1", "::1", "localhost"):
            log.warning(
                "rotctld for %s listens on %s:%d: rotctld has no authentication, anyone who "
                "can reach this address can turn the antenna",
                self.rotator_id,
                host,
                self.port,
            )
        self._wake_r, self._wake_w = os.pipe()
        self._stopping = False
        self._accept_thread = threading.Thread(
            target=self._accept_loop, name=f"rotctld-{self.rotator_id}", daemon=True
        )
        self._accept_thread.start()
        log.info("rotctld for %s listening on %s:%d", self.rotator_id, *self.address)

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
        os.write(self._wake_w, b"x")
        if self._accept_thread is not None:
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
        with selectors.DefaultSelector() as sel:
            sel.register(listener, selectors.EVENT_READ)
            sel.register(self._wake_r, selectors.EVENT_READ)
            while True:
                events = sel.select()
                if any(key.fileobj == self._wake_r for key, _ in events):
                    return
                try:
                    conn, peer = listener.accept()
                except BlockingIOError:
                    continue
                except OSError as exc:
                    log.warning("rotctld for %s: accept failed: %s", self.rotator_id, exc)
                    continue
                conn.setblocking(True)
                self._admit(conn, peer)

    def _admit(self, conn: socket.socket, peer: tuple[str, int]) -> None:
        with self._lock:
            if self._stopping or len(self._clients) >= self._max_clients:
                conn.close()
                self._refused_since += 1
                now = self._clock()
                if now - self._refused_logged_s >= REFUSAL_LOG_S:  # rule 8: one line, a count
                    log.warning(
                        "rotctld for %s: turned away %d connection(s), the last from %s:%d "
                        "(%d clients connected, the most it takes)",
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
                name=f"rotctld-{self.rotator_id}-{peer[1]}",
                daemon=True,
            )
            self._clients[conn] = thread
        thread.start()

    def _serve(self, conn: socket.socket, peer: tuple[str, int]) -> None:
        log.info("rotctld for %s: client %s:%d connected", self.rotator_id, peer[0], peer[1])
        parser = RequestParser()
        commands = RotctldCommands(self.rotator)  # one per client: p answers in its terms
        guard = HttpGuard()
        last_bytes = self._clock()
        pending_since: float | None = None  # the first byte of a command not yet complete
        try:
            while True:
                # rule 8: silent for the idle timeout, or a command left unfinished for a while
                now = self._clock()
                deadline = last_bytes + self._idle_timeout_s
                if pending_since is not None:
                    deadline = min(deadline, pending_since + self._useful_within_s)
                if now >= deadline:
                    log.info(
                        "rotctld for %s: client %s:%d dropped: %s",
                        self.rotator_id,
                        peer[0],
                        peer[1],
                        "idle" if now >= last_bytes + self._idle_timeout_s else "no command",
                    )
                    return
                conn.settimeout(deadline - now)
                try:
                    data = conn.recv(4096)
                except TimeoutError:
                    continue
                if not data:
                    break
                last_bytes = self._clock()
                data = guard.feed(data)
                if guard.http:
                    log.warning(
                        "rotctld for %s: %s:%d sent %s: connection closed, nothing executed "
                        "(a web page may try to reach rotctld on this host)",
                        self.rotator_id,
                        peer[0],
                        peer[1],
                        guard.http,
                    )
                    return
                for item in parser.feed(data):
                    if isinstance(item, Quit):
                        return
                    conn.sendall(commands.execute(item))
                if parser.idle:
                    pending_since = None
                elif pending_since is None:
                    pending_since = last_bytes
        except OSError as exc:
            log.debug("rotctld for %s: client %s:%d: %s", self.rotator_id, *peer, exc)
        finally:
            with self._lock:
                self._clients.pop(conn, None)
            conn.close()
            log.info(
                "rotctld for %s: client %s:%d gone%s",
                self.rotator_id,
                peer[0],
                peer[1],
                "" if parser.idle else " (an unfinished command was dropped)",
            )
