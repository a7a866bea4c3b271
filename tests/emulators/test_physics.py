"""Axis motion model, driven by a fake clock (plain floats): no sleeps anywhere."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from bridge.emulators.physics import DRIVER_COMMAND, DRIVER_PANEL, Axis


def test_moves_at_constant_speed_and_arrives_exactly() -> None:
    axis = Axis(0.0, speed_deg_s=6.0)
    assert axis.start_move(90.0, now=10.0)
    assert axis.position_deg_at(15.0) == pytest.approx(30.0)
    assert axis.arrival_time_s() == pytest.approx(25.0)
    assert axis.advance(24.9) is None
    assert axis.is_moving
    assert axis.advance(100.0) == pytest.approx(25.0)
    assert axis.position_deg == 90.0
    assert not axis.is_moving


def test_hy_gain_rotor_goes_the_long_way_round() -> None:
    axis = Axis(10.0, speed_deg_s=10.0)
    axis.start_move(350.0, now=0.0)
    # Through south, never across the 0/360 stop: halfway it points at 180.
    assert axis.position_deg_at(17.0) == pytest.approx(180.0)
    assert axis.arrival_time_s() == pytest.approx(34.0)


def test_target_beyond_a_stop_is_clamped() -> None:
    axis = Axis(-90.0, min_deg=-180.0, max_deg=540.0, speed_deg_s=100.0)
    axis.start_move(999.0, now=0.0)
    assert axis.target_deg == 540.0
    axis.advance(100.0)
    assert axis.position_deg == 540.0


def test_stop_freezes_the_position_where_it_is() -> None:
    axis = Axis(100.0, speed_deg_s=4.0)
    axis.start_move(0.0, now=0.0)
    assert axis.stop(now=5.0)
    assert axis.position_deg == pytest.approx(80.0)
    assert axis.position_deg_at(50.0) == pytest.approx(80.0)
    assert not axis.stop(now=6.0)


def test_zero_length_move_does_not_start_the_motor() -> None:
    axis = Axis(45.0)
    assert not axis.start_move(45.0, now=0.0)
    assert not axis.is_moving


def test_jammed_axis_runs_its_motor_but_stays_put_then_resumes() -> None:
    axis = Axis(0.0, speed_deg_s=10.0)
    axis.start_move(100.0, now=0.0)
    axis.jam(now=2.0)
    assert axis.position_deg_at(50.0) == pytest.approx(20.0)
    assert axis.arrival_time_s() is None
    assert axis.advance(50.0) is None
    assert axis.is_moving and axis.is_jammed
    axis.unjam(now=60.0)
    assert axis.position_deg_at(61.0) == pytest.approx(30.0)
    assert axis.arrival_time_s() == pytest.approx(68.0)


def test_manual_move_is_tagged_as_driven_by_the_panel() -> None:
    axis = Axis(0.0)
    axis.start_move(200.0, now=0.0)
    assert axis.driver == DRIVER_COMMAND
    axis.manual_move(10.0, now=1.0)
    assert axis.driver == DRIVER_PANEL
    assert axis.target_deg == 10.0
    axis.advance(100.0)
    assert axis.driver is None and axis.position_deg == 10.0


def test_time_running_backwards_is_ignored() -> None:
    axis = Axis(0.0, speed_deg_s=1.0)
    axis.start_move(100.0, now=10.0)
    axis.advance(20.0)
    axis.advance(5.0)
    assert axis.position_deg == pytest.approx(10.0)


def test_set_position_places_the_axis_with_the_motor_off() -> None:
    axis = Axis(0.0)
    axis.start_move(300.0, now=0.0)
    axis.set_position(123.0, now=1.0)
    assert axis.position_deg == 123.0 and not axis.is_moving


@pytest.mark.parametrize(
    "kwargs",
    [
        {"position_deg": 0.0, "min_deg": 10.0, "max_deg": 0.0},
        {"position_deg": 0.0, "speed_deg_s": 0.0},
        {"position_deg": 400.0},
    ],
)
def test_rejects_impossible_geometry(kwargs: dict[str, float]) -> None:
    with pytest.raises(ValueError):
        Axis(**kwargs)


@given(
    start=st.floats(0, 360),
    target=st.floats(-50, 410),
    speed=st.floats(0.5, 100),
    times=st.lists(st.floats(0, 1000), min_size=1, max_size=20),
)
def test_position_stays_between_start_and_target(
    start: float, target: float, speed: float, times: list[float]
) -> None:
    axis = Axis(start, speed_deg_s=speed)
    axis.start_move(target, now=0.0)
    goal = min(360.0, max(0.0, target))
    low, high = min(start, goal), max(start, goal)
    previous_gap = abs(goal - start)
    for now in sorted(times):
        axis.advance(now)
        assert low <= axis.position_deg <= high
        gap = abs(goal - axis.position_deg)
        assert gap <= previous_gap + 1e-9
        previous_gap = gap


# -- coasting (rule 6) --


def test_a_coast_runs_on_the_way_it_turned_and_decelerates_to_rest() -> None:
    axis = Axis(0.0, speed_deg_s=2.0)
    axis.start_move(100.0, now=0.0)
    assert axis.stop(10.0, coast_deg=2.0, coast_s=1.0)  # at 20, turning up
    assert not axis.is_moving and axis.is_coasting and axis.target_deg is None
    assert axis.coast_end_s() == pytest.approx(11.0) and axis.arrival_time_s() is None
    assert axis.position_deg_at(10.0) == pytest.approx(20.0)
    assert axis.position_deg_at(10.5) == pytest.approx(21.5)  # 3/4 of it in the first half
    assert axis.advance(10.75) is None and axis.is_coasting
    assert axis.advance(12.0) is None  # resting is no arrival
    assert not axis.is_coasting and axis.position_deg == 22.0


def test_a_coast_goes_down_when_turning_down_and_stops_at_a_limit() -> None:
    axis = Axis(100.0, speed_deg_s=10.0)
    axis.start_move(0.0, now=0.0)
    axis.stop(1.0, coast_deg=2.0, coast_s=1.0)
    axis.advance(5.0)
    assert axis.position_deg == 88.0
    axis.start_move(0.0, now=5.0)
    axis.stop(13.95, coast_deg=2.0, coast_s=1.0)  # 0.5 from the end stop
    axis.advance(20.0)
    assert axis.position_deg == 0.0


def test_no_coast_when_idle_jammed_or_unasked_and_a_new_move_starts_from_the_coast() -> None:
    axis = Axis(0.0, speed_deg_s=1.0)
    assert not axis.stop(0.0, coast_deg=2.0, coast_s=1.0) and not axis.is_coasting
    axis.start_move(50.0, now=0.0)
    axis.stop(5.0)
    assert not axis.is_coasting
    axis.start_move(50.0, now=5.0)
    axis.jam(6.0)
    axis.stop(7.0, coast_deg=2.0, coast_s=1.0)
    assert not axis.is_coasting and axis.position_deg_at(9.0) == pytest.approx(6.0)
    axis.unjam(9.0)
    axis.start_move(50.0, now=9.0)
    axis.stop(10.0, coast_deg=2.0, coast_s=1.0)  # at 7
    assert not axis.stop(10.5, coast_deg=2.0, coast_s=1.0)  # a stop in a coast changes nothing
    assert axis.position_deg_at(10.5) == pytest.approx(8.5)
    axis.start_move(0.0, now=10.5)  # turns back from where the coast had it
    assert not axis.is_coasting and axis.position_deg_at(11.5) == pytest.approx(7.5)
