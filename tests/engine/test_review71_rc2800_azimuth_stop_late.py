"""Review 71: an RC2800 az/el's stop now begins with the axis the line's last frame named
(rc2800.py rule 9), so that a stop a few milliseconds after an ``E`` CR poll keeps the box's
200 ms between its axes. But it then writes the azimuth's ``A`` CR ``S`` CR a whole axis gap
after the STOP, however long ago that ``E`` CR went: the gap is owed from the last frame to
the other axis, so the azimuth's stop could go as soon as that gap has run out. While a rotor
turns the bridge polls ``A``, ``E``, ``A``... 200 ms apart, so half of all STOPs land after an
``E`` CR, and their azimuth (the axis a user turns most, and the only one turning here) now
stops up to 200 ms later than the box's rule needs, and later than before the change, where
it went at once (1.2 degrees more at 6 degrees a second; more on a fast rotor). The
elevation, standing still, is stopped first. In virtual time (tests/engine/virtual.py)."""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
FAST = {"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0}
AXIS_GAP_S = 0.2  # the box's 200 ms between its axes (more-controllers.md)
STOP_AFTER_E_S = 0.15  # the STOP comes this long after the poll's E CR (not a deadline)
SLACK_S = 0.02  # a few byte times at 9600 baud


def test_the_azimuths_stop_goes_when_the_axis_gap_allows_not_a_gap_after_the_stop(
    rig: Rig,
) -> None:
    v = rig("rc2800", emulator=FAST)
    v.run_until_state(MotionState.IDLE, 30)
    v.target(200, None)  # the azimuth turns, the elevation stays
    v.run_until(lambda h: h.state is MotionState.MOVING and h.truth().az_deg > 30, 30, "turning")
    v.run_until(lambda h: h.writes[-1].data == b"E\r" and h.writes[-1].t == h.now, 5, "E asked")
    e_t = v.now
    v.run_for(STOP_AFTER_E_S)
    assert v.writes[-1].t == e_t and v.truth().is_moving  # the line quiet since that E CR
    too_soon = v.truth().too_soon
    stop_t = v.now
    v.stop()
    v.run_until(lambda h: not h.truth().is_moving, 10, "stopped")
    az_stop = [w.t for w in v.writes if w.t >= stop_t and w.data.startswith(b"A\r")]
    assert az_stop and az_stop[0] <= e_t + AXIS_GAP_S + SLACK_S, [
        (round(w.t - e_t, 3), w.data) for w in v.writes if w.t >= e_t
    ]
    assert v.truth().too_soon == too_soon  # the box's axis gap kept
