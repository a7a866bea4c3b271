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


SAY_THEY_DRIVE = ["prosistel", "prosistel-combi", "rc2800", "rc2800-az"]  # R/B, MV/ST


@pytest.mark.parametrize("model", SAY_THEY_DRIVE)
def test_a_turn_the_controller_says_it_stopped_driving_is_dropped_at_once_not_stalled(
    model: str,
) -> None:
    """Prosistel's and the RC2800's readings say whether the motor runs: a box power-cycled
    mid-turn says it does not, and the turn is over then (controller.py rule 12), not a stall
    ``stall_timeout_s`` later (observed: 'rotor stalled at 32° ... brake paddle pressed', and
    rotor health counted a stall)."""
    with VirtualRotator(model) as v:
        t, at = _power_cycled_mid_turn(v)
        assert v.errors(ErrorKind.SERIAL, since=t) == []
        # (a line the power cycle cut short may be told as junk: what it is)
        said = [(at, e.message) for at, e in v.events if at >= t and e.kind != "protocol"]
        assert len(said) == 1, said
        when, message = said[0]
        assert message.startswith("the controller stopped turning short of its target at ")
        assert "(it says its motor is off: power cycled or reset" in message
        assert message.endswith("its turn to 300° was dropped, not resumed: send the target again")
        assert v.errors(ErrorKind.STALLED, since=t)[0].message == message
        stall_s = v.cfg.motion.stall_timeout_s
        assert when - t < stall_s / 2  # the settle time, not the stall's (observed: 10.4 s)
        status = v.status
        assert status.last_error == message
        assert status.target_az_deg is None and status.state is MotionState.IDLE
        assert status.health is not None and status.health.stalls == 0  # observed: 1
        assert status.health.az.arrival_error_deg is None  # it arrived nowhere (a review: 121)
        assert status.health.az.coast_deg is None  # the stop found it still (a review: 0.0)
        assert v.truth().az_deg == pytest.approx(at, abs=3.0)  # not resumed by the bridge
        assert not v.truth().is_moving


@pytest.mark.parametrize("model", SAY_THEY_DRIVE)
def test_a_jammed_rotor_whose_motor_still_runs_is_a_stall_as_ever(model: str) -> None:
    with VirtualRotator(model) as v:
        v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "ready")
        v.run_for(1.0)
        v.target(300.0)
        v.run_until(lambda h: h.truth().az_deg > 30, 60, "turning")
        t = v.now
        v.jam()
        v.run_for(30.0)
        said = [e.message for e in v.errors(since=t)]
        assert len(said) == 1 and said[0].startswith("rotor stalled at "), said
        health = v.status.health
        assert health is not None and health.stalls == 1


@pytest.mark.parametrize("model", ["prosistel", "prosistel-combi"])
def test_one_flipped_bit_that_says_braked_makes_no_jam_a_turn_given_up(model: str) -> None:
    """A Prosistel's ``R`` (0x52) is one bit from ``B`` (0x42): one reading of a jammed rotor
    garbled so is not the box giving its turn up; the stall is told and counted as ever."""
    with VirtualRotator(model) as v:
        v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "ready")
        v.run_for(1.0)
        v.target(300.0)
        v.run_until(lambda h: h.truth().az_deg > 30, 60, "turning")
        t = v.now
        v.jam()
        v.run_for(2 * v.cfg.motion.settle_s)  # still that long: only the flag could tell
        flipped: list[float] = []
        last = [b""]

        def flip(data: bytes, now: float) -> bytes:  # (the device's output comes bytewise)
            before, last[0] = last[0], data[-1:]
            if flipped or before != b"," or data[:1] != b"R":
                return data
            flipped.append(now)
            return b"B" + data[1:]

        v.to_host = flip
        v.run_for(30.0)
        assert flipped
        said = [e.message for e in v.errors(since=t)]
        assert len(said) == 1 and said[0].startswith("rotor stalled at "), said
        health = v.status.health
        assert health is not None and health.stalls == 1


@pytest.mark.parametrize("model", SAY_THEY_DRIVE)
def test_a_jam_the_box_gives_up_on_after_driving_it_is_still_a_stall(model: str) -> None:
    """A box with a stall protection of its own drives a jammed rotor a while, then cuts its
    motor and says so (``B``, ``ST``), as a power-cycled one does: seen driving the rotor
    still for ``settle_s`` and more, it is a jam, told and counted by rotor health as a stall
    (an attack pass: said 'the controller stopped turning short', no stall counted)."""
    with VirtualRotator(model) as v:
        v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "ready")
        v.run_for(1.0)
        v.target(300.0)
        v.run_until(lambda h: h.truth().az_deg > 30, 60, "turning")
        t = v.now
        v.jam()
        v.run_for(3 * v.cfg.motion.settle_s)  # the box drives the jammed rotor that long
        v.power_cycle()  # then cuts its motor out: on the line, the power cycle's braked
        v.run_for(30.0)
        said = [e.message for e in v.errors(since=t) if e.kind != "protocol"]
        assert len(said) == 1 and said[0].startswith("rotor stalled at "), said
        health = v.status.health
        assert health is not None and health.stalls == 1
