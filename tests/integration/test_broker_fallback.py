"""``mqtt.protocol`` and brokers without MQTT 5 (connection.py rules 1 and 6), with real
brokers: NATS answers an MQTT 5 CONNECT with "Unsupported protocol version"; ``NoMqtt5`` in
front of mosquitto closes the socket without a CONNACK, as RabbitMQ and amqtt do. The default
("auto") steps down to MQTT 3.1.1 on NATS's answer and says so once; on a close it never does
(anyone on the path can close a connection) and says the fix once; "5" never steps down; the
remote says that the broker does not speak MQTT 5 instead of "no answer".
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from bridge.mqtt.client import MqttClient
from bridge.mqtt.remote import RemoteLink
from bridge.settings_mqtt import MqttSettings
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


@pytest.mark.parametrize("protocol", ["auto", "5"])
def test_a_close_never_steps_down_and_the_fix_is_said_once(
    protocol: str, closer: NoMqtt5, caplog: pytest.LogCaptureFixture
) -> None:
    """A close before the CONNACK is what RabbitMQ does on MQTT 5, but also a broker
    restarting, a connection limit or anyone on the path: never a reason to drop MQTT 5's
    rules. The fix for a broker without MQTT 5 is said, once."""
    settings = MqttSettings(
        host="127.0.0.1", port=closer.port, protocol=protocol, client_id=f"t{protocol}"
    )
    client = MqttClient(
        settings,
        will_topic="rotor/bridge/state",
        subscriptions=[],
        on_message=lambda *a: None,
        reconnect_max_s=1,
    )
    client.start()
    try:
        wait_until(lambda: len(closer.levels) >= 4, 20, "four tries")
    finally:
        client.stop()
    assert set(closer.levels) == {5}, closer.levels
    (line,) = said(caplog, "closed the connection before accepting it")
    assert "a broker without MQTT 5 (RabbitMQ 3, amqtt) closes it this way too" in line
    assert 'set mqtt.protocol = "3.1.1" for it' in line
    assert said(caplog, FELL_BACK) == []


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
