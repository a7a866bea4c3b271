"""Review 129: a controller that answers every poll, late (an RT-21 0.58 s after its poll, a
GS-232B 1.5 s after, as behind a serial server: link.py rule 12 waits for such answers and
keeps them online), turning to its target on an adapter that resets every 2-3 s, is told
'does not answer: the turn dropped with the port, not seen since, a stop sent' and its turn
is stopped short (at 56 or 83 of 170). Since ec5b8ce3 the silence goes on across a replug
(link.py rule 2, ``carry_silence``), but what rule 12 learned does not: each new link gives
its first poll up at the bare reply time, takes the late answer for no reading, and the
silence carried grows by that much at every replug until the lost turn's 'never answered'
path (controller.py ``_lost_silent``) stops it. At dd1e5dce the same turns reach 170 with
no stop and no such words. A regression.

In virtual time: the emulated box at rest, its answers late from then on, then turned from
20 to 170 while its port fails every UP_S and is reopened DOWN_S later for RESETS_S.
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
LATE_RUN_S = 10.0  # at rest with late answers, learned (virtual time, not a deadline)
DOWN_S = 0.5  # the worker's reconnect_min_s: the port reopened this much later (virtual time)
RESETS_S = 30.0  # the adapter resets this long into the turn (virtual time)
WATCH_S = 60.0  # the turn, with room (virtual time)
STEP_S = 0.05  # a step of virtual time between resets: not a deadline


@pytest.mark.parametrize(("model", "late_s", "up_s"), [("rt21", 0.58, 2.0), ("gs232b", 1.5, 3.0)])
def test_a_late_answering_turn_on_a_resetting_adapter_reaches_its_target(
    rig: Rig, model: str, late_s: float, up_s: float
) -> None:
    v = rig(model, emulator={"start_az_deg": START_DEG})
    v.run_until_state(MotionState.IDLE, SETTLE_S)
    v.answer_after(late_s)
    v.run_for(LATE_RUN_S)
    t = v.now
    v.target(TARGET_DEG)
    drop_t = v.now + up_s
    while v.now < t + WATCH_S:
        v.run_for(STEP_S)
        if v.now >= drop_t and v.now < t + RESETS_S:
            v.link_down("adapter reset")
            v.run_for(DOWN_S)
            v.link_up()
            drop_t = v.now + up_s
    said = [e.message for e in v.errors(since=t) if "answer" in e.message]
    assert said == [], said  # observed: 'does not answer: the turn dropped with the port, ...
    assert v.truth().az_deg == pytest.approx(TARGET_DEG, abs=1.0)  # observed: 56, 83
