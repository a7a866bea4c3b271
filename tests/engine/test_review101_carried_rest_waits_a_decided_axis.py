"""Review 101 (31a878ae, motion.py rule 2 ``still_from``): a turn the controller finishes by
itself (``carried``) is called at rest only after ``max(settle_s, carried_seen_s)`` from its last
move: the slowest axis's time, whichever axis turns and whether or not that slowest axis has
already been shown still for its own time. After a replug mid azimuth-only turn on a GS-232B
whose elevation is set slow (``el_speed_deg_s = 1.0``: its ``axis_seen_s`` 4.8 s), the
elevation shows no move for 6 s (longer than its own time: it is not turning), then the azimuth
jams with its motor driving. controller.py rule 13 stops a carried turn that rests short of its
aim "in case its motor still drives": before 31a878ae that stop went out 1.5 s after the jam
(rule 2's ``settle_s``), now 4.9 s after it, the jammed motor driven 3.4 s longer and the status
saying 'moving' all that while (with ``el_speed_deg_s = 0.5``: 9.3 s). Waiting for the
elevation's time is review 89's fault again (the slowest axis's time for every axis): the
azimuth's own time (1.1 s) is what a slow azimuth needs to show it moves on."""

from __future__ import annotations

from bridge.core.model import ErrorKind
from bridge.session import motion as mo
from tests.engine.carried import at_rest, replugged
from tests.engine.virtual import VirtualRotator

SLOW_EL_DEG_S = 1.0  # an elevation set slow (its axis_seen_s 4.8 s; the azimuth's 1.1 s)
EL_SHOWN_STILL_S = 6.0  # after the replug, before the jam: past the elevation's own time


def test_a_jam_of_a_carried_azimuth_turn_is_stopped_by_the_azimuths_own_time() -> None:
    emulator = {"start_az_deg": 62, "start_el_deg": 0}
    with VirtualRotator(
        "gs232b", emulator=emulator, settings={"el_speed_deg_s": SLOW_EL_DEG_S}
    ) as v:
        cfg = v.cfg.motion
        seen = mo.axis_seen_s(cfg)
        assert seen["elevation"] < EL_SHOWN_STILL_S  # (the set-up: not a deadline)
        at_rest(v)
        v.target(250, 0)
        v.run_until(lambda h: h.truth().az_deg >= 80.0, 60, "the azimuth turning")
        replugged(v)
        v.run_for(EL_SHOWN_STILL_S)  # the elevation still all along, the azimuth turning on
        assert v.truth().is_moving and v.status.moving
        jam_t = v.now
        v.jam()  # the azimuth jams, its motor driving
        v.run_until(lambda h: "stop" in {f.outcome for f in h.frames(since=jam_t)}, 30, "stopped")
        [stop] = [f for f in v.frames(since=jam_t) if f.outcome == "stop"]
        [error] = v.errors(ErrorKind.STOP, since=jam_t)
        assert "short of its turn" in error.message
        # the azimuth's own time, as rule 2's settle_s, and a moving poll: observed 4.9 s
        allowed = max(cfg.settle_s, seen["azimuth"]) + v.cfg.moving_poll_interval_s
        assert stop.time_s - jam_t <= allowed, (stop.time_s - jam_t, allowed)
