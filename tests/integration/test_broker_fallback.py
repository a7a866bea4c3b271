"""``mqtt.protocol`` and brokers without MQTT 5 (connection.py rules 1 and 6), with real
brokers: NATS answers an MQTT 5 CONNECT with "Unsupported protocol version"; ``NoMqtt5`` in
front of mosquitto closes the socket without a CONNACK, as RabbitMQ and amqtt do. The default
("auto") steps down to MQTT 3.1.1 on NATS's answer and says so once; on a close only once the
broker accepted MQTT 3.1.1 between two closed MQTT 5 attempts (a close alone, which anyone on
the path can cause, a connection limit that closes both, a broker that comes back speaking
MQTT 5: never) and says the fix until then; "5" never steps down; the remote says that the
broker does not speak MQTT 5 instead of "no answer".
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from bridge.interfaces.mqtt.client import MqttClient
from bridge.interfaces.mqtt.remote import RemoteLink
from bridge.settings.mqtt import MqttSettings
from tests.support import wait_until
from tests.support.brokers import Nats, NoMqtt5, find_nats

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
        pytest.fail("nats-server is not installed (tests/run installs Debian's nats-server)")
    n = Nats(tmp_path / "nats").start()
    yield n
    n.stop()


def closed_client(port: int, protocol: str) -> MqttClient:
    settings = MqttSettings(host="127.0.0.1", port=port, protocol=protocol, client_id="tclose")
    return MqttClient(
        settings,
        will_topic="rotor/bridge/state",
        subscriptions=[],
        on_message=lambda *a: None,
        reconnect_max_s=1,
    )


def test_a_broker_that_closes_mqtt_5_and_takes_3_1_1_gets_3_1_1(
    closer: NoMqtt5, caplog: pytest.LogCaptureFixture
) -> None:
    """RabbitMQ 3 and amqtt close an MQTT 5 connection before any CONNACK: with "auto" the
    bridge asks in MQTT 3.1.1 once, and steps down when that was accepted and MQTT 5 is closed
    again; it runs on 3.1.1 from then on, and says so once."""
    client = closed_client(closer.port, "auto")
    client.start()
    try:
        wait_until(lambda: client.connected.is_set(), 30, "connected on MQTT 3.1.1")
        assert not client.v5
    finally:
        client.stop()
    assert closer.levels[:4] == [5, 4, 5, 4], closer.levels  # closed, trial, closed, for good
    (line,) = said(caplog, FELL_BACK)
    assert "closed MQTT 5 connections before answering them and accepted an MQTT 3.1.1" in line
    assert "a retained target moves the rotor once" in line
    (first,) = said(caplog, "closed the connection before accepting it")  # the first close
    assert "asks the broker in MQTT 3.1.1 to tell" in first


@pytest.mark.parametrize("case", ["forced 5", "closes 3.1.1 too", "came back speaking 5"])
def test_a_close_alone_never_steps_down(
    case: str, closer: NoMqtt5, caplog: pytest.LogCaptureFixture
) -> None:
    """A close before the CONNACK is also a broker restarting, a connection limit or anyone on
    the path: never a reason to drop MQTT 5's rules. "5" never tries 3.1.1; a broker that
    closes 3.1.1 too (a limit) gives no evidence; one that closed a single MQTT 5 attempt and
    then takes MQTT 5 (a restart) keeps MQTT 5. The fix is said once."""
    closer.close_all = case == "closes 3.1.1 too"
    if case == "came back speaking 5":
        closer.v5_closes_left = 1
    client = closed_client(closer.port, "5" if case == "forced 5" else "auto")
    client.start()
    try:
        if case == "came back speaking 5":
            wait_until(lambda: client.connected.is_set(), 30, "connected on MQTT 5")
            assert client.v5
        else:
            wait_until(lambda: closer.levels.count(5) >= 4, 30, "four MQTT 5 tries")
    finally:
        client.stop()
    if case == "forced 5":
        assert set(closer.levels) == {5}, closer.levels
    assert said(caplog, FELL_BACK) == []
    (line,) = said(caplog, "closed the connection before accepting it")
    assert "a broker without MQTT 5 (RabbitMQ 3, amqtt) closes it this way too" in line
    assert 'set mqtt.protocol = "3.1.1" for it' in line


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
