"""Attack 22: a stop torn by an unplug leaves its first byte in the box's line buffer, and the
stop the bridge owes and sends first on replug is read behind it as one unknown command.

The USB adapter drops out while the stop is on the wire: the box got ``S`` (a GS-232), ``S`` of
``SA SE`` (an Easycomm) or ``A`` of ``A CR S CR`` (an RC2800), the rest was lost with the
adapter. The box, powered on its own, keeps the half line and goes on turning. On replug the
bridge sends its stop first (docs/architecture.md, a rotator of two boxes: "an unplugged box
owes its stop and sends it first on replug"), but nothing ends the half line before it: the
GS-232 reads ``SS`` and answers ``?>`` (which the bridge passes over as junk), the Easycomm
reads ``SSA`` and stops only the elevation, the RC2800 reads ``AA`` and stops the axis it had
selected, the elevation (the STOP came after a poll of it). The azimuth turns on until the
stop is checked and sent again ``stop_resend_s`` (2 s) later: 12 degrees more at 6 degrees a
second. (The stop express knows what a half frame does to the frame after it and never
leaves one, interfaces/mqtt/express.py rule 9; the replug's first frame lands in whatever the
unplug left. A bare line end first is no cure: it would carry out a cut ``M18`` of ``M180``.)

In virtual time (tests/engine/virtual.py): ``link_down`` loses what was still on its way to the
box (rule 3), as an adapter pulled does; the box keeps what it had.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
FAST = {"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0}
UNPLUGGED_S = 0.5  # how long the adapter is out (not a deadline)
# the replug's stop, once it is on the wire and taken, leaves the rotor where it was: a reply
# time and the coast, under half a second at 6 degrees a second
RUN_ON_DEG = 3.0


@pytest.mark.parametrize(
    ("model", "elevation"), [("gs232b", None), ("easycomm2", 60.0), ("rc2800", 60.0)]
)
def test_the_stop_sent_on_replug_stops_a_box_a_torn_stop_left_a_half_line_in(
    rig: Rig, model: str, elevation: float | None
) -> None:
    v = rig(model, emulator=FAST)
    v.run_until_state(MotionState.IDLE, 30)
    v.target(200, elevation)
    v.run_until(lambda h: h.state is MotionState.MOVING and h.truth().az_deg > 30, 30, "turning")
    # (an RC2800 stops the axis it has selected: the STOP comes after a poll of the elevation)
    v.run_until(lambda h: getattr(h.truth(), "selected", "E") == "E", 1, "the elevation asked")
    v.stop()
    byte_s = 10 / v.cfg.baud
    v.run_for(byte_s * 1.5)  # the stop's first byte has reached the box, the rest has not
    v.link_down()
    v.run_for(UNPLUGGED_S)
    az_at_replug = v.truth().az_deg
    assert v.truth().is_moving  # the box never got the stop
    v.link_up()
    v.run_until(lambda h: not h.truth().is_moving, 30, "stopped")
    assert v.truth().az_deg - az_at_replug < RUN_ON_DEG, (az_at_replug, v.truth().az_deg)
