"""Review 122: the demo's look at its MQTT port (bridge/demo/mosquitto.py ``answers``, since
"demo: a broker answers when a CONNECT gets a CONNACK") gives a broker 2 s to send its CONNACK,
and a broker that takes longer is said to speak no MQTT. The bridge itself waits 5 s for one
(bridge/interfaces/mqtt/paho_client.py ``accepts_mqtt311``, paho's connect timeout): a broker
that is slow to let a client in (an authentication plugin asking a server, a loaded Raspberry
Pi, a broker reached through a slow link) serves the bridge and the demo's own console, and
served the demo before that commit. Now the demo tells the user "takes connections but answers
no MQTT (no CONNACK): not a broker" about their working broker, and with
``--no-private-broker`` refuses to run at all (exit 1); without it, it bridges to a private
mosquitto that their Home Assistant cannot see (README: the demo uses the broker at
127.0.0.1:1883 "if one answers ... so it shows up in a Home Assistant on that broker").

Real mosquitto, behind a TCP relay that hands on each connection's first answer from the
broker (its CONNACK) late."""

from __future__ import annotations

import logging
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.demo_process import run_demo_in_process
from tests.support.brokers import SlowBroker
from tests.support.mosquitto import Mosquitto


@pytest.fixture
def slow_broker(broker: Mosquitto) -> Iterator[SlowBroker]:
    relay = SlowBroker(broker.port)
    yield relay
    relay.close()


def test_a_broker_slow_to_connack_is_still_the_demos_broker(
    slow_broker: SlowBroker,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    caplog: pytest.LogCaptureFixture,
) -> None:
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))
    caplog.set_level(logging.INFO)
    port = slow_broker.port
    code = run_demo_in_process(port, "--no-private-broker", "--duration-s", "12")
    said = capsys.readouterr()
    assert "answers no MQTT" not in said.err, f"the user's broker called no broker: {said.err}"
    assert code == 0, f"the demo refused the user's working broker (exit {code}): {said.err}"
    assert f"the MQTT broker already running at 127.0.0.1:{port}" in said.out, said.out
    assert "connected to MQTT broker" in caplog.text, "the bridge never connected to it"
