"""The tests' MQTT probe stamps each message as its thread takes it (tests/support/mqtt.py
``Probe``), so on a busy machine a message published before a test reads the clock can be
stamped after it: a CI run took a restarted bridge's first run's ``online`` for the new run's.
``caught_up`` is a round trip through the broker: what the broker sent before has arrived. The
busy machine is played here: the probe's thread takes each message slowly."""

from __future__ import annotations

import time
from typing import Any

import pytest

from tests.support import Mosquitto, Probe


def test_what_was_published_before_caught_up_is_stamped_before_it(
    broker: Mosquitto, monkeypatch: pytest.MonkeyPatch
) -> None:
    arrived = Probe._on_message

    def slow_thread(self: Probe, client: Any, userdata: Any, msg: Any) -> None:
        if msg.topic.startswith("before/"):
            time.sleep(0.2)  # (no wait for anything: played) paho's thread waits for a core
        arrived(self, client, userdata, msg)

    monkeypatch.setattr(Probe, "_on_message", slow_thread)
    sender = Probe(broker.port, "")
    probe = Probe(broker.port, "before/#")
    everything = Probe(broker.port)  # "#": another probe's round trips are not its messages
    try:
        for n in range(3):
            sender.publish(f"before/{n}", "then")
        t = probe.caught_up()
        assert [m.topic for m in probe.messages] == ["before/0", "before/1", "before/2"]
        assert all(m.t < t for m in probe.messages)
        sender.publish("before/3", "after")
        assert probe.wait_for("before/3", timeout_s=5, after=t).text == "after"
        assert probe.caught_up() > t  # a second round trip waits for its own
        everything.caught_up()
        assert [m.topic for m in everything.messages] == [f"before/{n}" for n in range(4)]
    finally:
        everything.close()
        probe.close()
        sender.close()


def test_a_probe_that_only_publishes_cannot_catch_up(broker: Mosquitto) -> None:
    sender = Probe(broker.port, "")
    try:
        with pytest.raises(ValueError, match="subscribes"):
            sender.caught_up()
    finally:
        sender.close()
