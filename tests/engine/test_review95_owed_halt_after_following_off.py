"""Review 95 (e0f93948, motion.py rule 4: ``owes_halt``, "cleared when tracking and following
end"): while a refused start's halt is owed, a move only on axes decided still is a hand's turn
once the next reading confirms it, the first held back and shown nothing of. The session clears
the flag where a part ends through ``RotatorSession._end`` or a proposal's ``ended``, but not
where a feature command ends it (feature_commands.py ``end``/``start``: ``follow OFF``, a track
start ending following, a follow start ending tracking, the sky worker ending tracking). So
after ``follow OFF`` nothing is owed any more (no part, no halt), yet the motion still holds
back a hand's first reading: a bridge just started by a GS-232B at rest, a follow start
refused at once (the halt owed: review 89), following turned off, then a hand at the azimuth
(decided still, the elevation not yet): the reading that shows the hand's move (66, from 62)
publishes 'idle' at 62, and 'moving' comes one reading later, where the same hand with no
follow start at all is shown moving at that reading (rule 4: "with no halt owed a hand is told
at once")."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import ErrorKind, MotionState
from tests.engine.test_review73_restart_hand import _restarted_at_rest
from tests.engine.test_review84_elevation_carried_turn import START_AZ
from tests.engine.test_review89_restart_mid_slow_elevation_turn import (
    gs232_with_a_slow_elevation_by_a_keep_out,
)
from tests.engine.virtual import VirtualRotator

AZ_SEEN_S = 1.15  # past the azimuth's own axis_seen_s (1.07 s), before the elevation's (2.12 s)


def never_followed(v: VirtualRotator) -> None:
    v.run_for(AZ_SEEN_S)  # (the azimuth decided still, the elevation not: not a deadline)


def followed_refused_then_off(v: VirtualRotator) -> None:
    t = v.now
    v.follow(True)
    v.heard("JA1ABC", "PM95")
    v.run_for(AZ_SEEN_S / 2)  # (not a deadline)
    assert [e.kind for e in v.errors(since=t)] == [ErrorKind.REFUSED]
    v.follow(False)  # following off: no part left to owe the halt
    v.run_for(AZ_SEEN_S / 2)  # (not a deadline)
    assert v.status.following is None


def moving_shown_after_a_hand(before_the_hand: Callable[[VirtualRotator], None]) -> float:
    """A bridge just started by the GS-232B at rest, ``before_the_hand`` done, then a hand at
    the azimuth: how long after the hand the status first says moving."""
    with gs232_with_a_slow_elevation_by_a_keep_out() as v:
        _restarted_at_rest(v)
        before_the_hand(v)
        assert v.truth().az_deg == START_AZ and not v.truth().is_moving  # (never moved)
        v.manual_rotate(START_AZ + 120)  # a hand at the panel (away from the keep-out)
        return v.run_until(
            lambda h: h.status.state is MotionState.MOVING, 10, "the bridge shows the hand"
        )


def test_a_hand_after_following_is_turned_off_is_shown_as_soon_as_without_it() -> None:
    control = moving_shown_after_a_hand(never_followed)
    # observed: 0.2 s later (one reading held back: 'idle' at 62 while it read 66)
    assert moving_shown_after_a_hand(followed_refused_then_off) == pytest.approx(control)
