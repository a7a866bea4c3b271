"""Attack 33: a program on 127.0.0.1:1883 that takes connections but speaks no MQTT (a hostile
neighbour, a hung broker, an SSH tunnel whose far end is gone) is taken by ``./demo`` for "the MQTT
broker already running at 127.0.0.1:1883" (bridge/demo/mosquitto.py ``answers`` is a TCP connect
that succeeds, no CONNACK asked for). The banner says so and prints the ``mosquitto_pub`` commands
to turn the rotator, but the bridge never connects: nothing is published, no command reaches it,
the typed ones neither (the demo's own prompt goes through the broker), and no line says why; at
the end it says the broker "no longer answers". README: the demo uses the broker at
127.0.0.1:1883 "if one answers", else starts a private one. A port that answers no MQTT is no
broker: the demo says so (and ends, or bridges to a private mosquitto that answers), instead of
running dead while saying it is bridged."""

from __future__ import annotations

import logging
import socket
from pathlib import Path

import pytest

from tests.demo_process import run_demo_in_process


def test_a_port_that_speaks_no_mqtt_is_not_announced_as_the_broker(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    caplog: pytest.LogCaptureFixture,
) -> None:
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))
    caplog.set_level(logging.INFO)
    with socket.socket() as silent:  # connections complete in the kernel's backlog, unanswered
        silent.bind(("127.0.0.1", 0))
        silent.listen(16)
        port = silent.getsockname()[1]
        code = run_demo_in_process(port, "--duration-s", "3")
    said = capsys.readouterr()
    connected = "connected to MQTT broker" in caplog.text
    claimed = f"the MQTT broker already running at 127.0.0.1:{port}" in said.out + said.err
    assert not claimed, f"the demo announced a silent port as its broker: {said.out[:400]}"
    assert code != 0 or connected, (
        f"the demo ran to its end (exit {code}) never connected to any broker, unsaid: "
        f"{said.err[-400:]}"
    )


def test_a_port_that_speaks_no_mqtt_ends_a_demo_told_to_start_no_broker_saying_so(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """With ``--no-private-broker`` the demo has nothing to fall back on: it ends at once, its
    one line saying that what is on the port is no MQTT broker (not that nothing is there)."""
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))
    with socket.socket() as silent:
        silent.bind(("127.0.0.1", 0))
        silent.listen(16)
        port = silent.getsockname()[1]
        code = run_demo_in_process(port, "--no-private-broker")
    said = capsys.readouterr()
    assert code == 1, said.err
    assert f"127.0.0.1:{port} takes connections but answers no MQTT" in said.err, said.err
    assert "bridged to" not in said.out, said.out
    assert sorted(p.name for p in tmp_path.iterdir()) == []
