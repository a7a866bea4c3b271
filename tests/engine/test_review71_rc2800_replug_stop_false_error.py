"""Review 71: an RC2800's first stop of a connection selects its first axis twice (``A`` CR
``A`` CR ``S`` CR, rc2800.py rule 10), so that the first selection takes in the half frame an
unplug left in the box (attack 22: ``A`` of a torn stop or poll). The box answers that first
line as the command it reads, ``AA`` or ``EA``: an unknown command, ``A ERR=1`` (``E ERR=1``
with the elevation selected): the answer the fix itself provokes, and expects. The codec
takes it for bytes no reply has, and R/error tells the user "controller sent 8 bytes that
are no valid reply", after a replug whose stop did stop the rotor. (The GS-232's like case,
the ``?>`` to the line end written before the stop, is passed over as the answer to it:
gs232.py rule 6.) In virtual time (tests/engine/virtual.py): ``link_down`` loses what was
still on its way to the box; the box keeps what it had."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
FAST = {"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0}
UNPLUGGED_S = 0.5  # how long the adapter is out (not a deadline)
AFTER_S = 3.0  # how long R/error is watched after the replug (not a deadline)
RUN_ON_DEG = 3.0  # a reply time and the coast at 6 degrees a second (as attack 22's test)


@pytest.mark.parametrize("torn", [b"A\r", b"E\r"])
def test_an_rc2800_replug_stop_behind_a_torn_poll_says_nothing_on_r_error(
    rig: Rig, torn: bytes
) -> None:
    v = rig("rc2800", emulator=FAST)
    v.run_until_state(MotionState.IDLE, 30)
    v.target(200, 60)
    v.run_until(lambda h: h.state is MotionState.MOVING and h.truth().az_deg > 30, 30, "turning")
    v.run_until(lambda h: h.writes[-1].data == torn and h.writes[-1].t == h.now, 5, "a poll")
    v.run_for(10 / v.cfg.baud * 1.5)  # the poll's letter has reached the box, its CR has not
    v.link_down()
    v.stop()  # while the port is out: owed, the first frame on replug
    v.run_for(UNPLUGGED_S)
    replug, az_at_replug = v.now, v.truth().az_deg
    assert v.truth().is_moving
    v.link_up()
    v.run_until(lambda h: not h.truth().is_moving, 5, "stopped")
    assert v.truth().az_deg - az_at_replug < RUN_ON_DEG  # the stop did take
    v.run_for(AFTER_S)
    assert v.state is MotionState.IDLE
    assert v.errors(since=replug) == [], v.errors(since=replug)
