"""A port replugged (or a controller silent) while the rotor turns to the user's target: the
first reading back is a turn (motion.py rule 4), which stops when readings show it still, never
by the clock. An attack pass: its first reading taken, its replies then lost for a moment, the
clock settled it, the status said idle while it turned, and where unasked turns are stopped
(controller.py rule 10) the user's own turn was stopped, blamed on a noisy line or a hand."""

from __future__ import annotations

import pytest

from bridge.core.model import ErrorKind, MotionState, Target
from tests.engine.virtual import VirtualRotator
from tests.engine.virtual_composite import VirtualComposite


def _replug_then_lose_replies(
    v: VirtualRotator | VirtualComposite, box: VirtualRotator, lost_s: float
) -> float:
    """Unplug ``box`` mid-turn for 2 s, replug, let its first reading through, then lose its
    replies for ``lost_s``. Returns the unplug time."""
    t = v.now
    box.link_down()
    v.run_for(2.0)
    tl = v.now
    box.link_up()
    v.run_until(lambda h: any(tt >= tl and s.available for tt, s in box.statuses), 5)
    v.run_for(0.02)  # the first reading back taken (it was turning: shown as it is)
    box.set_silent(True)
    v.run_for(lost_s)
    box.set_silent(False)
    return t


@pytest.mark.parametrize("lost_s", [1.5, 2.5])
def test_a_turn_across_a_replug_is_not_stopped_as_unasked_after_a_few_lost_replies(
    lost_s: float,
) -> None:
    with VirtualRotator("easycomm3") as v:  # unasked_moves = "stop", its default
        v.run_until(lambda h: h.status.available, 10)
        v.run_for(1.0)
        v.target(200.0, 0.0)
        v.run_until(lambda h: h.truth().az_deg > 8, 30)
        t = _replug_then_lose_replies(v, v, lost_s)
        v.run_for(60.0)
        stops = [e.message for e in v.errors(ErrorKind.STOP, since=t)]
        assert stops == [], stops  # observed: "the rotor turned with no command from the bridge"
        assert v.truth().az_deg == pytest.approx(200.0, abs=1.0)  # observed: 30-36


@pytest.mark.parametrize("lost", ["az", "el"])
def test_a_composite_turn_cut_by_a_replug_of_one_box_is_stopped_in_both(lost: str) -> None:
    """Composite rule 8: the box that answers is stopped when the other's port goes, and the
    box whose port went owes a stop, its first frame back (an attack pass: it turned on alone
    to the target, 60/80 where 300/80 was asked, or the azimuth swung on with the elevation
    stopped); R/error says why (the port); no later turn nobody asked for is stopped as one."""
    with VirtualComposite("easycomm3", "gs232b") as v:
        v.run_until(lambda h: h.status.available, 20)
        v.run_for(1.0)
        v.aim(Target(200.0, 60.0))
        v.run_until(lambda h: h.az.truth().az_deg > 8 and h.el.truth().el_deg > 4, 30)
        gone = v.az if lost == "az" else v.el
        t = _replug_then_lose_replies(v, gone, 1.5)
        az, el = v.az.truth().az_deg, v.el.truth().el_deg
        v.run_for(60.0)
        assert [e.message for e in v.az.errors(ErrorKind.STOP, since=t)] == []
        assert not v.az.truth().is_moving and not v.el.truth().is_moving
        assert v.az.truth().az_deg == pytest.approx(az, abs=15.0)  # observed: 200
        assert v.el.truth().el_deg == pytest.approx(el, abs=15.0)  # observed: 60
        said = [e.message for e in gone.errors(ErrorKind.SERIAL, since=t)]
        assert said[:1] == ["virtual port unplugged"], said  # why, on R/error


@pytest.mark.parametrize("lost_s", [0.0, 1.5])
@pytest.mark.parametrize(
    "model", ["gs232b", "easycomm3-az", "rt21", "rot2prog", "md01", "rc2800-az", "prosistel"]
)
def test_no_idle_status_while_a_rotor_known_to_turn_turns_after_a_replug(
    model: str, lost_s: float
) -> None:
    emu = {"az_speed_deg_s": 6.0} if model == "rt21" else {}
    with VirtualRotator(model, emulator=emu) as v:
        v.run_until(lambda h: h.status.available, 20)
        v.run_for(1.0)
        v.target(200.0)
        v.run_until(lambda h: abs(h.truth().az_deg) > 8, 30)
        _replug_then_lose_replies(v, v, lost_s)
        lying = 0.0  # seconds an online status said idle while the rotor turned
        for _ in range(200):
            v.run_for(0.05)
            if v.status.available and v.status.state is MotionState.IDLE and v.truth().is_moving:
                lying += 0.05
        # a moment is a poll; observed: seconds (the first reading back settles by the clock)
        assert lying <= 1.0, (lying, v.truth().az_deg)


def test_a_turn_across_a_silence_is_not_stopped_as_unasked_after_a_few_lost_replies() -> None:
    """The same after the controller went silent mid-turn (offline) and answered again: the
    turn was stopped going offline (controller.py rule 2: no reading watches it), not as one
    nobody asked for, and the rotor stays where that stop left it."""
    with VirtualRotator("easycomm3") as v:
        v.run_until(lambda h: h.status.available, 10)
        v.run_for(1.0)
        v.target(200.0, 0.0)
        v.run_until(lambda h: h.truth().az_deg > 8, 30)
        t = v.now
        v.set_silent(True)
        v.run_until(lambda h: not h.status.available, 10, "offline")
        v.run_for(2.0)
        rest = v.truth().az_deg
        assert not v.truth().is_moving and rest < 100
        v.set_silent(False)
        v.run_until(lambda h: h.status.available, 5, "answering again")
        v.run_for(0.02)
        v.set_silent(True)
        v.run_for(1.5)
        v.set_silent(False)
        v.run_for(60.0)
        assert [e.message for e in v.errors(ErrorKind.STOP, since=t)] == []
        assert v.truth().az_deg == pytest.approx(rest, abs=1.0)


@pytest.mark.parametrize("model", ["rotorez", "rotorcard"])
def test_a_rotor_ez_turn_across_a_replug_is_not_stopped_after_a_few_lost_replies(
    model: str,
) -> None:
    """The Rotor-EZ's "after-stop" guard: the rest the clock made is short of the target out."""
    with VirtualRotator(
        model, settings={"brake_delay_s": 1.0}, emulator={"speed_deg_s": 6.0, "brake_delay_s": 1.0}
    ) as v:
        v.run_until(lambda h: h.status.available, 10)
        v.run_for(6.0)
        v.target(200.0)
        v.run_until(lambda h: h.truth().az_deg > 8, 30)
        t = _replug_then_lose_replies(v, v, 2.5)
        v.run_for(60.0)
        assert [e.message for e in v.errors(ErrorKind.STOP, since=t)] == []
        assert v.truth().az_deg == pytest.approx(200.0, abs=1.0)


def _came_to_rest_while_unplugged(v: VirtualRotator) -> None:
    v.run_until(lambda h: h.status.available, 20)
    v.run_for(10)
    v.target(60, 20) if v.cfg.spec.has_elevation else v.target(60)
    v.run_for(2)
    assert v.truth().is_moving
    v.link_down()
    v.run_for(60)
    assert not v.truth().is_moving
    v.link_up()
    v.run_until(lambda h: h.session.controller.motion.anchor_deg is not None, 30, "a reading")


@pytest.mark.parametrize("model", ["rotorez", "rotorcard", "satel"])
def test_a_target_after_a_replug_that_finds_the_rotor_at_rest_sends_no_stop(model: str) -> None:
    """A review: taken for turning (it was, when its port went), a rotor that came to rest
    meanwhile got a stop before the next target on a controller stopped first (a stop to a
    rotor at rest, the target 1.5 s later). The target waits for the next reading."""
    with VirtualRotator(model) as v:
        _came_to_rest_while_unplugged(v)
        t = v.now
        v.target(120, 30) if v.cfg.spec.has_elevation else v.target(120)
        v.run_for(40)
        stop = v.cfg.spec.codec_factory().encode_stop()
        assert stop not in v.sent(since=t), v.sent(since=t)[:4]  # observed: the stop first


@pytest.mark.parametrize("model", ["rotorez", "gs232b"])
def test_a_replug_that_finds_the_rotor_at_rest_counts_no_move_in_rotor_health(model: str) -> None:
    """A review: the first reading back, taken for a turn, was counted a move that turned
    nothing."""
    with VirtualRotator(model) as v:
        _came_to_rest_while_unplugged(v)
        v.run_for(30)
        health = v.status.health
        assert health is not None and health.moves == 0, health  # observed: 1, nothing turned
