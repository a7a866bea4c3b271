"""Review 143 (2): a Rotor-EZ (or RotorCard) turn under way on a line where a burst of
interference (the motor's, a relay's) flips the top bit of one digit of each answer and puts
three stray bytes right behind it for 4.5 s is stopped short, its target dropped, 'answers only
garbled replies', 3.2-3.4 s into the burst. The box answered every poll at once, each answer
whole and a byte off (review 129: such answers are the controller's, garbled, and a turn
through them reaches its target); b28cd556^ took them so and the rotor reached its target.
Rotor-EZ's codec hands the answer and the stray bytes behind it over as one junk
(``;\\xb081\\xff\\xfe\\xfd``): three of its seven bytes the reply alphabet, so since b28cd556
(link.py rule 11, and db323d25's 'a piece mostly the alphabet') it is torn past any form and
ends no silence. Review 140 (2) was fixed for stray bytes in front of an answer whose ``;`` is
off (separate pieces); behind it, in the same piece, the regression stays (two stray bytes:
still garbled; three or more: torn).

In virtual time: the emulated box turning from 20 to 300, watched, then the burst: the first
digit of each answer (the byte after its ``;``) with its top bit set and STRAY right behind
the answer's last digit, for BURST_S.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.garblers import Garble
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
START_DEG = 20.0
TARGET_DEG = 300.0
SETTLE_S = 60  # for the first readings to be taken, at rest (virtual time)
TURNING_S = 10.0  # the turn well under way, watched (virtual time, not a deadline)
BURST_S = 4.5  # between one silence time (3 s) and two (virtual time)
WATCH_S = 120.0  # the rest of the turn, with room (virtual time)
STRAY = b"\xff\xfe\xfd"


def digit_off_and_stray_bytes_after(until: float) -> Garble:
    """Until ``until``, the first digit of each ``;ddd`` answer reaches the host with its top
    bit set, and STRAY right behind its third digit; everything else as sent."""
    digits = [-1]  # digits of a ``;ddd`` answer so far (-1: none begun)

    def garble(data: bytes, now: float) -> bytes:
        out = bytearray()
        for byte in data:
            if now >= until:
                out.append(byte)
                continue
            if byte == 0x3B:
                digits[0] = 0
                out.append(byte)
                continue
            if digits[0] < 0:
                out.append(byte)
                continue
            digits[0] += 1
            out.append(byte | 0x80 if digits[0] == 1 else byte)
            if digits[0] == 3:
                out += STRAY
                digits[0] = -1
        return bytes(out)

    return garble


@pytest.mark.parametrize("model", ["rotorez", "rotorcard"])
def test_a_turn_through_answers_a_digit_off_with_stray_bytes_behind_reaches_its_target(
    rig: Rig, model: str
) -> None:
    v = rig(model, emulator={"start_az_deg": START_DEG})
    v.run_until_state(MotionState.IDLE, SETTLE_S)
    v.target(TARGET_DEG)
    v.run_for(TURNING_S)
    assert v.truth().is_moving
    t = v.now
    v.to_host = digit_off_and_stray_bytes_after(t + BURST_S)
    v.run_for(WATCH_S)
    said = [e.message for e in v.errors(since=t) if "answer" in e.message]
    assert said == [], said  # observed: 'answers only garbled replies (no valid reply for 3.2 s)
    assert not v.frames("stop", since=t)  # observed: stopped 3.2-3.4 s into the burst
    assert v.truth().az_deg == pytest.approx(TARGET_DEG, abs=1.0)  # observed: 91-99
