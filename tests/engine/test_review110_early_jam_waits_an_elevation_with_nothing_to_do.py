"""Review 110 (attacking 2f3db9a5, motion.py rule 2 ``carried_rest_from``): a carried turn rests
once every axis has shown no move for its own time, counted for an axis not seen move from the
first reading back. So an azimuth-only turn carried over a replug that jams in the first seconds
is stopped only when the elevation's own time is over, though the elevation had nothing to do in
that turn (the lost target's elevation, 0, is where it stands). Review 101's GS-232B with its
elevation set slow (``el_speed_deg_s = 1.0``: its own time 4.8 s), the azimuth jammed 1 s after
the port answers, its motor driving: controller.py rule 13's stop went 3.9 s after the jam, not
by the azimuth's own time (1.7 s, as it is for a jam 4 s on); with ``el_speed_deg_s = 0.5``
8.5 s. Review 101's guard jams only after the elevation has been shown still for its time
(6 s), and this window stays open. Before 2f3db9a5: 1.7 s."""

from __future__ import annotations

import pytest

from bridge.core.model import ErrorKind
from bridge.session import motion as mo
from tests.engine.carried import carried_azimuth_turn
from tests.engine.virtual import VirtualRotator

SLOW_EL_DEG_S = 1.0  # review 101's: an elevation set slow (its own time 4.8 s)
SLOWER_EL_DEG_S = 0.5  # (observed 8.5 s)
JAM_AFTER_S = 1.0  # after the port answers: the azimuth's carried move already read


# the elevation at its aim, or left out of the target; review 110's two slow elevations
@pytest.mark.parametrize("el_aim", [0.0, None])
@pytest.mark.parametrize("el_speed_deg_s", [SLOW_EL_DEG_S, SLOWER_EL_DEG_S])
def test_an_early_jam_of_an_azimuth_only_carried_turn_is_stopped_by_the_azimuths_time(
    el_aim: float | None, el_speed_deg_s: float
) -> None:
    emulator = {"start_az_deg": 62, "start_el_deg": 0}
    with VirtualRotator(
        "gs232b", emulator=emulator, settings={"el_speed_deg_s": el_speed_deg_s}
    ) as v:
        cfg = v.cfg.motion
        seen = mo.axis_seen_s(cfg)
        assert JAM_AFTER_S < seen["elevation"]  # (the set-up: inside the elevation's own time)
        carried_azimuth_turn(v, el_aim)
        v.run_for(JAM_AFTER_S)  # (the azimuth read turning on: not a deadline)
        assert v.truth().is_moving and v.status.moving and v.truth().el_deg == 0.0
        jam_t = v.now
        v.jam()  # the azimuth jams, its motor driving
        v.run_until(lambda h: "stop" in {f.outcome for f in h.frames(since=jam_t)}, 30, "stopped")
        [stop, *_] = [f for f in v.frames(since=jam_t) if f.outcome == "stop"]
        assert any("short of its turn" in e.message for e in v.errors(ErrorKind.STOP, since=jam_t))
        # the azimuth's own time and a moving poll, as for a jam later on: observed 3.9 s (8.5 s
        # with the elevation at 0.5 deg/s)
        allowed = max(cfg.settle_s, seen["azimuth"]) + v.cfg.moving_poll_interval_s
        assert stop.time_s - jam_t <= allowed, (stop.time_s - jam_t, allowed)
