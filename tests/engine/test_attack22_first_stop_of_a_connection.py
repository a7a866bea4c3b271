"""Attack 22's fix, from the other side: the connection's first stop is written so that no half
frame the unplug left in the box eats it (protocols/base.py rule 9, session/link.py rule 13),
and what that costs on a line the unplug left clean, or left a cut move in, is nothing a user
sees.

A GS-232's first stop is a line end and ``S`` CR where no target can have been cut (a cut ``S``
is ended as the stop it was), and ``S`` CR twice where one may: a line end there would carry
out the cut move (interfaces/mqtt/express.py rule 9). Easycomm's is ``SA SE`` twice; an
RC2800's selects its first axis twice. In virtual time (tests/engine/virtual.py): ``link_down``
loses what was still on its way to the box; the box keeps what it had.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator, moves

Rig = Callable[..., VirtualRotator]
FAST = {"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0}
UNPLUGGED_S = 0.5  # how long the adapter is out (not a deadline)
RUN_ON_DEG = 3.0  # a reply time and the coast at 6 degrees a second (as the attack's test)


def test_a_target_cut_by_the_unplug_is_not_carried_out_by_the_replugs_stop(rig: Rig) -> None:
    """The box holds ``M180`` of ``M180`` CR when the adapter goes; a STOP comes while it is out.
    A line end first would make that ``M180`` CR, a move; the stop written twice makes it
    ``M180S``, refused, and the second ``S`` CR stops."""
    v = rig("gs232b-az", emulator={"start_az_deg": 10.0, **FAST})
    v.run_until_state(MotionState.IDLE, 30)
    v.target(180)
    v.run_until(lambda h: bool(h.writes) and h.writes[-1].data == b"M180\r", 5, "target written")
    byte_s = 10 / v.cfg.baud
    v.run_for(byte_s * 4.5)  # M180 has reached the box, its CR has not
    v.link_down()
    v.stop()  # while the port is out: owed, the first frame on replug
    v.run_for(UNPLUGGED_S)
    replug = v.now
    assert not v.truth().is_moving and moves(v) == []
    v.link_up()
    v.run_until(lambda h: h.state is MotionState.IDLE, 10, "idle")
    v.run_for(2.0)
    assert moves(v, since=replug) == [], v.frames(since=replug)
    assert v.frames("stop", since=replug)
    assert abs(v.truth().az_deg - 10.0) < 0.5, v.truth().az_deg


def test_a_box_that_answers_the_line_end_before_the_stop_is_told_of_nothing(rig: Rig) -> None:
    """Where no target can have been cut the first stop is CR ``S`` CR; a GS-232 that answers
    the empty line ``?>`` (interfaces/mqtt/express.py rule 9) has answered that, not refused the
    stop: nothing on R/error, and the stop taken at once."""
    v = rig("gs232b", emulator=FAST)
    v.run_until_state(MotionState.IDLE, 30)
    v.target(200, 40)
    v.run_until(lambda h: h.state is MotionState.MOVING and h.truth().az_deg > 30, 30, "turning")
    v.link_down()
    v.stop()  # owed
    v.run_for(UNPLUGGED_S)
    replug, az_at_replug = v.now, v.truth().az_deg
    answered = v.glitch_once(b"\r", b"?>")  # the empty line's ?>, then the stop's CR
    v.link_up()
    assert v.sent(since=replug)[0] == b"\rS\r"
    v.run_until(lambda h: not h.truth().is_moving, 5, "stopped")
    v.run_for(2.0)
    assert answered
    assert v.truth().az_deg - az_at_replug < RUN_ON_DEG
    assert v.errors(since=replug) == [], v.errors(since=replug)


@pytest.mark.parametrize("firmware", ["generic", "satnogs", "k3ng"])
def test_an_easycomm_replug_stop_behind_a_torn_stop_stops_both_axes(
    rig: Rig, firmware: str
) -> None:
    """Attack 22's Easycomm case on every firmware the emulator knows: the box holds ``S`` of the
    torn ``SA SE`` (a SatNOGS box ignores ``SSA SE`` whole, a K3NG stops only the elevation)."""
    v = rig("easycomm2", emulator={"firmware": firmware, **FAST})
    v.run_until_state(MotionState.IDLE, 30)
    v.target(200, 60)
    v.run_until(lambda h: h.state is MotionState.MOVING and h.truth().az_deg > 30, 30, "turning")
    v.stop()
    v.run_for(10 / v.cfg.baud * 1.5)  # the stop's S has reached the box, the rest has not
    v.link_down()
    v.run_for(UNPLUGGED_S)
    az_at_replug = v.truth().az_deg
    assert v.truth().is_moving
    v.link_up()
    v.run_until(lambda h: not h.truth().is_moving, 5, "stopped")
    assert v.truth().az_deg - az_at_replug < RUN_ON_DEG, (az_at_replug, v.truth().az_deg)


@pytest.mark.parametrize("model", ["gs232b", "easycomm2", "rc2800"])
def test_a_replug_stop_on_a_clean_line_stops_at_once_and_says_nothing(rig: Rig, model: str) -> None:
    """No half frame in the box (the unplug came between frames): the doubled stop, or the
    RC2800's doubled selection, stops the rotor at once, keeps an RC2800's 200 ms between its
    axes, and nothing it is answered is told on R/error."""
    v = rig(model, emulator=FAST)
    v.run_until_state(MotionState.IDLE, 30)
    v.target(200, 60)
    v.run_until(lambda h: h.state is MotionState.MOVING and h.truth().az_deg > 30, 30, "turning")
    v.run_until(lambda h: h.device.log[-1].time_s < h.now - 0.05, 1, "a quiet line")
    v.link_down()
    v.stop()  # owed
    v.run_for(UNPLUGGED_S)
    replug, az_at_replug = v.now, v.truth().az_deg
    v.link_up()
    v.run_until(lambda h: not h.truth().is_moving, 5, "stopped")
    assert v.truth().az_deg - az_at_replug < RUN_ON_DEG
    v.run_until(lambda h: h.state is MotionState.IDLE, 10, "idle")
    v.run_for(3.0)
    assert v.state is MotionState.IDLE
    assert v.errors(since=replug) == [], v.errors(since=replug)
    assert getattr(v.truth(), "too_soon", 0) == 0


@pytest.mark.parametrize("model", ["rotorez", "rotorcard"])
def test_a_rotor_ez_replug_stop_behind_a_torn_poll_stops_the_rotor(rig: Rig, model: str) -> None:
    """The same exposure on an Idiom board: the unplug cut a poll ``AI1;`` after ``AI``, the box
    holds the open frame, and the replug's stop ``;`` ends it as ``AI;``, an invalid command
    (its banner): no stop. The first stop of a connection is ``;`` twice: the first ends the
    half frame, the second stops (a ``;`` to a still rotor is answered by the banner)."""
    v = rig(model, emulator={"brake_delay_s": 0.0})
    v.run_until_state(MotionState.IDLE, 30)
    v.target(200)
    v.run_until(lambda h: h.state is MotionState.MOVING and h.truth().az_deg > 30, 30, "turning")
    v.run_until(lambda h: h.writes[-1].data == b"AI1;" and h.writes[-1].t == h.now, 5, "polled")
    v.run_for(10 / v.cfg.baud * 2.5)  # AI has reached the box, 1; has not
    v.link_down()
    v.stop()  # owed
    v.run_for(UNPLUGGED_S)
    az_at_replug = v.truth().az_deg
    assert v.truth().is_moving
    v.link_up()
    v.run_until(lambda h: not h.truth().is_moving, 5, "stopped")
    assert abs(v.truth().az_deg - az_at_replug) < RUN_ON_DEG, (az_at_replug, v.truth().az_deg)
