"""Review 129: a controller once told 'does not answer' (silent at the bridge's start, then
answering) whose turn the port drops later, while it is silent again (its answers lost a
second before an adapter reset: the interference that resets the adapter), is never
stopped and nothing is said: the turn runs on unwatched to its end (300 here, its limits
and a stall unseen). Since ec5b8ce3 a silence carried across a replug is said once
(``_silence_reported`` kept at the connect when a silence is carried), but nothing clears
that flag when the controller answers again, so the 'never answered' path of the new
connection, which says 'does not answer' and stops the turn the port dropped
(controller.py rule 13), is skipped for good (and ``_never_t`` wakes no one). At dd1e5dce
the turn is stopped 3.5-4 s after the reset, at 95-98, and the words say so. A
regression (High: a turn no reading watches goes unstopped).

In virtual time: the emulated box silent at the start, then answering, turned from 20 to 300,
silent again SILENT_S before its adapter resets.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
START_DEG = 20.0
TARGET_DEG = 300.0
SILENT_START_S = 6.0  # silent at the start: 'does not answer' said (virtual time)
SETTLE_S = 90  # then answering, at rest (virtual time)
TURNING_S = 8.0  # the turn well under way, watched (virtual time, not a deadline)
SILENT_S = 1.0  # its answers lost this long before the reset (virtual time)
DOWN_S = 0.5  # the worker's reconnect_min_s: the port reopened this much later (virtual time)
WATCH_S = 40.0  # the silence on the new connection, and the rest of the turn (virtual time)
STOPPED_BY_DEG = 150.0  # stopped at the silence time: far short of the target


@pytest.mark.parametrize("model", ["gs232b", "rotorez", "easycomm3"])
def test_a_silent_turn_dropped_by_the_port_is_stopped_after_an_earlier_silence(
    rig: Rig, model: str
) -> None:
    v = rig(model, emulator={"start_az_deg": START_DEG}, connect=False)
    v.set_silent(True)
    v.link_up()
    v.run_for(SILENT_START_S)
    assert [e.message for e in v.errors()][-1:] == ["controller on /dev/ttyVIRTUAL does not answer"]
    v.set_silent(False)
    v.run_until_state(MotionState.IDLE, SETTLE_S)
    v.target(TARGET_DEG)
    v.run_for(TURNING_S)
    assert v.truth().is_moving
    v.set_silent(True)
    v.run_for(SILENT_S)
    t = v.now
    v.link_down("adapter reset")
    v.run_for(DOWN_S)
    v.link_up()
    v.run_for(WATCH_S)
    said = [e.message for e in v.errors(since=t) if "answer" in e.message]
    assert any("a stop sent" in why for why in said), said  # observed: nothing said
    assert v.frames("stop", since=t)  # observed: none
    assert v.truth().az_deg < STOPPED_BY_DEG  # observed: 300, the whole turn unwatched
