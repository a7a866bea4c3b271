"""The first look's hello (B/bridge/hello, interfaces/mqtt/look.py and client.py rule 14) with a
real mosquitto: it comes back to the bridge before anything else goes out, and nothing of it
lingers on the broker for a client that subscribes to the base topic later."""

from __future__ import annotations

from bridge.interfaces.mqtt.claim import Claim, Instance
from bridge.interfaces.mqtt.client import MqttClient
from bridge.settings import MqttSettings
from tests.support import Probe, retained_snapshot, wait_until
from tests.support.mosquitto import Mosquitto


def test_the_hello_is_the_first_message_and_does_not_linger(broker: Mosquitto) -> None:
    watcher = Probe(broker.port, "t/#")  # watching B/# from before the bridge connects
    watcher.publish("t/watching", "yes")
    watcher.wait_value("t/watching", "yes", 5)  # subscribed: it sees all that comes next
    settings = MqttSettings(port=broker.port, base_topic="t", client_id="look-under-test")
    me = Instance.me("look-under-test")
    client = MqttClient(
        settings,
        will_topic="t/bridge/state",
        subscriptions=[],
        on_message=lambda *a: None,
        claim=Claim(me, "t", "t/bridge/info", "t/bridge/hello"),
    )
    client.start()
    try:
        wait_until(lambda: client.connected.is_set() and not client.gated, 10, "the look done")
        client.publish_retained("t/bridge/info", me.info([]))
        watcher.wait_value("t/bridge/info", me.info([]), 5)
        first = next(m for m in watcher.messages if m.topic != "t/watching")
        assert (first.topic, first.payload, first.retain) == (
            "t/bridge/hello",
            b"look-under-test 1",
            False,
        )
        later = retained_snapshot(broker.port, "t/#")  # a watcher who comes now
        assert later == {"t/bridge/state": b"online", "t/bridge/info": me.info([]).encode()}
    finally:
        client.stop()
        watcher.close()
