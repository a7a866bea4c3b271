"""Rotor-EZ family motion rules: execute, re-target, brake delay, jitter, front panel, faults.

Fake clock throughout (plain floats passed as `now`): a five-second brake delay costs nothing.
"""

from __future__ import annotations

from typing import Any

import pytest

from bridge.emulators import as_built
from bridge.emulators.rotorez import BEARING_OUTCOMES, Outcome, RotorEZ


def make(model: str = "rotorez", **kwargs: Any) -> RotorEZ:
    options: dict[str, Any] = {"power_on_junk": False, "jitter_deg": 0, "speed_deg_s": 6.0}
    options.update(kwargs)
    return RotorEZ(model, **options)


def reading(device: RotorEZ, at: float) -> bytes:
    device.receive(b"AI1;", at)
    return device.due_output(at + 0.05)


# -- executing a bearing --


def test_ap1_with_cr_stores_and_executes() -> None:
    device = make()
    device.receive(b"AP1200\r", 0.0)
    assert device.is_moving(0.0)
    assert device.true_az_deg(10.0) == pytest.approx(60.0)
    assert reading(device, 10.0) == b";060"
    assert device.true_az_deg(40.0) == 200.0 and not device.is_moving(40.0)
    assert [f.outcome for f in device.log] == ["executed", "query"]


def test_ap1_with_semicolon_only_stores_and_am1_executes() -> None:
    device = make()
    device.receive(b"AP1200;", 0.0)
    assert not device.is_moving(10.0)
    assert device.state(10.0).stored_target_az_deg == 200.0
    device.receive(b"AM1;", 10.0)
    assert device.true_az_deg(20.0) == pytest.approx(60.0)
    assert [f.outcome for f in device.log] == ["stored", "executed"]


def test_am1_without_a_stored_target_does_nothing() -> None:
    device = make(start_az_deg=90)
    device.receive(b"AM1;", 0.0)
    assert device.log[-1].outcome == "ignored: no stored target"
    assert not device.is_moving(1.0) and device.true_az_deg(1.0) == 90


def test_bearing_000_and_360_are_the_two_ends_of_travel() -> None:
    device = make(start_az_deg=180, speed_deg_s=100.0)
    device.receive(b"AP1360\r", 0.0)  # arrives at 1.8 s, brake delay until 6.8 s
    assert device.true_az_deg(3.0) == 360.0
    device.receive(b"AP1000\r", 3.0)
    assert device.log[-1].outcome == "ignored: brake delay"
    device.receive(b"AP1000\r", 20.0)
    assert device.true_az_deg(30.0) == 0.0


def test_ten_to_350_goes_the_long_way_through_south() -> None:
    device = make(start_az_deg=10, speed_deg_s=10.0)
    device.receive(b"AP1350\r", 0.0)
    assert reading(device, 17.0) == b";180"


# -- a Hy-Gain rotor's travel, its stop at south (rule 12) --


@pytest.mark.parametrize("model", ["rotorez", "dcu1"])
def test_a_hy_gain_rotor_turns_350_to_10_across_north(model: str) -> None:
    device = make(model, start_az_deg=350, speed_deg_s=10.0, stop_at_south=True)
    device.receive(b"AP1010;AM1;", 0.0)  # (the DCU-1's one way to turn it)
    assert device.true_az_deg(1.0) == pytest.approx(0.0)  # 20 degrees, through north
    assert device.true_az_deg(1.5) == pytest.approx(5.0)
    assert device.true_az_deg(3.0) == 10.0 and not device.is_moving(3.0)
    assert [e.kind for e in device.events][-2:] == ["move", "arrived"]


def test_a_hy_gain_rotor_turns_170_to_190_the_long_way_through_north() -> None:
    device = make(start_az_deg=170, speed_deg_s=10.0, stop_at_south=True)
    device.receive(b"AP1190\r", 0.0)
    assert reading(device, 17.0) == b";000"  # never through south, where its stop is
    assert device.true_az_deg(40.0) == 190.0


def test_readings_of_a_hy_gain_rotor_cross_north_as_a_compass_reads() -> None:
    device = make(start_az_deg=10, speed_deg_s=1.0, stop_at_south=True)
    device.receive(b"AP1350\r", 0.0)
    assert [reading(device, t) for t in (9.0, 10.0, 11.0)] == [b";001", b";000", b";359"]
    assert device.state(12.0).az_deg == pytest.approx(358.0)
    assert device.state(12.0).target_az_deg == 350.0


@pytest.mark.parametrize(("start", "via"), [(90.0, 135.0), (270.0, 225.0)])
def test_180_on_a_hy_gain_rotor_is_the_end_nearer_the_rotor(start: float, via: float) -> None:
    device = make(start_az_deg=start, speed_deg_s=10.0, stop_at_south=True)
    device.receive(b"AP1180\r", 0.0)
    assert device.true_az_deg(4.5) == pytest.approx(via)  # 90 degrees to the stop, not 270
    assert device.true_az_deg(10.0) == 180.0 and not device.is_moving(10.0)


def test_the_panel_turns_a_hy_gain_rotor_across_north() -> None:
    device = make(start_az_deg=5, speed_deg_s=10.0, stop_at_south=True)
    device.manual_rotate(355.0, 0.0)
    assert device.true_az_deg(0.5) == pytest.approx(0.0)
    assert device.true_az_deg(2.0) == 355.0


@pytest.mark.parametrize(("start", "readings"), [(170.0, b";180;179"), (190.0, b";180;181")])
def test_a_hy_gain_rotor_at_its_stop_jitters_inside_its_travel(
    start: float, readings: bytes
) -> None:
    """At either end (come to 180 from the east, 170, or from the west, 190) the second reading
    of the pair is a degree inside the travel, never past the stop on the other end's side."""
    device = make(start_az_deg=start, speed_deg_s=10.0, jitter_deg=1, stop_at_south=True)
    device.receive(b"AP1180\r", 0.0)
    assert reading(device, 5.0) + reading(device, 6.0) == readings


@pytest.mark.parametrize(("model", "reads"), [("rotorcard", b";180"), ("rotorez", b";010")])
def test_each_model_as_built_turns_350_to_10_its_own_way(model: str, reads: bytes) -> None:
    """emulators rule 3: a RotorCard's Yaesu rotor stops at north, so 350 to 10 goes round
    through south; a Rotor-EZ's Hy-Gain rotor turns 20 degrees across north."""
    device = make(model, start_az_deg=350, speed_deg_s=10.0, **as_built(model))
    device.receive(b"AP1010\r", 0.0)
    assert reading(device, 17.0) == reads


def test_turning_reading_follows_the_true_position_even_with_jitter() -> None:
    device = make(jitter_deg=3, speed_deg_s=1.0)
    device.receive(b"AP1100\r", 0.0)
    assert [reading(device, t) for t in (10.0, 11.0, 12.0, 13.0)] == [
        b";010",
        b";011",
        b";012",
        b";013",
    ]


# -- re-target while turning (Idiom FAQ) --


def test_new_bearing_while_turning_stops_the_rotor_and_is_not_obeyed() -> None:
    device = make()
    device.receive(b"AP1300\r", 0.0)
    device.receive(b"AP1100\r", 5.0)
    state = device.state(5.0)
    assert not state.is_moving and state.az_deg == pytest.approx(30.0)
    assert state.in_brake_delay and state.brake_delay_ends_s == pytest.approx(10.0)
    assert device.true_az_deg(60.0) == pytest.approx(30.0)  # never turns to 100 (nor to 300)
    assert device.log[-1].outcome == "ignored: re-target while turning (stopped)"


def test_hamlib_style_retarget_stops_then_its_am1_hits_the_brake_delay() -> None:
    device = make()
    device.receive(b"AP1300;", 0.0)
    device.receive(b"AM1;", 0.5)
    device.receive(b"AP1100;", 5.5)  # Hamlib's next set_position
    device.receive(b"AM1;", 6.0)
    outcomes = [(f.data, f.outcome) for f in device.log]
    assert outcomes == [
        (b"AP1300;", "stored"),
        (b"AM1;", "executed"),
        (b"AP1100;", "ignored: re-target while turning (stopped)"),
        (b"AM1;", "ignored: brake delay"),
    ]
    assert device.state(20.0).stored_target_az_deg == 300.0  # the ignored bearing was not stored
    assert device.true_az_deg(20.0) == pytest.approx(30.0)
    assert device.bearing_frames_in_brake_delay() == [device.log[3]]


def test_retarget_with_am1_alone_also_stops() -> None:
    device = make()
    device.receive(b"AP1300;AM1;", 0.0)
    device.receive(b"AM1;", 1.0)
    assert not device.is_moving(1.0)
    assert device.log[-1].outcome == Outcome.IGNORED_RETARGET


def test_rotorcard_retarget_stops_too_but_has_no_brake_delay() -> None:
    device = make("rotorcard")
    device.receive(b"AP1300\r", 0.0)
    device.receive(b"AP1100\r", 5.0)
    assert not device.is_moving(5.0) and not device.in_brake_delay(5.0)
    device.receive(b"AP1100\r", 5.0)
    assert device.log[-1].outcome == "executed"
    assert device.true_az_deg(7.0) == pytest.approx(42.0)  # from 30 towards 100


# -- brake delay --


def test_brake_delay_runs_from_the_exact_arrival_instant() -> None:
    device = make(start_az_deg=0, speed_deg_s=10.0)
    device.receive(b"AP1050\r", 0.0)  # arrives at 5.0 s; nobody asks until 9.9 s
    device.receive(b"AP1100\r", 9.9)
    assert device.log[-1].outcome == "ignored: brake delay"
    assert device.true_az_deg(9.9) == 50.0
    device.receive(b"AP1100\r", 10.0)
    assert device.log[-1].outcome == "executed"
    kinds = [(e.kind, e.time_s) for e in device.events if e.kind != "power on"]
    assert kinds[:3] == [("move", 0.0), ("arrived", 5.0), ("brake set", 10.0)]


@pytest.mark.parametrize("brake_delay_s", [0.0, 2.0, 5.0])
def test_brake_delay_length_is_configurable(brake_delay_s: float) -> None:
    device = make(brake_delay_s=brake_delay_s, speed_deg_s=100.0)
    device.receive(b"AP1010\r", 0.0)  # arrives at 0.1 s
    device.receive(b"AP1020\r", 0.1 + brake_delay_s)
    assert device.log[-1].outcome == "executed"
    if brake_delay_s:
        device.power_cycle(50.0)
        device.receive(b"AP1030\r", 50.0)
        device.receive(b"AP1040\r", 50.1 + brake_delay_s - 0.01)
        assert device.log[-1].outcome == "ignored: brake delay"


def test_rotorcard_has_no_brake_delay() -> None:
    device = make("rotorcard", speed_deg_s=100.0)
    device.receive(b"AP1010\r", 0.0)
    device.receive(b"AP1020\r", 0.1)
    assert device.log[-1].outcome == "executed"
    assert not device.in_brake_delay(0.1)


def test_serial_stop_is_silent_and_starts_the_brake_delay() -> None:
    device = make()
    device.receive(b"AP1300\r", 0.0)
    device.receive(b";", 2.0)
    assert device.due_output(3.0) == b""
    assert device.log[-1].outcome == "stop"
    assert device.in_brake_delay(6.9) and not device.in_brake_delay(7.0)
    assert device.true_az_deg(100.0) == pytest.approx(12.0)


def test_semicolon_during_the_brake_delay_is_invalid() -> None:
    device = make()
    device.receive(b"AP1300\r", 0.0)
    device.receive(b";", 2.0)
    device.receive(b";", 3.0)
    assert device.due_output(4.0) == b"C2000 IDIOM V1.4S "
    assert device.log[-1].outcome == "invalid"


def test_queries_and_options_work_during_the_brake_delay() -> None:
    device = make(start_az_deg=0, speed_deg_s=100.0)
    device.receive(b"AP1045\r", 0.0)
    assert reading(device, 1.0) == b";045"
    device.receive(b"e", 1.1)
    assert device.options["endpoint"] is False and device.in_brake_delay(1.1)


def test_bearing_outcomes_group_everything_that_carried_a_bearing() -> None:
    device = make(speed_deg_s=100.0)
    device.receive(b"AP1010;AM1;AI1;", 0.0)
    device.receive(b"AP1020\r", 1.0)
    bearing = [f.data for f in device.log if f.outcome in BEARING_OUTCOMES]
    assert bearing == [b"AP1010;", b"AM1;", b"AP1020\r"]


# -- jitter (Idiom's analog note) --


def test_stationary_reading_alternates_between_two_values_jitter_apart() -> None:
    device = make(start_az_deg=90, jitter_deg=2)
    readings = [reading(device, float(t)) for t in range(6)]
    assert readings == [b";090", b";092"] * 3


def test_jitter_near_the_360_stop_stays_within_range() -> None:
    device = make(start_az_deg=359, jitter_deg=3)
    assert {reading(device, float(t)) for t in range(4)} == {b";359", b";356"}


def test_zero_jitter_reads_steady() -> None:
    device = make(start_az_deg=200, jitter_deg=0)
    assert {reading(device, float(t)) for t in range(5)} == {b";200"}


@pytest.mark.parametrize("jitter_deg", [1, 2, 5])
@pytest.mark.parametrize("start_az_deg", [0.0, 0.4, 123.5, 358.7, 360.0])
def test_jitter_is_bounded(jitter_deg: int, start_az_deg: float) -> None:
    device = make(start_az_deg=start_az_deg, jitter_deg=jitter_deg)
    for t in range(6):
        value = int(reading(device, float(t))[1:])
        error = abs(value - start_az_deg) % 360
        assert min(error, 360 - error) <= jitter_deg + 0.5


def test_default_jitter_is_one_degree() -> None:
    device = RotorEZ(start_az_deg=45, power_on_junk=False)
    assert [reading(device, float(t)) for t in range(4)] == [b";045", b";046"] * 2


# -- front panel and faults --


def test_brake_paddle_halts_and_cancels_a_serial_rotation() -> None:
    device = make()
    device.receive(b"AP1300\r", 0.0)
    assert device.press_brake(5.0)
    assert device.in_brake_delay(9.0) and not device.in_brake_delay(10.0)
    assert device.true_az_deg(100.0) == pytest.approx(30.0)
    assert not device.press_brake(20.0)


def test_pointing_control_overrides_a_serial_rotation() -> None:
    device = make()
    device.receive(b"AP1300\r", 0.0)
    device.manual_rotate(0.0, 5.0)  # was at 30, now heads back to 0
    state = device.state(5.0)
    assert state.driver == "panel" and state.target_az_deg == 0.0
    assert reading(device, 7.0) == b";018"
    assert device.true_az_deg(10.0) == 0.0
    assert device.in_brake_delay(14.9) and not device.in_brake_delay(15.0)


def test_serial_bearing_during_a_manual_move_stops_it() -> None:
    device = make()
    device.manual_rotate(100.0, 0.0)
    device.receive(b"AP1200\r", 5.0)
    assert not device.is_moving(5.0) and device.true_az_deg(5.0) == pytest.approx(30.0)


def test_pointing_at_where_the_rotor_already_is_just_stops_it() -> None:
    device = make(start_az_deg=0)
    device.receive(b"AP1300\r", 0.0)
    device.manual_rotate(30.0, 5.0)
    assert not device.is_moving(5.0) and device.in_brake_delay(5.0)


def test_jam_keeps_the_motor_running_with_the_bearing_stuck() -> None:
    device = make(jitter_deg=1)
    device.receive(b"AP1300\r", 0.0)
    device.jam(5.0)
    state = device.state(60.0)
    assert state.is_moving and state.is_jammed and state.az_deg == pytest.approx(30.0)
    # the potentiometer is still, so the reading jitters like any stationary one
    assert {reading(device, t) for t in (61.0, 62.0, 63.0)} == {b";030", b";031"}
    device.receive(b";", 64.0)  # a stop still cuts the motor
    assert not device.is_moving(64.0)
    assert device.log[-1].outcome == "stop"


def test_unjam_resumes_the_move() -> None:
    device = make()
    device.receive(b"AP1300\r", 0.0)
    device.jam(5.0)
    device.unjam(100.0)
    assert device.true_az_deg(105.0) == pytest.approx(60.0)


def test_power_cycle_stops_the_rotor_and_forgets_the_target() -> None:
    device = make()
    device.receive(b"AP1300\r", 0.0)
    device.power_cycle(5.0)
    state = device.state(5.0)
    assert not state.is_moving and not state.in_brake_delay
    assert state.az_deg == pytest.approx(30.0) and state.stored_target_az_deg is None
    device.receive(b"AM1;", 6.0)
    assert device.log[-1].outcome == "ignored: no stored target"


def test_next_wakeup_tracks_arrival_then_brake_then_nothing() -> None:
    device = make(speed_deg_s=10.0)
    assert device.next_wakeup(0.0) is None
    device.receive(b"AP1050\r", 0.0)
    assert device.next_wakeup(1.0) == pytest.approx(5.0)
    assert device.next_wakeup(6.0) == pytest.approx(10.0)
    assert device.next_wakeup(10.0) is None


def test_time_running_backwards_is_treated_as_now() -> None:
    device = make(speed_deg_s=10.0)
    device.receive(b"AP1100\r", 10.0)
    device.receive(b"AI1;", 5.0)
    assert device.log[-1].time_s == 10.0
    assert device.true_az_deg(12.0) == pytest.approx(20.0)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"model": "yaesu"},
        {"jitter_deg": -1},
        {"brake_delay_s": -1.0},
        {"baud": 0},
        {"start_az_deg": 400.0},
        {"speed_deg_s": 0.0},
    ],
)
def test_impossible_configurations_are_refused(kwargs: dict[str, Any]) -> None:
    model = kwargs.pop("model", "rotorez")
    with pytest.raises(ValueError):
        make(model, **kwargs)
