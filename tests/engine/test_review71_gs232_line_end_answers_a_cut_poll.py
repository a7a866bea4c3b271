"""Review 71: where no target can have been cut, a GS-232's first stop of a connection is a
line end, then ``S`` CR (gs232.py rule 6), so that a cut ``S`` is ended as the stop it was,
"a cut ``C`` or ``C2`` as the poll". And the box answers that poll: its position line comes
first, ahead of the answer to the connection's own first poll, written in the same instant
behind the stop. The codec owes one answer and gets two, and R/error says "controller sent
16 bytes that are no valid reply" (the line end's ``?>`` to an empty line is passed over, the
answer to the poll it completed is not), after a replug whose stop did stop the rotor. A
poll is what the unplug cuts most often: the bridge polls a turning rotor every 0.2 s. In
virtual time (tests/engine/virtual.py): ``link_down`` loses what was still on its way to the
box; the box keeps what it had."""

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


@pytest.mark.parametrize(
    ("model", "poll"), [("gs232b", b"C2\r"), ("gs232a", b"C2\r"), ("gs232b-az", b"C\r")]
)
def test_a_gs232_replug_stop_behind_a_cut_poll_says_nothing_on_r_error(
    rig: Rig, model: str, poll: bytes
) -> None:
    v = rig(model, emulator=FAST)
    v.run_until_state(MotionState.IDLE, 30)
    v.target(200, None if model.endswith("-az") else 60)
    v.run_until(lambda h: h.state is MotionState.MOVING and h.truth().az_deg > 30, 30, "turning")
    v.run_until(lambda h: h.writes[-1].data == poll and h.writes[-1].t == h.now, 5, "a poll")
    v.run_for(10 / v.cfg.baud * (len(poll) - 0.5))  # the poll but its CR has reached the box
    v.link_down()
    v.stop()  # while the port is out: owed, the first frame on replug
    v.run_for(UNPLUGGED_S)
    replug, az_at_replug = v.now, v.truth().az_deg
    assert v.truth().is_moving
    v.link_up()
    assert v.sent(since=replug)[0] == b"\rS\r"  # no target can have been cut: the line end
    v.run_until(lambda h: not h.truth().is_moving, 5, "stopped")
    assert v.truth().az_deg - az_at_replug < RUN_ON_DEG  # the stop did take
    v.run_for(AFTER_S)
    assert v.state is MotionState.IDLE
    assert v.errors(since=replug) == [], v.errors(since=replug)
