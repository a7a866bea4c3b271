"""Review 129: a turn under way whose controller's answers are lost for SILENT_S (just short
of its 3 s silence time: still online, the turn watched) before the adapter resets, and
which answers at once when the port is back, is stopped 6-23 ms into the new connection,
before its first poll can be answered, and the target dropped: 'does not answer: the turn
dropped with the port, not seen since, a stop sent'. Its readings back would have followed
the turn to its end (controller.py rule 13). Since ec5b8ce3 the silence goes on across the
replug and the lost turn's 'never answered' path stops it at the silence's end without
waiting for the answer owed (``_lost_silent``); on one connection rule 2 would have asked
once more and let that answer decide (``ask_verdict``). At dd1e5dce the turn reaches its
target, nothing said. A regression.

In virtual time: the emulated box turning from 20 to 170, watched; its answers lost for
SILENT_S, then its adapter reset, the line good again when the port reopens.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
START_DEG = 20.0
TARGET_DEG = 170.0
SETTLE_S = 90  # for the first readings to be taken, at rest (virtual time)
TURNING_S = 4.0  # the turn under way, watched (virtual time, not a deadline)
SILENT_S = 2.95  # its answers lost this long before the reset: short of 3 s (virtual time)
DOWN_S = 0.5  # the worker's reconnect_min_s: the port reopened this much later (virtual time)
WATCH_S = 60.0  # the rest of the turn, with room (virtual time)


@pytest.mark.parametrize("model", ["gs232b", "rotorez", "rt21", "prosistel"])
def test_a_turn_answered_at_once_after_a_replug_reaches_its_target(rig: Rig, model: str) -> None:
    v = rig(model, emulator={"start_az_deg": START_DEG})
    v.run_until_state(MotionState.IDLE, SETTLE_S)
    v.target(TARGET_DEG)
    v.run_for(TURNING_S)
    v.set_silent(True)
    v.run_for(SILENT_S)
    assert v.status.available and v.truth().is_moving  # (still online, turning)
    t = v.now
    v.link_down("adapter reset")
    v.run_for(DOWN_S)
    v.set_silent(False)
    v.link_up()
    v.run_for(WATCH_S)
    said = [e.message for e in v.errors(since=t) if "answer" in e.message]
    assert said == [], said  # observed: 'does not answer: the turn dropped with the port, ...'
    assert not v.frames("stop", since=t)  # observed: stopped 6-23 ms after the replug
    assert v.truth().az_deg == pytest.approx(TARGET_DEG, abs=1.0)  # observed: 65
