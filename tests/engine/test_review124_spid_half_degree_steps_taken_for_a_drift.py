"""Review 124 (cold review of motion.py rule 2; not a regression: 51a2f016 does the same): a
carried axis's move past ``noise_deg`` counts only at CREEP_SHARE of its slowest "a reading's
step less", and the step is the model's (``reading_step_deg``: 0.1 for the SPID family), not the
resolution a Rot2Prog's replies tell (PH/PV pulses a degree: spid.py rule 1). A Rot2Prog at 2
pulses a degree reads in half degrees: turning at 0.3 of rule 6's slowest (0.2 deg/s, above
CREEP_SHARE's 0.167) it reads a half degree every 2.5 s, 0.4 of it counted, under CREEP_SHARE's
0.42 over that time; no move counts, and its rest is called a few seconds after the port is back:
controller.py rule 13 stops the healthy turn 44 degrees short, R/error "rotor at rest ... short
of its turn ... (jammed, stopped at the panel, or its power cut meanwhile)". (At 1 pulse a
degree the same set-up is stopped short too; the sweep found phases where it finishes.)"""

from __future__ import annotations

import pytest

from bridge.core.model import ErrorKind
from bridge.session import motion as mo
from tests.engine.carried import at_rest, replugged
from tests.engine.virtual import VirtualRotator

AIM = (60.0, 30.0)


@pytest.mark.xfail(
    strict=True,
    reason="review 124: a healthy Rot2Prog turn (2 pulses/deg) at 0.3 of its slowest, carried"
    " over a replug, is stopped 44 deg short, with a false 'jammed'",
)
@pytest.mark.parametrize("share", [0.3, 0.35])  # of rule 6's slowest: above CREEP_SHARE
@pytest.mark.parametrize("out_s", [2.0, 2.3])  # (the readings' phases: not deadlines)
def test_a_healthy_carried_turn_read_in_half_degrees_is_left_to_finish(
    share: float, out_s: float
) -> None:
    base = {"resolution_ppd": 2, "start_az_deg": 10.0, "start_el_deg": 0.0}
    with VirtualRotator("rot2prog", emulator=base) as probe:
        slowest = mo.slowest_deg_s(probe.cfg.motion)
    assert share > mo.CREEP_SHARE
    speeds = {"az_speed_deg_s": share * slowest["azimuth"]}
    emulator = base | speeds | {"el_speed_deg_s": share * slowest["elevation"]}
    with VirtualRotator("rot2prog", emulator=emulator) as v:
        at_rest(v)
        v.target(*AIM)
        v.run_until(lambda h: h.truth().el_deg >= 4.5, 120, "the elevation turning")
        replugged(v, out_s)
        v.run_for(1.0)  # (its readings back: not a deadline)
        assert v.truth().is_moving  # it finishes its old turn by itself
        t = v.now
        v.run_until(lambda h: not h.truth().is_moving, 600, "the turn over")
        v.run_for(10.0)  # (its rest told: not a deadline)
        assert [e.message for e in v.errors(ErrorKind.STOP, since=t)] == []
        assert "stop" not in {f.outcome for f in v.frames(since=t)}
        assert v.truth().az_deg == pytest.approx(AIM[0], abs=1.0)
        assert v.truth().el_deg == pytest.approx(AIM[1], abs=1.0)
