"""The real service process: `rotor-bridge run -c FILE`, started, signalled and killed."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from bridge import emulators
from tests.support import BridgeProcess, Probe, retained_snapshot, wait_until
from tests.support.mosquitto import Mosquitto, free_port
from tests.support.process import bridge_env
from tests.support.rig import Rig
from tests.support.waiting import slow


def write_config(tmp: Path, port: int, link: Path) -> Path:
    cfg = tmp / "bridge.toml"
    cfg.write_text(
        f"""
state_file = "{tmp / "state.json"}"
[mqtt]
host = "127.0.0.1"
port = {port}
base_topic = "rotor"
password = "do-not-log-me"
username = "someone"

[[rotators]]
id = "tower"
model = "rotorez"
port = "{link}"
brake_delay_s = 1
idle_poll_interval_s = 0.3
"""
    )
    return cfg


def start_bridge(cfg: Path, log: Path) -> subprocess.Popen[bytes]:
    """`rotor-bridge run -c CFG` at the file's own log level, its output in ``log``."""
    bridge = BridgeProcess(cfg.parent, cfg, log_level=None, log_path=log).start()
    assert bridge.proc is not None
    return bridge.proc


def test_broker_down_at_start_then_up_then_sigterm_is_a_clean_exit(tmp_path: Path) -> None:
    port = free_port()
    emu = emulators.start("rotorez", link=str(tmp_path / "tty"), brake_delay_s=1, jitter_deg=0)
    proc = start_bridge(write_config(tmp_path, port, tmp_path / "tty"), tmp_path / "bridge.log")
    broker = Mosquitto(tmp_path / "broker", port=port, extra_conf="allow_anonymous true")
    try:
        # the bridge starts before any broker exists and keeps trying
        emu.wait_for_frame(b"AI1;", "query", timeout_s=10)
        assert proc.poll() is None
        broker.start()
        probe = Probe(port, "rotor/#")
        probe.wait_value("rotor/bridge/state", "online", timeout_s=40)
        probe.wait_value("rotor/availability", "online")
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(slow(10)) == 0  # a guard: a bridge that hangs on SIGTERM fails here
        snap = retained_snapshot(port, "rotor/#")
        assert snap["rotor/bridge/state"] == b"offline"
        assert snap["rotor/availability"] == b"offline"
        probe.close()
        log = (tmp_path / "bridge.log").read_text()
        assert "do-not-log-me" not in log
    finally:
        if proc.poll() is None:
            proc.kill()
        broker.stop()
        emu.close()


@pytest.mark.parametrize("nohup", [False, True])
def test_sighup_a_closed_terminal_is_a_clean_stop_but_not_under_nohup(
    tmp_path: Path, nohup: bool
) -> None:
    """An attack pass: closing the terminal of a bridge run by hand killed it (exit 129), with
    no offline said but the last will's; SIGHUP now stops it as SIGTERM does. A review: under
    ``nohup``, which asks for SIGHUP to be ignored, it runs on."""
    broker = Mosquitto(tmp_path / "broker").start()
    emu = emulators.start("rotorez", link=str(tmp_path / "tty"), brake_delay_s=1, jitter_deg=0)
    cfg = write_config(tmp_path, broker.port, tmp_path / "tty")
    ignore = (lambda: signal.signal(signal.SIGHUP, signal.SIG_IGN)) if nohup else None
    with (tmp_path / "bridge.log").open("wb") as log:
        proc = subprocess.Popen(
            [sys.executable, "-m", "bridge", "run", "-c", str(cfg)],
            stdout=log,
            stderr=subprocess.STDOUT,
            env=bridge_env(),
            preexec_fn=ignore,
        )
    try:
        probe = Probe(broker.port, "rotor/#")
        probe.wait_value("rotor/availability", "online", timeout_s=40)
        proc.send_signal(signal.SIGHUP)
        if nohup:
            probe.publish("rotor/target", "90")  # answered only by a bridge still running
            probe.wait_value("rotor/state", "moving", timeout_s=20)
            assert proc.poll() is None
            proc.send_signal(signal.SIGTERM)
        assert proc.wait(slow(10)) == 0
        said = "SIGTERM" if nohup else "SIGHUP"
        assert f"{said} received, shutting down" in (tmp_path / "bridge.log").read_text()
        assert retained_snapshot(broker.port, "rotor/#")["rotor/availability"] == b"offline"
        probe.close()
    finally:
        if proc.poll() is None:
            proc.kill()
        broker.stop()
        emu.close()


def test_killed_bridge_is_marked_offline_by_its_last_will(tmp_path: Path) -> None:
    broker = Mosquitto(tmp_path / "broker").start()
    emu = emulators.start("rotorez", link=str(tmp_path / "tty"), brake_delay_s=1)
    proc = start_bridge(write_config(tmp_path, broker.port, tmp_path / "tty"), tmp_path / "log")
    try:
        probe = Probe(broker.port, "rotor/#")
        probe.wait_value("rotor/bridge/state", "online", timeout_s=20)
        t = time.monotonic()
        proc.kill()  # no goodbye: only the broker can tell
        proc.wait(slow(5))
        probe.wait_value("rotor/bridge/state", "offline", timeout_s=10, after=t)
        wait_until(
            lambda: retained_snapshot(broker.port, "rotor/#")["rotor/bridge/state"] == b"offline"
        )
        probe.close()
    finally:
        if proc.poll() is None:
            proc.kill()
        broker.stop()
        emu.close()


@pytest.mark.parametrize("model", ["rotorez", "rot2prog"])
def test_sigterm_mid_turn_writes_a_stop_before_the_process_ends(
    tmp_path: Path, broker: Mosquitto, probe: Probe, model: str
) -> None:
    """app.py rule 6, an attack pass: ``systemctl stop`` while the rotor turned closed the port
    in 0.2 s with no stop on the wire, and the rotor turned on, watched by nobody, to its
    target (55 degrees at the signal, 182 three seconds after the exit, on to 300). A Rot2Prog's
    half-duplex line owes its reply first (link.py rule 3): the stop still goes before the end."""
    with Rig(tmp_path, broker, probe) as rig:
        emu = rig.add("tower", model, emu={"start_az_deg": 10})
        bridge = rig.start_process()
        rig.ready("tower", timeout_s=slow(30))
        start = emu.state().az_deg
        probe.publish("rotor/target", "300")
        emu.wait_until(
            lambda d, now: d.state(now).az_deg, lambda az: abs(az - start) > 10, slow(10)
        )
        seen, at_signal = len(emu.log()), emu.state().az_deg
        assert bridge.proc is not None
        bridge.proc.send_signal(signal.SIGTERM)
        assert bridge.proc.wait(slow(10)) == 0
        stops = [f for f in emu.log()[seen:] if f.outcome == "stop"]
        assert stops, f"no stop on the wire after SIGTERM: {emu.log()[seen:]}"
        rest = emu.wait_until(lambda d, now: d.state(now), lambda s: not s.is_moving, slow(10))
        assert abs(rest.az_deg - at_signal) < 30, (at_signal, rest)  # not on to its target
