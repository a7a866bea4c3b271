"""Review 105: a line that goes bad in the first second and a half after a clean start is asked
at the moving rate for as long as the bridge runs.

motion.py rule 4 asks a bridge just started at the moving rate until readings at rest for each
axis's ``axis_seen_s`` say whether a turn was under way (``found_unjudged``; controller.py
``poll``'s ``busy``). Those readings must be taken: where the line goes bad (a failing position
sensor, a cable knocked) before they are, every reading after is doubted (rule 9), none is
taken, the restart's turn is never judged, and a GS-232B is asked about 400 times a minute for
good, where the same failure two seconds after the start is asked at the idle rate (about 80
a minute: "Readings at rest that go on disagreeing ... are asked for at the usual polls").

In virtual time: the emulated GS-232B at rest at 150, a clean start; from the moment the
rotator is shown idle (or two seconds later), each ``1`` it sends reaches the host as the next
of ``2``, ``3``, ``4``, ``0`` (150 reads 250, 350, 450, 50: no two agree).
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.test_review105_first_readings_polled_at_the_moving_rate_forever import (
    asked_in_a_minute,
    failing,
)
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
ONLINE_S = 30.0  # a clean start (virtual time)
LATER_S = 2.0  # the start's turn judged by then (GS-232B: its axis_seen_s, and a poll)


def polled_after_failing(rig: Rig, after_s: float) -> int:
    v = rig("gs232b-az", emulator={"start_az_deg": 150.0})
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, ONLINE_S, "online")
    v.run_for(after_s)  # (a quiet period: not a deadline)
    v.to_host = failing()
    return asked_in_a_minute(v)


@pytest.mark.xfail(
    strict=True,
    reason="review 105: a GS-232B whose readings go bad as it is first shown idle is asked at "
    "the moving rate for good: about 400 queries a minute, 80 if they go bad 2 s later",
)
def test_a_line_gone_bad_before_the_start_was_judged_is_not_polled_at_the_moving_rate_for_good(
    rig: Rig,
) -> None:
    later = polled_after_failing(rig, LATER_S)
    at_once = polled_after_failing(rig, 0.0)
    assert at_once <= 2 * later, (at_once, later)
