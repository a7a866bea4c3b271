"""Review 47: the lock's fight (stops.py rule 7) lets only its FIRST stop through the brake
window of the stop before it (the lock ON's); the next merge into the fight's own stop (rule 1).
On a noisy line that first stop is spent on noise: one flipped bit (150 reads 350) 1.4 s after
the lock ON brings a fight stop at once, and a turn by hand at the panel that starts a moment
later, its first replies garbled (attack 9), is held for a whole brake window from that stop
(five seconds on a Rotor-EZ): fought at 6.4 s, 28 degrees from rest, where before the change it
was fought when the lock ON's window ended (5.4 s, 22 degrees) and review 43's turn without the
flip is fought at 8. The line that garbles the turn's replies is the line that flips a bit.
The fight's stops keep a second from the last stop now, whatever rule 1's brake window."""

from __future__ import annotations

from collections.abc import Callable

from tests.engine.test_review43_lock_fight_in_brake_window import turned_by_hand_and_fought
from tests.engine.test_session_doubt import at_rest, flip_next_hundreds
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


def test_a_flipped_reading_before_a_turn_by_hand_does_not_hold_back_its_fight(rig: Rig) -> None:
    v = at_rest(rig, "rotorez")
    rest = v.status.bearing_deg
    assert rest is not None
    v.lock(True)
    v.run_for(0.5)  # (past the moving poll interval after the lock's stop: a sign is fought)
    flipped = flip_next_hundreds(v)  # line noise: one reading of 350
    v.run_for(1.0)
    assert len(flipped) == 1
    turned_by_hand_and_fought(v, rest)  # (as without the flipped reading: review 43's test)
