"""Review 143 (1): a box that goes dead mid-turn (its power lost, a cable pulled at the box)
and whose line hands the host a few stray bytes as it goes (two on a Rotor-EZ, three on an
RT-21, six on an MD-01, a short junk line on Easycomm and Prosistel: a relay's or the supply's
burst as the box drops) is told as 'answers only garbled
replies ... a noisy line?', where b28cd556^ told it as 'stopped answering (no valid reply for
3 s)'. The stop goes at the same time in both trees: what changed is the words on R/error,
which send the owner to the line, not to the box's power and cable. db323d25 (link.py rule 11)
fixed review 140 (1) for one stray byte only: ``garbles`` marks ``_torn_t`` once the
exchange's formless junk reaches TORN_SHARE of the least reply bytes (2 on a Rotor-EZ, 3 on an
RT-21, 6 on an MD-01 or an Easycomm), in one exchange, where ``_tears`` (and b28cd556^)
tells an exchange as torn only when two in a row, together, read a whole reply's bytes with
none formed. A regression of the words
(51bc69b4, narrowed by db323d25).

In virtual time: the emulated box turning from 20 to 300, watched; then a few bytes reach the
host and nothing after them.
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
WATCH_S = 30.0  # the silence, the stop and its words, with room (virtual time)


def junk_then_nothing(junk: bytes) -> Garble:
    """The box's next output reaches the host as ``junk`` alone; nothing after it."""
    sent = [False]

    def garble(data: bytes, now: float) -> bytes:
        if sent[0]:
            return b""
        sent[0] = True
        return junk

    return garble


@pytest.mark.parametrize(
    ("model", "junk"),
    [
        ("rotorez", b"\xff\xfe"),
        ("rotorez", b"\x00\x00"),
        ("rt21", b"\xff\xfe\xfd"),
        ("rt21", b"\xff\xfe;"),
        ("md01", b"\xff\xfe\xfd\xfc\xfb\xfa"),
        ("easycomm2", b"\xff\xfe\xfd\xfc\xfb\xfa\n"),
        ("prosistel", b"\xff\xfe\xfd\xfc\xfb\r"),
    ],
)
def test_a_box_gone_dead_mid_turn_after_a_few_stray_bytes_is_said_to_have_stopped_answering(
    rig: Rig, model: str, junk: bytes
) -> None:
    v = rig(model, emulator={"start_az_deg": START_DEG})
    v.run_until_state(MotionState.IDLE, SETTLE_S)
    v.target(TARGET_DEG)
    v.run_for(TURNING_S)
    assert v.truth().is_moving
    t = v.now
    v.to_host = junk_then_nothing(junk)
    v.run_for(WATCH_S)
    assert v.frames("stop", since=t)  # (both trees: stopped at the silence time)
    said = [e.message for e in v.errors(since=t) if "answer" in e.message and "/dev/" in e.message]
    assert said, "never said"
    assert "stopped answering" in said[0], said[0]  # observed: 'answers only garbled replies'
