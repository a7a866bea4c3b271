"""Review 119 (cold review of 48918b44 and 766fa6eb, motion.py rule 2): a carried axis's reading
one step off where it stood is no move, only a hold till a turn at that axis's slowest would read
a second step on, and a creep or drift is a move only at CREEP_SHARE of that slowest speed or
faster. A controller that slows its last degrees (K3NG's slow-down before the target, an
MD-01's ramp) turns them at a fraction of its speed: a GS-232B's elevation (nominal 2.5 deg/s,
rule 6's slowest 1.67) at a quarter of it, 0.625 deg/s (what its X1 gives), is 0.375 of that
slowest, above CREEP_SHARE (0.25). A turn the bridge sends is left to arrive (its target is
known), and before 48918b44 a carried one was too (every step read counted as its creep); now,
carried over a replug, its rest is called at the first degree that takes longer than the hold,
and controller.py rule 13 stops it some 8 degrees short with R/error "rotor at rest ... short
of its turn ... (jammed, stopped at the panel, or its power cut meanwhile)", none of which
happened."""

from __future__ import annotations

import pytest

from bridge.core.model import ErrorKind
from bridge.session import motion as mo
from tests.engine.carried import at_rest, replugged
from tests.engine.virtual import VirtualRotator

AIM_EL = 80.0
SLOW_FROM_DEG = 10.0  # the slow-down's span before the aim (K3NG's default)
SLOW_SHARE = 0.25  # of the nominal speed in that span


def slows_down(v: VirtualRotator, speed: float) -> None:
    """The elevation's last degrees turned at ``speed`` (the controller's own slow-down)."""
    axis = v.device._el  # type: ignore[attr-defined]
    target = axis.target_deg
    axis.advance(v.now)
    axis.speed_deg_s = speed
    axis.start_move(target, v.now)


@pytest.mark.parametrize("out_s", [2.0, 2.2])  # (the readings' phases: not deadlines)
def test_a_carried_turn_slowing_near_its_aim_is_left_to_finish(out_s: float) -> None:
    with VirtualRotator("gs232b", emulator={"start_az_deg": 20, "start_el_deg": 0}) as v:
        cfg = v.cfg.motion
        slow = SLOW_SHARE * cfg.spec.nominal_el_speed_deg_s
        assert slow > mo.CREEP_SHARE * mo.slowest_deg_s(cfg)["elevation"]  # (faster than a drift)
        at_rest(v)
        v.target(None, AIM_EL)
        v.run_until(lambda h: h.truth().el_deg >= 40.0, 60, "the elevation turning")
        replugged(v, out_s)
        t = v.now
        v.run_until(lambda h: h.truth().el_deg >= AIM_EL - SLOW_FROM_DEG, 60, "near its aim")
        assert v.status.moving  # (the carried turn followed)
        slows_down(v, slow)
        v.run_until(lambda h: not h.truth().is_moving, 60, "the turn over")
        v.run_for(10.0)  # (its rest told: not a deadline)
        assert [e.message for e in v.errors(ErrorKind.STOP, since=t)] == []
        assert "stop" not in {f.outcome for f in v.frames(since=t)}
        assert v.truth().el_deg == pytest.approx(AIM_EL)
