"""Review 122: ``answers`` (bridge/demo/mosquitto.py, since "demo: a broker answers when a CONNECT
gets a CONNACK") counts a broker that refuses the demo's login as one that answers ("refusing a
login too: that is a broker"), so the demo takes a mosquitto that asks for a username and
password, as most set up by hand or for Home Assistant do, for its broker. The demo has no flag
to give it a login: its bridge is refused ("the broker asks for a login: set mqtt.username and
mqtt.password_file (retrying)", keys a demo has not), its console too, so it runs dead: the banner
says "bridged to the MQTT broker already running", the ``mosquitto_pub`` lines it prints are
refused, a typed bearing goes nowhere, and at its end it says the broker "no longer answers".
Rule 6 of bridge/demo/__init__.py was written against exactly this ("a demo bridged to it would
run dead"); README: if no broker answers "it starts a private mosquitto". The demo should start
its private mosquitto on a free port (or end saying why), not claim a broker it cannot use.

Real mosquitto with ``allow_anonymous false`` and a password file."""

from __future__ import annotations

import logging
from pathlib import Path

import pytest

from bridge import demo
from bridge.cli import build_parser
from tests.faults.conftest import mosquitto_password_file
from tests.support.mosquitto import Mosquitto


def test_a_broker_that_refuses_the_demos_login_is_not_announced_as_its_broker(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    caplog: pytest.LogCaptureFixture,
) -> None:
    passwd = mosquitto_password_file(tmp_path / "passwd", {"ham": "secret"})
    conf = f"user root\nallow_anonymous false\npassword_file {passwd}\n"  # readable as root too
    broker = Mosquitto(tmp_path / "broker", extra_conf=conf).start()
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.setattr("tempfile.tempdir", str(work))
    caplog.set_level(logging.INFO)
    try:
        args = build_parser().parse_args(
            ["demo", "--mqtt-port", str(broker.port), "--web-port", "0", "--duration-s", "4"]
        )
        code = demo.run(args)
    finally:
        broker.stop()
    said = capsys.readouterr()
    connected = "connected to MQTT broker" in caplog.text
    claimed = f"the MQTT broker already running at 127.0.0.1:{broker.port}" in said.out
    assert not (claimed and not connected), (
        f"the demo said it was bridged to a broker that refused it (exit {code}): "
        f"{said.out[:300]} / {caplog.text[-600:]}"
    )
    assert code != 0 or connected, f"the demo ran to its end never connected: {said.err[-400:]}"


def test_a_broker_that_refuses_the_demos_login_ends_a_demo_told_to_start_no_broker_saying_so(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """With ``--no-private-broker`` the demo has nothing to fall back on: it ends at once, its
    one line saying the broker refuses its login (not that no broker is there)."""
    passwd = mosquitto_password_file(tmp_path / "passwd", {"ham": "secret"})
    conf = f"user root\nallow_anonymous false\npassword_file {passwd}\n"
    broker = Mosquitto(tmp_path / "broker", extra_conf=conf).start()
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.setattr("tempfile.tempdir", str(work))
    try:
        args = build_parser().parse_args(
            ["demo", "--mqtt-port", str(broker.port), "--web-port", "0", "--no-private-broker"]
        )
        code = demo.run(args)
    finally:
        broker.stop()
    said = capsys.readouterr()
    assert code == 1, said.err
    assert f"the MQTT broker at 127.0.0.1:{broker.port} refuses the demo's login" in said.err, (
        said.err
    )
    assert "no MQTT broker at" not in said.err, said.err
    assert "bridged to" not in said.out, said.out
    assert sorted(p.name for p in work.iterdir()) == []
