"""Review 43: the lock's own check (stops.py rule 7) handed its stop to the merge (rule 1),
which keeps a brake window (five seconds on a Rotor-EZ) after the last stop while no reading
taken showed the rotor turning. Readings the doubt does not take never show it, and they are
all rule 7 has. So a turn by hand at the panel of a locked Rotor-EZ whose first readings come
garbled (attack 9's two noise bytes) was fought at once when it started five seconds or more
after the lock ON (158 from 150), but when it started a second after it, the stop waited out
the window: 176 (180 when it started at once; 190 with five replies in six garbled). The
fight's stops now keep a second from the last stop, not a brake window (review 47)."""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState
from tests.engine.test_attack9_turn_unseen_after_two_garbles import garble_after_the_first_move
from tests.engine.test_session_doubt import at_rest
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


def test_a_turn_by_hand_right_after_the_lock_on_is_fought_at_once(rig: Rig) -> None:
    v = at_rest(rig, "rotorez")
    rest = v.status.bearing_deg
    assert rest is not None
    v.lock(True)
    v.run_for(1.0)  # (inside the Rotor-EZ's brake window after the lock's stop)
    turned_by_hand_and_fought(v, rest)


def turned_by_hand_and_fought(v: VirtualRotator, rest: float) -> None:
    """A hand at the panel turns the locked rotor from ``rest`` toward 300, the replies after
    its first reading garbled (attack 9): fought within 20 degrees, as the same turn begun five
    seconds or more after the lock ON is (at 158)."""
    t = v.now
    garbled = garble_after_the_first_move(v, rest)
    v.manual_rotate(300.0)  # a hand at the panel, the rotor locked
    v.run_for(40)
    assert len(garbled) == 2
    assert v.status.locked
    assert MotionState.MOVING in {s.state for s in v.published(since=t)}
    assert v.truth().az_deg < rest + 20
