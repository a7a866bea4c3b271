"""Attack 23, connection.py rule 6: an attempt the bridge's own client ended for want of an
answer is said as unanswered, never as the broker's close (the words that send the user to its
ACL). The frozen broker itself is tests/faults/test_attack23_stalled_broker_blamed_on_its_acl.py
(paho's keep-alive, 5 s); here the other way the client gives up, paho_client.py rule 5's
CONNACK_TIMEOUT_S (the default keep-alive, 60 s, is longer), and the ends that are closes."""

from __future__ import annotations

from types import SimpleNamespace

import paho.mqtt.client as paho
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.reasoncodes import ReasonCode

from bridge.interfaces.mqtt.connection import unanswered


def _code(name: str) -> ReasonCode:
    return ReasonCode(PacketTypes.DISCONNECT, name)


def test_an_attempt_ended_by_our_keep_alive_or_connack_wait_is_said_unanswered() -> None:
    ours = paho.DisconnectFlags(is_disconnect_packet_from_server=False)
    client = SimpleNamespace(connack_timed_out=False)
    assert unanswered(ours, _code("Keep alive timeout"), client, 5) == (
        "within the keep-alive (5 s)"
    )
    waited = SimpleNamespace(connack_timed_out=True)  # (the socket shut down: a plain end)
    assert unanswered(ours, _code("Unspecified error"), waited, 60) == "within 10 s"


def test_an_attempt_the_broker_closed_is_no_unanswered_one() -> None:
    client = SimpleNamespace(connack_timed_out=False)
    ours = paho.DisconnectFlags(is_disconnect_packet_from_server=False)
    theirs = paho.DisconnectFlags(is_disconnect_packet_from_server=True)
    assert unanswered(ours, _code("Unspecified error"), client, 5) is None
    assert unanswered(theirs, _code("Keep alive timeout"), client, 5) is None
