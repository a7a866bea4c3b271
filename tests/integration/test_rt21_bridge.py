"""Green Heron RT-21 end to end: real mosquitto, real pyserial on a pty, the bridge, and the RT-21
emulator (written from the documents and judged by Hamlib's rotctl -m 405) as the controller."""

from __future__ import annotations

import json
import time

from tests.support.rig import Rig


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
