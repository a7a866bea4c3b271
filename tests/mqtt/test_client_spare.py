"""client.py rule 14 with stale.py rule 3, end to end with a real mosquitto: a nested bridge's
availability read *before* its ``bridge/state`` (filters subscribed in that order: MQTT promises
no order) is spared by ``spare`` at the look's end; a removed rotator's topics are still deleted.
Without the client's ``spare`` (or the app's wiring) nothing else protects it: the fault test
in tests/faults relies on mosquitto's filter order (``bridge/state`` subscribed first). And a
deletion the look asked for is not sent over a value published after it was asked."""

from __future__ import annotations

import time

from bridge.interfaces.mqtt.claim import Claim, Instance
from bridge.interfaces.mqtt.client import MqttClient
from bridge.interfaces.mqtt.stale import StaleTopics
from bridge.interfaces.mqtt.topics import Topics
from bridge.settings import MqttSettings
from tests.support import Probe, retained_snapshot, wait_until
from tests.support.mosquitto import Mosquitto


def test_a_nested_bridge_read_before_its_bridge_state_is_spared(broker: Mosquitto) -> None:
    seed = Probe(broker.port, "t/#")
    for topic, value in [
        ("t/site2/availability", "online"),
        ("t/site2/bearing", "10"),
        ("t/gone/availability", "online"),
        ("t/gone/bearing", "20"),
        ("t/site2/bridge/state", "online"),
    ]:
        seed.publish(topic, value, retain=True)
    seed.wait_value("t/site2/bridge/state", "online", 5)
    seed.close()
    stale = StaleTopics(Topics("t", {"a": "t/a", "b": "t/b"}), {"t/a", "t/b"})
    settings = MqttSettings(port=broker.port, base_topic="t", client_id="spare-under-test")
    me = Instance.me("spare-under-test")
    client: MqttClient

    def on_message(topic: str, payload: bytes, retain: bool, *_: object) -> None:
        if retain and payload:
            for t in stale.stale(topic):
                client.clear_retained(t)

    # the availability filter first: the nested bridge's state comes after its availability
    subs = ["t/+/availability", *(s for s in stale.subscriptions if s != "t/+/availability")]
    client = MqttClient(
        settings,
        will_topic="t/bridge/state",
        subscriptions=subs,
        on_message=on_message,
        claim=Claim(me, "t", "t/bridge/info", "t/bridge/hello"),
    )
    client.spare = stale.spared
    client.start()
    try:
        wait_until(lambda: client.connected.is_set() and not client.gated, 10, "the look done")
        time.sleep(0.5)
        left = retained_snapshot(broker.port, "t/#")
        assert "t/gone/bearing" not in left  # (a removed rotator's: deleted)
        assert left.get("t/site2/bearing") == b"10", "a nested bridge's bearing deleted"
        assert left.get("t/site2/availability") == b"online"
    finally:
        client.stop()


def test_a_deletion_asked_in_the_look_is_not_sent_over_a_value_published_since(
    broker: Mosquitto,
) -> None:
    """Rule 14: the first look asks to delete what it reads (stale.py), and sends the
    deletions once it ends, after the values cached meanwhile. A topic the bridge published
    after asking (a controller's version read while the look ran) was deleted over its new
    value, for good: its next status hands on the same payload, and nothing goes out again."""
    seed = Probe(broker.port, "t/#")
    seed.publish("t/a/version", "old", retain=True)
    seed.wait_value("t/a/version", "old", 5)
    seed.close()
    settings = MqttSettings(port=broker.port, base_topic="t", client_id="newer-under-test")
    client: MqttClient

    def on_message(topic: str, payload: bytes, retain: bool, *_: object) -> None:
        if topic == "t/a/version" and retain and payload == b"old":
            client.clear_retained(topic)  # (the look's: sent at its end)
            client.publish_retained(topic, "new")  # (and the version read right after)

    client = MqttClient(
        settings,
        will_topic="t/bridge/state",
        subscriptions=["t/a/version"],
        on_message=on_message,
        claim=Claim(Instance.me("newer-under-test"), "t", "t/bridge/info", "t/bridge/hello"),
    )
    probe = Probe(broker.port, "t/#")
    client.start()
    try:
        wait_until(lambda: client.connected.is_set() and not client.gated, 10, "the look done")
        client.publish_event("t/a/error", "after the look")  # (what the look sent came first)
        probe.wait_value("t/a/error", "after the look", 10)
        assert [m.payload for m in probe.on("t/a/version")][-1:] == [b"new"]
        assert retained_snapshot(broker.port, "t/a/version") == {"t/a/version": b"new"}
    finally:
        client.stop()
        probe.close()


def test_a_topic_the_look_deleted_is_not_deleted_again_when_it_is_published_empty(
    broker: Mosquitto,
) -> None:
    """Rule 14 (``_deleted``): a DCU-1 has no version, and hands its ``R/version`` on empty. When
    its first status came after the look had ended, the old Rotor-EZ's version the look had
    deleted was deleted a second time (every subscriber told twice). Once another client has
    published there since, the empty value is a deletion again, and goes out."""
    seed = Probe(broker.port, "t/#")
    for topic in ("t/a/version", "t/b/version"):
        seed.publish(topic, "9.9", retain=True)
        seed.wait_value(topic, "9.9", 5)
    settings = MqttSettings(port=broker.port, base_topic="t", client_id="deleted-under-test")
    client: MqttClient
    heard: list[bytes] = []

    def on_message(topic: str, payload: bytes, retain: bool, *_: object) -> None:
        heard.append(payload)
        if retain and payload == b"9.9":
            client.clear_retained(topic)  # (the look's: sent at its end)

    client = MqttClient(
        settings,
        will_topic="t/bridge/state",
        subscriptions=["t/+/version", "t/mark"],
        on_message=on_message,
        claim=Claim(Instance.me("deleted-under-test"), "t", "t/bridge/info", "t/bridge/hello"),
    )
    client.watch_owned(["t/a/version", "t/b/version"])
    probe = Probe(broker.port, "t/#")
    client.start()
    try:
        wait_until(lambda: client.connected.is_set() and not client.gated, 10, "the look done")
        client.publish_retained("t/a/version", "")  # (the first status, after the look)
        client.publish_event("t/a/error", "one")  # (what was sent before it came first)
        probe.wait_value("t/a/error", "one", 10)
        assert [m.payload for m in probe.on("t/a/version")] == [b"9.9", b""]
        seed.publish("t/b/version", "stray", retain=True)  # another client's, since the look
        seed.publish("t/mark", "after the stray")  # (one client's messages keep their order)
        wait_until(lambda: b"after the stray" in heard, 10, "the stray heard")
        client.publish_retained("t/b/version", "")
        wait_until(
            lambda: retained_snapshot(broker.port, "t/b/version") == {}, 10, "the stray deleted"
        )
    finally:
        client.stop()
        probe.close()
        seed.close()
