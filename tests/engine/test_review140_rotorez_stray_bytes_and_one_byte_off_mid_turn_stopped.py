"""Review 140 (2): a Rotor-EZ (or RotorCard) turn under way on a line where a burst of
interference (the motor's, a relay's) puts three stray bytes in front of each answer and flips
the top bit of its ``;`` for 4.5 s is stopped short, its target dropped, 'answers only garbled
replies', 3.2-3.4 s into the burst. The box answered every poll at once, each answer whole and
a byte off (review 129's burst: such answers are the controller's, garbled, and a turn through
them reaches its target). At b28cd556^ it did here too, and at b28cd556 (each junk judged
alone: the stray bytes torn, the answer a byte off garbled). Since 51bc69b4 (link.py rule 11)
mid-turn formless junk with no reply of the controller's form in its exchange is torn past any
form, and ends no silence, when the exchange's junk so far is mostly outside the model's reply
alphabet: the answer a byte off (``\\xbb123``: three of its four bytes the alphabet's) is
counted together with the stray bytes in front of it (four alien of seven), so a burst of
answers the controller gave, whole, each a byte off, is silence now. Rotor-EZ's four-byte
answer tips with three stray bytes (two: 3 of 6, still of form); in a probe of the like (stray
bytes as the poll reaches the box, the first byte of each line off) RT-21, MD-01, GS-232,
Prosistel, RC2800 reach their target with up to eight. A regression of 51bc69b4 (b28cd556^
and b28cd556: garbled answers, the rotor at its target).

In virtual time: the emulated box turning from 20 to 300, watched, then the burst: three stray
bytes (0xFF 0xFE 0xFD) reach the host right in front of each answer, whose ``;`` has its top
bit set, for BURST_S.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.engine.garblers import Garble, reached_through_the_burst, turning_for_a_burst
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
START_DEG = 20.0
BURST_S = 4.5  # between one silence time (3 s) and two (virtual time)
WATCH_S = 120.0  # the rest of the turn, with room (virtual time)
STRAY = b"\xff\xfe\xfd"


def stray_bytes_and_semicolon_off(until: float) -> Garble:
    """Until ``until``, each ``;`` (a Rotor-EZ answer's first byte) reaches the host with its
    top bit set, STRAY in front of it; everything else as sent."""

    def garble(data: bytes, now: float) -> bytes:
        if now >= until:
            return data
        return data.replace(b";", STRAY + b"\xbb")

    return garble


@pytest.mark.parametrize("model", ["rotorez", "rotorcard"])
def test_a_turn_through_a_burst_of_stray_bytes_and_answers_a_byte_off_reaches_its_target(
    rig: Rig, model: str
) -> None:
    v = rig(model, emulator={"start_az_deg": START_DEG})
    t = turning_for_a_burst(v)
    v.to_host = stray_bytes_and_semicolon_off(t + BURST_S)
    v.run_for(WATCH_S)
    reached_through_the_burst(v, t)
