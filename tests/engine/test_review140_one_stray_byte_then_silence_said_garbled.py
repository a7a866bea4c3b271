"""Review 140 (1): a box that goes dead mid-turn (its power lost, a cable pulled at the box)
and whose line hands the host one stray byte as it goes (a NUL as the box's driver drops, an
0xFF as the line floats) is told as 'answers only garbled replies ... a noisy line?', where
b28cd556^ and b28cd556 itself told it as 'stopped answering (no valid reply for 3 s)'. The stop
goes at the same time in all three trees: what changed is the words on R/error that send the
owner to the line, not to the box's power and cable (review 99: one NUL as a box switched off
was told as the wrong baud rate). Since 51bc69b4 (link.py rule 11) formless junk mid-turn that
is mostly outside the model's reply alphabet, with no reply of its form in its exchange, marks
``_torn_t`` as it comes (``garbles``), and rule 2's words read ``torn_since_heard``: one lone
byte is enough, though rule 11 says a stray byte now and then is no answer and ``_tears``
counts no stray byte as a torn answer. A regression of the words (51bc69b4) on the models whose
codec hands a lone byte over as junk at once: Rotor-EZ, RT-21 (0x00 and 0xFF), MD-01 (0xFF;
its 0x00 is in its alphabet). GS-232, Easycomm, Prosistel and RC2800 still say 'stopped
answering'.

In virtual time: the emulated box turning from 20 to 300, watched; then one byte reaches the
host and nothing after it.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.engine.garblers import Garble, turning_for_a_burst
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
START_DEG = 20.0
WATCH_S = 30.0  # the silence, the stop and its words, with room (virtual time)


def one_byte_then_nothing(byte: bytes) -> Garble:
    """The box's next output reaches the host as ``byte`` alone; nothing after it."""
    sent = [False]

    def garble(data: bytes, now: float) -> bytes:
        if sent[0]:
            return b""
        sent[0] = True
        return byte

    return garble


@pytest.mark.parametrize(
    ("model", "byte"),
    [
        ("rotorez", b"\x00"),
        ("rotorez", b"\xff"),
        ("rt21", b"\x00"),
        ("rt21", b"\xff"),
        ("md01", b"\xff"),
    ],
)
def test_a_box_gone_dead_mid_turn_after_one_stray_byte_is_said_to_have_stopped_answering(
    rig: Rig, model: str, byte: bytes
) -> None:
    v = rig(model, emulator={"start_az_deg": START_DEG})
    t = turning_for_a_burst(v)
    v.to_host = one_byte_then_nothing(byte)
    v.run_for(WATCH_S)
    assert v.frames("stop", since=t)  # (all trees: stopped at the silence time)
    said = [e.message for e in v.errors(since=t) if "answer" in e.message and "/dev/" in e.message]
    assert said, "never said"
    assert "stopped answering" in said[0], said[0]  # observed: 'answers only garbled replies'
