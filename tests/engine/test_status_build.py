"""status.py rule 6 and motion.py's ``_with``: the status and the motion a reading makes,
built without their frozen dataclasses' ``__init__``, are the values that ``__init__`` builds:
every field, in the dataclass's order, equal, and still frozen. And the ``status.Seen`` the
controller builds by position holds each value under its own name."""

from __future__ import annotations

import dataclasses

import pytest

from bridge.core.model import RotatorStatus
from bridge.session import motion as mo
from bridge.session import status as st
from tests.engine.virtual import VirtualRotator


def test_the_status_of_a_turning_rotor_is_the_dataclass_s_own() -> None:
    v = VirtualRotator("rotorez", emulator={"speed_deg_s": 4.0})
    v.run_for(3.0)
    v.manual_rotate(90.0)
    v.run_for(2.0)
    status = v.session.status
    assert status.moving and status.bearing_deg is not None
    names = [f.name for f in dataclasses.fields(RotatorStatus)]
    assert list(vars(status)) == names
    built = RotatorStatus(**{n: getattr(status, n) for n in names})
    assert status == built and hash(repr(status)) == hash(repr(built))
    with pytest.raises(dataclasses.FrozenInstanceError):
        status.bearing_deg = 1.0  # type: ignore[misc]


def test_a_reading_s_motion_is_the_dataclass_s_own() -> None:
    cfg = mo.MotionConfig(spec=VirtualRotator("rotorez").session.cfg.spec)
    m, _ = mo.reading(mo.Motion(), cfg, 10.0, 0.0)
    m2, _ = mo.reading(m, cfg, 20.0, 0.2)  # moved: a new motion from the reading's changes
    assert m2 is not m and m2.state is mo.MotionState.MOVING
    names = [f.name for f in dataclasses.fields(mo.Motion)]
    assert list(vars(m2)) == names
    assert m2 == dataclasses.replace(
        m,
        position_deg=20.0,
        anchor_deg=20.0,
        changed_t=0.2,
        last_move_t=0.2,
        still_since_t=None,
        state=mo.MotionState.MOVING,
        el_position_deg=None,
        el_anchor_deg=None,
        az_moved_deg=20.0,  # (motion.py rule 2: a found turn's azimuth, its own movement)
        az_moved_t=0.2,
        az_crept_t=0.2,
    )
    with pytest.raises(dataclasses.FrozenInstanceError):
        m2.position_deg = 1.0  # type: ignore[misc]


@pytest.mark.parametrize("locked", [False, True])
@pytest.mark.parametrize("answering", [False, True])
def test_what_the_controller_hands_the_status_is_each_value_by_its_name(
    locked: bool, answering: bool
) -> None:
    """Controller.seen builds status.Seen by position (at every reading): each field is the
    value of its name, none swapped with a neighbour of its type."""
    v = VirtualRotator("rotorez", emulator={"speed_deg_s": 4.0})
    v.run_for(3.0)
    v.manual_rotate(90.0)
    v.run_for(30.0)  # (at rest there: a target kept short of is shown only then)
    session, ctl = v.session, v.session.controller
    assert ctl.link is not None and ctl.link.slew is None
    ctl.version, ctl.controller_time, ctl.answering = "version", "clock", answering
    ctl.az_shown.value, ctl.el_shown.value = 11.0, 22.0
    ctl.stops.owed = not locked  # (never the lock's value: a swap would show)
    ctl.keep_short_of(200.0)  # (rule 10: stopped short of it)
    features = st.Features(tracking_ended="ended")
    seen = ctl.seen(session.status, session.view, None, locked, 33.0, features)
    assert seen._asdict() == {
        "previous": session.status,
        "view": session.view,
        "version": "version",
        "controller_time": "clock",
        "motion": ctl.motion,
        "connected": True,
        "answering": answering,
        "locked": locked,
        "options": ctl.options.values,
        "bearing_deg": 11.0,
        "elevation_deg": 22.0,
        "slew": None,
        "pending": None,
        "pending_wire": None,
        "wall_offset_s": 33.0,
        "features": features,
        "stop_owed": not locked,
        "short_of_deg": 200.0,
    }
