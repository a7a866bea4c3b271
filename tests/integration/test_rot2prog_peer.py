"""The bridge against a peer it did not write: the rot2prog package's simulator (PyPI), over a
socat pty pair, exactly as the SPID fact sheet runs Hamlib against it (spid.md section 7)."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.support import wait_until
from tests.support.rig import Rig


@pytest.fixture
def rot2prog_sim(tmp_path: Path):
    a, b = tmp_path / "ptyA", tmp_path / "ptyB"
    socat = subprocess.Popen(
        ["socat", "-d", "-d", f"pty,raw,echo=0,link={a}", f"pty,raw,echo=0,link={b}"],
        stderr=subprocess.PIPE,
    )
    wait_until(lambda: a.exists() and b.exists(), 10, "socat's pty pair")
    code = (
        "import logging, sys, time, rot2prog\n"
        "logging.basicConfig(level=logging.DEBUG, stream=sys.stderr)\n"
        f"rot2prog.ROT2ProgSim({str(a)!r}, 2)\n"
        "time.sleep(3600)\n"
    )
    log = open(tmp_path / "sim.log", "wb")  # noqa: SIM115
    sim = subprocess.Popen([sys.executable, "-c", code], stderr=log, stdout=log)
    try:
        yield b, tmp_path / "sim.log"
    finally:
        sim.kill()
        socat.kill()
        sim.wait()
        socat.wait()
        log.close()


def test_a_target_on_mqtt_becomes_the_simulators_position(rig: Rig, rot2prog_sim) -> None:
    port, sim_log = rot2prog_sim
    rig.rotators.append(
        {
            "id": "sat",
            "model": "rot2prog",
            "port": str(port),
            "idle_poll_interval_s": 0.5,
            "moving_poll_interval_s": 0.2,
        }
    )
    rig.start()
    rig.probe.wait_value("rotor/availability", "online", timeout_s=15)
    rig.probe.wait_value("rotor/state", "idle", timeout_s=15)
    assert (
        rig.probe.last("rotor/bearing").text == "0"
        and rig.probe.last("rotor/elevation").text == "0"
    )
    t = time.monotonic()
    rig.probe.publish("rotor/target", '{"azimuth": 123.5, "elevation": 45}')
    rig.probe.wait_value("rotor/bearing", "123.5", timeout_s=15, after=t)
    rig.probe.wait_value("rotor/elevation", "45", timeout_s=15, after=t)
    rig.probe.wait_value("rotor/state", "idle", timeout_s=15, after=t)
    # negative angles (the ccw side, named by a target outside 0..360) snap down to the 0.5
    # degree grid, as Hamlib does; R/bearing is the true bearing, the status has the raw one
    t = time.monotonic()
    rig.probe.publish("rotor/target", "-10.3 -5")
    rig.probe.wait_value("rotor/bearing", "349.5", timeout_s=15, after=t)
    rig.probe.wait_for(
        "rotor/status",
        lambda m: (
            (json.loads(m.payload)["raw_bearing"], json.loads(m.payload)["overlap"])
            == (-10.5, "ccw")
        ),
        timeout_s=5,
        after=t,
    )
    # elevation alone leaves the azimuth where it is
    t = time.monotonic()
    rig.probe.publish("rotor/target/elevation", "30")
    rig.probe.wait_value("rotor/elevation", "30", timeout_s=15, after=t)
    assert rig.probe.last("rotor/bearing").text == "349.5"
    text = sim_log.read_text()
    assert "Incomplete" not in text and "Invalid" not in text, text[-2000:]
