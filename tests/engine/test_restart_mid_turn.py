"""A controller power-cycled (or reset) mid-turn, its serial adapter left plugged in: it forgets
its target and the rotor stands. An earlier pass: 10-14 s later the bridge said "rotor stalled
... brake paddle pressed or rotor stuck" on every model, a Rotor-EZ's power-on byte seen or
not, and rotor health counted a stall: a wrong diagnosis a user acts on (a climb to a rotor
that is not stuck). Where the controller says it restarted (the Rotor-EZ's and RotorCard's
0xE0), the turn is said abandoned with its cause (controller.py rule 12), never resumed by
the bridge; where nothing says so, the stall names a restart as a possible cause."""

from __future__ import annotations

import pytest

from bridge.core.model import ErrorKind, MotionState
from tests.engine.virtual import VirtualRotator


def _power_cycled_mid_turn(v: VirtualRotator) -> tuple[float, float]:
    """Turn towards 300, power-cycle the controller 30 degrees into the turn, run a minute;
    returns the power cycle's time and where the rotor stood then."""
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "ready")
    v.run_for(1.0)
    v.target(300.0)
    v.run_until(lambda h: h.truth().az_deg > 30, 60, "turning")
    t, at = v.now, v.truth().az_deg
    v.power_cycle()
    v.run_for(60.0)
    return t, at


@pytest.mark.parametrize("model", ["rotorez", "rotorcard"])
def test_a_turn_a_power_on_byte_ended_is_said_abandoned_not_stalled(model: str) -> None:
    with VirtualRotator(model) as v:
        t, at = _power_cycled_mid_turn(v)
        assert v.errors(ErrorKind.STALLED, since=t) == []  # observed: 'rotor stalled at 32°'
        said = [e.message for e in v.errors(ErrorKind.SERIAL, since=t)]
        assert len(said) == 1, said
        assert said[0].startswith("the controller restarted mid-turn (its power-on byte came)")
        assert "its turn to 300° was not resumed: send the target again" in said[0]
        status = v.status
        assert status.last_error == said[0]  # R/status says why too
        assert status.target_az_deg is None  # the lost target no longer shown
        assert status.state is MotionState.IDLE
        assert status.health is not None and status.health.stalls == 0  # observed: 1
        assert v.truth().az_deg == pytest.approx(at, abs=3.0)  # not resumed by the bridge
        assert not v.truth().is_moving


@pytest.mark.parametrize("model", ["gs232b", "rt21", "md01"])
def test_a_stall_after_a_restart_nothing_announced_names_the_restart(model: str) -> None:
    emu = {"az_speed_deg_s": 6.0} if model == "rt21" else {}
    with VirtualRotator(model, emulator=emu) as v:
        t, at = _power_cycled_mid_turn(v)
        said = [e.message for e in v.errors(ErrorKind.STALLED, since=t)]
        assert len(said) == 1, said
        assert "or the controller restarted (power cycled or reset)" in said[0]
        assert said[0].endswith("target dropped: send the target again")
        assert v.status.target_az_deg is None
        assert v.truth().az_deg == pytest.approx(at, abs=3.0)
