"""Review 71: an RC2800 az/el's stop right after an ``E`` CR poll now begins ``E`` CR ``S`` CR,
the azimuth's ``A`` CR ``S`` CR waiting out the box's 200 ms between axes (rc2800.py rule 9).
Every STOP from MQTT reaches the session twice, the stop lane's and the main connection's copy
a few tens of milliseconds later, and the second is owed as a repeat 0.1 s after the first
(session/stops.py rule 1). That repeat, a stop written, cancels what waits in the outbox (the
azimuth's frame, still 0.1 s from going) and begins again with the axis the last frame named:
the elevation, once more. The azimuth, the only axis turning here, gets its stop 0.3 s after
the STOP instead of 0.2 s (before the change: at once), and the repeat meant to make up for a
lost stop frame never goes to it: 1.8 degrees of coast at 6 degrees a second where it was 0.03.
In virtual time (tests/engine/virtual.py)."""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
FAST = {"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0}
AXIS_GAP_S = 0.2  # the box's 200 ms between its axes (more-controllers.md)
COPY_S = 0.05  # the main connection's copy of the stop lane's STOP comes this much later
SLACK_S = 0.02  # a few byte times at 9600 baud
RUN_ON_DEG = 1.5  # the azimuth's coast if its stop goes when the axis gap allows (1.2 + slack)


def test_the_repeat_of_a_double_stop_does_not_push_back_the_azimuths_stop(rig: Rig) -> None:
    v = rig("rc2800", emulator=FAST)
    v.run_until_state(MotionState.IDLE, 30)
    v.target(200, None)  # the azimuth turns, the elevation stays
    v.run_until(lambda h: h.state is MotionState.MOVING and h.truth().az_deg > 30, 30, "turning")
    v.run_until(lambda h: h.writes[-1].data == b"E\r" and h.writes[-1].t == h.now, 5, "E asked")
    e_t, az_at_stop = v.now, v.truth().az_deg
    v.stop()  # the stop lane's
    v.run_for(COPY_S)
    v.stop()  # the main connection's copy
    v.run_until(lambda h: not h.truth().is_moving, 10, "stopped")
    az_stop = [w.t for w in v.writes if w.t >= e_t and w.data.startswith(b"A\r")]
    assert az_stop and az_stop[0] <= e_t + AXIS_GAP_S + SLACK_S, [
        (round(w.t - e_t, 3), w.data) for w in v.writes if w.t >= e_t
    ]
    assert v.truth().az_deg - az_at_stop < RUN_ON_DEG
    assert v.truth().too_soon == 0  # the box's axis gap kept
