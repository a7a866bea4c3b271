"""interfaces/mqtt/remote.py rule 5, the decisions alone (no broker): before the first connection a
refused login or a failed TLS handshake is kept as one line for the start-up error, not logged; once
the remote has been connected, both are logged and retried like the bridge's."""

from __future__ import annotations

import logging
import ssl

import pytest

from bridge.interfaces.mqtt.remote import RemoteLink
from bridge.settings.mqtt import MqttSettings


def link() -> RemoteLink:
    return RemoteLink(MqttSettings(host="station.example.org", port=8883), "remote-t", [], print)


def fail_with(lk: RemoteLink, exc: OSError) -> None:
    """What paho does: the callback from inside its ``except OSError``."""
    try:
        raise exc
    except OSError:
        lk._failed()


def test_a_refused_login_before_the_first_connection_is_fatal_and_said_once(
    caplog: pytest.LogCaptureFixture,
) -> None:
    lk = link()
    with caplog.at_level(logging.INFO):
        lk._refused("Not authorized")
    assert lk.fatal
    assert lk.failure == (
        "the broker refused the login (Not authorized): check mqtt.username and mqtt.password_file"
    )
    assert not [r for r in caplog.records if r.levelno >= logging.INFO]


def test_another_refusal_is_said_but_not_fatal() -> None:
    lk = link()
    lk._refused("Server unavailable")
    assert not lk.fatal
    assert lk.failure == "the broker refused the connection (Server unavailable)"


def test_an_untrusted_certificate_is_fatal_and_names_the_keys() -> None:
    lk = link()
    exc = ssl.SSLCertVerificationError(
        1,
        "[SSL: CERTIFICATE_VERIFY_FAILED] certificate verify failed: unable to get local "
        "issuer certificate (_ssl.c:1006)",
    )
    fail_with(lk, exc)
    assert lk.fatal
    assert lk.failure is not None
    assert lk.failure.startswith(
        "TLS handshake failed: certificate verify failed: unable to get local issuer "
        "certificate: check mqtt.tls.ca_file"
    )
    assert "_ssl.c" not in lk.failure and "\n" not in lk.failure


def test_no_broker_there_is_kept_but_not_fatal() -> None:
    lk = link()
    fail_with(lk, ConnectionRefusedError(111, "Connection refused"))
    assert not lk.fatal
    assert lk.failure == "[Errno 111] Connection refused"


def test_once_connected_failures_are_logged_and_retried_as_the_bridge_does(
    caplog: pytest.LogCaptureFixture,
) -> None:
    lk = link()
    lk._refused("Not authorized")
    lk._opened(None)  # a connection accepted: the start is over
    assert lk.failure is None and not lk.fatal
    with caplog.at_level(logging.INFO):
        lk._refused("Not authorized")
    assert not lk.fatal
    said = [r.getMessage() for r in caplog.records if r.levelno == logging.ERROR]
    assert said == [
        "MQTT broker refused the connection: Not authorized: the broker asks for a login: set "
        "mqtt.username and mqtt.password_file (retrying)"
    ]
