"""Review 129: a turn under way on a line where a burst of interference (the motor's, a
relay's) flips one bit of each answer for 4.5 s is stopped short and its target dropped,
'answers only garbled replies', 3.4-3.6 s into the burst. The box answered every poll at
once, each answer whole, of its form (``AZ=...  EL=...``), one byte off. Since 9f1e2bcd
(link.py rule 2) junk the codec calls NOISE or SPOILED, mid-turn, is taken as torn past any
form and ends no silence; but a reading with one byte flipped is such junk too, so a burst of
them is silence now, where at dd1e5dce it kept the turn online up to twice the silence time
(GARBLED_SILENCE_FACTOR) and the rotor reached its target. A regression. Sweeps with every
byte flipped at random (seeded): RC2800 at 1 % of bytes, 7 of 25 turns from 20 to 300
stopped short (0 of 25 at dd1e5dce); GS-232B at 2 %, 4 of 25 (0 of 25).

In virtual time: the emulated box turning from 20 to 300, watched, then the burst: the first
byte of each answer line with its top bit set, for BURST_S.
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


def first_byte_of_each_line_off(until: float) -> Garble:
    """Until ``until``, the first byte of each answer line (after a CR or LF) reaches the
    host with its top bit set (a bit flipped on the line); everything else as sent."""
    at_start = [False]

    def garble(data: bytes, now: float) -> bytes:
        out = bytearray()
        for byte in data:
            if at_start[0] and byte not in b"\r\n" and now < until:
                byte |= 0x80
                at_start[0] = False
            if byte in b"\r\n":
                at_start[0] = True
            out.append(byte)
        return bytes(out)

    return garble


@pytest.mark.parametrize("model", ["gs232b", "rc2800", "prosistel"])
def test_a_turn_through_a_burst_of_answers_one_byte_off_reaches_its_target(
    rig: Rig, model: str
) -> None:
    v = rig(model, emulator={"start_az_deg": START_DEG})
    t = turning_for_a_burst(v)
    v.to_host = first_byte_of_each_line_off(t + BURST_S)
    v.run_for(WATCH_S)
    reached_through_the_burst(v, t)
