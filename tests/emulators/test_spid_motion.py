"""SPID motion, MD-01 move and debug lines, front panel and faults, with a fake clock (floats)."""

from __future__ import annotations

from typing import Any

import pytest

from bridge.emulators.base import RotatorState
from bridge.emulators.spid import MOTION_OUTCOMES, Outcome, Spid, SpidState

STATUS = bytes.fromhex("57 00 00 00 00 00 00 00 00 00 00 1F 20")
STOP = bytes.fromhex("57 00 00 00 00 00 00 00 00 00 00 0F 20")


def set_frame(h_pulses: int, v_pulses: int, ppd: int = 2) -> bytes:
    """A set command as spid.md section 3 lays it out (ASCII pulse counts, thousands first)."""
    return b"W%04d%c%04d%c\x2f " % (h_pulses, ppd, v_pulses, ppd)


def move_frame(direction: int) -> bytes:
    """Hamlib 4.5.4's move: H1 = direction, PH/PV uninitialised (0x7F/0x7E seen on the wire)."""
    return bytes([0x57, direction, 0, 0, 0, 0x7F, 0, 0, 0, 0, 0x7E, 0x14, 0x20])


def make(model: str = "rot2prog", **kwargs: Any) -> Spid:
    return Spid(model, **kwargs)


def position(device: Spid, at: float) -> tuple[float, float | None]:
    state = device.state(at)
    return state.az_deg, state.el_deg


# -- az and el together --


def test_default_speeds_are_one_degree_az_and_half_a_degree_el_per_second() -> None:
    device = make()
    device.receive(set_frame(740, 740), 0.0)  # az 10, el 10
    assert position(device, 4.0) == (pytest.approx(4.0), pytest.approx(2.0))
    assert position(device, 10.0) == (10.0, pytest.approx(5.0))
    assert device.state(10.0).is_moving  # elevation still on its way
    assert position(device, 20.0) == (10.0, 10.0)
    assert not device.state(20.0).is_moving
    arrivals = [(e.time_s, e.detail) for e in device.events if e.kind == "arrived"]
    assert arrivals == [(10.0, "az at 10"), (20.0, "el at 10")]


def test_speeds_are_configurable() -> None:
    device = make(az_speed_deg_s=6.0, el_speed_deg_s=3.0)
    device.receive(set_frame(2 * 420, 2 * 390), 0.0)  # az 60, el 30
    assert position(device, 5.0) == (pytest.approx(30.0), pytest.approx(15.0))
    assert position(device, 10.0) == (60.0, 30.0)


def test_state_is_a_rotator_state_with_the_elevation_targets() -> None:
    device = make()
    device.receive(set_frame(740, 760), 0.0)
    state = device.state(1.0)
    assert isinstance(state, RotatorState) and isinstance(state, SpidState)
    assert (state.target_az_deg, state.target_el_deg, state.driver) == (10.0, 20.0, "command")
    assert not state.in_brake_delay and state.resolution_ppd == 2


def test_a_new_set_while_moving_re_targets_at_once() -> None:
    device = make(az_speed_deg_s=10.0, el_speed_deg_s=10.0)
    device.receive(set_frame(2 * 460, 2 * 410), 0.0)  # az 100, el 50
    device.receive(set_frame(2 * 340, 2 * 370), 3.0)  # az -20, el 10: turn round, no stop
    assert position(device, 3.0) == (pytest.approx(30.0), pytest.approx(30.0))
    assert position(device, 4.0) == (pytest.approx(20.0), pytest.approx(20.0))
    assert position(device, 10.0) == (-20.0, 10.0)
    assert [f.outcome for f in device.log] == ["set", "set"]
    assert not [e for e in device.events if e.kind == "stopped"]


def test_status_while_moving_reports_the_position_on_the_resolution_grid() -> None:
    device = make(az_speed_deg_s=1.0, el_speed_deg_s=0.1)
    device.receive(set_frame(2 * 460, 2 * 460), 0.0)
    device.receive(STATUS, 4.3)  # true az 4.3, el 0.43
    assert device.reported_position(4.3) == (4.5, 0.5)
    assert device.due_output(5.0) == bytes.fromhex("57 03 06 04 05 02 03 06 00 05 02 20")


def test_stop_halts_both_axes_and_answers_the_exact_stopped_position() -> None:
    device = make(az_speed_deg_s=2.0, el_speed_deg_s=1.0)
    device.receive(set_frame(2 * 460, 2 * 410), 0.0)
    device.receive(STOP, 5.0)
    assert device.due_output(6.0) == bytes.fromhex("57 03 07 00 00 02 03 06 05 00 02 20")
    state = device.state(100.0)
    assert not state.is_moving and (state.az_deg, state.el_deg) == (10.0, 5.0)
    assert device.log[-1].outcome == "stop"


def test_stop_while_idle_still_answers() -> None:
    device = make(start_az_deg=1.0)
    device.receive(STOP, 0.0)
    assert len(device.due_output(1.0)) == 12


def test_a_reply_reflects_the_instant_its_frame_completed() -> None:
    device = make(az_speed_deg_s=10.0)
    device.receive(set_frame(2 * 460, 720), 0.0)
    device.receive(STATUS, 1.0)
    assert device.due_output(3.0)[1:5] == bytes([3, 7, 0, 0])  # 10.0, though it is 30 by now


def test_rot1prog_moves_azimuth_only() -> None:
    device = make("rot1prog", az_speed_deg_s=5.0)
    device.receive(b"W4000\x00\x00\x00\x00\x00\x00\x2f ", 0.0)  # 400 - 360 = 40
    state = device.state(4.0)
    assert state.az_deg == pytest.approx(20.0) and state.el_deg is None
    assert state.target_el_deg is None


# -- coasting (rule 11) --


def test_a_coasting_rotor_answers_the_stop_with_where_it_was_then_and_rests_further_on() -> None:
    device = make(az_speed_deg_s=2.0, el_speed_deg_s=1.0, coast_deg=1.5, coast_s=1.0)
    device.receive(set_frame(2 * 460, 2 * 410), 0.0)  # az 100, el 50
    device.receive(STOP, 5.0)  # at az 10, el 5
    assert position(device, 5.5) == (pytest.approx(11.125), pytest.approx(6.125))
    assert device.state(5.5).is_moving and device.state(5.5).target_az_deg is None
    device.receive(STATUS, 5.5)  # mid-coast: 11.125 / 6.125 on the half-degree grid
    assert device.due_output(6.5) == bytes.fromhex(
        "57 03 07 00 00 02 03 06 05 00 02 20"  # the stop's: az 10, el 5
        "57 03 07 01 00 02 03 06 06 00 02 20"  # the status's: az 11, el 6
    )
    assert position(device, 6.0) == (11.5, 6.5) and not device.state(6.0).is_moving
    device.receive(STATUS, 100.0)
    assert device.due_output(101.0) == bytes.fromhex("57 03 07 01 05 02 03 06 06 05 02 20")
    coasted = [(e.time_s, e.detail) for e in device.events if e.kind == "coasted"]
    assert coasted == [(6.0, "az at rest at 11.5"), (6.0, "el at rest at 6.5")]
    assert device.next_wakeup(100.0) is None


def test_a_coast_follows_the_turn_down_and_a_second_stop_answers_the_coast_position() -> None:
    device = make(az_speed_deg_s=2.0, start_az_deg=50.0, start_el_deg=20.0, coast_deg=2.0)
    device.receive(set_frame(2 * 360, 2 * 370), 0.0)  # az 0, el 10: both turn down
    device.receive(STOP, 5.0)  # az 40, el 17.5
    assert len(device.due_output(5.3)) == 12
    assert device.next_wakeup(5.3) == pytest.approx(5.8)  # at rest then: coast_s is 0.8
    device.receive(STOP, 5.4)  # half-way in time, 3/4 of the way
    assert device.reported_position(5.4) == (38.5, 16.0)
    assert device.due_output(7.0) == bytes.fromhex("57 03 09 08 05 02 03 07 06 00 02 20")
    assert position(device, 10.0) == (38.0, 15.5)
    assert [f.outcome for f in device.log] == ["set", "stop", "stop"]


def test_a_set_during_a_coast_starts_from_where_the_rotor_is() -> None:
    device = make(az_speed_deg_s=2.0, coast_deg=2.0, coast_s=1.0)
    device.receive(set_frame(2 * 460, 720), 0.0)  # az 100
    device.receive(STOP, 5.0)  # az 10
    device.receive(set_frame(2 * 360, 720), 5.5)  # az 0: from 11.5, back down
    assert position(device, 6.5) == (pytest.approx(9.5), 0.0)
    assert position(device, 20.0) == (0.0, 0.0)
    assert not [e for e in device.events if e.kind == "coasted"]


def test_the_panel_stop_and_an_md01_move_leaving_an_axis_out_coast_too() -> None:
    device = make(coast_deg=1.0, coast_s=0.5)
    device.receive(set_frame(2 * 460, 720), 0.0)
    device.press_brake(4.0)
    assert position(device, 10.0) == (5.0, 0.0)
    md01 = make("md01", start_az_deg=100.0, start_el_deg=45.0, coast_deg=1.0, coast_s=0.5)
    md01.receive(move_frame(0x06), 0.0)  # right and up
    md01.receive(move_frame(0x04), 10.0)  # up only: the azimuth's motor is cut
    assert position(md01, 20.0) == (pytest.approx(111.0), pytest.approx(55.0))


def test_without_coast_deg_a_stop_is_dead_and_a_jammed_rotor_never_coasts() -> None:
    device = make(az_speed_deg_s=2.0)
    device.receive(set_frame(2 * 460, 720), 0.0)
    device.receive(STOP, 5.0)
    assert not device.state(5.0).is_moving and position(device, 10.0) == (10.0, 0.0)
    jammed = make(az_speed_deg_s=2.0, coast_deg=2.0)
    jammed.receive(set_frame(2 * 460, 720), 0.0)
    jammed.jam(5.0)
    jammed.receive(STOP, 6.0)
    assert not jammed.state(6.0).is_moving and position(jammed, 10.0) == (10.0, 0.0)


# -- limits --


def test_a_target_beyond_the_limits_is_clamped_and_logged_so() -> None:
    device = make(az_speed_deg_s=1000.0, el_speed_deg_s=1000.0)
    device.receive(set_frame(9999, 9999), 0.0)  # 4639.5 deg both ways
    assert device.log[-1].outcome == "set: clamped"
    assert position(device, 5.0) == (540.0, 210.0)
    device.receive(set_frame(0, 0), 5.0)  # -360 deg
    assert position(device, 10.0) == (-180.0, -20.0)


def test_limits_can_be_narrowed() -> None:
    device = make(az_min_deg=0.0, az_max_deg=450.0, el_min_deg=0.0, el_max_deg=90.0)
    device.receive(set_frame(2 * 860, 2 * 370), 0.0)  # az 500, el 10
    assert device.state(0.0).target_az_deg == 450.0 and device.state(0.0).target_el_deg == 10.0
    assert device.frames(Outcome.SET_CLAMPED)
    assert set(MOTION_OUTCOMES) == {"set", "set: clamped", "move"}


@pytest.mark.parametrize(
    "kwargs",
    [
        {"az_min_deg": -400.0},
        {"el_max_deg": 700.0},
        {"start_az_deg": 600.0},
        {"model": "rot1prog", "start_el_deg": 5.0},
        {"model": "rot1prog", "el_max_deg": 90.0},
        {"model": "nope"},
        {"debug_lines": "sometimes"},
        {"debug_lines": "before"},  # a Rot2Prog prints no debug lines
        {"coast_deg": -1.0},
        {"coast_deg": 1.0, "coast_s": 0.0},
    ],
)
def test_bad_configuration_is_refused(kwargs: dict[str, Any]) -> None:
    with pytest.raises(ValueError):
        make(**kwargs)


# -- MD-01 move --


def test_md01_move_right_runs_until_stop() -> None:
    device = make("md01", start_az_deg=100.0)
    assert device.due_output(0.0) == b""
    device.receive(move_frame(0x02), 0.0)
    assert device.due_output(1.0) == b""  # Hamlib reads nothing after a move
    assert device.log[-1].outcome == "move"
    assert position(device, 30.0) == (pytest.approx(130.0), 0.0)
    device.receive(STOP, 30.0)
    assert len(device.due_output(31.0)) == 12
    assert position(device, 100.0) == (pytest.approx(130.0), 0.0)


@pytest.mark.parametrize(
    ("direction", "az_deg", "el_deg"),
    [(0x01, 90.0, 45.0), (0x02, 110.0, 45.0), (0x04, 100.0, 50.0), (0x08, 100.0, 40.0)]
    + [(0x05, 90.0, 50.0), (0x06, 110.0, 50.0), (0x09, 90.0, 40.0), (0x0A, 110.0, 40.0)],
)
def test_md01_move_directions(direction: int, az_deg: float, el_deg: float) -> None:
    device = make("md01", start_az_deg=100.0, start_el_deg=45.0, el_speed_deg_s=0.5)
    device.receive(move_frame(direction), 0.0)
    assert position(device, 10.0) == (pytest.approx(az_deg), pytest.approx(el_deg))


def test_md01_move_ends_at_the_limit() -> None:
    device = make("md01", start_az_deg=530.0, az_speed_deg_s=10.0)
    device.receive(move_frame(0x02), 0.0)
    assert position(device, 5.0) == (540.0, 0.0) and not device.state(5.0).is_moving


def test_md01_move_replaces_the_motion_an_axis_not_named_stops() -> None:
    device = make("md01", start_az_deg=100.0, start_el_deg=45.0)
    device.receive(move_frame(0x02), 0.0)
    device.receive(move_frame(0x04), 10.0)  # up only: azimuth stops
    assert position(device, 20.0) == (pytest.approx(110.0), pytest.approx(50.0))


def test_md01_a_set_after_a_move_re_targets() -> None:
    device = make("md01", start_az_deg=100.0, az_speed_deg_s=10.0, el_speed_deg_s=10.0)
    device.receive(move_frame(0x01), 0.0)
    device.receive(set_frame(2 * 460, 2 * 380), 1.0)  # az 100, el 20
    assert position(device, 10.0) == (100.0, 20.0)


@pytest.mark.parametrize("direction", [0x00, 0x03, 0x0C, 0x0F, 0x10, 0x32])
def test_md01_nonsense_directions_are_invalid(direction: int) -> None:
    device = make("md01", start_az_deg=100.0)
    device.receive(move_frame(direction), 0.0)
    assert device.log[-1].outcome == "invalid" and not device.state(1.0).is_moving


# -- MD-01 debug lines --


@pytest.mark.parametrize("where", ["before", "after"])
def test_md01_debug_lines_fall_between_frames(where: str) -> None:
    device = make("md01", debug_lines=where, now=100.0)
    assert device.due_output(100.0) == b""  # nothing at power-on
    device.receive(STATUS, 101.5)
    out = device.due_output(102.0)
    line, frame = b"1500: cmd status\r\n", bytes.fromhex("57 03 06 00 00 02 03 06 00 00 02 20")
    assert out == (line + frame if where == "before" else frame + line)


def test_md01_debug_line_on_request_waits_for_the_frame_in_flight() -> None:
    device = make("md01", baud=600, now=0.0)
    device.receive(STATUS, 1.0)
    partial = device.due_output(1.1)
    assert 0 < len(partial) < 12
    line = device.emit_debug_line(1.1, "az motor current 1.2 A")
    assert line == b"1100: az motor current 1.2 A\r\n"
    rest = device.due_output(5.0)
    assert (partial + rest)[12:] == line


def test_md01_debug_line_digits_restart_at_power_on() -> None:
    device = make("md01", now=10.0)
    device.power_cycle(20.0)
    assert device.emit_debug_line(20.25) == b"250: debug\r\n"


def test_only_the_md01_prints_debug_lines() -> None:
    with pytest.raises(ValueError, match="debug"):
        make("rot2prog").emit_debug_line(0.0)
    with pytest.raises(ValueError, match="CR or LF"):
        make("md01").emit_debug_line(0.0, "two\r\nlines")


# -- front panel and faults --


def test_panel_stop_halts_both_axes() -> None:
    device = make()
    assert not device.press_brake(0.0)
    device.receive(set_frame(740, 740), 0.0)
    assert device.press_brake(4.0)
    assert position(device, 50.0) == (pytest.approx(4.0), pytest.approx(2.0))


def test_manual_rotate_turns_az_and_optionally_el() -> None:
    device = make(az_speed_deg_s=10.0, el_speed_deg_s=10.0)
    device.manual_rotate(-50.0, 0.0, el_deg=30.0)
    assert device.state(1.0).driver == "panel"
    assert position(device, 10.0) == (-50.0, 30.0)
    assert device.reported_position(10.0) == (-50.0, 30.0)
    with pytest.raises(ValueError):
        device.manual_rotate(600.0, 10.0)
    with pytest.raises(ValueError):
        make("rot1prog").manual_rotate(10.0, 0.0, el_deg=5.0)


def test_jam_keeps_the_motors_running_but_nothing_turns_then_unjam_resumes() -> None:
    device = make(az_speed_deg_s=1.0, el_speed_deg_s=1.0)
    device.receive(set_frame(740, 740), 0.0)
    device.jam(2.0)
    state = device.state(8.0)
    assert state.is_jammed and state.is_moving and (state.az_deg, state.el_deg) == (2.0, 2.0)
    device.receive(STATUS, 8.0)
    assert device.due_output(9.0)[1:5] == bytes([3, 6, 2, 0])  # the reading is stuck at 2.0
    device.unjam(9.0)
    assert position(device, 13.0) == (6.0, 6.0)
    assert position(device, 17.0) == (10.0, 10.0)


def test_power_cycle_stops_the_motors_drops_half_frames_and_unsent_bytes() -> None:
    device = make(az_speed_deg_s=1.0)
    device.receive(set_frame(740, 720), 0.0)
    device.receive(STATUS + STATUS[:5], 3.0)
    device.power_cycle(3.05)  # the reply was 3 bytes into the line
    assert device.due_output(10.0) == b""
    assert position(device, 10.0) == (pytest.approx(3.05), 0.0)
    device.receive(STATUS, 10.0)
    assert len(device.due_output(11.0)) == 12
    assert [f.outcome for f in device.log] == ["set", "status", "status"]


def test_time_never_runs_backwards() -> None:
    device = make(az_speed_deg_s=1.0)
    device.receive(set_frame(740, 720), 0.0)
    assert position(device, 5.0)[0] == pytest.approx(5.0)
    assert position(device, 1.0)[0] == pytest.approx(5.0)
    device.receive(STATUS, 2.0)
    assert device.log[-1].time_s == 5.0


def test_next_wakeup_covers_replies_and_arrivals() -> None:
    device = make(az_speed_deg_s=1.0, el_speed_deg_s=1.0)
    assert device.next_wakeup(0.0) is None
    device.receive(set_frame(740, 724), 0.0)  # el arrives at 2 s, az at 10 s
    assert device.next_wakeup(0.0) == pytest.approx(2.0)
    assert device.next_wakeup(3.0) == pytest.approx(10.0)
