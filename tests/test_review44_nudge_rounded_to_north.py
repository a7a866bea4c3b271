"""Review 44 of e8e37c52 (pointing.py rule 2, ``_north_step``): a value a controller that
rounds is sent as north after its rounding goes to the end nearer the rotor's reading, on a
GS-232 as on a SatEL. A nudge is taken on the controller's own scale (rule 6: +10 at 350 is
360, 10 degrees on; it turns the way it names, never the other way round) and carries the end
it turns to (``Target.az_end_deg``) only where it lands on 0 or 360 exactly: one that lands a
fraction short of an end is judged as a bearing, and ``_north_step`` now sends it to the end
nearer where it started. A GS-232B at raw 100 nudged +259.6 (359.6, sent as 360 until
e8e37c52) goes out as ``M000``: the rotor turns 100 degrees back, against the nudge, to the
other end of its travel, where a nudge of -10 after it is refused as past the end; at raw 260,
-259.6 (0.4) goes out as 360. A box of tenths, at 100 nudged +259.96, the same. What a user
notices: the rotor turns the other way from the nudge and ends at the other end.
(Fixed: a nudge whose raw value is sent as an end after its rounding keeps it as its own
end, ``end``, pointing.py rule 6.)"""

from __future__ import annotations

import pytest

from bridge.core.model import MotionState, RotatorStatus
from bridge.pointing import Pointing, norm360
from bridge.protocols import REGISTRY


def _at(raw: float) -> RotatorStatus:
    return RotatorStatus("t", MotionState.IDLE, bearing_deg=norm360(raw), raw_bearing_deg=raw)


@pytest.mark.parametrize(
    ("model", "fraction"),
    [("gs232b", 0.4), ("gs232a", 0.4), ("rotorcard", 0.4), ("prosistel", 0.4)]
    + [("easycomm2", 0.04), ("rc2800", 0.04)],
)
def test_a_nudge_rounded_onto_an_end_goes_to_the_end_it_turns_to(
    model: str, fraction: float
) -> None:
    p = Pointing.of(REGISTRY[model])
    clockwise = 260.0 - fraction  # from 100 to a fraction short of 360
    sent = []
    for raw, step in ((100.0, clockwise), (260.0, -clockwise)):
        judged = p.judge(p.nudge(_at(raw), step, None), raw).az_deg
        assert judged is not None
        sent.append(p._sent(judged)[0])  # what the controller is sent
    assert sent == [360.0, 0.0], f"{model}: +{clockwise:g} at 100 and -{clockwise:g} at 260"
