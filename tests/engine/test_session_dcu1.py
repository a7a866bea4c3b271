"""A Hy-Gain DCU-1 in virtual time: a controller that never answers.

The bridge cannot see this rotor. What it may show (status.py rule 3): a commanded move as
``moving`` with ``estimated`` set, the target and the time the move should be over; after that
``unknown`` with no target. What it must do (motion rules 4 and 6): treat the rotor as possibly
turning until the estimate has passed, so a second target stops it, waits out the brake and only
then goes (the DCU-1 ignores bearings while it turns or brakes, like the Rotor-EZ).
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from bridge.emulators.rotorez_models import Outcome
from bridge.session.motion import blind_busy_s
from tests.engine.virtual import WALL_EPOCH_S, VirtualRotator

Rig = Callable[..., VirtualRotator]
UNKNOWN, MOVING = MotionState.UNKNOWN, MotionState.MOVING
DISOBEYED = (Outcome.IGNORED_RETARGET, Outcome.IGNORED_BRAKE_DELAY, Outcome.IGNORED_NO_TARGET)


def settled(rig: Rig) -> VirtualRotator:
    """Connected long enough for the start-up assumption (maybe turning) to have passed."""
    v = rig("dcu1", emulator={"start_az_deg": 30})
    cfg = v.cfg.motion
    v.run_for(blind_busy_s(cfg.az_span_deg, cfg) + cfg.brake_delay_s + 1)
    return v


def frames(v: VirtualRotator, since: float) -> list[tuple[bytes, str]]:
    return [(f.data, f.outcome) for f in v.frames(since=since)]


def test_a_dcu1_is_available_and_unknown_and_never_asked(rig: Rig) -> None:
    v = settled(rig)
    assert v.status.available and v.status.connected
    assert v.status.state is UNKNOWN and v.status.bearing_deg is None
    assert v.device.log == []  # minutes, not one poll: it cannot answer
    assert len(v.statuses) == 2  # the first one, then connected; nothing since


def test_a_dcu1_move_is_shown_estimated_then_unknown_with_no_target(rig: Rig) -> None:
    v = settled(rig)
    t = v.now
    v.target(90)
    v.run_for(0.2)

    assert frames(v, t) == [(b"AP1090;", Outcome.STORED), (b"AM1;", Outcome.EXECUTED)]
    s = v.status
    assert s.state is MOVING and s.estimated and s.target_az_deg == 90
    assert s.bearing_deg is None  # never more than it knows
    # the start is unknown: the whole span, 50 % slower than nominal, plus two seconds
    cfg = v.cfg.motion
    busy_s = 1.5 * cfg.az_span_deg / cfg.nominal_speed_deg_s + 2.0
    assert s.expected_end_unix == pytest.approx(WALL_EPOCH_S + t + busy_s)
    v.run_until(lambda v: v.truth().az_deg == 90 and not v.truth().is_moving, 30, "arrived")
    assert v.status.state is MOVING  # the bridge cannot have seen it

    v.run_until(lambda v: v.status.state is UNKNOWN, busy_s + 1, "unknown")
    assert v.now == pytest.approx(t + busy_s, abs=0.01)
    s = v.status
    assert s.target_az_deg is None and not s.estimated and s.expected_end_unix is None
    assert [st.state for st in v.published(since=t)] == [MOVING, UNKNOWN]  # no chatter

    # the next move starts from where this one should have ended: a shorter estimate
    t = v.now + cfg.brake_delay_s
    v.run_until(lambda v: v.now >= t, 10)
    v.target(120)
    v.run_for(0.2)
    assert frames(v, t) == [(b"AP1120;", Outcome.STORED), (b"AM1;", Outcome.EXECUTED)]
    busy_s = 1.5 * 30 / cfg.nominal_speed_deg_s + 2.0
    assert v.status.expected_end_unix == pytest.approx(WALL_EPOCH_S + t + busy_s, abs=0.01)


def test_a_second_dcu1_target_during_the_estimate_waits_for_stop_and_brake(rig: Rig) -> None:
    v = settled(rig)
    v.target(200)
    v.run_for(10)
    assert v.truth().is_moving and v.status.state is MOVING
    t = v.now
    v.target(100)
    v.run_until(lambda v: len(v.frames(since=t)) == 4, 20, "stop and the new target")

    assert frames(v, t) == [
        (b"AS1;", Outcome.STOP),
        (b"AS1;", Outcome.STOP),  # (every stop twice: nothing can show one lost, stops rule 6)
        (b"AP1100;", Outcome.STORED),
        (b"AM1;", Outcome.EXECUTED),
    ]
    _, stop, store, _ = v.frames(since=t)
    assert store.time_s - stop.time_s >= v.cfg.motion.brake_delay_s
    waiting = [s for s in v.published(since=t) if s.state is UNKNOWN]
    assert waiting and all(s.target_az_deg is None for s in waiting)  # stopped: unknown
    assert v.status.state is MOVING and v.status.target_az_deg == 100

    v.run_until(lambda v: v.status.state is UNKNOWN, 120, "the estimate over")
    assert v.truth().az_deg == pytest.approx(100) and not v.truth().is_moving
    assert v.frames(*DISOBEYED) == [] and v.errors() == []


def test_the_first_dcu1_target_after_connecting_stops_first(rig: Rig) -> None:
    """Connected in the middle of a move the bridge knows nothing of: it may be turning."""
    v = rig("dcu1", emulator={"start_az_deg": 30})
    v.run_for(1)
    t = v.now
    v.target(90)
    v.run_until(lambda v: len(v.frames()) == 4, 20, "stop and target")

    assert frames(v, t) == [
        (b"AS1;", Outcome.STOP),
        (b"AS1;", Outcome.STOP),  # (every stop twice: nothing can show one lost, stops rule 6)
        (b"AP1090;", Outcome.STORED),
        (b"AM1;", Outcome.EXECUTED),
    ]
    assert v.frames()[2].time_s - v.frames()[1].time_s >= v.cfg.motion.brake_delay_s
