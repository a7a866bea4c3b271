"""Yaesu GS-232A/B end to end: real mosquitto, real pyserial on a pty, the bridge, and the GS-232
emulator (written from the documents and judged by Hamlib's rotctl) as the controller."""

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
