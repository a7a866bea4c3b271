"""Yaesu GS-232A/B end to end: real mosquitto, real pyserial on a pty, the bridge, and the GS-232
emulator (written from the documents and judged by Hamlib's rotctl) as the controller."""

from __future__ import annotations

import json
import time

import pytest

from tests.support.rig import Rig


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

    rig.probe.publish("rotor/target", '{"azimuth": 123, "elevation": 45}')
    emu.wait_for(lambda s: (s.az_deg, s.el_deg) == (123.0, 45.0) and not s.is_moving, 20)
    t = time.monotonic()
    rig.probe.wait_value("rotor/state", "idle", timeout_s=10, after=t)
    assert (status(rig)["bearing"], status(rig)["elevation"]) == (123, 45)
    assert [f.data for f in emu.frames("move")] == [b"W123 045"]

    rig.probe.publish("rotor/target", '{"azimuth": 300, "elevation": 10}')
    emu.wait_for(lambda s: s.is_moving and s.az_deg > 140, 10)
    rig.probe.publish("rotor/stop", "STOP")
    stopped = emu.wait_for(lambda s: not s.is_moving, 5)
    assert stopped.az_deg < 290 and emu.frames("stop")
    t = time.monotonic()
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
    emu = rig.add("tower", model="gs232b-450", emu={"start_az_deg": 350})
    rig.start()
    ready(rig)
    rig.probe.publish("rotor/target", "20")  # 30 degrees on through north, not 330 back
    emu.wait_for(lambda s: s.az_deg == 380.0 and not s.is_moving, 20)
    assert [f.data for f in emu.frames("move")] == [b"M380"]
    t = time.monotonic()
    rig.probe.wait_value("rotor/state", "idle", timeout_s=10, after=t)
    doc = status(rig)
    assert (doc["bearing"], doc["raw_bearing"], doc["overlap"]) == (20, 380, "cw")


def test_junk_and_refusals_give_an_error_and_change_nothing(rig: Rig) -> None:
    emu = rig.add("tower", model="gs232b-450", emu={"start_az_deg": 77})
    rig.start()
    ready(rig)
    t = time.monotonic()
    for junk in (b"?>\r\n", b"AZ=3", b"garbage\r\n", b"+0123+0045\r\n"):
        emu.inject(junk)
    err = json.loads(rig.probe.wait_for("rotor/error", after=t).payload)
    assert err["kind"] == "protocol" and "no valid reply" in err["message"]
    n = len(emu.frames("query"))
    emu.wait_until(lambda d, now: len(d.frames("query")), lambda k: k >= n + 4, 15)
    assert {m.text for m in rig.probe.on("rotor/bearing")} == {"77"}


def test_a_bearing_the_box_refuses_is_reported_and_moves_nothing(rig: Rig) -> None:
    emu = rig.add("tower", model="gs232b-450", emu={"start_az_deg": 77})
    emu.inject(b"P36\r", to="device")  # the box set to 360 degrees; the bridge told 450
    emu.wait_for(lambda s: s.az_range_deg == 360.0, 5)
    rig.start()
    ready(rig)
    t = time.monotonic()
    rig.probe.publish("rotor/target", "400")  # past 360: on the controller's own scale
    refused = rig.probe.wait_for("rotor/error", lambda m: "protocol" in m.text, after=t)
    assert "no valid reply" in json.loads(refused.payload)["message"]
    stalled = rig.probe.wait_for("rotor/error", lambda m: "stalled" in m.text, after=t)
    assert "stalled at 77" in json.loads(stalled.payload)["message"]  # and it says where
    assert emu.frames("refused")[-1].data == b"M400"
    assert emu.state().az_deg == 77.0 and not emu.state().is_moving
    assert {m.text for m in rig.probe.on("rotor/bearing")} == {"77"}


def test_unplug_and_replug(rig: Rig) -> None:
    emu = rig.add("sat", model="gs232a", emu={"start_az_deg": 33, "start_el_deg": 3})
    rig.start()
    ready(rig)
    t = time.monotonic()
    emu.unplug()
    rig.probe.wait_value("rotor/availability", "offline", after=t)
    t = time.monotonic()
    emu.replug()
    rig.probe.wait_value("rotor/availability", "online", timeout_s=15, after=t)
    rig.probe.publish("rotor/target", "40 10")
    emu.wait_for(lambda s: (s.az_deg, s.el_deg) == (40.0, 10.0) and not s.is_moving, 15)
