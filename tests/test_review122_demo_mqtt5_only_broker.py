"""Review 122: since "demo: a broker answers when a CONNECT gets a CONNACK", the demo's look at
its MQTT port (bridge/demo/mosquitto.py ``answers``) is an MQTT 3.1.1 CONNECT only. A broker
listener that speaks MQTT 5 alone (rumqttd's v5 listener, a broker set to MQTT 5) closes such a
connection without a CONNACK (MQTT 5 spec 3.1.2.2: it MAY send a CONNACK, then MUST close), and
the demo says of it "takes connections but answers no MQTT (no CONNACK): not a broker"; with
``--no-private-broker`` it refuses to run (exit 1), without it it bridges to a private mosquitto
that Home Assistant on that broker cannot see. The bridge and the demo's console connect with
MQTT 5 first and work on it, as the demo did before that commit.

Real mosquitto, behind a relay that closes every CONNECT that is not MQTT 5."""

from __future__ import annotations

import logging
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.demo_process import run_demo_in_process
from tests.support.brokers import Mqtt5Only
from tests.support.mosquitto import Mosquitto


@pytest.fixture
def mqtt5_only(broker: Mosquitto) -> Iterator[Mqtt5Only]:
    relay = Mqtt5Only(broker.port)
    yield relay
    relay.close()


def test_a_broker_that_speaks_only_mqtt5_is_still_the_demos_broker(
    mqtt5_only: Mqtt5Only,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    caplog: pytest.LogCaptureFixture,
) -> None:
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))
    caplog.set_level(logging.INFO)
    port = mqtt5_only.port
    code = run_demo_in_process(port, "--no-private-broker", "--duration-s", "6")
    said = capsys.readouterr()
    assert "answers no MQTT" not in said.err, f"the user's broker called no broker: {said.err}"
    assert code == 0, f"the demo refused the user's working broker (exit {code}): {said.err}"
    assert f"the MQTT broker already running at 127.0.0.1:{port}" in said.out, said.out
    assert "connected to MQTT broker (MQTT 5" in caplog.text, caplog.text[-600:]
