"""A broker whose ACL denies the bridge its heartbeat topic (client.py rule 19): mosquitto grants
the subscription and drops the beats, so none comes back. The bridge must not take that for a
broker that holds everything up (every move refused for ever): it never calls the broker late,
and says once, naming the topic, that it cannot read its beats back.

Real parts: mosquitto with an ACL file, the main connection (MqttClient)."""

from __future__ import annotations

from pathlib import Path

from bridge.interfaces.mqtt.client import MqttClient
from bridge.interfaces.mqtt.heartbeat import UNREAD_S
from bridge.settings import MqttSettings
from tests.support import slow, wait_until
from tests.support.mosquitto import Mosquitto

BEAT = "rotor/bridge/heartbeat"


def test_beats_the_acl_keeps_from_coming_back_never_make_the_broker_late_and_are_said_once(
    tmp_path: Path,
) -> None:
    acl = tmp_path / "acl"
    acl.write_text(f"topic readwrite rotor/#\ntopic deny {BEAT}\n")
    # started as root, mosquitto would become user "mosquitto", who cannot read pytest's tmp
    broker = Mosquitto(
        tmp_path / "broker", extra_conf=f"allow_anonymous true\nacl_file {acl}\nuser root"
    )
    broker.start()
    denied: list[tuple[str, str]] = []
    lateness: list[float | None] = []
    client = MqttClient(
        MqttSettings(port=broker.port, base_topic="rotor", client_id="late-acl", protocol="5"),
        will_topic="rotor/bridge/state",
        subscriptions=["rotor/target"],
        on_message=lambda *_: lateness.append(client.broker_late()),
        heartbeat=BEAT,
        on_denied=lambda topic, problem: denied.append((topic, problem)),
    )
    try:
        client.start()
        wait_until(lambda: denied, slow(3 * UNREAD_S), "the beats said unread")
        assert [topic for topic, _ in denied] == [BEAT]
        assert "read back" in denied[0][1]
        assert any(BEAT in problem for problem in client.problems)  # (B/bridge/info's list)
        publisher = MqttClient(
            MqttSettings(port=broker.port, base_topic="rotor", client_id="late-acl-ha"),
            will_topic="rotor/ha/state",
            subscriptions=[],
            on_message=lambda *_: None,
        )
        publisher.start()
        try:
            wait_until(publisher.connected.is_set, slow(10), "the publisher connected")
            publisher.publish_event("rotor/target", "200")
            wait_until(lambda: lateness, slow(10), "the target read")
        finally:
            publisher.stop()
        assert lateness == [None], "a broker whose beats never come back was called late"
        assert len(denied) == 1  # said once
    finally:
        client.stop()
        broker.stop()
