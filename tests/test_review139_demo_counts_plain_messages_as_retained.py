"""Review 139, finding 2: since 725af295 the demo's console on a broker that speaks MQTT 3.1.1
alone (nats-server, aedes, RabbitMQ 3) clears at its end "every topic of the demo's that carried
a message since it connected" (bridge/demo/console.py rule 2) and says it "removed its N retained
messages" with N the count of those topics. Many of them never held a retained message: the
bridge's heartbeat (``B/bridge/heartbeat``), its hello and fence markers, ``R/audit`` and
``R/error`` (service.py rule 3: not retained), and the commands other clients sent (the banner's
own ``mosquitto_pub -t R/target -m 120``, Home Assistant's buttons). Each gets an empty retained
PUBLISH that the broker hands every subscriber as an empty message (the banner's ``watch:``
line shows a dozen blank commands and readings at the end), and the count said is the wrong one:
the same run says another number on mosquitto. Its parent (16dff1c0) learnt what was retained
from a new subscription and counted only those.

Real nats-server; the demo's bridge stands in as an MQTT 3.1.1 client publishing what a bridge
does, retained and not; a user's target is published beside it."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import paho.mqtt.client as paho
import pytest
from paho.mqtt.enums import CallbackAPIVersion

from bridge.interfaces.mqtt.topics import Topics
from tests.support.brokers import Nats, find_nats
from tests.support.waiting import slow
from tests.test_review134_demo_console_replays_a_typed_target import console_through

BASE = "rotor-demo-r139"


@pytest.fixture
def nats(tmp_path: Path) -> Iterator[Nats]:
    if find_nats() is None:
        pytest.fail("nats-server is not installed (tests/run installs Debian's nats-server)")
    n = Nats(tmp_path / "nats").start()
    yield n
    n.stop()


def publish(port: int, messages: list[tuple[str, bytes, bool]]) -> None:
    """(topic, payload, retained), over MQTT 3.1.1, each acknowledged."""
    connected = threading.Event()

    def on_connect(client: paho.Client, *_: Any) -> None:
        connected.set()

    c = paho.Client(CallbackAPIVersion.VERSION2, client_id="r139bridge", protocol=paho.MQTTv311)
    c.on_connect = on_connect
    c.connect("127.0.0.1", port)
    c.loop_start()
    try:
        assert connected.wait(slow(20)), "the stand-in for the demo's bridge never connected"
        for topic, payload, retain in messages:
            c.publish(topic, payload, qos=1, retain=retain).wait_for_publish(slow(10))
    finally:
        c.disconnect()
        c.loop_stop()


def test_the_demo_on_an_mqtt311_broker_says_how_many_retained_messages_it_removed(
    nats: Nats,
) -> None:
    topics = Topics(BASE, {"rotorez": BASE})
    r = topics.rotator("rotorez")
    retained = [
        (topics.bridge_state, b"offline", True),
        (topics.bridge_info, b"{}", True),
        (r.bearing, b"120", True),
        (r.state, b"idle", True),
        (r.availability, b"offline", True),
    ]
    plain = [
        (topics.bridge_heartbeat, b"1765123456", False),  # the bridge's: never retained
        (r.audit, b'{"event": "executed"}', False),
        (r.error, b'{"error": "refused"}', False),
        (r.target, b"120", False),  # the banner's "turn:" line, typed in another terminal
    ]
    console = console_through(nats.port, topics, mqtt5=False)
    try:
        assert console.sync(slow(20)), "the MQTT 3.1.1 console never connected"
        publish(nats.port, retained + plain)
        removed = console.remove_retained(slow(10))
    finally:
        console.close()
    assert removed == len(retained), (
        f"the demo says it removed {removed} retained messages; {len(retained)} were retained"
    )
