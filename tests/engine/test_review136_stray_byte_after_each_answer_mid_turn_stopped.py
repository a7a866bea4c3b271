"""Review 136 (1): a turn under way on a line where a burst of interference (a relay's, the
motor's) puts one stray byte (0xFF) right behind each answer for 4.5 s is stopped short, its
target dropped, 'stopped answering (no valid reply for 3 s)', 3.3-3.5 s into the burst. The
box answered every poll at once, each answer whole and of its form; the stray byte, in the
same exchange, spoils the reading held (link.py rule 9), as it did before. Since b28cd556
(link.py rule 11) junk that forms no reply mid-turn and is mostly outside the model's reply
alphabet is taken as an answer torn past any form and ends no silence: the lone 0xFF is such
junk, so a burst of whole answers each followed by one stray byte is silence now, where at
b28cd556^ it was the controller's answer, garbled (GARBLED_SILENCE_FACTOR), and the rotor
reached its target. A regression, on the models whose codec hands the stray byte over as junk
of its own (RT-21: at once; Rotor-EZ: outside a ``;ddd`` frame; MD-01: outside a frame;
Prosistel: a line's noise before its STX); on the GS-232, Easycomm and RC2800 lines it goes
in front of the next line and makes that reading untrusted, which is garbled as before. The
same byte in front of each answer (in its exchange) stops a Rotor-EZ's and a Prosistel's turn
too (a Rotor-EZ's ``;ddd`` after it is untrusted but harmless: known junk).

In virtual time: the emulated box turning from 20 to 300, watched, then the burst: 0xFF after
the last byte of each answer, for BURST_S.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.engine.garblers import Garble, reached_through_the_burst, turning_for_a_burst
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
START_DEG = 20.0
BURST_S = 4.5  # between one silence time (3 s) and two (virtual time)
WATCH_S = 330.0  # the rest of the turn, with room (an MD-01 at 1 deg/s; virtual time)
STRAY = b"\xff"


def stray_byte_after_each_answer(model: str, until: float) -> Garble:
    """Until ``until``, one STRAY byte reaches the host right behind the last byte of each of
    ``model``'s answers (RT-21: its ``;``; Rotor-EZ: the third digit of ``;ddd``; MD-01: its
    frame's closing 0x20; Prosistel: its CR); everything else as sent."""
    end = {"rt21": 0x3B, "md01": 0x20}.get(model, 0x0D)
    digits = [-1]  # Rotor-EZ: digits of a ``;ddd`` frame so far (-1: none begun)

    def garble(data: bytes, now: float) -> bytes:
        out = bytearray()
        for byte in data:
            out.append(byte)
            if now >= until:
                continue
            if model == "rotorez":
                if byte == 0x3B:
                    digits[0] = 0
                elif digits[0] >= 0:
                    digits[0] += 1
                    if digits[0] == 3:
                        out += STRAY
                        digits[0] = -1
            elif byte == end:
                out += STRAY
        return bytes(out)

    return garble


@pytest.mark.parametrize("model", ["rt21", "prosistel", "prosistel-combi", "rotorez", "md01"])
def test_a_turn_through_a_burst_of_answers_each_followed_by_a_stray_byte_reaches_its_target(
    rig: Rig, model: str
) -> None:
    v = rig(model, emulator={"start_az_deg": START_DEG})
    t = turning_for_a_burst(v)
    v.to_host = stray_byte_after_each_answer(model.split("-")[0], t + BURST_S)
    v.run_for(WATCH_S)
    reached_through_the_burst(v, t)


def stray_byte_before_each_answer(model: str, until: float) -> Garble:
    """Until ``until``, one STRAY byte reaches the host right in front of the first byte of
    each of ``model``'s answers (Rotor-EZ: its ``;``; Prosistel: its STX); everything else as
    sent."""
    first = 0x3B if model == "rotorez" else 0x02

    def garble(data: bytes, now: float) -> bytes:
        out = bytearray()
        for byte in data:
            if byte == first and now < until:
                out += STRAY
            out.append(byte)
        return bytes(out)

    return garble


@pytest.mark.parametrize("model", ["prosistel", "prosistel-combi", "rotorez"])
def test_a_turn_through_a_burst_of_answers_each_after_a_stray_byte_reaches_its_target(
    rig: Rig, model: str
) -> None:
    v = rig(model, emulator={"start_az_deg": START_DEG})
    t = turning_for_a_burst(v)
    v.to_host = stray_byte_before_each_answer(model.split("-")[0], t + BURST_S)
    v.run_for(WATCH_S)
    reached_through_the_burst(v, t)
