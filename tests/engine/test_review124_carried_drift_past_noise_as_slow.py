"""Review 124 (cold review of motion.py rule 2 after 766fa6eb..2d0bfa69): a carried axis's move
past ``noise_deg`` counts only if it turned CREEP_SHARE of the axis's slowest "by what it turned
at least, a reading's step less", timed from its last reading where it stood ("a drift past
``noise_deg`` slower than any turn is no move"). Both ends of that are taken at their worst: the
distance a reading's step short, the time from a reading that may have been most of a step
behind. An MD-01 read in tenths (10 pulses a degree, noise_deg 0) turning at 0.3 of rule 6's
slowest (0.2 deg/s, above CREEP_SHARE's 0.167) reads a tenth every half second, polled every
0.2 s: three tenths on from where it stood read 0.2 degrees in 1.2 s, slower than CREEP_SHARE,
so none of its moves counts and its rest is called a second or two after the port is back;
controller.py rule 13 stops the healthy turn 44 degrees short with R/error "rotor at rest ...
short of its turn ... (jammed, stopped at the panel, or its power cut meanwhile)". At 51a2f016
it finished at its target."""

from __future__ import annotations

from typing import Any

import pytest

from bridge.core.model import ErrorKind
from bridge.session import motion as mo
from tests.engine.carried import at_rest, replugged
from tests.engine.virtual import VirtualRotator

SHARE = 0.3  # of rule 6's slowest: above CREEP_SHARE (a turn, not a drift)


@pytest.mark.parametrize(
    ("model", "emulator", "aim", "out_s", "after_s"),
    [
        (
            "md01",
            {"resolution_ppd": 10, "start_az_deg": 10.0, "start_el_deg": 0.0},
            (60.0, 30.0),
            2.0,
            1.0,
        ),
        (
            "md01",
            {"resolution_ppd": 10, "start_az_deg": 10.0, "start_el_deg": 0.0},
            (60.0, 30.0),
            2.2,
            0.4,
        ),
    ],
)
def test_a_healthy_carried_turn_read_in_tenths_is_left_to_finish(
    model: str,
    emulator: dict[str, Any],
    aim: tuple[float, float],
    out_s: float,
    after_s: float,
) -> None:
    with VirtualRotator(model, emulator=emulator) as probe:
        slowest = mo.slowest_deg_s(probe.cfg.motion)
    assert SHARE > mo.CREEP_SHARE
    speeds = {"az_speed_deg_s": SHARE * slowest["azimuth"]}
    emulator = emulator | speeds | {"el_speed_deg_s": SHARE * slowest["elevation"]}
    start = emulator["start_az_deg"]
    with VirtualRotator(model, emulator=emulator) as v:
        at_rest(v)
        v.target(*aim)
        v.run_until(lambda h: h.truth().az_deg >= start + 5.0, 120, "the azimuth turning")
        replugged(v, out_s)
        v.run_for(after_s)  # (its readings back: not a deadline)
        assert v.truth().is_moving  # it finishes its old turn by itself
        t = v.now
        v.run_until(lambda h: not h.truth().is_moving, 600, "the turn over")
        v.run_for(10.0)  # (its rest told: not a deadline)
        assert [e.message for e in v.errors(ErrorKind.STOP, since=t)] == []
        assert "stop" not in {f.outcome for f in v.frames(since=t)}
        assert v.truth().az_deg == pytest.approx(aim[0], abs=1.0)
        assert v.truth().el_deg == pytest.approx(aim[1], abs=1.0)
