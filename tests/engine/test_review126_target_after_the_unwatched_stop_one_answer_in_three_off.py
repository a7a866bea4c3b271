"""Review 126: after the unwatched stop at rest, on a line that reads one answer in three 60
degrees off (two in three right), an operator's target turn is published at bearings the rotor
never had, 60 degrees off every third reading, and once it arrives it is shown MOVING for good,
its bearing flipping between the target and 60 degrees past it (retained), asked at the moving
rate. At dc9c17f2^ (two agreeing readings at rest taken) the same turn was shown idle at its
target, the off readings told as line noise.

How (as far as traced): three in a row at rest (``_pair_holds``, dc9c17f2) never agree on
this line, so the rotor moved meanwhile stays shown where it stood, 20 degrees from where it is
(test_review126_one_answer_in_three_off_after_the_unwatched_stop); the turn starts from there,
its first off reading is asked again once, and from then on every reading is taken, the off
ones too. Not traced further.

In virtual time: the emulated Easycomm II box at rest at 150, confirmed on a clean line; its
answers off by +60 and -60 in turn until the first unwatched stop; a hand turns it towards 120
while the line stays bad; then two answers in three come through whole, the third 60 degrees
off, for good; half a minute on, the operator sends 200.
"""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState
from tests.engine.garblers import every_answer_off, hand_after_the_unwatched_stop
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
HAND_DEG = 120.0
TARGET_DEG = 200.0
BETTER_S = 30.0  # the better line before the target (virtual time)
TURN_S = 60.0  # 80 degrees at 6 deg/s and a settle, with lots of room (virtual time)
NEAR_DEG = 0.5  # shown where it rests (the box's tenth of a degree, rounded)


def test_a_target_turn_after_the_unwatched_stop_is_shown_idle_at_its_target(rig: Rig) -> None:
    v = hand_after_the_unwatched_stop(rig, REST_DEG, HAND_DEG)
    v.to_host = every_answer_off([0.0, 0.0, 60.0])
    v.run_for(BETTER_S)
    v.target(TARGET_DEG)
    v.run_for(TURN_S)
    assert v.truth().az_deg == TARGET_DEG  # (it arrived)
    assert v.status.state is MotionState.IDLE, v.status
    assert v.status.bearing_deg is not None, v.status
    assert abs(v.status.bearing_deg - TARGET_DEG) <= NEAR_DEG, v.status.bearing_deg
