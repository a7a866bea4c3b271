"""Real parts for tests: a mosquitto broker on a free loopback port, and an MQTT probe client.

Waiting is always on a condition with a deadline, never a bare sleep.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

import paho.mqtt.client as paho
from paho.mqtt.enums import CallbackAPIVersion

from bridge.mosquitto import Mosquitto, free_port  # noqa: F401  (re-exported for tests)


def wait_until(predicate: Callable[[], object], timeout_s: float = 10.0, what: str = "") -> object:
    deadline = time.monotonic() + timeout_s
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout_s} s waiting for {what or predicate}")
        time.sleep(0.01)


@dataclass
class Message:
    topic: str
    payload: bytes
    retain: bool
    t: float
    qos: int = 0

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
                Message(msg.topic, bytes(msg.payload), bool(msg.retain), time.monotonic(), msg.qos)
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
