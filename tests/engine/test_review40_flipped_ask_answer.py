"""Review 40: a turn by hand at a locked rotor is doubted on its first reading that shows the
move and asked again at once (session/controller.py rule 9). When the answer to that ask comes
with one flipped bit (156 read as 356: a well-formed reading, no garble), it disagrees with the
doubted one, the doubt counts two disagreements in a row, and the readings after it are asked
for at the idle rate and must agree within ``doubt_deg`` alone: a rotor turning at 6 degrees a
second, polled every second, never does. One flipped bit, and the whole turn goes unseen: the
bearing shows the rotor idle where it stood until it rests again, and the lock never fights it.
(Attack 9's fix, an answer given up is no disagreement, covers two garbled answers; a flipped
one is a disagreement still.) An RT-21 is left out: its replies have no head the flip can find
(``flip_next_hundreds``); a SatEL's turn is seen all the same. The lock now fights such a turn
by itself: a reading at rest doubted under the lock sends its stop again (stops.py rule 7)."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.test_session_doubt import flip_next_hundreds, locked_at_rest
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
ASK_WITHIN_S = 0.5  # a poll this soon after the one before, at rest: the ask at once (the
# idle rate is 1 s)


def flip_the_answer_to_the_ask(v: VirtualRotator, since: int) -> list[float]:
    """Once the bridge asks again at once (a poll right after the one before, among the frames
    written from ``since`` on), the answer to it read with one bit flipped in its hundreds digit
    (``flip_next_hundreds``); returns the list the instant goes into."""

    def asked(h: VirtualRotator) -> bool:
        writes = h.writes[since:]
        return any(b.t - a.t < ASK_WITHIN_S for a, b in zip(writes, writes[1:], strict=False))

    v.run_until(asked, 30, "the ask at once")
    return flip_next_hundreds(v)


@pytest.mark.parametrize(
    "model", ["rotorez", "rotorcard", "gs232b", "gs232a", "easycomm2", "prosistel", "rc2800"]
)
def test_a_turn_by_hand_on_a_locked_rotor_is_fought_after_a_flipped_answer(
    rig: Rig, model: str
) -> None:
    v, rest = locked_at_rest(rig, model)
    t = v.now
    since = len(v.writes)
    v.manual_rotate(300.0)  # a hand at the panel, the rotor locked
    flipped = flip_the_answer_to_the_ask(v, since)
    v.run_for(40)
    assert len(flipped) == 1
    # what the lock does to a turn by hand when no reply is flipped, or two come garbled
    # (test_attack9_turn_unseen_after_two_garbles.py): it is fought within a few degrees
    assert v.truth().az_deg < rest + 20
    assert MotionState.MOVING in {s.state for s in v.published(since=t)}
