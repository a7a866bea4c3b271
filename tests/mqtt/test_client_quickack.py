"""MQTT rule 9 (bridge/interfaces/mqtt/connection.py):
after every read from the broker the client sets TCP_QUICKACK
on its socket, so the kernel acknowledges a command at once instead of after its delayed-ACK
timer (which a mosquitto with Nagle on waits for before it sends the next command, a STOP
perhaps). The mechanism, on the real socket paho reads from, against a real mosquitto; what it
is worth in milliseconds is measured in benchmarks/latency.py ("0-3 ms after a silent command"),
not asserted here: the kernel sends the same ACK 40 ms later anyway, so only the order of
events tells the two apart deterministically."""

from __future__ import annotations

import socket
import threading
from typing import Any

import pytest

from bridge.interfaces.mqtt.client import MqttClient
from bridge.settings import MqttSettings
from tests.support import Mosquitto, Probe, wait_until

QUICKACK = ("setsockopt", socket.IPPROTO_TCP, socket.TCP_QUICKACK, 1)

Event = tuple[Any, ...]


class RecordingSocket(socket.socket):
    """The TCP connection paho opens, unchanged, noting what paho's thread does with it."""

    def __init__(self, sock: socket.socket, events: list[Event]) -> None:
        super().__init__(sock.family, sock.type, sock.proto, fileno=sock.detach())
        self.events = events

    def recv(self, bufsize: int, flags: int = 0) -> bytes:
        data = super().recv(bufsize, flags)
        if data:
            self.events.append(("recv", len(data)))
        return data

    def setsockopt(self, level: int, option: int, value: Any, *rest: Any) -> None:
        self.events.append(("setsockopt", level, option, value))
        super().setsockopt(level, option, value, *rest)


def test_every_command_read_is_acknowledged_before_the_next_read(
    broker: Mosquitto, probe: Probe, monkeypatch: pytest.MonkeyPatch
) -> None:
    events: list[Event] = []  # appended on paho's thread only: recv, setsockopt, message
    made: list[RecordingSocket] = []
    real_create_connection = socket.create_connection

    def create_connection(*args: Any, **kwargs: Any) -> socket.socket:
        sock = RecordingSocket(real_create_connection(*args, **kwargs), events)
        made.append(sock)
        return sock

    handled = threading.Event()

    def on_message(topic: str, payload: bytes, retained: bool, *_who: object) -> None:
        events.append(("message", payload))
        handled.set()

    monkeypatch.setattr(socket, "create_connection", create_connection)  # paho's way in
    client = MqttClient(
        MqttSettings(port=broker.port, client_id="quickack-test"),
        will_topic="rotor/bridge/state",
        subscriptions=["rotor/stop", "rotor/lock"],
        on_message=on_message,
    )
    client.start()
    try:
        wait_until(client.connected.is_set, 10, "the client connected")
        probe.wait_value("rotor/bridge/state", "online")  # its subscriptions are in place
        # commands the bridge does not answer, one at a time, then one more that ends the run
        for i, (topic, payload) in enumerate(
            [("rotor/lock", "OFF"), ("rotor/stop", "STOP"), ("rotor/lock", "OFF")] * 3
            + [("rotor/stop", "end")]
        ):
            handled.clear()
            probe.publish(topic, payload, qos=0)
            wait_until(handled.is_set, 10, f"command {i} handled")
    finally:
        client.stop()
    assert len(made) == 1, made  # the bridge's one connection

    messages = [i for i, e in enumerate(events) if e[0] == "message"]
    assert len(messages) == 10, events
    for i in messages[:-1]:
        following = events[i + 1 :]
        next_read = next((k for k, e in enumerate(following) if e[0] == "recv"), len(following))
        assert QUICKACK in following[:next_read], (
            f"no TCP_QUICKACK between {events[i]} and the next read: {events}"
        )
