"""Review 136 (2): the words on R/error for the offline of review 136 (1), the line staying so:
a box that answers every poll mid-turn at once, each answer whole and of its form, each
followed by one stray byte (0xFF), is taken offline with 'controller ... stopped answering (no
valid reply for 3 s) while the rotor turned to its target', as a box switched off or a cable
pulled. At b28cd556^ the same line was told as it is, 'answers only garbled replies (no valid
reply for 6 s) ... a noisy line?'. Since b28cd556 (link.py rule 11) the stray byte, mid-turn,
is junk torn past any form (mostly outside the reply alphabet) and the exchange it spoiled
counts as silence; but the controller answered, and the owner is sent to the cable and the
power instead of the noise (and the answers it sent are not what 'torn' means: rule 11's torn
answer forms no reply, these each formed one). A regression of the words.

In virtual time: the emulated box turning from 20 to 300, watched, then for good 0xFF after the
last byte of each answer (review 136 (1)'s garbler).
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.engine.garblers import turning_for_a_burst
from tests.engine.test_review136_stray_byte_after_each_answer_mid_turn_stopped import (
    START_DEG,
    stray_byte_after_each_answer,
)
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
WATCH_S = 30.0  # the offline and its words, with room (virtual time)


@pytest.mark.parametrize("model", ["rt21", "prosistel", "rotorez"])
def test_a_box_answering_whole_replies_each_with_a_stray_byte_is_not_said_silent(
    rig: Rig, model: str
) -> None:
    v = rig(model, emulator={"start_az_deg": START_DEG})
    t = turning_for_a_burst(v)
    v.to_host = stray_byte_after_each_answer(model, float("inf"))
    v.run_for(WATCH_S)
    said = [e.message for e in v.errors(since=t) if "valid reply for" in e.message]
    assert said, "never taken offline"  # (both trees: the line stays bad)
    assert "stopped answering" not in said[0] and "garbled" in said[0], said[0]
