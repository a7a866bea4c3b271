"""Review 71: a SatNOGS controller answers ``SA SE`` with its position (easycomm.py rule 9),
and a connection's first stop is now ``SA SE`` twice (rule 11), so the stop owed across an
unplug is answered with two position lines. The connection's first poll goes in the same
instant, right behind the stop, so those answers come while its query is open, and the
codec takes them for the poll's: R/error says "controller sent 28 bytes that are no valid
reply", after a replug whose stop did stop the rotor. (Before the change the one ``SA SE``'s
answer was told so too, 14 bytes: the connection's first stop on the most common Easycomm box
was never passed over as a stop's answer, which rule 9 says an attack pass had fixed.) In
virtual time (tests/engine/virtual.py)."""

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


@pytest.mark.parametrize("model", ["easycomm2", "easycomm2-az"])
def test_a_satnogs_replug_stop_on_a_clean_line_says_nothing_on_r_error(
    rig: Rig, model: str
) -> None:
    v = rig(model, emulator={"firmware": "satnogs", **FAST})
    v.run_until_state(MotionState.IDLE, 30)
    v.target(200, None if model.endswith("-az") else 60)
    v.run_until(lambda h: h.state is MotionState.MOVING and h.truth().az_deg > 30, 30, "turning")
    v.run_until(lambda h: h.device.log[-1].time_s < h.now - 0.05, 1, "a quiet line")
    v.link_down()
    v.stop()  # owed: the first frame on replug
    v.run_for(UNPLUGGED_S)
    replug, az_at_replug = v.now, v.truth().az_deg
    v.link_up()
    v.run_until(lambda h: not h.truth().is_moving, 5, "stopped")
    assert v.truth().az_deg - az_at_replug < RUN_ON_DEG  # the stop did take
    v.run_for(AFTER_S)
    assert v.state is MotionState.IDLE
    assert v.errors(since=replug) == [], v.errors(since=replug)
