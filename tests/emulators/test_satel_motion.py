"""SatEL motion rules: slews and the after-move report, stop/reset/enable, the misuse rule and
its corruption, stored points driving motion, jogs, front panel and faults.

Fake clock throughout (plain floats passed as `now`): a 45-second slew costs nothing.
"""

from __future__ import annotations

from typing import Any

import pytest

from bridge.emulators.satel import Outcome, SatEL

BYTE_S = 10 / 9600
PROCESSING_S = 0.002


def make(**kwargs: Any) -> SatEL:
    options: dict[str, Any] = {"az_speed_deg_s": 10.0, "el_speed_deg_s": 5.0}
    options.update(kwargs)
    return SatEL(**options)


def enabled(**kwargs: Any) -> SatEL:
    device = make(**kwargs)
    device.receive(b"g", 0.0)
    return device


def lines(data: bytes) -> list[bytes]:
    return data.split(b"\r\n")


# -- slewing and the after-move report --


def test_default_speeds_fit_a_full_slew_inside_hamlibs_60_s_timeout() -> None:
    device = SatEL()
    device.receive(b"gp360 90\r\n", 0.0)
    assert device.next_wakeup(0.0) == pytest.approx(45.0)  # az 8 deg/s; el 4 deg/s -> 22.5 s


def test_p_slews_both_axes_at_their_own_speeds() -> None:
    device = enabled()
    device.receive(b"p100 45\r\n", 1.0)
    assert [f.outcome for f in device.log] == ["motion enabled", "slew"]
    state = device.state(5.0)
    assert state.is_moving and state.slewing and state.driver == "command"
    assert (state.az_deg, state.el_deg) == (pytest.approx(40.0), pytest.approx(20.0))
    assert (state.target_az_deg, state.target_el_deg) == (100.0, 45.0)
    state = device.state(10.5)  # el arrived at 10.0, az still on its way
    assert state.el_deg == 45.0 and state.az_deg == pytest.approx(95.0) and state.slewing
    state = device.state(11.0)
    assert (state.az_deg, state.el_deg, state.is_moving, state.slewing) == (100, 45, False, False)


def test_after_move_report_is_composed_at_the_arrival_instant() -> None:
    device = enabled()
    device.receive(b"p100 45\r\n", 1.0)  # az arrives at 11.0, el at 10.0
    assert device.next_wakeup(2.0) == pytest.approx(11.0)
    assert device.due_output(10.99) == b""
    first_due = 11.0 + PROCESSING_S + BYTE_S
    assert device.next_wakeup(11.0) == pytest.approx(first_due)
    out = device.due_output(60.0)  # read late: still the state at 11.0
    assert lines(out)[:5] == [
        b"Motion ENABLED",
        b"Mode 0 - azimuth break at NORTH",
        b"Time: 2001/00/00 00:00:11",
        b"Azimuth = 100     Absolute = 100",
        b"Elevation = 045",
    ]
    assert [e.kind for e in device.events][-2:] == ["move", "arrived"]
    assert device.events[-1].time_s == pytest.approx(11.0)


def test_p_to_where_the_rotors_are_reports_at_once() -> None:
    device = enabled(start_az_deg=20, start_el_deg=40)
    device.receive(b"p20 40\r\n", 3.0)
    assert not device.state(3.0).slewing
    assert b"Azimuth = 020" in device.due_output(3.5)
    device.receive(b"z", 3.5)  # not a misuse: nothing is slewing
    assert not device.misuse_frames()


def test_p_beyond_the_stops_ends_at_the_stops() -> None:
    device = enabled(az_speed_deg_s=1000.0, el_speed_deg_s=1000.0)
    device.receive(b"p999 120\r", 0.0)
    state = device.state(5.0)
    assert (state.az_deg, state.el_deg) == (360.0, 90.0)
    assert b"Azimuth = 360     Absolute = 360\r\nElevation = 090" in device.due_output(5.0)


def test_p_with_motion_disabled_is_ignored() -> None:
    device = make()
    device.receive(b"p100 45\r\n", 0.0)
    assert device.log[-1].outcome == "ignored: motion disabled"
    assert not device.state(1.0).is_moving
    assert device.due_output(100.0) == b""


# -- stop, reset, enable --


def test_s_during_a_slew_stops_disables_motion_and_the_move_reports() -> None:
    device = enabled()
    device.receive(b"p100 45\r\n", 0.0)
    device.receive(b"s", 4.0)
    state = device.state(10.0)
    assert (state.az_deg, state.el_deg) == (pytest.approx(40.0), pytest.approx(20.0))
    assert not state.is_moving and not state.motion_enabled
    assert device.log[-1].outcome == "stop" and not device.misuse_frames()
    out = device.due_output(10.0)
    assert lines(out)[0] == b"Motion DISABLED" and b"Azimuth = 040" in out
    assert b"Time: 2001/00/00 00:00:04" in out


def test_stop_report_can_be_switched_off() -> None:
    device = enabled(report_on_stop=False)
    device.receive(b"p100 45\r\nS", 0.0)
    assert device.due_output(30.0) == b""
    assert not device.state(30.0).is_moving


def test_s_while_idle_only_disables_motion() -> None:
    device = enabled()
    device.receive(b"s", 1.0)
    assert not device.state(1.0).motion_enabled and device.log[-1].outcome == "stop"
    device.receive(b"p10 10\r", 2.0)
    assert device.log[-1].outcome == "ignored: motion disabled"


def test_reset_during_a_slew_is_allowed_and_resets_everything_but_the_position() -> None:
    device = enabled()
    device.receive(b"t2002/02/14 12:20:30\r2002/03/14 19:45:30 40 60\r", 0.0)
    device.receive(b"p100 45\r\n", 0.0)
    device.receive(b"*", 5.0)
    state = device.state(8.0)
    assert (state.az_deg, state.el_deg) == (pytest.approx(50.0), pytest.approx(25.0))
    assert not state.is_moving and not state.motion_enabled and not state.misuse_count
    assert state.stored_points == () and state.controller_time == "2001/00/00 00:00:03"
    assert device.due_output(100.0) == b""  # the move's report died with the reset
    assert device.log[-1].outcome == "reset"


def test_g_enables_motion_silently() -> None:
    device = make()
    device.receive(b"g", 0.0)
    assert device.state(0.0).motion_enabled and device.due_output(1.0) == b""
    assert device.state(0.0).options["motion_enabled"]


def test_power_cycle_is_a_reset_without_a_logged_frame() -> None:
    device = enabled(start_az_deg=30)
    device.receive(b"p100 45\r", 0.0)
    device.power_cycle(1.0)
    state = device.state(2.0)
    assert not state.motion_enabled and not state.is_moving and state.az_deg == 40.0
    assert [f.outcome for f in device.log] == ["motion enabled", "slew"]
    assert device.events[-1].kind == "power on"


# -- the misuse rule --


def test_lf_after_the_cr_of_a_p_line_is_not_a_misuse() -> None:
    device = enabled()
    device.receive(b"p100 45\r", 0.0)
    device.receive(b"\n", 0.5)  # Hamlib's LF, however late
    assert not device.misuse_frames()
    device.receive(b"\n", 1.0)  # a second one is
    assert [f.data for f in device.misuse_frames()] == [b"\n"]


def test_any_other_byte_while_slewing_is_recorded_as_misuse_and_dropped() -> None:
    device = enabled()
    device.receive(b"p100 45\r\n", 0.0)
    device.receive(b"z?p10 10\r", 2.0)
    misuse = device.misuse_frames()
    assert [f.data for f in misuse] == [bytes([b]) for b in b"z?p10 10\r"]
    assert {f.outcome for f in misuse} == {"misuse: input while slewing"}
    assert all(f.time_s == 2.0 for f in misuse)
    out = device.due_output(11.0)
    assert out.count(b"Motion ENABLED") == 1 and b"SatEL" not in out  # only the after-move report
    state = device.state(11.0)
    assert (state.az_deg, state.el_deg, state.misuse_count) == (100.0, 45.0, 9)
    assert not state.corrupted


def test_misuse_with_corruption_wedges_the_controller_until_reset() -> None:
    device = enabled(corrupt_on_misuse=True)
    device.receive(b"p100 45\r\n", 0.0)
    device.receive(b"z", 3.0)
    state = device.state(20.0)
    assert state.corrupted and not state.motion_enabled and not state.is_moving
    assert (state.az_deg, state.el_deg) == (pytest.approx(30.0), pytest.approx(15.0))
    assert device.due_output(20.0) == b""  # no after-move report, no answer to the z
    device.receive(b"gp100 45\r", 21.0)
    assert [f.outcome for f in device.log[-2:]] == ["ignored: corrupted state"] * 2
    assert device.due_output(21.0) == b""
    device.receive(b"z", 22.0)
    assert lines(device.due_output(23.0))[0] == b"Motion DISABLED"
    device.receive(b"*gp100 45\r", 24.0)
    assert device.state(24.0).slewing and not device.state(24.0).corrupted


def test_jogs_are_not_slews_so_commands_during_them_are_fine() -> None:
    device = make()
    device.receive(b"r", 0.0)
    state = device.state(3.0)
    assert state.az_deg == pytest.approx(30.0) and state.is_moving and not state.slewing
    device.receive(b"zu", 3.0)
    assert b"Azimuth = 030" in device.due_output(4.0)
    device.receive(b"s", 5.0)
    state = device.state(10.0)
    assert state.az_deg == pytest.approx(50.0) and state.el_deg == pytest.approx(10.0)
    assert not state.is_moving and not device.misuse_frames()
    device.receive(b"LD", 10.0)
    assert device.state(100.0).az_deg == 0.0 and device.state(100.0).el_deg == 0.0
    assert [f.outcome for f in device.frames(Outcome.JOG)] == ["jog"] * 4


# -- stored points drive motion --

SET_CLOCK = b"t2002/03/14 19:45:00\r"


def test_a_stored_point_moves_the_rotors_when_its_time_comes() -> None:
    device = enabled()
    device.receive(SET_CLOCK + b"2002/03/14 19:45:30 40 60\r", 10.0)
    assert device.next_wakeup(10.0) == pytest.approx(40.0)
    assert not device.state(39.9).is_moving
    state = device.state(41.0)
    assert state.slewing and state.driver == "ephemeris" and state.stored_points == ()
    assert state.az_deg == pytest.approx(10.0)
    device.receive(b"z", 42.0)  # misuse: an ephemeris move is a slew too
    assert len(device.misuse_frames()) == 1
    state = device.state(60.0)
    assert (state.az_deg, state.el_deg, state.is_moving) == (40.0, 60.0, False)
    assert device.due_output(60.0) == b""  # ephemeris moves end silently


def test_a_due_point_with_motion_disabled_is_consumed_without_moving() -> None:
    device = make()
    device.receive(SET_CLOCK + b"2002/03/14 19:45:30 40 60\r", 0.0)
    state = device.state(31.0)
    assert state.stored_points == () and not state.is_moving and state.az_deg == 0.0
    assert device.events[-1].kind == "point skipped"


def test_setting_the_clock_forward_fires_only_the_latest_due_point() -> None:
    device = enabled()
    device.receive(SET_CLOCK, 0.0)
    device.receive(b"2002/03/14 19:46:00 10 10\r2002/03/14 19:47:00 20 20\r", 0.0)
    device.receive(b"2002/03/14 20:00:00 30 30\r", 0.0)
    device.receive(b"t2002/03/14 19:50:00\r", 1.0)
    state = device.state(1.0)
    assert state.target_az_deg == 20.0 and len(state.stored_points) == 1


def test_a_point_due_during_a_p_slew_waits_for_its_end() -> None:
    device = enabled()
    device.receive(SET_CLOCK + b"2002/03/14 19:45:01 0 0\r", 0.0)
    device.receive(b"p100 0\r", 0.0)  # arrives at 10.0
    assert device.state(5.0).target_az_deg == 100.0
    state = device.state(10.0)
    assert state.driver == "ephemeris" and state.target_az_deg == 0.0
    assert b"Azimuth = 100" in device.due_output(10.5)  # the p's report still came


# -- front panel and faults --


def test_panel_stop_acts_like_s() -> None:
    device = enabled()
    device.receive(b"p100 45\r\n", 0.0)
    assert device.press_brake(2.0)
    assert not device.state(2.0).motion_enabled and b"Azimuth = 020" in device.due_output(3.0)
    assert not device.press_brake(4.0)


def test_manual_rotate_turns_the_rotors_and_ends_a_slew() -> None:
    device = enabled()
    device.manual_rotate(50.0, 0.0, el_deg=10.0)
    state = device.state(1.0)
    assert state.driver == "panel" and state.az_deg == pytest.approx(10.0)
    assert device.state(10.0).az_deg == 50.0 and device.state(10.0).el_deg == 10.0
    with pytest.raises(ValueError):
        device.manual_rotate(361.0, 11.0)


def test_jam_keeps_the_slew_from_ending_and_unjam_resumes_it() -> None:
    device = enabled()
    device.receive(b"p100 45\r\n", 0.0)
    device.jam(2.0)
    assert device.next_wakeup(3.0) is None
    state = device.state(50.0)
    assert state.is_jammed and state.slewing and state.az_deg == pytest.approx(20.0)
    assert device.due_output(50.0) == b""
    device.unjam(50.0)
    assert device.next_wakeup(50.0) == pytest.approx(58.0)
    assert b"Azimuth = 100" in device.due_output(60.0)


def test_time_running_backwards_is_treated_as_now() -> None:
    device = enabled()
    device.receive(b"p100 45\r\n", 5.0)
    assert device.state(1.0).time_s == 5.0
    assert device.state(6.0).az_deg == pytest.approx(10.0)
