"""Review 123's fix, guarded: once readings at rest went on disagreeing to the unwatched stop,
two agreeing are no longer enough to take a bearing (a failed sensor's few values agree with
themselves by chance), three in a row are. A rotor that rests somewhere new when the line comes
right (moved by hand while the bridge could not watch it) must still be shown there, idle, a
reading or so later: the stricter pair must not leave the bearing stuck where it stood, nor
the rotor shown turning.

In virtual time: the emulated Easycomm box at rest at 150, confirmed on a clean line; then each
answer's azimuth reaches the host off by +60 or -60 in turn until the first unwatched stop; a
hand turns the rotor to 120 while the line stays bad; the line comes right once it rests.
"""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState
from tests.engine.garblers import hand_after_the_unwatched_stop
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
HAND_DEG = 120.0
CLEAN_S = 10.0  # the line right again: a few idle polls (virtual time)
TURNED_DEG = 5.0  # the hand turned it further than any doubt's tolerance
NEAR_DEG = 0.5  # shown where it rests (the box's tenth of a degree, rounded)


def test_a_rotor_resting_somewhere_new_after_the_unwatched_stop_is_shown_there(
    rig: Rig,
) -> None:
    v = hand_after_the_unwatched_stop(rig, REST_DEG, HAND_DEG)
    rests = v.truth().az_deg
    assert abs(rests - REST_DEG) > TURNED_DEG, rests  # (the premise: somewhere new)
    assert v.status.bearing_deg == REST_DEG  # (the line bad: shown where it stood)
    v.to_host = None
    v.run_for(CLEAN_S)
    assert v.truth().az_deg == rests  # (still: nobody turned it since)
    assert v.status.state is MotionState.IDLE, v.status
    assert v.status.bearing_deg is not None, v.status
    assert abs(v.status.bearing_deg - rests) <= NEAR_DEG, (v.status.bearing_deg, rests)
