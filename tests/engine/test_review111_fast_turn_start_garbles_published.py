"""Review 111: a fast turn confirmed at the start on its line has every garbled answer for the
rest of that turn published as the bearing.

controller.py rule 9: mid-turn a reading further from the last taken than the rotor can have
turned is asked again at once (``_doubts_turning``: "a flipped digit mid-turn was published for
one poll on seven models"). A connection's first readings taken as a turn on their line
(FIRST_TURN_READINGS, ``_steady``) set ``_turn_trusted``: "the turn's readings trusted till it
rests", so none of that turn's answers is doubted, even on a rotor configured for the speed it
turns at, whose garbles a start at rest would have caught. A SPID Rot2Prog configured for its
30 deg/s, turned by hand from 10 to 300 when the bridge opens its port: its sixth answer, 100
degrees off, is published as the bearing, 10.5 with the rotor at 119.5, and fed to the motion
as a move back and forth. A regression of 2c285cc4: before it (753e06b6) the allowance of the
configured speed confirmed such a turn on two first answers, not on its line, and its garbles
were doubted as any turn's (this test passes there).

In virtual time: the emulated Rot2Prog (``az_speed_deg_s`` 30, and so configured) turning by
hand from 10 to 300 when the bridge opens its port; its sixth position frame reaches the host
100 degrees low; the rest as sent.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.engine.garblers import frames_off
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
FAST_DEG_S = 30.0  # as review 100's fast rotor, here also configured
FROM_DEG = 10.0
HAND_TO_DEG = 300.0
SIXTH_OFF = [0.0, 0.0, 0.0, 0.0, 0.0, -100.0]  # the sixth frame 100 degrees low
UNDER_WAY_S = 0.5  # the hand's turn under way before the port opens (not a deadline)
TURN_S = 20.0  # 290 degrees at 30 deg/s, with room (virtual time)
BACK_DEG = 5.0  # a turn upwards never reads this far below what it read before


@pytest.mark.xfail(
    strict=True,
    reason="review 111: a Rot2Prog turning at 30 deg/s at the start, confirmed on its line, "
    "has its sixth answer, 100 degrees off, published as the bearing (10.5 at 119.5)",
)
def test_a_garbled_answer_of_a_fast_turn_confirmed_at_the_start_is_never_published(
    rig: Rig,
) -> None:
    v = rig(
        "rot2prog",
        emulator={"start_az_deg": FROM_DEG, "az_speed_deg_s": FAST_DEG_S},
        settings={"az_speed_deg_s": FAST_DEG_S},
        connect=False,
    )
    v.manual_rotate(HAND_TO_DEG)
    v.run_for(UNDER_WAY_S)
    t = v.now
    v.to_host = frames_off(SIXTH_OFF)
    v.link_up()
    v.run_until(lambda h: not h.truth().is_moving, TURN_S, "the turn ends")
    shown = [s.bearing_deg for s in v.published(since=t) if s.bearing_deg is not None]
    highest = shown[0] if shown else None
    for bearing in shown:
        assert highest is not None and bearing >= highest - BACK_DEG, (
            f"published {bearing:g} after {highest:g} on a turn upwards: {shown}"
        )
        highest = max(highest, bearing)
    assert len(shown) > 1, shown  # (the turn was shown)
