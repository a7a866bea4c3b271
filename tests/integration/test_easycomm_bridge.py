"""Easycomm II/III controllers end to end: real mosquitto, real pyserial on a pty, the bridge, and
the Easycomm controller emulator (written from the documents and judged by Hamlib's rotctl) as
the controller."""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest

from tests.support.rig import FAST_POLLING, Rig


def ready(rig: Rig) -> None:
    rig.probe.wait_value("rotor/availability", "online", timeout_s=15)
    rig.probe.wait_value("rotor/state", "idle", timeout_s=15)


def status(rig: Rig) -> dict[str, object]:
    doc: dict[str, object] = json.loads(rig.retained()["rotor/status"])
    return doc


@pytest.mark.parametrize("model", ["easycomm2", "easycomm3", "easycomm2-separate"])
def test_az_el_target_bearing_and_stop(rig: Rig, model: str) -> None:
    emu = rig.add("sat", model=model, emu={"start_az_deg": 10, "start_el_deg": 5})
    rig.start()
    ready(rig)
    snap = rig.retained()
    assert snap["rotor/bearing"] == b"10" and snap["rotor/elevation"] == b"5"

    t = time.monotonic()  # before the move: its idle may come before the emulator is asked
    rig.probe.publish("rotor/target", '{"azimuth": 123.4, "elevation": 45}')
    emu.wait_for(lambda s: (s.az_deg, s.el_deg) == (123.4, 45.0) and not s.is_moving, 20)
    rig.probe.wait_value("rotor/state", "idle", timeout_s=10, after=t)
    assert (status(rig)["bearing"], status(rig)["elevation"]) == (123.4, 45)  # tenths
    assert [f.data for f in emu.frames("move")] == [b"AZ123.4", b"EL45.0"]

    rig.probe.publish("rotor/target", '{"azimuth": 300, "elevation": 10}')
    emu.wait_for(lambda s: s.is_moving and s.az_deg > 140, 10)
    t = time.monotonic()  # before the stop, whose idle may come before the emulator is asked
    rig.probe.publish("rotor/stop", "STOP")
    stopped = emu.wait_for(lambda s: not s.is_moving, 5)
    assert stopped.az_deg < 290 and [f.data for f in emu.frames("stop")][:2] == [b"SA", b"SE"]
    rig.probe.wait_value("rotor/state", "idle", timeout_s=10, after=t)
    # where it stopped, read back in tenths
    assert status(rig)["bearing"] == pytest.approx(emu.state().az_deg, abs=0.051)
    assert emu.frames("refused", "ignored", "unanswered") == []


def test_easycomm3_reports_the_controllers_version(rig: Rig) -> None:
    rig.add("sat", model="easycomm3", emu={"version": "SatNOGS 2.2"})
    rig.start()
    ready(rig)
    rig.probe.wait_for("rotor/status", lambda m: json.loads(m.payload)["version"] == "SatNOGS 2.2")


def test_azimuth_controller_turns_and_refuses_an_elevation(rig: Rig) -> None:
    emu = rig.add("az", model="easycomm2-az", emu={"start_az_deg": 200})
    rig.start()
    ready(rig)
    rig.probe.publish("rotor/target", "95.5")
    emu.wait_for(lambda s: s.az_deg == 95.5 and not s.is_moving, 20)
    assert [f.data for f in emu.frames("move")] == [b"AZ95.5"]
    assert {f.data for f in emu.frames("query")} == {b"AZ", b"EL"}  # asked AZ EL, as all are
    t = time.monotonic()
    rig.probe.publish("rotor/target", "100 20")  # an elevation it cannot do
    err = json.loads(rig.probe.wait_for("rotor/error", after=t).payload)
    assert "no elevation" in err["message"]
    assert len(emu.frames("move")) == 1


def test_junk_gives_an_error_and_changes_nothing(rig: Rig) -> None:
    emu = rig.add("sat", model="easycomm2", emu={"start_az_deg": 77, "start_el_deg": 7})
    rig.start()
    ready(rig)
    rig.junk_reported(
        "sat", b"AZ=123\n", b"garbage\r\n", b"\xff\xfeAZ3", b"AZ999.0 EL0.0\n", polls=8
    )
    assert {m.text for m in rig.probe.on("rotor/bearing")} == {"77"}
    assert {m.text for m in rig.probe.on("rotor/elevation")} == {"7"}
    assert emu.frames("move") == [] and not emu.state().is_moving


def test_the_easycomm2_driver_drives_a_bridges_own_easycomm_port(rig: Rig, tmp_path: Path) -> None:
    """The two halves close the loop: rotator "dish" is an Easycomm II controller whose serial
    line is the station-side Easycomm pty of rotator "station", which turns an emulated MD-01.
    A target sent to "dish" goes out as ``AZ.. EL..``, is judged by "station" and turns its
    rotor; the bearing comes back by ``AZ EL``; a stop of "dish" (``SA SE``) stops the rotor."""
    link = tmp_path / "station-easycomm"
    emu = rig.add(
        "station",
        model="md01",
        emu={"start_az_deg": 10, "start_el_deg": 5, "az_speed_deg_s": 10},
        easycomm_pty=str(link),
    )
    rig.rotators.append({"id": "dish", "model": "easycomm2", "port": str(link), **FAST_POLLING})
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

    # the station refuses (locked) and answers a set with nothing (gs232 package rule 3: the
    # refusal is on the station's R/error): the dish sees its rotor make no progress and says
    # so on its error topic as a stall, and nothing turns
    rig.probe.publish(rig.topic("station", "lock"), "ON")
    rig.probe.wait_value(rig.topic("station", "lock/state"), "ON")
    t = time.monotonic()
    rig.probe.publish(rig.topic("dish", "target"), "100 20")
    err = json.loads(rig.probe.wait_for(rig.topic("dish", "error"), after=t).payload)
    assert err["kind"] == "stalled"  # no alarm line comes any more to say "locked"
    assert not emu.state().is_moving and emu.state().az_deg == stopped.az_deg
