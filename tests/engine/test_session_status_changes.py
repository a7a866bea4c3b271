"""A status is built again only when something it shows changed (session.py rule 18): each thing
a user reads in the status, changed alone on a still rotor, is published in the step that
changed it (and a step that changed nothing publishes nothing). Each case changes one value the
session compares, and nothing else the status is made from: a value left out of the comparison
would keep its change out of the status until something else (a reading) came by."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest

from bridge.core.model import Control, MotionState, Origin, RotatorStatus, Source, Target
from bridge.session.follow import Follow
from tests.engine.test_follow import STATION
from tests.engine.test_wind import WIND
from tests.engine.virtual import VirtualRotator


def still(**kw: Any) -> VirtualRotator:
    """An MD-01 at rest, answering, its status settled."""
    v = VirtualRotator(
        "md01",
        settings={"az_speed_deg_s": 10.0, "el_speed_deg_s": 5.0, **kw.pop("settings", {})},
        emulator={"az_speed_deg_s": 10.0, "el_speed_deg_s": 5.0},
        **kw,
    )
    v.run_until(lambda h: h.status.available, 10, "the controller answers")
    v.run_for(5.0)
    return v


def _put(v: VirtualRotator, put: Callable[[], object]) -> None:
    put()
    v._take()


Case = tuple[
    dict[str, Any],  # how the rotator is made (still())
    Callable[[VirtualRotator], None],  # the change
    Callable[[RotatorStatus], bool],  # what the newest status shows
]
CASES: dict[str, Case] = {
    "lock off": ({"locked": True}, lambda v: v.lock(False), lambda s: not s.locked),
    "lease taken": (
        {},
        lambda v: _put(v, lambda: v.mailbox.put_control(Control("DL1ABC", v.wall() + 600))),
        lambda s: s.control is not None and s.control.operator == "DL1ABC",
    ),
    "a refusal (the last error)": (
        {"locked": True},
        lambda v: v.target(200.0),
        lambda s: s.last_error == "rotator is locked",
    ),
    "a note (the last error)": (
        {},
        lambda v: _put(v, lambda: v.mailbox.put_note("not yours")),
        lambda s: s.last_error == "not yours",
    ),
    "a wind reading": (
        {"settings": WIND},
        lambda v: _put(v, lambda: v.mailbox.put_wind(33.0)),
        lambda s: s.wind is not None and s.wind.speed_kmh == 33.0,
    ),
    "following on": (
        {"follow": STATION},
        lambda v: v.follow(True),
        lambda s: s.following is not None,
    ),
}


@pytest.mark.parametrize("name", list(CASES))
def test_a_change_alone_on_a_still_rotor_is_published_in_its_step(name: str) -> None:
    make, change, shows = CASES[name]
    with still(**make) as v:
        assert not shows(v.status), "the change is a change"
        t = v.now
        change(v)
        fresh = v.published(since=t)
        assert fresh and shows(fresh[-1]), f"{name}: not in the status published at once"


def test_the_lease_given_back_and_following_off_are_published_too() -> None:
    with still(follow=STATION) as v:
        _put(v, lambda: v.mailbox.put_control(Control("DL1ABC", v.wall() + 600)))
        v.follow(True)
        v.run_for(2.0)
        t = v.now
        _put(v, lambda: v.mailbox.put_control(None))
        assert v.published(since=t) and v.published(since=t)[-1].control is None
        t = v.now
        v.mailbox.put_follow(Follow(False))
        v._take()
        fresh = v.published(since=t)
        assert fresh and fresh[-1].following is None


def test_a_step_that_changed_nothing_publishes_nothing() -> None:
    with still() as v:
        t = v.now
        v.run_for(30.0)  # polls: the same reading again and again
        assert v.published(since=t) == []
        v.stop()  # a command is still a change (a stop went out)
        assert v.published(since=t)
        assert v.status.last_command_source is not None


def test_following_held_for_a_transmission_is_published_while_nothing_else_changes() -> None:
    """Only following's own view changes (held): no target, no motion, no error."""
    with still(follow=STATION) as v:
        v.follow(True)
        v.heard("DL1ABC", "JO40")
        v.run_for(40.0)  # turned to JO40 and at rest
        t = v.now
        v.heard("G4XYZ", "IO91", transmitting=True)  # a new partner while we transmit
        fresh = v.published(since=t)
        assert fresh and fresh[-1].following is not None and fresh[-1].following.held


def test_a_newer_target_waiting_for_the_brake_is_shown_at_once() -> None:
    """A Rotor-EZ stops and waits out its brake before a new bearing: a target that replaces
    the waiting one changes only the waiting target, and the status shows it at once."""
    with VirtualRotator("rotorez") as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.target(200.0)
        v.run_for(3.0)  # turning
        v.target(100.0)  # a stop, then the brake: the target waits
        v.run_for(0.2)
        assert v.session.targets.pending is not None, "still waiting for the brake"
        t = v.now
        v.target(150.0)
        fresh = v.published(since=t)
        assert fresh and fresh[-1].target_az_deg == 150.0


@pytest.mark.parametrize("model", ["md01", "rotorez", "gs232b"])
def test_a_target_shown_waiting_is_shown_with_who_sent_it(model: str) -> None:
    """The status that first shows a new target (still waiting to go out: asked first, or a
    brake) names its source and operator, not the previous command's (a contract check: a
    rotctld target showed ``last_command_source: mqtt`` until it went out)."""
    with VirtualRotator(model) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.command(Target(100.0, None, Source.MQTT, origin=Origin(Source.MQTT, "DL1ABC")))
        v.run_until(
            lambda h: (
                h.status.state is MotionState.IDLE
                and h.status.bearing_deg is not None
                and abs(h.status.bearing_deg - 100.0) < 2.0
            ),
            200,
            "arrived",
        )
        v.run_for(2.0)
        t = v.now
        v.command(
            Target(200.0, None, Source.ROTCTLD, origin=Origin(Source.ROTCTLD, None, "10.0.0.9"))
        )
        v.run_until(
            lambda h: (
                h.published(since=t) and any(s.target_az_deg == 200.0 for s in h.published(since=t))
            ),
            10,
            "the target shown",
        )
        shown = [s for s in v.published(since=t) if s.target_az_deg == 200.0]
        assert [(s.last_command_source, s.last_operator) for s in shown[:1]] == [
            ("rotctld", "rotctld 10.0.0.9")
        ]
