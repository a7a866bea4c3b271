"""connection.py rules 1 and 6, the decisions alone: when ``mqtt.protocol = "auto"`` steps down
to MQTT 3.1.1 and when it does not, what is said, and that paho's client then really sends an
MQTT 3.1.1 CONNECT with a clean session (paho_client.py rule 3). The callbacks are driven as
paho calls them, with the reason codes brokers send; the real brokers are in
tests/integration/test_broker_fallback.py."""

from __future__ import annotations

import socket

import paho.mqtt.client as paho
import pytest
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.reasoncodes import ReasonCode

from bridge.interfaces.mqtt.connection import Connection
from bridge.interfaces.mqtt.paho_client import new_client
from bridge.settings import MqttSettings
from tests.support.brokers import protocol_level
from tests.support.waiting import slow

FELL_BACK = "using MQTT 3.1.1 from now on"
CLOSED = "closed the connection before accepting it"


def connection(protocol: str) -> Connection:
    settings = MqttSettings(host="127.0.0.1", port=1, protocol=protocol, client_id="fallback-t")
    return Connection(settings, "fallback-t", subscriptions=["rotor/target"], on_message=print)


def refused(conn: Connection, code: int) -> None:
    reason = ReasonCode(PacketTypes.CONNACK, identifier=code)
    conn._on_connect(conn._client, None, paho.ConnectFlags(False), reason, None)


def accepted(conn: Connection) -> None:
    ok = ReasonCode(PacketTypes.CONNACK, identifier=0)
    conn._on_connect(conn._client, None, paho.ConnectFlags(False), ok, None)


def closed(conn: Connection, code: int = 0x80) -> None:
    reason = ReasonCode(PacketTypes.DISCONNECT, identifier=code)
    conn._on_disconnect(conn._client, None, paho.DisconnectFlags(False), reason, None)


def said(caplog: pytest.LogCaptureFixture, words: str) -> list[str]:
    return [r.getMessage() for r in caplog.records if words in r.getMessage()]


def test_auto_steps_down_on_unsupported_protocol_once(caplog: pytest.LogCaptureFixture) -> None:
    conn = connection("auto")
    assert conn.v5
    refused(conn, 0x84)
    closed(conn)  # paho closes the socket after a refusal
    assert not conn.v5 and conn._client._protocol == paho.MQTTv311
    assert len(said(caplog, FELL_BACK)) == 1
    assert said(caplog, "refused the connection") == [] and said(caplog, CLOSED) == []
    refused(conn, 0x84)  # a 3.1.1 broker's "unacceptable protocol version" now: said, not again
    assert len(said(caplog, FELL_BACK)) == 1
    assert len(said(caplog, "refused the connection")) == 1


def test_auto_never_steps_down_on_closes_before_any_connack(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """RabbitMQ closes on MQTT 5 that way; so does a broker restarting, a connection limit or
    anyone on the path who wants the bridge on MQTT 3.1.1's weaker rules."""
    conn = connection("auto")
    for _ in range(10):
        closed(conn, 0x80)
    assert conn.v5 and said(caplog, FELL_BACK) == []
    (line,) = said(caplog, CLOSED)  # said once in a row, with the fix
    assert 'set mqtt.protocol = "3.1.1" for it' in line


@pytest.mark.parametrize(
    ("protocol", "why"),
    [("5", "forced"), ("3.1.1", "forced"), ("auto", "accepted before"), ("auto", "keepalive")],
)
def test_no_step_down_where_the_protocol_is_not_the_reason(
    protocol: str, why: str, caplog: pytest.LogCaptureFixture
) -> None:
    conn = connection(protocol)
    v5 = conn.v5
    if why == "accepted before":  # MQTT 5 worked: a later close is an ACL, a limit, a restart
        accepted(conn)
        closed(conn)
    closed(conn, 0x8D if why == "keepalive" else 0x80)  # 0x8D: paho's keepalive timeout
    assert conn.v5 == v5
    assert said(caplog, FELL_BACK) == []
    # never silent; paho's own keep-alive is said as the broker not answering, not as its close
    # with its access rules to check (connection.py rule 6, attack 23)
    (line,) = said(caplog, "did not answer the connection" if why == "keepalive" else CLOSED)
    assert ("access rules" in line) == (why != "keepalive")
    # the fix is named while MQTT 5 was never accepted: not after it worked, not under 3.1.1
    assert ('set mqtt.protocol = "3.1.1" for it' in line) == (why in ("forced", "keepalive") and v5)


def test_a_refusal_for_another_reason_never_steps_down(caplog: pytest.LogCaptureFixture) -> None:
    conn = connection("auto")
    refused(conn, 0x87)  # Not authorized
    closed(conn)
    assert conn.v5
    assert said(caplog, FELL_BACK) == [] and said(caplog, CLOSED) == []
    assert len(said(caplog, "Not authorized")) == 1


def test_after_the_step_down_paho_sends_an_mqtt_3_1_1_connect_with_a_clean_session() -> None:
    """paho_client.py rule 3 holds paho to the two attributes it builds its CONNECT from."""
    settings = MqttSettings(host="127.0.0.1", port=1, client_id="fallback-p")
    client = new_client(settings, "fallback-p")
    with socket.create_server(("127.0.0.1", 0)) as server:
        # as the main connection: set up for MQTT 5 and a clean start, then stepped down
        client.connect_async("127.0.0.1", server.getsockname()[1], clean_start=True)
        client.use_mqtt311()
        client.reconnect()  # what paho's loop does for the next attempt
        peer, _ = server.accept()
        with peer:
            peer.settimeout(slow(5))
            connect = peer.recv(4096)
    client.socket().close()
    assert protocol_level(connect) == 4
    flags = connect[2 + 2 + 4 + 1]  # fixed header (2), name length (2), "MQTT", level
    assert flags & 0x02  # clean session


@pytest.mark.parametrize("tls", [False, True])
def test_closes_around_an_accepted_trial_step_down_only_without_tls(
    tls: bool, monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    """Closing connections needs no key: anyone on the path can close the first and the third
    connection and let the 3.1.1 trial between them through, TLS or not (a load balancer with
    one broker of two down does the same). Over TLS nobody on the path can answer "Unsupported
    protocol version", so the close must not be the weaker way down either (docs/brokers.md:
    TLS is what keeps MQTT 5's rules)."""
    monkeypatch.setattr("bridge.interfaces.mqtt.connection.accepts_mqtt311", lambda *a: True)
    settings = MqttSettings(
        host="127.0.0.1", port=1, client_id="fallback-tls", tls={"enabled": tls}
    )
    conn = Connection(settings, "fallback-tls", subscriptions=["rotor/t"], on_message=print)
    closed(conn)  # the first close: a trial, accepted
    trial = conn._trial
    if trial is not None:
        trial.join(slow(5))
    closed(conn)  # the next MQTT 5 attempt closed too
    assert conn.v5 is tls
    assert (said(caplog, FELL_BACK) == []) is tls
    if tls:
        (line,) = said(caplog, CLOSED)  # the fix is said, without the promise of a trial
        assert 'set mqtt.protocol = "3.1.1" for it' in line and "asks the broker" not in line
