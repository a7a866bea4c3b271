"""Review 71: attack 22's exposure on a Green Heron RT-21, which the fix left out (base.py rule
9 sends it ``encode_stop`` "as before"). Its stop is ``;`` alone, and ``;`` is also what
ends every command it takes (``BI1;``, ``AP1ddd.d`` CR ``;``). The USB adapter drops out with
a poll ``BI1;`` cut after ``BI1``, or a target cut after its CR (the rotor turning to it, the
closing ``;`` lost): the box keeps the open command. A STOP comes while the port is out; on
replug the bridge sends it first, and the box reads that ``;`` as the end of the command it
holds: a poll answered (told on R/error as bytes no reply has), or the target's close. No
stop: the rotor turns on until the stop is checked and sent again ``stop_resend_s`` (2 s)
later, 12 degrees at 6 degrees a second. The Rotor-EZ's like case is fixed by ``;`` twice
(rotorez.py rule 8); the RT-21 (also a composite's elevation box, protocols/axes.py rule 2)
is not. In virtual time (tests/engine/virtual.py): ``link_down`` loses what was still on its
way to the box; the box keeps what it had."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
UNPLUGGED_S = 0.5  # how long the adapter is out (not a deadline)
RUN_ON_DEG = 3.0  # a reply time and the coast at 6 degrees a second (as attack 22's test)


@pytest.mark.parametrize(
    ("cut", "reached"),
    [(b"BI1;", 3), (b"AP1200.0\r;", 9)],  # the poll without its ;, the target without its ;
)
def test_an_rt21_replug_stop_behind_a_cut_command_stops_the_rotor(
    rig: Rig, cut: bytes, reached: int
) -> None:
    v = rig("rt21", emulator={"az_speed_deg_s": 6.0})
    v.run_until_state(MotionState.IDLE, 30)
    v.target(200)
    if cut == b"BI1;":  # a poll while the rotor turns
        v.run_until(
            lambda h: h.state is MotionState.MOVING and h.truth().az_deg > 30, 30, "turning"
        )
    v.run_until(lambda h: h.writes[-1].data == cut and h.writes[-1].t == h.now, 5, "written")
    v.run_for(10 / v.cfg.baud * (reached + 0.5))  # all but its closing ; has reached the box
    v.link_down()
    v.stop()  # while the port is out: owed, the first frame on replug
    v.run_for(UNPLUGGED_S)
    az_at_replug = v.truth().az_deg
    assert v.truth().is_moving
    v.link_up()
    v.run_until(lambda h: not h.truth().is_moving, 30, "stopped")
    assert abs(v.truth().az_deg - az_at_replug) < RUN_ON_DEG, (az_at_replug, v.truth().az_deg)


AFTER_S = 3.0  # how long R/error is watched after the replug (not a deadline)


def test_an_rt21_replug_stop_behind_a_cut_poll_says_nothing_on_r_error(rig: Rig) -> None:
    """The first ``;`` ends the cut ``BI1`` as the poll it was, and the box answers it with a
    bearing nobody asks for any more (rt21.py rule 6): dropped, not told on R/error."""
    v = rig("rt21", emulator={"az_speed_deg_s": 6.0})
    v.run_until_state(MotionState.IDLE, 30)
    v.target(200)
    v.run_until(lambda h: h.state is MotionState.MOVING and h.truth().az_deg > 30, 30, "turning")
    v.run_until(lambda h: h.writes[-1].data == b"BI1;" and h.writes[-1].t == h.now, 5, "a poll")
    v.run_for(10 / v.cfg.baud * 3.5)  # BI1 has reached the box, its ; has not
    v.link_down()
    v.stop()
    v.run_for(UNPLUGGED_S)
    replug = v.now
    v.link_up()
    v.run_until(lambda h: not h.truth().is_moving, 30, "stopped")
    v.run_for(AFTER_S)
    assert any(b"BI1;" in f.data for f in v.device.log if f.time_s >= replug), v.device.log
    assert v.state is MotionState.IDLE
    assert v.errors(since=replug) == [], v.errors(since=replug)
