"""SatEL end to end: real mosquitto, real pty, the bridge, and the SatEL emulator (written from
the manual) with corrupt_on_misuse=True: any input but a stop during a slew would break it."""

from __future__ import annotations

import json
import re
import time
from datetime import UTC, datetime

from bridge.session.slew import SLEW_STOP_TRIES
from tests.support.rig import Rig


def ready(rig: Rig) -> None:
    rig.probe.wait_value("rotor/availability", "online", timeout_s=15)
    rig.probe.wait_value("rotor/state", "idle", timeout_s=15)


def near(state, az: float, el: float) -> bool:  # noqa: ANN001
    return abs(state.az_deg - az) <= 1 and abs(state.el_deg - el) <= 1 and not state.is_moving


def test_target_slews_and_nothing_is_sent_during_the_slew(rig: Rig) -> None:
    """As built, the rotors going in ten-degree steps (satel.py rule 7): 104/46 is sent as the
    step it reaches, 100/50, and the slew ends there with no error (sent as asked, the rotor
    stopped at 100/40, the report was taken for an old one and the target given up)."""
    built = {"step_deg": 10}
    emu = rig.add("sat", model="satel", emu={"start_az_deg": 10, "start_el_deg": 5, **built})
    rig.start()
    ready(rig)
    snap = rig.retained()
    assert snap["rotor/version"] == b"SatEL"
    assert emu.state().motion_enabled is True  # enabled on connect (and verified)
    t = time.monotonic()  # before the move: its idle may come before the emulator is asked
    rig.probe.publish("rotor/target", '{"azimuth": 104, "elevation": 46}')
    emu.wait_for(lambda s: s.slewing, 5)
    emu.wait_for(lambda s: near(s, 100, 50), 20)
    rig.probe.wait_value("rotor/state", "idle", timeout_s=10, after=t)
    status = json.loads(rig.retained()["rotor/status"])
    assert (status["bearing"], status["elevation"], status["estimated"]) == (100, 50, False)
    assert [f.data for f in emu.frames() if f.data.startswith(b"p")] == [b"p100 50\r"]
    assert status["last_error"] is None
    assert emu.device.misuse_frames() == [] and not emu.state().corrupted


def test_a_new_target_during_a_slew_ends_where_last_asked(rig: Rig) -> None:
    emu = rig.add("sat", model="satel", emu={"start_az_deg": 0, "start_el_deg": 0})
    rig.start()
    ready(rig)
    rig.probe.publish("rotor/target", "300 60")
    emu.wait_for(lambda s: s.slewing and s.az_deg > 20, 10)
    rig.probe.publish("rotor/target", "100 20")
    emu.wait_for(lambda s: near(s, 100, 20), 30)
    assert emu.device.misuse_frames() == [] and not emu.state().corrupted
    first_slew = emu.frames("slew")[0].time_s
    stops = [f for f in emu.frames("stop") if f.time_s > first_slew]
    assert [f.data for f in stops] == [b"s"]  # stopped the slew once, then redirected


def test_the_bearing_is_estimated_during_the_slew(rig: Rig) -> None:
    emu = rig.add(
        "sat",
        model="satel",
        emu={"start_az_deg": 0, "start_el_deg": 0, "az_speed_deg_s": 8, "el_speed_deg_s": 4},
    )
    rig.start()
    ready(rig)
    t = time.monotonic()
    rig.probe.publish("rotor/target", "80 40")
    est = rig.probe.wait_for(
        "rotor/status",
        lambda m: json.loads(m.payload)["estimated"] and 0 < json.loads(m.payload)["bearing"] < 80,
        timeout_s=10,
        after=t,
    )
    assert json.loads(est.payload)["state"] == "moving"
    emu.wait_for(lambda s: near(s, 80, 40), 30)
    final = rig.probe.wait_for(
        "rotor/status",
        lambda m: not json.loads(m.payload)["estimated"] and json.loads(m.payload)["bearing"] == 80,
        timeout_s=10,
        after=t,
    )
    assert json.loads(final.payload)["elevation"] == 40
    assert emu.device.misuse_frames() == []


def test_motion_is_enabled_again_after_a_controller_reset(rig: Rig) -> None:
    emu = rig.add("sat", model="satel")
    rig.start()
    ready(rig)
    emu.power_cycle()  # like '*': automatic motion off
    emu.wait_for(lambda s: s.motion_enabled is False, 5)
    emu.wait_for(lambda s: s.motion_enabled is True, 10)
    rig.probe.publish("rotor/target", "50 10")
    emu.wait_for(lambda s: near(s, 50, 10), 20)


def test_the_controller_clock_is_set_from_the_host(rig: Rig) -> None:
    emu = rig.add("sat", model="satel")
    rig.start()
    ready(rig)
    clock = emu.state().controller_time
    host = datetime.now(UTC).replace(tzinfo=None)
    assert abs((datetime.strptime(clock, "%Y/%m/%d %H:%M:%S") - host).total_seconds()) < 10
    status = json.loads(rig.retained()["rotor/status"])
    shown = datetime.strptime(status["controller_time"], "%Y/%m/%d %H:%M:%S")
    assert abs((shown - host).total_seconds()) < 10  # (not the date alone: midnight passes)


def test_junk_in_the_status_report_is_never_a_position(rig: Rig) -> None:
    emu = rig.add("sat", model="satel", emu={"start_az_deg": 33, "start_el_deg": 3})
    rig.start()
    ready(rig)
    for junk in (
        b"Azimuth = 999\r\n",
        b"Motion ENABLED\r\nAzimuth = 1x2\r\n",
        b"\xff\xfe\r\n",
        b"Elevation = 077\r\nNumber of stored positions: 00\r\n",
    ):
        emu.inject(junk)
    n = len(emu.frames("status"))
    emu.wait_until(lambda d, now: len(d.frames("status")), lambda k: k >= n + 3, 15)
    assert {m.text for m in rig.probe.on("rotor/bearing")} == {"33"}
    assert {m.text for m in rig.probe.on("rotor/elevation")} == {"3"}


def test_unplug_and_replug(rig: Rig) -> None:
    emu = rig.add("sat", model="satel", emu={"start_az_deg": 20, "start_el_deg": 2})
    rig.start()
    ready(rig)
    rig.unplug_and_replug("sat")
    rig.probe.publish("rotor/target", "60 30")
    emu.wait_for(lambda s: near(s, 60, 30), 20)
    assert emu.device.misuse_frames() == []


def test_a_satel_power_cycled_mid_slew_is_told_and_not_sent_its_point_again(rig: Rig) -> None:
    # the bridge takes the rotor for 8 times faster than it is: the wait for the report is short
    emu = rig.add(
        "sat",
        model="satel",
        emu={"start_az_deg": 0, "start_el_deg": 0, "az_speed_deg_s": 8, "el_speed_deg_s": 4},
        az_speed_deg_s=64,
        el_speed_deg_s=32,
    )
    rig.start()
    ready(rig)
    t = time.monotonic()
    rig.probe.publish("rotor/target", "40 10")
    emu.wait_for(lambda s: s.slewing and s.az_deg > 4, 10)
    emu.power_cycle()  # its report never comes, and its clock starts again at 2001/00/00
    stood = emu.state()
    err = rig.probe.wait_for("rotor/error", lambda m: b"mid-turn" in m.payload, 30, after=t)
    message = json.loads(err.payload)["message"]
    said = re.fullmatch(
        r"the controller restarted mid-turn \(its clock went back, to 2001/00/00 00:00:\d\d\) "
        r"at (\d+)°, elevation (\d+)°: its turn to 40°, elevation 10° was not resumed: send the "
        "target again",
        message,
    )
    assert said, message
    assert abs(int(said[1]) - stood.az_deg) <= 1 and abs(int(said[2]) - stood.el_deg) <= 1
    emu.wait_for(lambda s: s.motion_enabled, 10)  # (switched on again: nothing more is owed)
    status = rig.probe.wait_for(
        "rotor/status", lambda m: json.loads(m.payload)["last_error"] == message, 10, after=t
    )
    assert json.loads(status.payload)["target"] is None
    sent = [f.data for f in emu.frames() if f.time_s > stood.time_s and f.data != b"z"]
    assert sent == [b"s"] * SLEW_STOP_TRIES + [b"g"]  # stopped, asked: never the point again
    assert [f.data for f in emu.frames("slew")] == [b"p40 10\r"]
    assert near(emu.state(), stood.az_deg, stood.el_deg)
    assert emu.device.misuse_frames() == []
