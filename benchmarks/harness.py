"""The benchmarks' own plumbing: processes that are always cleaned up, a private broker, the bridge
as a real service process, an MQTT recorder, rotctld, /proc readings, statistics and tables.

Rules:
1. Every process a benchmark starts goes through a Scope (spawn), which ends it in reverse order
   on leaving the `with` block, whatever happened (exception, Ctrl-C, SIGTERM turned into
   KeyboardInterrupt by __main__). Children also get PR_SET_PDEATHSIG, so they die with us even
   if we are killed outright; the emulator host also exits when its stdin closes. (The signal
   follows the spawning *thread*: a thread that spawns must outlive its Scope, as the pool
   threads of the parallel rows do.)
2. The bridge under test runs as its own process (`python -m bridge run -c FILE`), so its CPU,
   memory and GIL are its own; emulators run in this process (their frame log is the ground
   truth, stamped on time.monotonic, the same clock as ours) or in the emulator host.
3. Nothing here imports bridge internals except the emulators (and ModelSpec data for frame
   sizes): what is measured is the service as a user runs it.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import paho.mqtt.client as paho
from paho.mqtt.enums import CallbackAPIVersion

REPO = Path(__file__).resolve().parent.parent
PYTHON = sys.executable
_PR_SET_PDEATHSIG = 1


class BenchError(RuntimeError):
    """A measurement could not be made (a process died, a deadline passed)."""


#: set when the run is being abandoned (Ctrl-C, a failed parallel row): loops stop early
ABORT = threading.Event()


def check_abort() -> None:
    if ABORT.is_set():
        raise BenchError("aborted")


# -- processes ----------------------------------------------------------------------------------
def _die_with_parent() -> None:  # runs in the child between fork and exec
    try:
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGTERM)
    except OSError:
        pass


def child_env() -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.upper().startswith("ROTOR_BRIDGE_")}
    env["PYTHONPATH"] = str(REPO) + (os.pathsep + env["PYTHONPATH"] if "PYTHONPATH" in env else "")
    env.setdefault("PYTHONUNBUFFERED", "1")
    return env


def stop_process(proc: subprocess.Popen[Any], timeout_s: float = 5.0) -> None:
    if proc.poll() is not None:
        return
    with contextlib.suppress(ProcessLookupError):
        proc.terminate()
    try:
        proc.wait(timeout_s)
    except subprocess.TimeoutExpired:
        with contextlib.suppress(ProcessLookupError):
            proc.kill()
        proc.wait(5)


class Scope(contextlib.ExitStack):
    """An ExitStack that also spawns processes and always ends them (rule 1)."""

    def __init__(self, workdir: Path) -> None:
        super().__init__()
        self.workdir = workdir
        self.processes: list[subprocess.Popen[bytes]] = []
        workdir.mkdir(parents=True, exist_ok=True)

    def spawn(
        self,
        argv: Sequence[str],
        *,
        log_name: str,
        stdin: int | None = subprocess.DEVNULL,
        stdout: int | None = None,
        cwd: Path = REPO,
    ) -> subprocess.Popen[bytes]:
        log = open(self.workdir / log_name, "ab")  # noqa: SIM115 (closed by the stack)
        self.callback(log.close)
        proc = subprocess.Popen(
            list(argv),
            stdin=stdin,
            stdout=log if stdout is None else stdout,
            stderr=log,
            cwd=cwd,
            env=child_env(),
            preexec_fn=_die_with_parent,
        )
        self.callback(stop_process, proc)
        self.processes.append(proc)
        return proc


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def wait_until(
    predicate: Callable[[], Any], timeout_s: float, what: str, interval_s: float = 0.01
) -> Any:
    deadline = time.monotonic() + timeout_s
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() > deadline:
            raise BenchError(f"timed out after {timeout_s:g} s waiting for {what}")
        time.sleep(interval_s)


def check_alive(proc: subprocess.Popen[Any], name: str, log: Path | None = None) -> None:
    if proc.poll() is not None:
        tail = log.read_text(errors="replace")[-1500:] if log and log.exists() else ""
        raise BenchError(f"{name} exited with status {proc.returncode}\n{tail}")


# -- broker -------------------------------------------------------------------------------------
def find_mosquitto() -> str:
    for path in ("/usr/sbin/mosquitto", "/usr/local/sbin/mosquitto", "/usr/bin/mosquitto"):
        if os.path.exists(path):
            return path
    raise BenchError("mosquitto is not installed (Debian: sudo apt-get install mosquitto)")


def start_broker(scope: Scope, extra_conf: str = "") -> int:
    """A private mosquitto with its default limits, on a free loopback port; returns the port."""
    port = free_port()
    conf = scope.workdir / "mosquitto.conf"
    conf.write_text(
        f"listener {port} 127.0.0.1\npersistence false\nallow_anonymous true\n{extra_conf}"
    )
    proc = scope.spawn([find_mosquitto(), "-c", str(conf)], log_name="mosquitto.log")

    def answers() -> bool:
        check_alive(proc, "mosquitto", scope.workdir / "mosquitto.log")
        with contextlib.suppress(OSError), socket.create_connection(("127.0.0.1", port), 0.2):
            return True
        return False

    try:
        wait_until(answers, 10, "mosquitto to listen")
    except BenchError:
        log = scope.workdir / "mosquitto.log"
        raise BenchError(f"mosquitto did not listen on {port}: {log.read_text()[-500:]}") from None
    return port


# -- the bridge as a service process ------------------------------------------------------------
def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int | float):
        return repr(v)
    if isinstance(v, str | Path):
        return '"' + str(v).replace("\\", "\\\\").replace('"', '\\"') + '"'
    raise TypeError(f"cannot write {v!r} as TOML")


def write_config(path: Path, config: dict[str, Any]) -> None:
    """Top-level scalars, [tables] of scalars, and [[rotators]]: all the bridge's file needs."""
    lines: list[str] = []
    for key, value in config.items():
        if not isinstance(value, dict | list):
            lines.append(f"{key} = {_toml_value(value)}")
    for key, value in config.items():
        if isinstance(value, dict):
            lines.append(f"\n[{key}]")
            lines += [f"{k} = {_toml_value(v)}" for k, v in value.items()]
        elif isinstance(value, list):
            for item in value:
                lines.append(f"\n[[{key}]]")
                lines += [f"{k} = {_toml_value(v)}" for k, v in item.items()]
    path.write_text("\n".join(lines) + "\n")


@dataclass
class BridgeProcess:
    proc: subprocess.Popen[bytes]
    log: Path
    started_t: float

    @property
    def pid(self) -> int:
        return self.proc.pid

    def check(self) -> None:
        check_alive(self.proc, "the bridge", self.log)


def start_bridge(
    scope: Scope,
    broker_port: int,
    rotators: list[dict[str, Any]],
    *,
    homeassistant: bool = True,
    log_level: str = "INFO",
    name: str = "bridge",
) -> BridgeProcess:
    config = {
        "log_level": log_level,
        "state_file": str(scope.workdir / f"{name}-state.json"),
        "mqtt": {"port": broker_port, "client_id": f"bench-{name}-{os.getpid()}"},
        "homeassistant": {"enabled": homeassistant},
        "rotators": rotators,
    }
    path = scope.workdir / f"{name}.toml"
    write_config(path, config)
    t0 = time.monotonic()
    proc = scope.spawn([PYTHON, "-m", "bridge", "run", "-c", str(path)], log_name=f"{name}.log")
    return BridgeProcess(proc, scope.workdir / f"{name}.log", t0)


# -- MQTT ---------------------------------------------------------------------------------------
@dataclass
class Message:
    topic: str
    payload: bytes
    retain: bool
    t: float

    @property
    def text(self) -> str:
        return self.payload.decode(errors="replace")


class Mqtt:
    """A recording client: every message under its filters, stamped on arrival (monotonic)."""

    def __init__(
        self,
        port: int,
        filters: Iterable[str] = ("#",),
        *,
        name: str = "bench",
        max_inflight: int = 20,
    ) -> None:
        self.messages: list[Message] = []
        self._cond = threading.Condition()
        self._filters = list(filters)
        self._connected = threading.Event()
        c = paho.Client(CallbackAPIVersion.VERSION2, client_id=f"{name}-{os.getpid()}-{id(self)}")
        c.max_inflight_messages_set(max_inflight)
        c.on_connect = self._on_connect
        c.on_message = self._on_message
        c.connect_async("127.0.0.1", port, keepalive=30)
        c.loop_start()
        self.client = c
        if not self._connected.wait(10):
            self.close()
            raise BenchError("benchmark MQTT client could not connect")

    def _on_connect(self, client, userdata, flags, rc, props) -> None:  # noqa: ANN001
        # The measuring client must not add Nagle delays of its own (its PUBACKs would hold
        # back the next command until the broker's delayed ACK, up to 40 ms on Linux).
        sock = client.socket()
        if sock is not None:
            with contextlib.suppress(OSError):
                sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        for f in self._filters:
            client.subscribe(f, qos=1)
        self._connected.set()

    def _on_message(self, client, userdata, msg) -> None:  # noqa: ANN001
        m = Message(msg.topic, bytes(msg.payload), bool(msg.retain), time.monotonic())
        with self._cond:
            self.messages.append(m)
            self._cond.notify_all()

    def publish(self, topic: str, payload: str | bytes, qos: int = 1) -> paho.MQTTMessageInfo:
        return self.client.publish(topic, payload, qos=qos, retain=False)

    def mark(self) -> int:
        with self._cond:
            return len(self.messages)

    def on(self, topic: str) -> list[Message]:
        with self._cond:
            return [m for m in self.messages if m.topic == topic]

    def last(self, topic: str) -> Message | None:
        with self._cond:
            for m in reversed(self.messages):
                if m.topic == topic:
                    return m
        return None

    def wait(
        self, predicate: Callable[[Message], bool], timeout_s: float, what: str, start: int = 0
    ) -> Message:
        deadline = time.monotonic() + timeout_s
        with self._cond:
            i = start
            while True:
                while i < len(self.messages):
                    if predicate(self.messages[i]):
                        return self.messages[i]
                    i += 1
                left = deadline - time.monotonic()
                if left <= 0:
                    raise BenchError(f"timed out after {timeout_s:g} s waiting for {what}")
                self._cond.wait(left)

    def wait_value(self, topic: str, value: str, timeout_s: float, start: int = 0) -> Message:
        return self.wait(
            lambda m: m.topic == topic and m.payload == value.encode(),
            timeout_s,
            f"{topic} = {value}",
            start,
        )

    def wait_all(self, topics: Iterable[str], value: str, timeout_s: float) -> None:
        """Until the latest message on each topic carries `value`."""
        wanted = list(topics)

        def done() -> bool:
            return all((m := self.last(t)) is not None and m.text == value for t in wanted)

        wait_until(done, timeout_s, f"{len(wanted)} topics = {value}", 0.02)

    def close(self) -> None:
        with contextlib.suppress(Exception):
            self.client.disconnect()
        self.client.loop_stop()
