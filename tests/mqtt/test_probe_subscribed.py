"""The tests' MQTT probe is ready once the broker has its subscription (tests/support/mqtt.py
``Probe``): its SUBSCRIBE goes out on paho's thread after the CONNACK, and a test that
publishes the moment the probe is made can reach the broker first on a busy machine. A
message the broker takes before the subscription is lost to the probe (not retained: for
ever), and the test waited for it until its deadline. The machine's slowness is played here:
paho's thread is held after the CONNACK's callback, before it writes the SUBSCRIBE."""

from __future__ import annotations

import time
from typing import Any

import pytest

from tests.support import Mosquitto, Probe


def test_a_message_published_as_soon_as_the_probe_is_made_reaches_it(
    broker: Mosquitto, monkeypatch: pytest.MonkeyPatch
) -> None:
    connected = Probe._on_connect

    def slow_thread(self: Probe, *args: Any) -> None:
        connected(self, *args)
        time.sleep(0.5)  # (no wait for anything: played) paho's thread waits for a core, and
        # writes the SUBSCRIBE after it

    monkeypatch.setattr(Probe, "_on_connect", slow_thread)
    sender = Probe(broker.port, "")
    try:
        probe = Probe(broker.port, "probe/subscribed")
        try:
            sender.publish("probe/subscribed", "now")  # not retained: now or never
            assert probe.wait_for("probe/subscribed", timeout_s=2).text == "now"
        finally:
            probe.close()
    finally:
        sender.close()
