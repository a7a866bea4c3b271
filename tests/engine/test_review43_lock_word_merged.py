"""Review 43: stops.py rule 7 says its word ("the lock's stop sent again") with the stop it
decides on, and hands that stop to the merge (rule 1). ``lock_check`` keeps only a moving poll
from the last stop; the merge keeps a whole brake window (five seconds on a Rotor-EZ). A turn
by hand that a locked Rotor-EZ's readings show a second after the lock ON, the replies after
its first garbled (attack 9), gets the word on R/error at once, while no frame goes: the
stop it names merged into the lock ON's, and the next one is written three seconds later.
The user reads that the bridge fought what it did not.
(Fixed: no stop and no word where the stop would merge, stops.py ``lock_check``'s ``merges``.)"""

from __future__ import annotations

from collections.abc import Callable

from tests.engine.test_attack9_turn_unseen_after_two_garbles import garble_after_the_first_move
from tests.engine.test_session_doubt import at_rest
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
LOCKS = "the lock's stop sent again"


def test_the_locks_word_is_said_only_with_a_stop_written(rig: Rig) -> None:
    v = at_rest(rig, "rotorez")
    rest = v.status.bearing_deg
    assert rest is not None
    v.lock(True)
    v.run_for(1.0)  # (inside the Rotor-EZ's brake window after the lock's stop)
    t = v.now
    garble_after_the_first_move(v, rest)  # (attack 9: its readings doubted)
    v.manual_rotate(300.0)  # a hand at the panel, the rotor locked
    v.run_for(30)
    said = [at for at, e in v.events if at >= t and LOCKS in e.message]
    assert said  # (the lock fought it)
    written = [w.t for w in v.writes if w.t >= t and w.data == b";"]
    reply_s = 0.1  # (a half-duplex line writes it after the reply in flight)
    for at in said:
        assert any(at <= w <= at + reply_s for w in written), (at, written)
