"""Review 115's guard (motion.py rule 2: what tells a carried axis's turn from a jam): a reading
one step off where an axis stood is no move by itself, and a creep or a drift slower than
CREEP_SHARE of the axis's slowest turn is none either. A healthy turn at the slowest speed rule
6 allows for (nominal over BLIND_SLOW_FACTOR), read in whole degrees with 2 degrees of noise
(a GS-232B: a move past the noise only every 3 degrees), carried over a replug, must still be
left to finish: no stop, no R/error, the rotor at the target it was sent. On a 450-degree rotor,
the azimuth across 360 and past it, and an elevation-only turn; the adapter out once or twice, long
enough for the readings back to meet the turns at each phase of a step."""

from __future__ import annotations

import pytest

from bridge.core.model import ErrorKind, MotionState
from bridge.session import motion as mo
from tests.engine.carried import replugged
from tests.engine.virtual import VirtualRotator

MODEL = "gs232b-450"
START_AZ = 420.0  # (raw: 60 true, past 360 on the 450-degree scale)
START_EL = 0.0


def slowest(model: str) -> dict[str, float]:
    """The speeds each axis turns at its slowest, as rule 6 allows for (motion.py)."""
    with VirtualRotator(model) as v:
        return mo.slowest_deg_s(v.cfg.motion)


@pytest.mark.parametrize("replugs", [1, 2])  # (the lost target kept over a second one)
@pytest.mark.parametrize("out_s", [2.0, 2.15, 2.3, 2.45])  # (a step's phases: not deadlines)
@pytest.mark.parametrize(("az", "el"), [(300.0, 40.0), (None, 60.0)])  # (across 360; el alone)
def test_a_turn_at_the_slowest_speeds_carried_over_a_replug_is_left_to_finish(
    az: float | None, el: float, out_s: float, replugs: int
) -> None:
    speeds = slowest(MODEL)
    emulator = {
        "start_az_deg": START_AZ,
        "start_el_deg": START_EL,
        "az_speed_deg_s": speeds["azimuth"],
        "el_speed_deg_s": speeds["elevation"],
    }
    with VirtualRotator(MODEL, emulator=emulator) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.run_until(lambda h: h.state is MotionState.IDLE, 30, "at rest")
        v.target(az, el)
        v.run_until(lambda h: h.truth().el_deg >= 10.0, 60, "the elevation turning")
        for _ in range(replugs):
            replugged(v, out_s)
            v.run_for(1.0)  # (its readings back: not a deadline)
        assert v.truth().is_moving  # it finishes its old turn by itself
        t = v.now
        v.run_until(lambda h: not h.truth().is_moving, 120, "the turn over")
        v.run_for(10.0)  # (its rest told: not a deadline)
        assert [e.message for e in v.errors(ErrorKind.STOP, since=t)] == []
        assert "stop" not in {f.outcome for f in v.frames(since=t)}
        assert v.truth().el_deg == pytest.approx(el, abs=1.0)
        assert v.truth().az_deg == pytest.approx(START_AZ if az is None else az, abs=1.0)
