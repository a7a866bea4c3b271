"""Review 136 (3): a turn the port dropped (controller.py rule 13's lost turn, ``_lost_aim``)
whose line comes back garbling every byte (or read at half rate) is stopped later than before:
Rotor-EZ 2.95 s after the reconnect (b28cd556^: 2.05 s), RT-21 3.05-3.25 s (2.45 s), MD-01
3.1 s (2.7 s); a Rotor-EZ's rotor at 73 (68), an RT-21's at 74-75 (70). b28cd556 passes
``turn`` to link.py rule 11 for a lost turn too (``self.turning() or self._lost_aim is not
None``): its torn junk, mostly outside the reply
alphabet, is no garbled answer any more, so the first readings after the replug no longer count
it toward controller.py rule 9's unwatched stop (``poll_garbled``), which stopped the turn
before; the turn now waits for rule 2's silence. The change meant to bring a turn's stop on
such a line forward (review 125) puts it back here. A regression (the parent stopped it
sooner on every one of these models; GS-232, Easycomm, RC2800, Prosistel: the same in both).

In virtual time: the emulated box turning from 20 to 300, watched, its port pulled for 1 s;
from the reconnect every byte it sends reaches the host XORed with 0x5A (review 113's ``torn``)
or at half rate (``at_half_rate``).
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.garblers import at_half_rate
from tests.engine.test_review113_every_byte_garbled_unwatched import torn
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
START_DEG = 20.0
TARGET_DEG = 300.0
SETTLE_S = 60  # for the first readings to be taken, at rest (virtual time)
TURNING_S = 5.0  # the turn under way, watched (virtual time, not a deadline)
OUT_S = 1.0  # the adapter out (virtual time)
WATCH_S = 30.0  # the first stop, with room (virtual time)
STEP_S = 0.05  # a step of virtual time to see the first stop: not a deadline
BEFORE_S = 2.8  # b28cd556^'s first stop at the latest (2.05-2.7 s), with room


@pytest.mark.parametrize("line", ["torn", "half rate"])
@pytest.mark.parametrize("model", ["rotorez", "rt21", "md01"])
def test_a_lost_turn_on_a_line_torn_after_the_replug_is_stopped_as_soon_as_before(
    rig: Rig, model: str, line: str
) -> None:
    v = rig(model, emulator={"start_az_deg": START_DEG})
    v.run_until_state(MotionState.IDLE, SETTLE_S)
    v.target(TARGET_DEG)
    v.run_for(TURNING_S)
    v.link_down()
    v.run_for(OUT_S)
    assert v.truth().is_moving  # (the turn goes on with the port out)
    t = v.now
    v.to_host = torn if line == "torn" else at_half_rate()
    v.link_up()
    while v.now < t + WATCH_S and not v.frames("stop", since=t):
        v.run_for(STEP_S)
    stop_s = v.now - t
    assert v.frames("stop", since=t), "no stop"
    assert stop_s <= BEFORE_S, (
        f"first stop {stop_s:.2f} s after the reconnect, the rotor at {v.truth().az_deg:.0f}"
    )
