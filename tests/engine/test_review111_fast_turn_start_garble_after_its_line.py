"""Review 111: a fast turn at the start, confirmed on its line, is shown idle where it was
confirmed for the rest of the turn when the very next answer is garbled.

controller.py rule 9: FIRST_TURN_READINGS (four) first readings on one steady line are a turn;
the last is taken, and "the next reading that goes on with it too" (``_steady_from``: one
reading's chance). Commit 2c285cc4 promises a fast turn confirmed within four answers, eight
with one garble. When the one garble is the fifth answer, the one that was to go on with the
line, the turn's chance is spent: the readings go to the doubt at rest, which compares each
with the one before within ``doubt_deg`` (5) alone, and a rotor stepping 14 degrees an exchange
never has two agree. A SPID Rot2Prog configured for its 30 deg/s, turned by hand from 10 to 300
when the bridge opens its port, is shown "idle" at 82.5 from two seconds in until it rests at
300 sixteen seconds later, R/error blaming "a noisy line or a failing position sensor"; on a
clean line, or with the garble one answer earlier, it is shown moving. A regression of
2c285cc4: before it (753e06b6) the allowance of the configured speed between two first readings
confirmed such a turn on two answers and its turn was doubted as any (this test passes there).

In virtual time: the emulated Rot2Prog (``az_speed_deg_s`` 30, and so configured) turning by
hand from 10 to 300 when the bridge opens its port; its fifth position frame reaches the host
100 degrees off; the rest as sent.
"""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState
from tests.engine.garblers import frames_off
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
FAST_DEG_S = 30.0  # as review 100's fast rotor, here also configured
FROM_DEG = 10.0
HAND_TO_DEG = 300.0
MIDWAY_DEG = 200.0
FIFTH_OFF = [0.0, 0.0, 0.0, 0.0, 100.0]  # the fifth frame off, the first four a clean line
UNDER_WAY_S = 0.5  # the hand's turn under way before the port opens (not a deadline)
TURN_S = 20.0  # 290 degrees at 30 deg/s, with room (virtual time)
NEAR_DEG = 30.0  # a second of the turn: what a reading a poll old can be behind


def test_a_fast_turn_at_the_start_garbled_after_its_line_is_shown_turning(rig: Rig) -> None:
    v = rig(
        "rot2prog",
        emulator={"start_az_deg": FROM_DEG, "az_speed_deg_s": FAST_DEG_S},
        settings={"az_speed_deg_s": FAST_DEG_S},
        connect=False,
    )
    v.manual_rotate(HAND_TO_DEG)
    v.run_for(UNDER_WAY_S)
    v.to_host = frames_off(FIFTH_OFF)
    v.link_up()
    v.run_until(lambda h: h.truth().az_deg >= MIDWAY_DEG, TURN_S, "the turn midway")
    assert v.truth().is_moving
    shown = v.status
    assert shown.state is MotionState.MOVING and shown.bearing_deg is not None, shown.state
    assert abs(shown.bearing_deg - v.truth().az_deg) <= NEAR_DEG, (
        f"shown {shown.state.value} at {shown.bearing_deg:g} with the rotor at "
        f"{v.truth().az_deg:g}; said {[e.message for e in v.errors()]}"
    )
