"""Review 43: the lock's own check (stops.py rule 7) handed its stop to the merge (rule 1),
which keeps a brake window (five seconds on a Rotor-EZ) after the last stop while no reading
taken showed the rotor turning. Readings the doubt does not take never show it, and they are
all rule 7 has. So a turn by hand at the panel of a locked Rotor-EZ whose first readings come
garbled (attack 9's two noise bytes) was fought at once when it started five seconds or more
after the lock ON (158 from 150), but when it started a second after it, the stop waited out
the window: 176 (180 when it started at once; 190 with five replies in six garbled). The
fight's first stop now goes through the lock ON's window; the next merge as before."""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState
from tests.engine.test_attack9_turn_unseen_after_two_garbles import garble_after_the_first_move
from tests.engine.test_lock_fights_by_itself import noisy, stops_written
from tests.engine.test_session_doubt import at_rest
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


def test_a_turn_by_hand_right_after_the_lock_on_is_fought_at_once(rig: Rig) -> None:
    v = at_rest(rig, "rotorez")
    rest = v.status.bearing_deg
    assert rest is not None
    v.lock(True)
    v.run_for(1.0)  # (inside the Rotor-EZ's brake window after the lock's stop)
    t = v.now
    garbled = garble_after_the_first_move(v, rest)
    v.manual_rotate(300.0)  # a hand at the panel, the rotor locked
    v.run_for(40)
    assert len(garbled) == 2
    assert v.status.locked
    assert MotionState.MOVING in {s.state for s in v.published(since=t)}
    # as the same turn begun five seconds or more after the lock ON: fought at 158
    assert v.truth().az_deg < rest + 20


def test_a_noisy_line_right_after_the_lock_on_gets_one_stop_more_in_its_brake_window(
    rig: Rig,
) -> None:
    """The price on a line that flips every other reading from the lock ON on: the fight's first
    stop in the lock ON's brake window, and no more there (a Rotor-EZ answers each idle ``;``
    with its banner); then one a brake window, as before."""
    v = at_rest(rig, "rotorez")
    t = v.now
    noisy(v, b"13")
    v.lock(True)
    v.run_for(60)
    stops = stops_written(v, t)
    window_s = 5.0  # (the Rotor-EZ's brake window)
    assert len([w for w in stops if w < stops[0] + window_s]) == 2, stops  # the lock's, one fight
    gaps = [b - a for a, b in zip(stops[1:], stops[2:], strict=False)]
    assert all(gap >= window_s for gap in gaps), gaps
    assert not v.truth().is_moving
