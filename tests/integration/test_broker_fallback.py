"""``mqtt.protocol`` and brokers without MQTT 5 (connection.py rules 1 and 6), with real
brokers: NATS answers an MQTT 5 CONNECT with "Unsupported protocol version"; ``NoMqtt5`` in
front of mosquitto closes the socket without a CONNACK, as RabbitMQ and amqtt do. The default
("auto") steps down to MQTT 3.1.1 and says so once; "5" never does, and says why it cannot
connect, once; the remote says that the broker does not speak MQTT 5 instead of "no answer".
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path

import pytest

from bridge.mqtt.client import MqttClient
from bridge.mqtt.connection import STEP_DOWN_CLOSES
from bridge.mqtt.remote import RemoteLink
from bridge.settings_mqtt import MqttSettings
from tests.support import Probe, wait_until
from tests.support.brokers import Nats, NoMqtt5, find_nats
from tests.support.rig import Rig

FELL_BACK = "using MQTT 3.1.1 from now on"


def said(caplog: pytest.LogCaptureFixture, words: str) -> list[str]:
    return [r.getMessage() for r in caplog.records if words in r.getMessage()]


@pytest.fixture
def closer(broker: object) -> Iterator[NoMqtt5]:
    relay = NoMqtt5(broker.port)  # type: ignore[attr-defined]
    yield relay
    relay.close()


@pytest.fixture
def nats(tmp_path: Path) -> Iterator[Nats]:
    if find_nats() is None:
        pytest.skip("nats-server is not installed (tests/run installs Debian's nats-server)")
    n = Nats(tmp_path / "nats").start()
    yield n
    n.stop()


def test_auto_steps_down_when_the_broker_closes_on_mqtt_5(
    tmp_path: Path, closer: NoMqtt5, caplog: pytest.LogCaptureFixture
) -> None:
    probe = Probe(closer.port)
    with Rig(tmp_path, closer, probe) as rig:
        emu = rig.add("tower", emu={"start_az_deg": 0})
        rig.start()
        rig.ready("tower")
        rig.probe.publish("rotor/target", "45")
        emu.wait_for(lambda s: abs(s.az_deg - 45) <= 3 and not s.is_moving, 20)
        app = rig.app
        assert app is not None
        wait_until(app.lane.connected.is_set, 10, "the stop lane connected")
        # said on B/bridge/info while it lasts, for Home Assistant and a dashboard
        info = rig.probe.wait_for("rotor/bridge/info", lambda m: "MQTT 3.1.1" in m.text)
        (problem,) = json.loads(info.payload)["problems"]
        assert "a retained target moves the rotor once" in problem
    probe.close()
    (line,) = said(caplog, FELL_BACK)
    assert f"before accepting MQTT 5, {STEP_DOWN_CLOSES} times in a row (no CONNACK;" in line
    assert 'set mqtt.protocol = "5"' in line  # for an MQTT 5 broker that was only not ready
    assert "carried out like any other" in line
    # the main connection tried MQTT 5 in a row; everything after it, the stop lane too, 3.1.1
    bridge = closer.levels[1:]  # (the probe's own CONNECT, 3.1.1, came first)
    tried = STEP_DOWN_CLOSES
    assert bridge[:tried] == [5] * tried and set(bridge[tried:]) == {4}, closer.levels
    # the closes before it are said once, as any close before a CONNACK
    assert len(said(caplog, "closed the connection before accepting it")) == 1


def test_mqtt_5_forced_never_steps_down_and_says_why_once(
    closer: NoMqtt5, caplog: pytest.LogCaptureFixture
) -> None:
    settings = MqttSettings(host="127.0.0.1", port=closer.port, protocol="5", client_id="t5")
    client = MqttClient(
        settings,
        will_topic="rotor/bridge/state",
        subscriptions=[],
        on_message=lambda *a: None,
        reconnect_max_s=1,
    )
    client.start()
    try:
        wait_until(lambda: len(closer.levels) >= 3, 20, "three tries")
    finally:
        client.stop()
    assert set(closer.levels) == {5}
    (line,) = said(caplog, "closed the connection before accepting it")
    assert 'a broker without MQTT 5 does that too: set mqtt.protocol = "auto"' in line
    assert said(caplog, FELL_BACK) == []


def test_a_broker_that_closes_on_both_protocols_is_said_once_after_the_step_down(
    closer: NoMqtt5, caplog: pytest.LogCaptureFixture
) -> None:
    closer.close_all = True
    settings = MqttSettings(host="127.0.0.1", port=closer.port, client_id="tauto")
    client = MqttClient(
        settings,
        will_topic="rotor/bridge/state",
        subscriptions=[],
        on_message=lambda *a: None,
        reconnect_max_s=1,
    )
    client.start()
    try:
        wait_until(lambda: len(closer.levels) >= STEP_DOWN_CLOSES + 3, 20, "three tries after")
    finally:
        client.stop()
    tried = STEP_DOWN_CLOSES
    assert closer.levels[:tried] == [5] * tried and set(closer.levels[tried:]) == {4}
    assert len(said(caplog, FELL_BACK)) == 1
    mqtt5, line = said(caplog, "closed the connection before accepting it")
    assert "it did so for MQTT 5 and for MQTT 3.1.1 alike" in line and "alike" not in mqtt5


def test_mqtt_5_forced_on_nats_is_refused_and_said_once(
    nats: Nats, caplog: pytest.LogCaptureFixture
) -> None:
    settings = MqttSettings(host="127.0.0.1", port=nats.port, protocol="5", client_id="t5n")
    client = MqttClient(
        settings,
        will_topic="rotor/bridge/state",
        subscriptions=[],
        on_message=lambda *a: None,
        reconnect_max_s=1,
    )
    answers: list[object] = []
    on_connect = client._client.on_connect

    def counted(*args: object) -> None:
        answers.append(args[3])
        on_connect(*args)  # type: ignore[misc]

    client._client.on_connect = counted
    client.start()
    try:
        wait_until(lambda: len(answers) >= 3, 20, "three answers")
    finally:
        client.stop()
    (line,) = said(caplog, "refused the connection")
    assert "Unsupported protocol version" in line
    assert said(caplog, FELL_BACK) == []


@pytest.mark.parametrize("where", ["nats", "closer"])
def test_the_remote_says_the_broker_does_not_speak_mqtt_5(
    where: str, request: pytest.FixtureRequest
) -> None:
    port = request.getfixturevalue(where).port
    link = RemoteLink(MqttSettings(host="127.0.0.1", port=port), "remote-t", [], print)
    link.start()
    try:
        failure = wait_until(lambda: link.failure, 20, "the remote's reason")
    finally:
        link.stop()
    if where == "nats":
        assert failure == (
            "this broker does not speak MQTT 5 (Unsupported protocol version), which the "
            "remote needs"
        )
        assert link.fatal
    else:
        assert failure.startswith("the broker closed the connection before accepting it (")
        assert "does not speak MQTT 5, which the remote needs" in failure
