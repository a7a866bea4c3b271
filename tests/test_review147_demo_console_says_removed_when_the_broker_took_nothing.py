"""Review 147, finding 1: the demo's console ends its run by clearing what the demo left
retained (bridge/demo/console.py ``remove_retained``, rule 6: the clean-up "waited for by a sync
round trip behind it"). It waits for that round trip and then ignores its answer: when the
broker's path goes dead right after the clean-up's first sync (a Wi-Fi drop, an external broker
restarting as the user types ``q``), nothing of the clean-up reaches the broker, the round trip
times out, and the console still says "removed its 2 retained messages": the demo's state and
Home Assistant configs stay retained on the broker while the user is told they were removed.
Older: 1998b9a5 and 9b73f8b9 ignored ``wait_for_publish``'s outcome alike.

Real mosquitto (MQTT 5); the console's connection through review 139's relay, dead (both ways)
right after the clean-up's first sync and never back; what stays retained read by an MQTT 3.1.1
client on the broker itself.

Fixed: console.py rule 6."""

from __future__ import annotations

import threading
from typing import Any

import paho.mqtt.client as paho
import pytest
from paho.mqtt.enums import CallbackAPIVersion

from bridge.interfaces.mqtt.topics import Topics
from tests.support.mosquitto import Mosquitto
from tests.support.waiting import slow, wait_until
from tests.test_review134_demo_console_replays_a_typed_target import BASE, Watcher, console_through
from tests.test_review139_demo_console_drops_a_typed_stop import DeadPath


def still_retained(port: int, topics: list[str]) -> list[str]:
    """Which of ``topics`` the broker still holds retained (a fresh subscription's answer, a
    round trip behind it)."""
    got: list[str] = []
    done = threading.Event()
    probe = f"{BASE}/probe/147"

    def on_message(client: paho.Client, u: Any, msg: paho.MQTTMessage) -> None:
        if msg.topic == probe:
            done.set()
        elif msg.retain and msg.payload:
            got.append(msg.topic)

    c = paho.Client(CallbackAPIVersion.VERSION2, client_id="r147probe", protocol=paho.MQTTv311)
    c.on_message = on_message
    c.on_connect = lambda client, *_: client.subscribe([(t, 1) for t in [*topics, probe]])
    c.on_subscribe = lambda client, *_: client.publish(probe, b"x", qos=1)
    c.connect("127.0.0.1", port)
    c.loop_start()
    try:
        assert done.wait(slow(20)), "the probe never came back"
    finally:
        c.disconnect()
        c.loop_stop()
    return sorted(got)


def test_the_clean_up_does_not_say_removed_when_the_broker_never_took_it(
    broker: Mosquitto, capsys: pytest.CaptureFixture[str]
) -> None:
    relay = DeadPath(broker.port)
    watcher = Watcher(broker.port)
    kept = [f"{BASE}/kept/{i}" for i in range(2)]
    for topic in kept:  # left retained by the demo's bridge
        watcher._client.publish(topic, b"x", qos=1, retain=True).wait_for_publish(slow(20))
    topics = Topics(BASE, {"rotorez": BASE})
    console = console_through(relay.port, topics, mqtt5=True)
    sync = console.sync
    syncs: list[bool] = []

    def sync_then_dead_path(timeout_s: float = 5.0) -> bool:
        ok = sync(timeout_s)
        syncs.append(ok)
        relay.dead = True  # the path carries nothing from here on
        return ok

    try:
        assert console.sync(slow(20)), "the console never connected through the relay"
        wait_until(lambda: all(console.retained(t) for t in kept), 20, "the retained seen")
        capsys.readouterr()
        console.sync = sync_then_dead_path  # type: ignore[method-assign]
        console.close(remove_retained=True)  # the user typed q
        said = capsys.readouterr().out
    finally:
        watcher.close()
        relay.close()
    assert syncs[:1] == [True], f"the clean-up's first sync did not go through: {syncs}"
    left = still_retained(broker.port, kept)
    assert left == kept, f"the clean-up reached the broker after all: {left}"
    assert "removed its" not in said, (
        f"the console says it removed what is still retained on the broker ({left}): {said!r}"
    )
