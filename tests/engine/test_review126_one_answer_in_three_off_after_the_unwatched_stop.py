"""Review 126: once readings at rest went on disagreeing to the unwatched stop, three in a row
must agree before a bearing is taken (controller.py rule 9, ``_pair_holds``, dc9c17f2, review
123); a line that reads one answer in three far off never gives three in a row. A rotor moved
while the bridge could not watch it is then shown where it stood, idle, for good (retained),
with an unwatched stop every few seconds and R/error saying the readings do not agree, though
two answers in every three read where it rests. At 51a2f016 (two agreeing taken) it was
shown where it rests a reading or two after the line got that much better.

Found by a sweep: an Easycomm II at rest at 150 on a line reading every third answer 60
degrees off; a hand turn at the panel was cut short at 107.9 by the unwatched stop, and the
rotor was shown idle at 150 for good.

In virtual time: the emulated Easycomm II box at rest at 150, confirmed on a clean line; its
answers reach the host off by +60 and -60 in turn until the first unwatched stop; a hand turns
it to 120 while the line stays bad (review 123's guard); then the line gets better: two
answers in three come through whole, the third 60 degrees off, for good.
"""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState
from tests.engine.garblers import every_answer_off, hand_after_the_unwatched_stop
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
HAND_DEG = 120.0
BETTER_S = 60.0  # a minute of the better line: some sixty answers (virtual time)
TURNED_DEG = 5.0  # the hand turned it further than any doubt's tolerance
NEAR_DEG = 0.5  # shown where it rests (the box's tenth of a degree, rounded)


def test_a_line_reading_two_answers_in_three_right_shows_where_the_rotor_rests(
    rig: Rig,
) -> None:
    v = hand_after_the_unwatched_stop(rig, REST_DEG, HAND_DEG)
    rests = v.truth().az_deg
    assert abs(rests - REST_DEG) > TURNED_DEG, rests  # (the premise: somewhere new)
    v.to_host = every_answer_off([0.0, 0.0, 60.0])
    v.run_for(BETTER_S)
    assert v.truth().az_deg == rests  # (still: nobody turned it since)
    assert v.status.state is MotionState.IDLE, v.status
    assert v.status.bearing_deg is not None, v.status
    assert abs(v.status.bearing_deg - rests) <= NEAR_DEG, (v.status.bearing_deg, rests)
