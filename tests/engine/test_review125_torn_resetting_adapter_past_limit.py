"""Review 125: review 118's fix (ab41651b: the torn run goes on across a replug) stops a
garbled turn at the start before ``az_min_deg`` on an adapter that resets every 2 s (its
test), but not at other reset periods of the same fault. A GS-232B line that garbles every
byte (review 113's ``torn``) on an adapter reset every 1.5 s runs to 42, 18 degrees past
az_min_deg 60, its first stop 17.6 s in; a GS-232A azimuth box read at half rate (review
118's ``at_half_rate``) on an adapter reset every 1 s runs to the end of its turn at 5 (first
stop 26 s in), every 1.5 s to 30, every 2.5 s to 49; a GS-232B read at half rate every 1.5 s
to 42; an RC2800 every 1.5 s to 54 (torn) or 42 (half rate). Not a regression: at 51a2f016
the GS-232s and the half-rate RC2800 were never stopped, the torn RC2800 ran to 54 the same
(the fix is partial).

In virtual time: the emulated box turning from 150 to 5 when the bridge starts (a hand at
its panel); every byte
it sends reaches the host garbled; the port fails every ``up_s`` and reopens DOWN_S later
(the worker's reconnect_min_s).
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.engine.garblers import (
    AZ_MIN_DEG,
    START_DEG,
    WATCH_S,
    Garble,
    at_half_rate,
    opened_through,
    turning_at_the_start,
)
from tests.engine.resetting import lowest_az_resetting
from tests.engine.test_review113_every_byte_garbled_unwatched import torn
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


@pytest.mark.xfail(
    strict=True,
    reason=(
        "review 125: a turn whose every byte is garbled, on an adapter resetting every "
        "1-2.5 s (not 2 s), runs past az_min_deg, up to the end of its turn"
    ),
)
@pytest.mark.parametrize(
    ("model", "garble", "up_s"),
    [
        ("gs232b", "torn", 1.5),
        ("gs232a-az", "half rate", 1.0),
        ("gs232a-az", "half rate", 1.5),
        ("gs232a-az", "half rate", 2.5),
        ("gs232b", "half rate", 1.5),
        ("rc2800", "torn", 1.5),
        ("rc2800", "half rate", 1.5),
    ],
)
def test_a_garbled_turn_on_a_resetting_adapter_is_stopped_before_the_limit(
    rig: Rig, model: str, garble: str, up_s: float
) -> None:
    v = turning_at_the_start(rig, model, None)  # (a hand at the panel)
    garbler: Garble = torn if garble == "torn" else at_half_rate()
    t = opened_through(v, garbler)
    lowest = lowest_az_resetting(v, t + WATCH_S, START_DEG, up_s)
    stops = v.frames("stop", since=t)
    assert lowest >= AZ_MIN_DEG, (
        f"turned from {START_DEG:g} down to {lowest:g}, past az_min_deg {AZ_MIN_DEG:g}; "
        f"first stop frame at {stops[0].time_s - t if stops else None}"
    )
