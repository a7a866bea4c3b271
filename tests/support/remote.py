"""What the remote (bridge/remote/) sent, as the station's broker saw it, and a link to the
station's broker that can stall."""

from __future__ import annotations

import contextlib
import re
import socket
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from types import TracebackType

from bridge.core.errors import RefusalCode, Refused
from bridge.interfaces.mqtt.heartbeat import beat_payload
from bridge.remote.run import Remote
from bridge.remote.settings import RemoteSettings
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt import Probe
from tests.support.waiting import slow, wait_until

_RECEIVED = re.compile(rb"Received PUBLISH from remote-\S+ \(.*'rotor/(\w+)'")


def remote_published(broker: Mosquitto, log_from: int) -> list[bytes]:
    """The leaves of the ``rotor/...`` topics a remote published, in order, since byte
    ``log_from`` of the broker's log (run with ``-v``)."""
    with open(broker.log, "rb") as f:
        f.seek(log_from)
        return _RECEIVED.findall(f.read())


@contextlib.contextmanager
def running_remote(
    broker_port: int, operator: str, endpoint: dict[str, object]
) -> Iterator[Remote]:
    """A remote for ``operator`` on the station's broker at ``broker_port`` (base topic
    ``rotor``) with the one ``endpoint``, started and its view of the station's first rotator
    current; stopped on leaving."""
    remote = Remote(
        RemoteSettings(
            operator=operator,
            mqtt={"host": "127.0.0.1", "port": broker_port, "base_topic": "rotor"},
            endpoints=[endpoint],
        )
    )
    try:
        remote.start()
        wait_until(
            lambda: remote.rotators[0].status.bearing_deg is not None,
            slow(10),
            "the remote's view of the station",
        )
        yield remote
    finally:
        remote.stop()


@dataclass
class Link:
    """A stand-in for the remote's link to the station's broker (remote/rotator.py ``Sender``):
    what it was handed, in order; down, it refuses as the real one does; a move's ``check``
    asked as the real one asks it (interfaces/mqtt/remote.py rule 9)."""

    up: bool = True
    sent: list[tuple[str, str]] = field(default_factory=list)

    def send(
        self,
        topic: str,
        payload: str,
        operator: str,
        expiry_s: int,
        check: Callable[[], None] | None = None,
        *,
        until_heard: bool = False,
        seen_s: float | None = None,
        after: tuple[str, ...] = (),
        reader: object = None,
        read_s: float | None = None,
    ) -> None:
        if not self.up:
            raise Refused(RefusalCode.OFFLINE, "not connected to the station's broker")
        if check is not None:
            check()
        self.sent.append((topic, payload))


class Heartbeat:
    """A stand-in station's heartbeat (interfaces/mqtt/heartbeat.py rule 1): the wall clock on
    ``rotor/bridge/heartbeat`` every ``every_s`` through ``probe``, from entering to leaving."""

    def __init__(self, probe: Probe, topic: str = "rotor/bridge/heartbeat", every_s: float = 0.5):
        self._probe, self._topic, self._every_s = probe, topic, every_s
        self._done = threading.Event()
        self._thread = threading.Thread(target=self._beat, daemon=True)

    def __enter__(self) -> Heartbeat:
        self._thread.start()
        return self

    def __exit__(
        self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self._done.set()
        self._thread.join(slow(5))

    def _beat(self) -> None:
        while not self._done.is_set():
            self._probe.client.publish(self._topic, beat_payload(time.time()), qos=0)
            self._done.wait(self._every_s)


def ask(port: int, line: bytes) -> bytes:
    """One rotctld request to a remote's endpoint on a fresh connection; its reply (one line:
    an RPRT, or ``p``'s two)."""
    with socket.create_connection(("127.0.0.1", port), timeout=slow(10)) as sock:
        sock.sendall(line)
        buf = b""
        while not buf.endswith(b"\n") or (line.startswith(b"p") and buf.count(b"\n") < 2):
            chunk = sock.recv(100)
            if not chunk:
                break
            buf += chunk
            if buf.startswith(b"RPRT") and buf.endswith(b"\n"):
                break
    return buf


class StallingLink:
    """A TCP link on a loopback port to ``target`` that can stall: stalled, what either side
    sends is taken and held (as a Wi-Fi link's buffers hold it) and a new connection gets no
    further than the link (``turned_away`` counts them); recovered, what it held is delivered,
    the old connection's first. ``flowing``: False for a link stalled from the start."""

    def __init__(self, target: int, flowing: bool = True) -> None:
        self.target = target
        self.flowing = threading.Event()
        if flowing:
            self.flowing.set()
        self.turned_away = 0  # connections closed while it stalled
        self._server = socket.create_server(("127.0.0.1", 0))
        self.port = int(self._server.getsockname()[1])
        self._socks: list[socket.socket] = []
        threading.Thread(target=self._accept, daemon=True).start()

    def stall(self) -> None:
        self.flowing.clear()

    def recover(self) -> None:
        self.flowing.set()

    def _accept(self) -> None:
        while True:
            try:
                conn, _ = self._server.accept()
            except OSError:
                return
            if not self.flowing.is_set():  # no connection is made across a stalled link
                self.turned_away += 1
                conn.close()
                continue
            upstream = socket.create_connection(("127.0.0.1", self.target))
            self._socks += [conn, upstream]
            for a, b in ((conn, upstream), (upstream, conn)):
                threading.Thread(target=self._pipe, args=(a, b), daemon=True).start()

    def _pipe(self, src: socket.socket, dst: socket.socket) -> None:
        with contextlib.suppress(OSError):
            while data := src.recv(65536):
                self.flowing.wait()  # held while the link stalls, delivered when it recovers
                dst.sendall(data)
        with contextlib.suppress(OSError):
            dst.shutdown(socket.SHUT_WR)

    def close(self) -> None:
        self.flowing.set()
        self._server.close()
        for s in self._socks:
            with contextlib.suppress(OSError):
                s.close()
