"""Review 154 (b44b3a3b: a network round waits until the first thing due, paho_client.py rule
2): ``_wait_ms`` takes ``math.ceil`` of the time to the first thing due, and a connection with
nothing on a clock has none: a tick that answers ``math.inf`` (connection.py's base, so the
remote's link, ``RemoteLink``), no CONNECT unanswered, and no keep-alive. The keep-alive is 0
when the broker says so: an MQTT 5 CONNACK's Server Keep Alive of 0 (review 148: moquette's
``server_keep_alive``, a broker that wants no pings); the stop lanes and the express ping
anyway (``ping_within``), the remote's link keeps the broker's word. ``math.ceil(inf)`` raises
OverflowError, which ``_round`` does not catch (OSError, TypeError, ValueError); the thread
logs it, shuts the socket down and goes round again, where ``_wait_ms`` raises again before
any poll: a loop at full speed, a traceback each turn (the journal flooded), and nothing read
on the connection ever again, its end included (paho never sees the socket shut down).

Real parts: mosquitto, the remote's link (RemoteLink) in-process, review 148's proxy adding a
Server Keep Alive of 0 to every MQTT 5 CONNACK it hands on, a paho client at the broker as the
station."""

from __future__ import annotations

import logging
import threading
from pathlib import Path

import pytest

from bridge.interfaces.mqtt.remote import RemoteLink
from bridge.settings.mqtt import MqttSettings
from tests.faults.test_review148_server_keep_alive_zero import KeepAliveOff
from tests.support import Probe
from tests.support.mosquitto import Mosquitto
from tests.support.waiting import slow, wait_until

TOPIC = "rotor/bridge/heartbeat"


def test_the_remotes_link_hears_the_station_under_a_broker_that_turns_keep_alive_off(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    # (the traceback of each turn of the loop kept out of the test's log: thousands a second)
    caplog.set_level(logging.CRITICAL, logger="bridge.interfaces.mqtt.paho_client")
    broker = Mosquitto(tmp_path / "broker").start()
    proxy = KeepAliveOff(broker.port)
    station = Probe(broker.port, "")
    heard = threading.Event()

    def hear(topic: str, payload: bytes, _retain: bool) -> None:
        if topic == TOPIC and payload == b"beat":
            heard.set()

    link = RemoteLink(MqttSettings(host="127.0.0.1", port=proxy.port), "remote-154", [TOPIC], hear)
    link.start()
    try:
        wait_until(lambda: link.up, slow(10), "the remote's link accepted (MQTT 5)")
        assert link.protocol == "MQTT 5" or "5" in str(link.protocol)
        assert station.publish(TOPIC, "beat")  # the station's word, after the link's SUBSCRIBE
        wait_until(heard.is_set, slow(5), "the remote's link hearing the station")
    finally:
        link.stop()
        station.close()
        proxy.close()
        broker.stop()
