"""connection.py rule 6: a login the broker refuses is said with the keys to check, as paho
reports it (the reason codes brokers send); the real broker's refusal is in
tests/faults/test_security.py."""

from __future__ import annotations

import logging
from pathlib import Path

import paho.mqtt.client as paho
import pytest
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.reasoncodes import ReasonCode

from bridge.interfaces.mqtt.connection import Connection
from bridge.settings import MqttSettings
from tests.faults.conftest import Pki


def refused_with(code: int, caplog: pytest.LogCaptureFixture, **login: object) -> list[str]:
    settings = MqttSettings(host="127.0.0.1", port=1, client_id="login-t", **login)  # type: ignore[arg-type]
    conn = Connection(settings, "login-t", subscriptions=["rotor/target"], on_message=print)
    reason = ReasonCode(PacketTypes.CONNACK, identifier=code)
    with caplog.at_level(logging.ERROR):
        conn._on_connect(conn._client, None, paho.ConnectFlags(False), reason, None)
    return [r.getMessage() for r in caplog.records if r.levelno == logging.ERROR]


@pytest.mark.parametrize("code", [0x86, 0x87])
def test_a_refused_login_names_the_keys_to_check(
    caplog: pytest.LogCaptureFixture, code: int
) -> None:
    """An attack pass: the bridge said "MQTT broker refused the connection: Not authorized
    (retrying)", naming no key (the remote named them)."""
    (line,) = refused_with(code, caplog, username="rotor", password="Sekr1tPW")
    assert line.startswith("MQTT broker refused the connection: ")
    assert line.endswith(
        ": check mqtt.username and mqtt.password (or password_file), and the broker's access "
        "rules (retrying)"
    )
    assert "Sekr1tPW" not in line


def test_a_refused_connection_without_a_login_says_to_set_one(
    caplog: pytest.LogCaptureFixture,
) -> None:
    assert refused_with(0x87, caplog) == [
        "MQTT broker refused the connection: Not authorized: the broker asks for a login: set "
        "mqtt.username and mqtt.password_file (retrying)"
    ]
    caplog.clear()
    assert refused_with(0x88, caplog) == [  # (no login's fault: said as before)
        "MQTT broker refused the connection: Server unavailable (retrying)"
    ]


def test_a_refused_certificate_login_names_the_certificate_not_a_password(
    caplog: pytest.LogCaptureFixture, tmp_path: Path
) -> None:
    """A review of login_hint: a broker that takes the client certificate as the login
    (use_identity_as_username) refused it, and the bridge said to set a user name and a
    password file, which that broker does not ask for."""
    pki = Pki(tmp_path / "pki")
    tls = {
        "enabled": True,
        "ca_file": str(pki.path("ca.crt")),
        "cert_file": str(pki.path("client.crt")),
        "key_file": str(pki.path("client.key")),
    }
    assert refused_with(0x87, caplog, tls=tls) == [  # type: ignore[arg-type]
        "MQTT broker refused the connection: Not authorized: check the client certificate "
        "(mqtt.tls.cert_file) and the broker's access rules (retrying)"
    ]
