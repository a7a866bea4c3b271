"""The session as the worker's loop sees it: the line takes time, and a wakeup is worth one.

worker.py sleeps in select() until ``session.next_wakeup()`` and then ticks the session. A
wakeup at which the session then finds nothing to do (its own check says "not yet") sends the
loop straight back round with a zero timeout until the clock has moved on: a busy loop, short on
a fine clock, as long as the clock's grain on a coarse one. The virtual line counts those turns
(tests/engine/virtual.py rule 4).
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


def test_bytes_take_their_time_on_the_line(rig: Rig) -> None:
    """The harness itself: a frame reaches the controller 10 bits a byte after it was written."""
    v = rig("rotorez")
    v.run_until_state(MotionState.IDLE, 30)
    v.target(100)
    v.run_for(1)
    [written] = [w for w in v.writes if w.data.startswith(b"AP1")]
    [heard] = [f for f in v.device.log if f.data.startswith(b"AP1")]
    on_the_line_s = len(written.data) * 10 / v.cfg.baud
    assert heard.time_s >= written.t + on_the_line_s - 1e-9
    assert heard.time_s <= written.t + on_the_line_s + 4 * 10 / v.cfg.baud  # maybe behind a poll


@pytest.mark.parametrize(
    ("model", "why"),
    [
        ("rotorez", "the version banner after connecting is judged once the line is quiet"),
        ("satel", "every report ends in blank lines, judged once the line is quiet"),
    ],
)
def test_no_wakeup_is_spent_for_nothing(rig: Rig, model: str, why: str) -> None:
    v = rig(model)
    v.run_for(60)
    assert v.spins == [], f"{why}: the loop spun at t={v.spins[:5]}"
