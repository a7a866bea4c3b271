"""Green Heron RT-21 end to end: real mosquitto, real pyserial on a pty, the bridge, and the RT-21
emulator (written from the documents and judged by Hamlib's rotctl -m 405) as the controller."""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest

from bridge.emulators.pty import EmulatedPort
from bridge.emulators.rt21 import Rt21
from tests.support import free_port
from tests.support.hamlib import run_rotctl
from tests.support.rig import Rig
from tests.support.waiting import wait_until


def ready(rig: Rig) -> None:
    rig.probe.wait_value("rotor/availability", "online", timeout_s=15)
    rig.probe.wait_value("rotor/state", "idle", timeout_s=15)


def status(rig: Rig) -> dict[str, object]:
    doc: dict[str, object] = json.loads(rig.retained()["rotor/status"])
    return doc


def test_target_to_the_tenth_stop_while_turning_and_the_bearing_read_back(rig: Rig) -> None:
    emu = rig.add("tower", model="rt21", emu={"start_az_deg": 10.3})
    rig.start()
    ready(rig)
    assert rig.retained()["rotor/bearing"] == b"10.3"

    t = time.monotonic()  # before the move: its idle may come before the emulator is asked
    rig.probe.publish("rotor/target", "123.4")
    emu.wait_for(lambda s: s.az_deg == 123.4 and not s.is_moving, 20)
    rig.probe.wait_value("rotor/state", "idle", timeout_s=10, after=t)
    assert status(rig)["bearing"] == 123.4
    assert [f.data for f in emu.frames("move")] == [b"AP1123.4\r;"]

    rig.probe.publish("rotor/target", "300")
    emu.wait_for(lambda s: s.is_moving and s.az_deg > 140, 10)
    t = time.monotonic()  # before the stop, whose idle may come before the emulator is asked
    rig.probe.publish("rotor/stop", "STOP")
    stopped = emu.wait_for(lambda s: not s.is_moving, 5)
    # the stop lane's STOP and the main connection's copy may both go out (lastword.py: a
    # stop carried out twice stops twice); nothing but stops
    stops = [f.data for f in emu.frames("stop")]
    assert stopped.az_deg < 290 and stops and set(stops) == {b";"} and len(stops) <= 2
    rig.probe.wait_value("rotor/state", "idle", timeout_s=10, after=t)
    assert status(rig)["bearing"] == round(emu.state().az_deg, 1)  # where it stopped, read back
    assert emu.frames("refused") == []


def test_junk_gives_an_error_and_changes_nothing(rig: Rig) -> None:
    emu = rig.add("tower", model="rt21", emu={"start_az_deg": 77.7})
    rig.start()
    ready(rig)
    rig.junk_reported("tower", b"garbage", b"\xff12", b"AZ;", b"361.0;", b"12;")
    assert {m.text for m in rig.probe.on("rotor/bearing")} == {"77.7"}
    assert emu.frames("move") == [] and emu.state().az_deg == 77.7


def test_a_new_bearing_while_turning_goes_straight_out(rig: Rig) -> None:
    emu = rig.add("tower", model="rt21", emu={"start_az_deg": 0})
    rig.start()
    ready(rig)
    rig.probe.publish("rotor/target", "200")
    emu.wait_for(lambda s: s.is_moving and s.az_deg > 40, 10)
    rig.probe.publish("rotor/target", "20.5")  # the box re-targets by itself: no stop first
    emu.wait_for(lambda s: s.az_deg == 20.5 and not s.is_moving, 20)
    assert [f.data for f in emu.frames("move")] == [b"AP1200.0\r;", b"AP1020.5\r;"]
    assert emu.frames("stop") == []


@pytest.mark.hamlib
def test_north_goes_out_as_the_box_takes_it_never_360(
    rig: Rig, rotctl_path: str, tmp_path: Path
) -> None:
    """Hamlib's judge: ``rotctl -m 405`` takes 0..359.9 (its caps; ``P 360`` is refused before
    a byte goes out, ``P 359.9`` is ``AP1359.9``), as the protocol sheet gives the RT-21's
    range. The bridge sent ``AP1360.0``, a heading the box is not known to take, for a target
    of 360 (pointing.py rule 2's 360, a GS-232's end of travel); north now goes out as the box
    takes it, ``AP1000.0``."""
    judge = EmulatedPort(Rt21(start_az_deg=10.0, now=time.monotonic()), link=tmp_path / "judge")
    try:
        refused = run_rotctl(rotctl_path, 405, str(judge.link), "P", "360", "0")
        taken = run_rotctl(rotctl_path, 405, str(judge.link), "P", "359.9", "0")
        assert taken.returncode == 0, f"rotctl failed: {taken.stderr[-800:]!r}"
        # (rotctl ends once its frame is written; the emulator's thread reads it after)
        wait_until(lambda: any(f.outcome == "move" for f in judge.log()), 10, "Hamlib's move")
        hamlibs = [f.data for f in judge.log() if f.outcome == "move"]
    finally:
        judge.close()
    assert refused.returncode != 0 and hamlibs == [b"AP1359.9\r;"]

    emu = rig.add("tower", model="rt21", emu={"start_az_deg": 10})
    rig.start()
    ready(rig)
    t = time.monotonic()
    rig.probe.publish("rotor/target", "360")
    emu.wait_for(lambda s: s.is_moving, 10)
    assert [f.data for f in emu.frames("move")] == [b"AP1000.0\r;"]
    emu.wait_for(lambda s: s.az_deg == 0.0 and not s.is_moving, 20)
    rig.probe.wait_value("rotor/state", "idle", timeout_s=10, after=t)
    assert status(rig)["bearing"] == 0


@pytest.mark.hamlib
def test_rotctld_reads_360_as_hamlibs_rt21_does(rig: Rig, rotctl_path: str, tmp_path: Path) -> None:
    """rotctld rule 5: Hamlib's ``-m 405`` reads the box's ``360.0;`` as ``0.00`` (rotorez.c),
    where its GS-232 backends read 360 as ``360.00``; the bridge's rotctld answers as the
    model's own backend would."""
    judge = EmulatedPort(Rt21(start_az_deg=360.0, now=time.monotonic()), link=tmp_path / "judge")
    try:
        done = run_rotctl(rotctl_path, 405, str(judge.link), "p")
        assert done.returncode == 0, f"rotctl failed: {done.stderr[-800:]!r}"
    finally:
        judge.close()
    hamlibs = done.stdout.split()
    assert hamlibs[0] == "0.00"

    port = free_port()
    rig.add("tower", model="rt21", emu={"start_az_deg": 360}, rotctld_port=port)
    rig.start()
    ready(rig)
    done = run_rotctl(rotctl_path, 2, port, "p")
    assert done.returncode == 0, f"rotctl failed: {done.stderr[-800:]!r}"
    assert done.stdout.split() == hamlibs
