"""The first look's hello (B/bridge/hello, interfaces/mqtt/look.py and client.py rule 14) with a
real mosquitto: it comes back to the bridge before anything else goes out, and nothing of it
lingers on the broker for a client that subscribes to the base topic later."""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from pathlib import Path

import pytest

from bridge.interfaces.mqtt.claim import Claim, Instance
from bridge.interfaces.mqtt.client import LOOK_MAX_S, MqttClient
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


@pytest.mark.parametrize("cached", [True, False], ids=["a status before the open", "none"])
def test_a_witnessed_on_the_hook_took_is_not_put_over_by_a_status_older_than_its_lock(
    broker: Mosquitto, cached: bool
) -> None:
    """Rule 14: the lock ON an earlier run left, which the hook took (its rotator locked), is
    left as the broker holds it; the rotator's status says OFF until that lock is saved
    (runtime/kept.py rule 2), and such a status, published after the open, put OFF over the ON
    (a switch shown OFF, and a crash then left the broker OFF). While the lock holds, an older
    value is not put over it; once it no longer holds (a lock OFF), the next value goes out.
    So too when the rotator's first status comes only after the open (a review, through Home
    Assistant: its lock switch showed OFF, then ON, at 8 starts of 15 of a bridge whose new
    state file left the lock to the broker)."""
    seed = Probe(broker.port, "t/#")
    seed.publish("t/r/lock/state", "ON", retain=True)
    seed.wait_value("t/r/lock/state", "ON", 5)
    settings = MqttSettings(port=broker.port, base_topic="t", client_id="witness-under-test")
    client = MqttClient(
        settings,
        will_topic="t/bridge/state",
        subscriptions=[],
        on_message=lambda *a: None,
        claim=Claim(Instance.me("witness-under-test"), "t", "t/bridge/info", "t/bridge/hello"),
    )
    if cached:
        client.publish_retained("t/r/lock/state", "OFF")  # (the status before the start)
    locked = [False]

    def took(heard: dict[str, bytes], unread: frozenset[str]) -> dict[str, Callable[[], bool]]:
        assert not unread  # (read: its probe came back)
        locked[0] = heard.get("t/r/lock/state") == b"ON"
        return {"t/r/lock/state": lambda: locked[0]} if locked[0] else {}

    client.watch_owned(["t/r/lock/state", "t/bridge/info"])  # (as the app: its own topics)
    client.witness({"t/r/lock/state"}, took)
    client.start()
    try:
        wait_until(lambda: client.connected.is_set() and not client.gated, 10, "the look done")
        assert locked[0]
        client.publish_retained("t/r/lock/state", "OFF")  # a status from before the lock's save
        client.publish_retained("t/r/lock/state", "ON")  # the lock saved: its status
        client.publish_retained("t/bridge/info", "marker")  # (after these, in order)
        seed.wait_value("t/bridge/info", "marker", 5)
        assert [m.text for m in seed.on("t/r/lock/state")] == ["ON"]  # (heard: no probe)
        assert retained_snapshot(broker.port, "t/r/lock/state") == {"t/r/lock/state": b"ON"}
        locked[0] = False  # a lock OFF: the status says so
        client.publish_retained("t/r/lock/state", "OFF")
        seed.wait_value("t/r/lock/state", "OFF", 5)
    finally:
        client.stop()
        seed.close()


@pytest.mark.parametrize("protocol", ["5", "3.1.1"])
def test_a_tracker_publishing_retained_does_not_keep_a_look_whose_hello_is_denied_open(
    tmp_path: Path, caplog: pytest.LogCaptureFixture, protocol: str
) -> None:
    """Rule 14 (review 33): the broker's ACL denies the hello, so the look ends on its timer;
    a tracker set to retain publishes its target twice a second, and under MQTT 5 the command
    topic, subscribed with retain-as-published, hands each on with the retain flag set, as
    the broker's replay of what it held. The look timed out LOOK_MAX_S, a minute, after the
    connect, the bridge gated all along; now LOOK_TIMEOUT_S after it. (Under MQTT 3.1.1 the
    broker clears the flag of a live message: the same.)"""
    acl = tmp_path / "acl"
    acl.write_text("topic readwrite t/#\ntopic deny t/bridge/hello\n")
    # started as root, mosquitto would become user "mosquitto", who cannot read pytest's tmp
    broker = Mosquitto(
        tmp_path / "broker", extra_conf=f"allow_anonymous true\nacl_file {acl}\nuser root"
    )
    broker.start()
    tracker = Probe(broker.port, "")
    quit_tracking = threading.Event()

    def track() -> None:
        while not quit_tracking.is_set():
            tracker.publish("t/rot1/target", "120", retain=True)
            quit_tracking.wait(0.5)  # the tracker's own pace: not a deadline

    tracking = threading.Thread(target=track, daemon=True)
    tracking.start()
    settings = MqttSettings(
        port=broker.port, base_topic="t", client_id="look-under-test", protocol=protocol
    )
    client = MqttClient(
        settings,
        will_topic="t/bridge/state",
        subscriptions=["t/rot1/target"],
        on_message=lambda *a: None,
        claim=Claim(Instance.me("look-under-test"), "t", "t/bridge/info", "t/bridge/hello"),
    )
    try:
        with caplog.at_level(logging.WARNING, logger="bridge.interfaces.mqtt.look"):
            client.start()
            wait_until(lambda: client.connected.is_set(), LOOK_MAX_S + 10, "the look's end")
        (said,) = [r.getMessage() for r in caplog.records if "no answer" in r.getMessage()]
        waited_s = float(said.split(" in ")[1].split(" s ")[0])
        assert waited_s < LOOK_MAX_S / 2  # (LOOK_TIMEOUT_S on a quiet machine)
    finally:
        quit_tracking.set()
        tracking.join()
        client.stop()
        tracker.close()
        broker.stop()
