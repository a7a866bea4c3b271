"""SPID Rot2Prog, Rot1Prog and MD-01 end to end: real mosquitto, real pty, the bridge, and the
SPID emulator (written from the documents) as the controller."""

from __future__ import annotations

import json
import time

import pytest

from tests.support.rig import Rig

AZEL = ["rot2prog", "md01"]


def ready(rig: Rig) -> None:
    rig.probe.wait_value("rotor/availability", "online", timeout_s=15)
    rig.probe.wait_value("rotor/state", "idle", timeout_s=15)


@pytest.mark.parametrize("model", AZEL)
def test_az_el_target_then_elevation_alone(rig: Rig, model: str) -> None:
    emu = rig.add("sat", model=model, emu={"start_az_deg": 10, "start_el_deg": 5})
    rig.start()
    ready(rig)
    snap = rig.retained()
    assert snap["rotor/bearing"] == b"10" and snap["rotor/elevation"] == b"5"
    t = time.monotonic()  # before the move: its idle may come before the emulator is asked
    rig.probe.publish("rotor/target", '{"azimuth": 123.5, "elevation": 45}')
    emu.wait_for(
        lambda s: abs(s.az_deg - 123.5) < 0.3 and abs(s.el_deg - 45) < 0.3 and not s.is_moving, 20
    )
    rig.probe.wait_value("rotor/state", "idle", timeout_s=10, after=t)
    status = json.loads(rig.retained()["rotor/status"])
    assert (status["bearing"], status["elevation"]) == (123.5, 45)
    rig.probe.publish("rotor/target/elevation", "60")
    emu.wait_for(lambda s: abs(s.el_deg - 60) < 0.3 and not s.is_moving, 20)
    assert abs(emu.state().az_deg - 123.5) < 0.3  # azimuth unchanged
    t = time.monotonic()
    rig.probe.publish("rotor/target", "200")  # a bare azimuth keeps the elevation
    emu.wait_for(lambda s: abs(s.az_deg - 200) < 0.3 and not s.is_moving, 20)
    assert abs(emu.state().el_deg - 60) < 0.3


def test_rot1prog_azimuth_only(rig: Rig) -> None:
    emu = rig.add("az", model="rot1prog", emu={"start_az_deg": 10})
    rig.start()
    ready(rig)
    rig.probe.publish("rotor/target", "-10.5")
    emu.wait_for(lambda s: abs(s.az_deg - -11) < 0.6 and not s.is_moving, 20)
    t = time.monotonic()
    rig.probe.publish("rotor/target", "100 20")  # an elevation it cannot do
    err = json.loads(rig.probe.wait_for("rotor/error", after=t).payload)
    assert "no elevation" in err["message"]


def test_retarget_while_moving_goes_straight_to_the_new_target(rig: Rig) -> None:
    emu = rig.add("sat", model="rot2prog", emu={"start_az_deg": 0, "az_speed_deg_s": 20})
    rig.start()
    ready(rig)
    rig.probe.publish("rotor/target", "150 0")  # clockwise: -210 would be past the -180 stop
    emu.wait_for(lambda s: s.is_moving and s.az_deg > 20, 10)
    rig.probe.publish("rotor/target", "100 10")
    emu.wait_for(
        lambda s: abs(s.az_deg - 100) < 0.3 and abs(s.el_deg - 10) < 0.3 and not s.is_moving, 20
    )
    assert emu.frames("stop") == []  # SPID takes a new target while turning: no stop first
    assert len(emu.frames("set")) == 2


def test_stop_and_limits(rig: Rig) -> None:
    emu = rig.add(
        "sat", model="rot2prog", emu={"start_az_deg": 0, "az_speed_deg_s": 10}, el_max_deg=90
    )
    rig.start()
    ready(rig)
    rig.probe.publish("rotor/target", "150 0")
    emu.wait_for(lambda s: s.is_moving and s.az_deg > 10, 10)
    rig.probe.publish("rotor/stop", "STOP")
    stopped = emu.wait_for(lambda s: not s.is_moving, 5)
    assert stopped.az_deg < 200
    for payload, why in (("600 0", "azimuth 600 outside"), ("100 95", "elevation 95 outside")):
        t = time.monotonic()
        rig.probe.publish("rotor/target", payload)
        err = json.loads(rig.probe.wait_for("rotor/error", after=t).payload)
        assert why in err["message"]
    assert len(emu.frames("set")) == 1


def test_md01_debug_lines_and_junk_never_become_positions(rig: Rig) -> None:
    emu = rig.add(
        "sat", model="md01", emu={"start_az_deg": 77, "start_el_deg": 7, "debug_lines": "after"}
    )
    rig.start()
    ready(rig)
    for junk in (b"12: W\x02\x03 fake\r\n", b"\x57\x01\x02", b"garbage\r\n"):
        emu.inject(junk)
    n = len(emu.frames("status"))
    emu.wait_until(lambda d, now: len(d.frames("status")), lambda k: k >= n + 4, 15)
    assert {m.text for m in rig.probe.on("rotor/bearing")} == {"77"}
    assert {m.text for m in rig.probe.on("rotor/elevation")} == {"7"}
