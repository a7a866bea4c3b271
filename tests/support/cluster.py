"""A fake DX cluster node for the tests: a real TCP listener on loopback that plays a script
per connection (what to send, when to wait for the test, when to drop the line) and records
what each client sent."""

from __future__ import annotations

import socket
import threading
from collections.abc import Callable
from dataclasses import dataclass, field

from tests.support.waiting import slow


@dataclass
class Session:
    """One accepted connection: what the client sent, as it came."""

    conn: socket.socket
    received: bytearray = field(default_factory=bytearray)

    def send(self, data: bytes) -> None:
        self.conn.sendall(data)

    def read_line(self, timeout_s: float = 10.0) -> bytes:
        """The client's next line (up to CRLF), what it sent before it included."""
        self.conn.settimeout(slow(timeout_s))
        while b"\r\n" not in self.received:
            data = self.conn.recv(1024)
            if not data:
                raise ConnectionError("the client closed")
            self.received += data
        line, _, rest = bytes(self.received).partition(b"\r\n")
        self.received = bytearray(rest)
        return line

    def nothing_sent_yet(self) -> bool:
        """Whether the client has sent nothing so far (read without waiting)."""
        self.conn.setblocking(False)
        try:
            data = self.conn.recv(1024)
        except BlockingIOError:
            return not self.received
        finally:
            self.conn.setblocking(True)
        self.received += data
        return not self.received


Script = Callable[[Session], None]


class FakeCluster:
    """``scripts[i]`` plays the i-th connection; it returns to drop the line (closed), or
    waits on ``done`` to keep it open until the test ends."""

    def __init__(self, scripts: list[Script]) -> None:
        self.scripts = scripts
        self.done = threading.Event()
        self.logins: list[bytes] = []
        self.errors: list[BaseException] = []
        self._server = socket.create_server(("127.0.0.1", 0))
        self.port: int = self._server.getsockname()[1]
        self._thread = threading.Thread(target=self._serve, name="fake-cluster", daemon=True)
        self._thread.start()

    def _serve(self) -> None:
        for script in self.scripts:
            try:
                conn, _ = self._server.accept()
            except OSError:
                return
            with conn:
                try:
                    script(Session(conn))
                except BaseException as exc:  # shown by the test that reads errors
                    self.errors.append(exc)

    def close(self) -> None:
        self.done.set()
        self._server.close()
        self._thread.join(timeout=slow(5))
