"""Yaesu GS-232A/B end to end: real mosquitto, real pyserial on a pty, the bridge, and the GS-232
emulator (written from the documents and judged by Hamlib's rotctl) as the controller."""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest

from bridge.emulators.gs232 import Gs232
from bridge.emulators.pty import EmulatedPort
from tests.support import free_port
from tests.support.hamlib import run_rotctl
from tests.support.rig import FAST_POLLING, Rig
from tests.support.waiting import wait_until


def ready(rig: Rig) -> None:
    rig.probe.wait_value("rotor/availability", "online", timeout_s=15)
    rig.probe.wait_value("rotor/state", "idle", timeout_s=15)


def status(rig: Rig) -> dict[str, object]:
    doc: dict[str, object] = json.loads(rig.retained()["rotor/status"])
    return doc


@pytest.mark.parametrize("model", ["gs232a", "gs232b"])
def test_az_el_target_bearing_and_stop(rig: Rig, model: str) -> None:
    emu = rig.add("sat", model=model, emu={"start_az_deg": 10, "start_el_deg": 5})
    rig.start()
    ready(rig)
    snap = rig.retained()
    assert snap["rotor/bearing"] == b"10" and snap["rotor/elevation"] == b"5"

    t = time.monotonic()  # before the move: its idle may come before the emulator is asked
    rig.probe.publish("rotor/target", '{"azimuth": 123, "elevation": 45}')
    emu.wait_for(lambda s: (s.az_deg, s.el_deg) == (123.0, 45.0) and not s.is_moving, 20)
    rig.probe.wait_value("rotor/state", "idle", timeout_s=10, after=t)
    assert (status(rig)["bearing"], status(rig)["elevation"]) == (123, 45)
    assert [f.data for f in emu.frames("move")] == [b"W123 045"]

    rig.probe.publish("rotor/target", '{"azimuth": 300, "elevation": 10}')
    emu.wait_for(lambda s: s.is_moving and s.az_deg > 140, 10)
    t = time.monotonic()
    rig.probe.publish("rotor/stop", "STOP")
    stopped = emu.wait_for(lambda s: not s.is_moving, 5)
    assert stopped.az_deg < 290 and emu.frames("stop")
    rig.probe.wait_value("rotor/state", "idle", timeout_s=10, after=t)
    assert status(rig)["bearing"] == round(emu.state().az_deg)  # where it stopped, read back
    assert emu.frames("refused") == []


def test_azimuth_box_turns_and_refuses_an_elevation(rig: Rig) -> None:
    emu = rig.add("az", model="gs232b-az", emu={"start_az_deg": 200})
    rig.start()
    ready(rig)
    rig.probe.publish("rotor/target", "95")
    emu.wait_for(lambda s: s.az_deg == 95.0 and not s.is_moving, 20)
    assert [f.data for f in emu.frames("move")] == [b"M095"]
    assert {f.data for f in emu.frames("query")} == {b"C"}
    t = time.monotonic()
    rig.probe.publish("rotor/target", "100 20")  # an elevation it cannot do
    err = json.loads(rig.probe.wait_for("rotor/error", after=t).payload)
    assert "no elevation" in err["message"]
    assert len(emu.frames("move")) == 1


def test_the_450_degree_rotor_takes_the_overlap(rig: Rig) -> None:
    emu = rig.add("tower", model="gs232b-az-450", emu={"start_az_deg": 350})
    rig.start()
    ready(rig)
    t = time.monotonic()
    rig.probe.publish("rotor/target", "20")  # 30 degrees on through north, not 330 back
    emu.wait_for(lambda s: s.az_deg == 380.0 and not s.is_moving, 20)
    assert [f.data for f in emu.frames("move")] == [b"M380"]
    rig.probe.wait_value("rotor/state", "idle", timeout_s=10, after=t)
    doc = status(rig)
    assert (doc["bearing"], doc["raw_bearing"], doc["overlap"]) == (20, 380, "cw")


@pytest.mark.hamlib
def test_p_360_turns_the_rotor_the_way_hamlib_sends_it(
    rig: Rig, rotctl_path: str, tmp_path: Path
) -> None:
    """Hamlib's judge: ``rotctl -m 603 P 360 0`` sends a GS-232B ``W360 000``, the clockwise end
    of its 0..360, 10 degrees on from 350. The bridge's rotctld port sent ``W000 000`` for the
    same ``P 360 0`` from Hamlib's client: the other end, the rotor sent 350 degrees back
    through south (a minute at 6 degrees a second) to point where it nearly was."""
    judge = EmulatedPort(
        Gs232("gs232b", start_az_deg=350.0, now=time.monotonic()), link=tmp_path / "judge"
    )
    try:
        done = run_rotctl(rotctl_path, 603, str(judge.link), "-s", "9600", "P", "360", "0")
        assert done.returncode == 0, f"rotctl failed: {done.stdout!r} {done.stderr[-800:]!r}"
        # (rotctl ends once its frame is written; the emulator's thread reads it after: CI saw
        # the log read before it)
        wait_until(lambda: any(f.outcome == "move" for f in judge.log()), 10, "Hamlib's move")
        hamlibs = [f.data for f in judge.log() if f.outcome == "move"]
    finally:
        judge.close()
    assert hamlibs == [b"W360 000"]

    port = free_port()
    emu = rig.add("sat", model="gs232b", emu={"start_az_deg": 350}, rotctld_port=port)
    rig.start()
    ready(rig)
    done = run_rotctl(rotctl_path, 2, port, "P", "360", "0")
    assert done.returncode == 0, f"rotctl failed: {done.stdout!r} {done.stderr[-800:]!r}"
    emu.wait_for(lambda s: s.is_moving, 10)
    assert [f.data for f in emu.frames("move")] == hamlibs
    arrived = emu.wait_for(lambda s: not s.is_moving, 20)
    assert arrived.az_deg == 360.0
    rig.probe.wait_for("rotor/status", lambda m: json.loads(m.payload)["bearing"] == 0)


@pytest.mark.hamlib
@pytest.mark.parametrize("model", ["gs232a", "gs232b"])
def test_p_reads_360_at_the_clockwise_end_as_hamlib_does(
    rig: Rig, rotctl_path: str, tmp_path: Path, model: str
) -> None:
    """Hamlib's judge: ``rotctl -m 601``/``603`` reads a box at the clockwise end of its 0..360
    as ``360.00``, the value ``P`` takes to keep it there. The bridge's rotctld port said
    ``0.00``: a client that sent ``P 360`` read the rotor short of it by a whole turn, and one
    that sends back what it read (a logger's "hold here", a step from the reading) named the
    other end, 360 degrees back."""
    hamlib_model = {"gs232a": 601, "gs232b": 603}[model]
    judge = EmulatedPort(
        Gs232(model, start_az_deg=360.0, now=time.monotonic()), link=tmp_path / "judge"
    )
    try:
        done = run_rotctl(rotctl_path, hamlib_model, str(judge.link), "-s", "9600", "p")
        assert done.returncode == 0, f"rotctl failed: {done.stdout!r} {done.stderr[-800:]!r}"
    finally:
        judge.close()
    hamlibs = done.stdout.split()
    assert hamlibs[0] == "360.00"

    port = free_port()
    rig.add("sat", model=model, emu={"start_az_deg": 360}, rotctld_port=port)
    rig.start()
    ready(rig)
    done = run_rotctl(rotctl_path, 2, port, "p")
    assert done.returncode == 0, f"rotctl failed: {done.stdout!r} {done.stderr[-800:]!r}"
    assert done.stdout.split() == hamlibs
    assert status(rig)["bearing"] == 0  # R/bearing stays a compass bearing, 0..360


def test_a_nudge_across_north_turns_the_short_way_and_stops_at_the_end(rig: Rig) -> None:
    """Pointing rule 6: the 0 and 360 of a GS-232B are the ends of a Yaesu rotor's travel, so
    ``+10`` from 350 is 10 degrees on, to 360 (``M360``): it went out as ``M000``, the other
    end, and turned the rotor 350 degrees back through south. A nudge past that end is refused
    on R/error and moves nothing; one back from it turns back."""
    emu = rig.add("tower", model="gs232b-az", emu={"start_az_deg": 350})
    rig.start()
    ready(rig)
    rig.probe.publish("rotor/nudge", "+10")
    emu.wait_for(lambda s: s.is_moving)
    assert [f.data for f in emu.frames("move")] == [b"M360"]
    arrived = emu.wait_for(lambda s: not s.is_moving, timeout_s=20)
    assert arrived.az_deg == 360.0
    rig.probe.wait_for("rotor/status", lambda m: json.loads(m.payload)["bearing"] == 0)
    rig.probe.wait_value("rotor/state", "idle", timeout_s=10)

    t = time.monotonic()
    rig.probe.publish("rotor/nudge", "+10")  # past the end: 350 degrees back is no nudge
    err = json.loads(rig.probe.wait_for("rotor/error", after=t).payload)
    assert "turns to azimuth 10 (controller 370), past the end" in err["message"]
    rig.probe.publish("rotor/nudge", "-20")  # back the way it came
    emu.wait_for(lambda s: s.az_deg == 340.0 and not s.is_moving, timeout_s=20)
    assert [f.data for f in emu.frames("move")] == [b"M360", b"M340"]


def test_junk_and_refusals_give_an_error_and_change_nothing(rig: Rig) -> None:
    rig.add("tower", model="gs232b-az-450", emu={"start_az_deg": 77})
    rig.start()
    ready(rig)
    rig.junk_reported("tower", b"?>\r\n", b"AZ=3", b"garbage\r\n", b"+0123+0045\r\n")
    assert {m.text for m in rig.probe.on("rotor/bearing")} == {"77"}


def test_a_bearing_the_box_refuses_is_reported_and_moves_nothing(rig: Rig) -> None:
    emu = rig.add("tower", model="gs232b-az-450", emu={"start_az_deg": 77})
    emu.inject(b"P36\r", to="device")  # the box set to 360 degrees; the bridge told 450
    emu.wait_for(lambda s: s.az_range_deg == 360.0, 5)
    rig.start()
    ready(rig)
    t = time.monotonic()
    rig.probe.publish("rotor/target", "400")  # past 360: on the controller's own scale
    refused = rig.probe.wait_for("rotor/error", lambda m: '"refused"' in m.text, after=t)
    assert "the controller refused the target" in json.loads(refused.payload)["message"]
    rig.probe.wait_value("rotor/state", "idle", after=t)  # at rest at once, no stall to wait
    assert emu.frames("refused")[-1].data == b"M400"
    assert emu.state().az_deg == 77.0 and not emu.state().is_moving
    assert {m.text for m in rig.probe.on("rotor/bearing")} == {"77"}


def test_the_gs232b_driver_drives_a_bridges_own_gs232_port(rig: Rig, tmp_path: Path) -> None:
    """The two halves close the loop: rotator "dish" is a GS-232B whose serial line is the
    station-side GS-232 pty of rotator "station", which turns an emulated MD-01. A target sent to
    "dish" goes out as ``W``, is judged by "station" and turns its rotor; the bearing comes
    back by ``C2``; a stop of "dish" stops the rotor."""
    link = tmp_path / "station-gs232"
    emu = rig.add(
        "station",
        model="md01",
        emu={"start_az_deg": 10, "start_el_deg": 5, "az_speed_deg_s": 10},
        gs232_pty=str(link),
    )
    rig.rotators.append({"id": "dish", "model": "gs232b", "port": str(link), **FAST_POLLING})
    rig.start()
    rig.ready("station", timeout_s=15)
    rig.probe.wait_value(rig.topic("dish", "availability"), "online", timeout_s=15)
    rig.probe.wait_value(rig.topic("dish", "state"), "idle", timeout_s=15)
    assert rig.retained()[rig.topic("dish", "bearing")] == b"10"

    rig.probe.publish(rig.topic("dish", "target"), "120 30")
    emu.wait_for(lambda s: abs(s.az_deg - 120) < 0.6 and abs(s.el_deg - 30) < 0.6, 30)
    emu.wait_for(lambda s: not s.is_moving, 10)
    dish = rig.topic("dish", "status")
    rig.probe.wait_for(dish, lambda m: json.loads(m.payload)["bearing"] == 120, timeout_s=15)
    assert json.loads(rig.retained()[dish])["elevation"] == 30

    rig.probe.publish(rig.topic("dish", "target"), "250 60")
    emu.wait_for(lambda s: s.is_moving and s.az_deg > 150, 30)
    rig.probe.publish(rig.topic("dish", "stop"), "STOP")
    stopped = emu.wait_for(lambda s: not s.is_moving, 10)
    assert stopped.az_deg < 245
