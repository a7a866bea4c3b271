"""The broker connection through a stalled broker (SIGSTOP), with a real mosquitto (issue 14,
items 2 and 3; interfaces/mqtt/client.py rules 12 and 13)."""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import contextmanager

import pytest

from bridge.interfaces.mqtt.client import MqttClient
from bridge.settings import MqttSettings
from tests.support import Probe, retained_snapshot, wait_until
from tests.support.mosquitto import Mosquitto

WILL = "t/bridge/state"


@contextmanager
def connected(broker: Mosquitto, keepalive_s: int) -> Iterator[MqttClient]:
    settings = MqttSettings(port=broker.port, keepalive_s=keepalive_s, client_id="stall-under-test")
    c = MqttClient(settings, will_topic=WILL, subscriptions=[], on_message=lambda *a: None)
    c.start()
    try:
        wait_until(c.connected.is_set, 10, "connected")
        yield c
    finally:
        c.stop()


@pytest.fixture
def client(broker: Mosquitto) -> Iterator[MqttClient]:
    """The shortest keepalive the settings take: a frozen broker is given up on soon."""
    with connected(broker, 5) as c:
        yield c


def round_trip(client: MqttClient, probe: Probe) -> None:
    """Twice an event from the client seen by the probe: the second went out after anything
    paho sent of its own accord when it reconnected (the first may overtake that)."""
    for n in range(2):
        t = time.monotonic()
        client.publish_event("t/sync", f"sync {n}")
        probe.wait_for("t/sync", lambda m, n=n: m.text == f"sync {n}", after=t)


def test_a_value_changed_during_a_stall_is_the_one_left_after_it(
    broker: Mosquitto, client: MqttClient, probe: Probe
) -> None:
    """Item 2: a discovery config (QoS 1) published while the broker was frozen stayed in
    paho's queue; changed again once the bridge had given up on the broker, the fresh value
    went out on the reconnect and paho's old one after it, for good."""
    client.publish_retained("t/config", "A", qos=1)
    probe.wait_value("t/config", "A", 5)
    broker.pause()
    try:
        client.publish_retained("t/config", "B", qos=1)  # taken by paho, never acknowledged
        wait_until(lambda: not client.connected.is_set(), 20, "the client gives up on the broker")
        client.publish_retained("t/config", "C", qos=1)
    finally:
        broker.resume()
    wait_until(client.connected.is_set, 30, "connected again")
    round_trip(client, probe)
    snap = retained_snapshot(broker.port, "t/#")
    assert snap["t/config"] == b"C"
    assert snap[WILL] == b"online"


def test_a_publish_the_client_did_not_take_is_sent_when_the_broker_has_room(
    broker: Mosquitto, probe: Probe
) -> None:
    """Item 3: with the broker frozen, ~80,000 QoS 1 messages ran paho out of message ids
    (MQTT_ERR_QUEUE_SIZE); the bridge took the refused publishes for sent and the broker kept
    the old retained value after it was back. Now paho holds at most MAX_QUEUED; what it does
    not take is sent again once the broker acknowledges again (no reconnect here: the stall is
    shorter than the keepalive). The flood takes seconds of CPU, many more on a busy machine
    (past 7.5 s in a loaded CI run: the keepalive of 5 s ran out, a reconnect, and the test
    failed): the keepalive here is one no flood outlasts, not a deadline."""
    with connected(broker, 600) as client:
        client.publish_retained("t/config", "old", qos=1)
        probe.wait_value("t/config", "old", 5)
        broker.pause()
        try:
            for i in range(70_000):  # past paho's 65,535 message ids
                client.publish_event("t/flood", str(i))
            client.publish_retained("t/config", "new", qos=1)
            assert client.connected.is_set()  # the same connection throughout
        finally:
            broker.resume()
        assert client.failed_publishes > 0
        wait_until(lambda: retained_snapshot(broker.port, "t/config").get("t/config") == b"new", 20)
        assert client.connected.is_set()
