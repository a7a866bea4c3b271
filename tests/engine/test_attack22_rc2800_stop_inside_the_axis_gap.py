"""Attack 22: an RC2800's stop breaks the box's 200 ms between its axes whenever it follows a
frame to the elevation (a poll, or a target's elevation frame).

The fact sheet (more-controllers.md, M2 RC2800): "leave about 200 ms between commands to the
two axes"; Hamlib's rc2800.c waits 200 ms between the axes of a set and of a stop ("do not
overwhelm the MCU"). The bridge keeps the gap for every frame but a stop's first, which always
selects the azimuth (``A`` CR ``S`` CR) and goes at once (base.py ``axis_gap_s``). While the
rotor turns the bridge polls the axes in turn, 200 ms apart, so about every other STOP lands a
few milliseconds after an ``E`` CR. The emulator takes such a command and counts it
(``too_soon``, emulators/rc2800.py rule 5); a box that drops or mis-takes the ``A`` selection
that soon stops the elevation it still has selected with the ``S``, and the azimuth turns on
until the stop is checked and sent again. Nothing is gained by it: a stop that began with the
axis the last frame addressed (``E`` CR ``S`` CR, the same axis, no gap owed) would go at once
and keep the rule.
"""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
FAST = {"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0}


def test_a_stop_right_after_a_poll_of_the_elevation_keeps_the_boxs_axis_gap(rig: Rig) -> None:
    v = rig("rc2800", emulator=FAST)
    v.run_until_state(MotionState.IDLE, 30)
    v.target(200, 60)
    v.run_until(lambda h: h.state is MotionState.MOVING and h.truth().az_deg > 30, 30, "turning")
    # the line's last frame is a poll of the elevation, and the box has taken it
    v.run_until(lambda h: h.writes[-1].data == b"E\r" and h.truth().selected == "E", 1, "E asked")
    assert v.truth().too_soon == 0
    v.stop()
    v.run_until(lambda h: not h.truth().is_moving, 10, "stopped")
    assert v.truth().too_soon == 0, [(round(w.t, 3), w.data) for w in v.writes[-6:]]
