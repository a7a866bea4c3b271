"""Review 136 (4): an RT-21 read at half rate (review 118/125's ``at_half_rate``: a box at
twice the host's baud rate, every second byte read, as another) is told as a silent box: mid-turn
'controller ... stopped answering (no valid reply for 3 s)', and on a turn the port dropped
and that comes back so 'does not answer: the turn dropped with the port'. At b28cd556^ both
were told as they are, 'answers only garbled replies' ('... the wrong baud rate or model, or
a noisy line?' after the replug), as every other model's half-rate line still is (Rotor-EZ,
MD-01, Prosistel, Easycomm) and as the same RT-21 line XORed with 0x5A is. Since b28cd556
(link.py rule 11) the half-rate junk, mid-turn and all outside the RT-21's reply alphabet, is
no garbled answer; nor, by the words, are its exchanges judged torn at their deadlines
(``_tears``; not traced further: three bytes read of each six-byte answer), so the offline
is silence's. The owner is sent to the cable and the power, not to the baud rate (attack 30's
defect, 'the wrong baud rate told as a cable', back on this model). A regression of the
words.

In virtual time: the emulated RT-21 turning from 20 to 300, watched; then (at once, or after
its port was pulled for 1 s and plugged back) every byte it sends read at half rate.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.garblers import at_half_rate
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
START_DEG = 20.0
TARGET_DEG = 300.0
SETTLE_S = 60  # for the first readings to be taken, at rest (virtual time)
TURNING_S = 5.0  # the turn under way, watched (virtual time, not a deadline)
OUT_S = 1.0  # the adapter out (virtual time)
WATCH_S = 30.0  # the offline and its words, with room (virtual time)


@pytest.mark.parametrize("replugged", [False, True], ids=["mid-turn", "lost turn"])
def test_an_rt21_read_at_half_rate_is_said_to_answer_garbled(rig: Rig, replugged: bool) -> None:
    v = rig("rt21", emulator={"start_az_deg": START_DEG})
    v.run_until_state(MotionState.IDLE, SETTLE_S)
    v.target(TARGET_DEG)
    v.run_for(TURNING_S)
    if replugged:
        v.link_down()
        v.run_for(OUT_S)
    assert v.truth().is_moving
    t = v.now
    v.to_host = at_half_rate()
    if replugged:
        v.link_up()
    v.run_for(WATCH_S)
    said = [e.message for e in v.errors(since=t) if "answer" in e.message and "/dev/" in e.message]
    assert said, "never taken offline"  # (both trees: the line stays bad)
    assert "garbled" in said[0], said[0]  # observed: 'stopped answering' / 'does not answer'
