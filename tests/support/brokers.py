"""Brokers other than mosquitto, for the broker matrix (docs/brokers.md): a private nats-server
with its MQTT listener on a free loopback port (MQTT 3.1.1 only: it answers an MQTT 5 CONNECT
with "Unsupported protocol version"), and ``NoMqtt5``, a relay in front of a real broker that
closes the socket on an MQTT 5 CONNECT without a CONNACK, as RabbitMQ 3.10 and amqtt do, and
passes an MQTT 3.1.1 connection through byte for byte.

nats-server comes from Debian's ``nats-server`` package (tests/run installs it); a test that
needs it is skipped with that said when it is missing. NATS serves MQTT only with JetStream on,
which needs a server name and a store directory: both are in the workdir.

A broker is started when the port answers and, where it says one (``ready``), its log says
its listeners are bound: another program on the port answers before the broker has even tried
to bind it, and the broker then exits while every client reaches the other program's (as
tests/support/mosquitto.py's).
"""

from __future__ import annotations

import abc
import contextlib
import shutil
import socket
import subprocess
import threading
import time
from pathlib import Path

from tests.support.mosquitto import BrokerError, free_port, listens
from tests.support.waiting import slow


def find_nats() -> str | None:
    return shutil.which("nats-server") or next(
        (p for p in ("/usr/sbin/nats-server", "/usr/bin/nats-server") if Path(p).exists()), None
    )


AEDES_DIR = Path(__file__).resolve().parents[1] / "brokers" / "aedes"
RABBITMQ_SERVER = Path("/usr/lib/rabbitmq/bin/rabbitmq-server")
AMQTT = Path(__file__).resolve().parents[2] / ".brokers" / "amqtt-venv" / "bin" / "amqtt"


def find_aedes() -> tuple[str, Path] | None:
    """Node.js and the server script, if aedes is installed beside it (scripts/bootstrap)."""
    node = shutil.which("node") or shutil.which("nodejs")
    if node is None or not (AEDES_DIR / "node_modules" / "aedes").is_dir():
        return None
    return node, AEDES_DIR / "server.cjs"


class _Process(abc.ABC):
    """A broker run as a child process on a free loopback port: ``start()``/``stop()``/
    ``restart()`` as ``tests.support.mosquitto.Mosquitto``; each broker says how (``_command``)."""

    name = "broker"
    start_s = 20.0  # how long it may take to listen (scaled by ``slow``)
    ready: bytes | None = None  # what its log says once its listeners are bound, if anything

    def __init__(self, workdir: Path) -> None:
        self.host = "127.0.0.1"
        self.port = free_port()
        self.workdir = workdir
        self.log = workdir / f"{self.name}.log"
        self.proc: subprocess.Popen[bytes] | None = None

    @abc.abstractmethod
    def _command(self) -> tuple[list[str], dict[str, str] | None]:
        """The command line and environment (None: this one's) that start it on ``port``."""

    def _new_ports(self) -> None:
        """Other free ports, the last ones having been taken meanwhile."""
        self.port = free_port()

    def start(self) -> _Process:
        for attempt in range(3):
            try:
                return self._start(slow(self.start_s))
            except BrokerError:
                if attempt == 2:
                    raise
                self._new_ports()
        raise AssertionError("unreachable")

    def _start(self, timeout_s: float) -> _Process:
        self.workdir.mkdir(parents=True, exist_ok=True)
        argv, env = self._command()
        with open(self.log, "ab") as log:
            logged = log.tell()  # (an earlier start's log stays before it)
            self.proc = subprocess.Popen(
                argv, stdout=log, stderr=subprocess.STDOUT, cwd=self.workdir, env=env
            )
        deadline = time.monotonic() + timeout_s
        while not (self._bound(logged) and listens(self.host, self.port, 0.2)):
            if self.proc.poll() is not None:
                raise BrokerError(f"{self.name} exited: {self.log.read_text()[-2000:]}")
            if time.monotonic() > deadline:
                self.stop()
                raise BrokerError(f"{self.name} did not listen on {self.host}:{self.port}")
            time.sleep(0.05)
        return self

    def _bound(self, logged: int) -> bool:
        """Whether the log since ``logged`` says the listeners are bound (``ready``)."""
        if self.ready is None:
            return True
        with open(self.log, "rb") as log:
            log.seek(logged)
            return self.ready in log.read()

    def stop(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(slow(20))
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.proc = None

    def restart(self) -> None:
        """Same port: clients reconnect to where it was."""
        self.stop()
        self._start(slow(self.start_s))


class Nats(_Process):
    """nats-server's MQTT listener on ``port`` (the NATS client port is another free one, on
    loopback too)."""

    name = "nats"
    ready = b"Server is ready"

    def __init__(self, workdir: Path) -> None:
        exe = find_nats()
        if exe is None:
            raise BrokerError("nats-server is not installed (Debian: apt-get install nats-server)")
        super().__init__(workdir)
        self.exe = exe
        self.nats_port = free_port()

    def _new_ports(self) -> None:
        self.port, self.nats_port = free_port(), free_port()

    def _command(self) -> tuple[list[str], dict[str, str] | None]:
        conf = self.workdir / "nats.conf"
        conf.write_text(
            f"server_name: rb_{self.port}\n"
            f"listen: {self.host}:{self.nats_port}\n"
            f'jetstream {{ store_dir: "{self.workdir / "jetstream"}" }}\n'
            f"mqtt {{ listen: {self.host}:{self.port} }}\n"
        )
        return [self.exe, "-c", str(conf)], None


class Aedes(_Process):
    """aedes 0.46, as Node-RED users embed it (node-red-contrib-aedes): MQTT 3.1.1 only (it
    refuses an MQTT 5 CONNECT with "Unsupported protocol version"), in memory (a restart loses
    every retained message)."""

    name = "aedes"
    ready = b"aedes listening on"

    def __init__(self, workdir: Path) -> None:
        found = find_aedes()
        if found is None:
            raise BrokerError(
                "aedes is not installed (scripts/bootstrap: npm ci in tests/brokers/aedes)"
            )
        super().__init__(workdir)
        self.node, self.script = found

    def _command(self) -> tuple[list[str], dict[str, str] | None]:
        return [self.node, str(self.script), str(self.port)], None


class RabbitMq(_Process):
    """RabbitMQ 3.10 (Debian's rabbitmq-server) with its MQTT plugin, a node of its own in the
    workdir (MQTT 3.1.1 only: it closes an MQTT 5 connection before any CONNACK; retained
    messages are replayed to exact-topic subscriptions only). ``./tests/run brokers``."""

    name = "rabbitmq"
    start_s = 60.0

    def _command(self) -> tuple[list[str], dict[str, str] | None]:
        if not RABBITMQ_SERVER.exists():
            raise BrokerError("rabbitmq-server is not installed (./tests/run brokers installs it)")
        w = self.workdir
        (w / "enabled_plugins").write_text("[rabbitmq_mqtt].\n")
        amqp, dist = free_port(), free_port()
        (w / "rabbitmq.conf").write_text(
            f"listeners.tcp.default = {self.host}:{amqp}\n"
            f"mqtt.listeners.tcp.default = {self.host}:{self.port}\n"
            "mqtt.allow_anonymous = true\n"
        )
        env = {
            "PATH": "/usr/bin:/bin:/usr/sbin:/sbin",
            "HOME": str(w),
            "RABBITMQ_NODENAME": f"rb{self.port}@localhost",
            "RABBITMQ_DIST_PORT": str(dist),
            "RABBITMQ_MNESIA_BASE": str(w / "mnesia"),
            "RABBITMQ_LOG_BASE": str(w / "logs"),
            "RABBITMQ_ENABLED_PLUGINS_FILE": str(w / "enabled_plugins"),
            "RABBITMQ_CONFIG_FILE": str(w / "rabbitmq.conf"),
        }
        return [str(RABBITMQ_SERVER)], env


class Amqtt(_Process):
    """amqtt 0.12 (PyPI), in a venv of its own in .brokers/amqtt-venv (MQTT 3.1.1 only: it
    refuses an MQTT 5 CONNECT, and never answers one that carries a will).
    ``./tests/run brokers``."""

    name = "amqtt"

    def _command(self) -> tuple[list[str], dict[str, str] | None]:
        if not AMQTT.exists():
            raise BrokerError("amqtt is not installed (./tests/run brokers installs it)")
        conf = self.workdir / "amqtt.yaml"
        conf.write_text(
            "listeners:\n  default:\n    type: tcp\n"
            f"    bind: {self.host}:{self.port}\n"
            "plugins:\n  amqtt.plugins.authentication.AnonymousAuthPlugin:\n"
            "    allow_anonymous: true\n"
        )
        return [str(AMQTT), "-c", str(conf)], None


def protocol_level(connect: bytes) -> int | None:
    """The protocol level of an MQTT CONNECT packet (4: 3.1.1, 5: MQTT 5), None if ``connect``
    is not (yet) a whole CONNECT's variable header."""
    if not connect or connect[0] >> 4 != 1:
        return None
    i = 1  # the remaining length: 1 to 4 bytes, 7 bits each
    while i < len(connect) and connect[i] & 0x80:
        i += 1
    i += 1
    if len(connect) < i + 2:
        return None
    name_len = int.from_bytes(connect[i : i + 2], "big")
    at = i + 2 + name_len
    return connect[at] if len(connect) > at else None


class NoMqtt5:
    """A relay on a free loopback port in front of ``port``: an MQTT 5 CONNECT is answered by
    closing the socket (no CONNACK); anything else is passed through both ways. ``levels``
    lists the protocol level of every CONNECT seen, in order."""

    def __init__(self, port: int) -> None:
        self.target = port
        self.levels: list[int | None] = []
        self.close_all = False  # closes on MQTT 3.1.1 too (an ACL, a connection limit)
        self.v5_closes_left: int | None = None  # closes only so many MQTT 5 ones (a restart)
        self._listener = socket.create_server(("127.0.0.1", 0))
        self.port = self._listener.getsockname()[1]
        self._socks: list[socket.socket] = []
        self._lock = threading.Lock()
        self._closed = False
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self) -> None:
        while True:
            try:
                sock, _ = self._listener.accept()
            except OSError:
                return
            threading.Thread(target=self._serve, args=(sock,), daemon=True).start()

    def _serve(self, sock: socket.socket) -> None:
        head = b""
        level: int | None = None
        while level is None and len(head) < 4096:
            try:
                data = sock.recv(4096)
            except OSError:
                data = b""
            if not data:
                sock.close()
                return
            head += data
            level = protocol_level(head)
        if self._refuses(level) or self.close_all or self._closed:
            sock.close()  # what RabbitMQ 3.10 does with MQTT 5
            return
        up = socket.create_connection(("127.0.0.1", self.target))
        with self._lock:
            self._socks += [sock, up]
        up.sendall(head)
        threading.Thread(target=self._pipe, args=(up, sock), daemon=True).start()
        self._pipe(sock, up)

    def _refuses(self, level: int | None) -> bool:
        """Whether a CONNECT of protocol ``level`` is answered by closing (``levels`` told)."""
        with self._lock:
            self.levels.append(level)
            closes_v5 = level == 5 and self.v5_closes_left != 0
            if closes_v5 and self.v5_closes_left is not None:
                self.v5_closes_left -= 1
        return closes_v5

    def _pipe(self, src: socket.socket, dst: socket.socket) -> None:
        with contextlib.suppress(OSError):
            while data := src.recv(65536):
                dst.sendall(data)
        for s in (src, dst):
            with contextlib.suppress(OSError):
                s.shutdown(socket.SHUT_RDWR)

    def close(self) -> None:
        self._closed = True
        self._listener.close()
        with self._lock:
            for s in self._socks:
                with contextlib.suppress(OSError):
                    s.close()


class Mqtt5Only(NoMqtt5):
    """A relay on a free loopback port in front of ``port`` that closes every CONNECT that is
    not MQTT 5 (a broker listener that speaks MQTT 5 alone: review 122) and passes an MQTT 5
    connection through both ways."""

    def _refuses(self, level: int | None) -> bool:
        with self._lock:
            self.levels.append(level)
        return level != 5


CONNACK_LATE_S = 3.0  # the broker's own pace, not a deadline: past the demo's 2 s, under paho's 5 s


class SlowBroker:
    """127.0.0.1:``port`` relays to ``backend``; the broker's first bytes on each connection (its
    CONNACK) are handed on ``CONNACK_LATE_S`` late, everything after at once (review 122)."""

    def __init__(self, backend: int) -> None:
        self._backend = backend
        self._listener = socket.create_server(("127.0.0.1", 0))
        self.port: int = self._listener.getsockname()[1]
        self._closed = threading.Event()
        self._socks: list[socket.socket] = []
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self) -> None:
        while True:
            try:
                client, _ = self._listener.accept()
                server = socket.create_connection(("127.0.0.1", self._backend))
            except OSError:
                return
            self._socks += [client, server]
            threading.Thread(target=self._pipe, args=(client, server, False), daemon=True).start()
            threading.Thread(target=self._pipe, args=(server, client, True), daemon=True).start()

    def _pipe(self, src: socket.socket, dst: socket.socket, late: bool) -> None:
        with contextlib.suppress(OSError):
            while data := src.recv(65536):
                if late:
                    late = False
                    if self._closed.wait(CONNACK_LATE_S):  # the broker's pace (not a deadline)
                        return
                dst.sendall(data)
        with contextlib.suppress(OSError):
            dst.shutdown(socket.SHUT_WR)

    def close(self) -> None:
        self._closed.set()
        self._listener.close()
        for s in self._socks:
            s.close()
