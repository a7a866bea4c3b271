"""Real parts for tests: a mosquitto broker on a free loopback port, and an MQTT probe client.

Waiting is always on a condition with a deadline, never a bare sleep.
"""

from __future__ import annotations

import shutil
import socket
import subprocess
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import paho.mqtt.client as paho
from paho.mqtt.enums import CallbackAPIVersion


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_until(predicate: Callable[[], object], timeout_s: float = 10.0, what: str = "") -> object:
    deadline = time.monotonic() + timeout_s
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout_s} s waiting for {what or predicate}")
        time.sleep(0.01)


class Mosquitto:
    """A private mosquitto; ``restart()`` keeps the port, so clients reconnect to it."""

    def __init__(self, workdir: Path, *, extra_conf: str = "", port: int | None = None) -> None:
        exe = shutil.which("mosquitto") or "/usr/sbin/mosquitto"
        if not Path(exe).exists():
            raise RuntimeError("mosquitto not installed: run ./tests/run, it installs it")
        self.exe = exe
        self.port = port or free_port()
        self.workdir = workdir
        self.conf = workdir / "mosquitto.conf"
        self.extra_conf = extra_conf
        self.proc: subprocess.Popen[bytes] | None = None
        self.log = workdir / "mosquitto.log"

    def start(self) -> Mosquitto:
        self.conf.write_text(
            f"listener {self.port} 127.0.0.1\n"
            "persistence false\n"
            f"{self.extra_conf or 'allow_anonymous true'}\n"
        )
        self.proc = subprocess.Popen(
            [self.exe, "-c", str(self.conf), "-v"],
            stdout=open(self.log, "ab"),  # noqa: SIM115
            stderr=subprocess.STDOUT,
        )
        wait_until(self._accepts, 10, f"mosquitto on port {self.port}")
        return self

    def _accepts(self) -> bool:
        assert self.proc is not None
        if self.proc.poll() is not None:
            raise RuntimeError(f"mosquitto exited: {self.log.read_text()[-2000:]}")
        try:
            with socket.create_connection(("127.0.0.1", self.port), timeout=0.2):
                return True
        except OSError:
            return False

    def stop(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.proc = None

    def restart(self) -> None:
        self.stop()
        self.start()


@dataclass
class Message:
    topic: str
    payload: bytes
    retain: bool
    t: float

    @property
    def text(self) -> str:
        return self.payload.decode()


class Probe:
    """An MQTT client that records everything under a topic filter."""

    def __init__(self, port: int, topic_filter: str = "#", client_id: str | None = None) -> None:
        self.messages: list[Message] = []
        self._cond = threading.Condition()
        self._connected = threading.Event()
        self.filter = topic_filter
        c = paho.Client(CallbackAPIVersion.VERSION2, client_id=client_id or f"probe-{id(self)}")
        c.on_connect = self._on_connect
        c.on_message = self._on_message
        c.reconnect_delay_set(0.1, 0.5)  # type: ignore[arg-type]
        c.connect_async("127.0.0.1", port, keepalive=10)
        c.loop_start()
        self.client = c
        wait_until(self._connected.is_set, 10, "probe connected")

    def _on_connect(self, client, userdata, flags, rc, props) -> None:  # noqa: ANN001
        client.subscribe(self.filter, qos=1)
        self._connected.set()

    def _on_message(self, client, userdata, msg) -> None:  # noqa: ANN001
        with self._cond:
            self.messages.append(
                Message(msg.topic, bytes(msg.payload), bool(msg.retain), time.monotonic())
            )
            self._cond.notify_all()

    def publish(self, topic: str, payload: str | bytes, retain: bool = False, qos: int = 1) -> None:
        info = self.client.publish(topic, payload, qos=qos, retain=retain)
        info.wait_for_publish(5)

    def on(self, topic: str) -> list[Message]:
        with self._cond:
            return [m for m in self.messages if m.topic == topic]

    def last(self, topic: str) -> Message | None:
        msgs = self.on(topic)
        return msgs[-1] if msgs else None

    def wait_for(
        self,
        topic: str,
        predicate: Callable[[Message], bool] = lambda m: True,
        timeout_s: float = 10.0,
        after: float | None = None,
    ) -> Message:
        """The first message on ``topic`` (received after ``after``) that satisfies predicate."""
        deadline = time.monotonic() + timeout_s
        with self._cond:
            while True:
                for m in self.messages:
                    if m.topic == topic and (after is None or m.t >= after) and predicate(m):
                        return m
                left = deadline - time.monotonic()
                if left <= 0:
                    seen = [(m.topic, m.payload[:80]) for m in self.messages if m.topic == topic]
                    raise AssertionError(
                        f"no matching message on {topic} in {timeout_s} s; saw {seen[-10:]}"
                    )
                self._cond.wait(left)

    def wait_value(
        self, topic: str, value: str, timeout_s: float = 10.0, after: float | None = None
    ) -> Message:
        return self.wait_for(topic, lambda m: m.text == value, timeout_s, after)

    def close(self) -> None:
        self.client.disconnect()
        self.client.loop_stop()


def retained_snapshot(
    port: int, topic_filter: str, settle_topic: str | None = None
) -> dict[str, bytes]:
    """What a new subscriber gets as retained messages right now (fresh connection)."""
    probe = Probe(port, topic_filter)
    try:
        # retained messages are delivered right after SUBACK; a round trip through a topic of
        # our own marks the end of them
        marker = settle_topic or f"probe-marker/{id(probe)}"
        probe.client.subscribe(marker, qos=1)
        probe.publish(marker, b"end")
        probe.wait_for(marker)
        return {m.topic: m.payload for m in probe.messages if m.retain}
    finally:
        probe.close()
