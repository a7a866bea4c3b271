"""``delivery.wait_published``: the offline message at shutdown is waited for while the
connection lives, and a message paho never queued (the connection went between the check and
the publish) ends the wait instead of raising out of ``stop()``."""

from __future__ import annotations

import threading

import paho.mqtt.client as paho
from paho.mqtt.enums import MQTTErrorCode

from bridge.interfaces.mqtt.delivery import wait_published


def test_a_message_never_queued_ends_the_wait_without_raising() -> None:
    lost = paho.MQTTMessageInfo(1)
    lost.rc = MQTTErrorCode.MQTT_ERR_NO_CONN  # what publish() returns once disconnected
    connected = threading.Event()
    connected.set()  # the flag not yet cleared: the race a shutdown met
    wait_published([lost], 0.5, connected)  # returns, does not raise


def test_a_published_message_ends_the_wait_at_once() -> None:
    done = paho.MQTTMessageInfo(2)
    done._set_as_published()
    connected = threading.Event()
    connected.set()
    wait_published([done], 0.5, connected)
    assert done.is_published()
