"""Review 124 (cold review of a0e05853, motion.py rule 2 ``_step_hold_s``): a carried axis's
reading one step off where it stood holds the turn's rest till a turn at CREEP_SHARE of that
axis's slowest would read a second step on: one step over a quarter of its slowest speed. On a
GS-232B (whole degrees, 2 degrees of noise) that is longer than the axis's own time
(``axis_seen_s``: noise and a step at its slowest, a moving poll's margin), by a third. With
the elevation set slow (``el_speed_deg_s`` 0.5, as review 110's rotor), an azimuth-and-elevation
turn carried over a replug and jammed (both motors driving) while its elevation reads one degree
past where it last moved is held 12 s from that reading: controller.py rule 13's stop goes some
11.5-12 s after the jam, 2.4 s later than at 51a2f016 (9.1-9.5 s, the elevation's own time),
the jammed motors driving all the while."""

from __future__ import annotations

import pytest

from bridge.core.model import ErrorKind
from bridge.session import motion as mo
from tests.engine.carried import at_rest, replugged
from tests.engine.virtual import VirtualRotator

EL_SPEED = 0.5  # deg/s: the elevation set slow (review 110's rotor), as the emulator turns it


@pytest.mark.parametrize("jam_after_s", [0.76, 0.99, 1.22])  # (the readings' phases)
def test_a_jammed_carried_turn_is_stopped_within_its_slow_elevations_own_time(
    jam_after_s: float,
) -> None:
    emulator = {"start_az_deg": 20, "start_el_deg": 0, "el_speed_deg_s": EL_SPEED}
    with VirtualRotator("gs232b", emulator=emulator, settings={"el_speed_deg_s": EL_SPEED}) as v:
        cfg = v.cfg.motion
        seen = mo.axis_seen_s(cfg)
        at_rest(v)
        v.target(200, 60)
        v.run_until(lambda h: h.truth().el_deg >= 5.0, 60, "the elevation turning")
        replugged(v)
        v.run_for(jam_after_s)  # (the carried turn read turning on: not a deadline)
        assert v.truth().is_moving and v.status.moving
        jam_t = v.now
        v.jam()  # both motors driving, the rotor still
        v.run_until(lambda h: "stop" in {f.outcome for f in h.frames(since=jam_t)}, 60, "stopped")
        [stop, *_] = [f for f in v.frames(since=jam_t) if f.outcome == "stop"]
        assert any("short of its turn" in e.message for e in v.errors(ErrorKind.STOP, since=jam_t))
        # the slower axis's own time and a moving poll
        allowed = max(cfg.settle_s, *seen.values()) + v.cfg.moving_poll_interval_s
        assert stop.time_s - jam_t <= allowed, (stop.time_s - jam_t, allowed)


@pytest.mark.parametrize("jam_after_s", [0.5, 0.87, 1.24, 1.61])  # (the readings' phases)
def test_a_jammed_carried_turn_at_speed_x1_is_stopped_within_its_elevations_own_time(
    jam_after_s: float,
) -> None:
    """The same hold at a stock setting: the speed option at X1 (a quarter of nominal, the
    elevation's slowest 0.42 deg/s): an elevation-only turn carried over a replug and jammed."""
    with VirtualRotator("gs232b", emulator={"start_az_deg": 20, "start_el_deg": 0}) as v:
        at_rest(v)
        v.option("speed", "1")
        v.run_for(2.0)  # (X1 sent and taken: not a deadline)
        assert v.truth().speed_level == 1
        cfg = v.session.controller.cfg
        seen = mo.axis_seen_s(cfg.motion)
        v.target(None, 80)
        v.run_until(lambda h: h.truth().el_deg >= 8.0, 60, "the elevation turning")
        replugged(v)
        v.run_for(jam_after_s)  # (the carried turn read turning on: not a deadline)
        assert v.truth().is_moving and v.status.moving
        jam_t = v.now
        v.jam()  # its motor driving, the rotor still
        v.run_until(lambda h: "stop" in {f.outcome for f in h.frames(since=jam_t)}, 60, "stopped")
        [stop, *_] = [f for f in v.frames(since=jam_t) if f.outcome == "stop"]
        assert any("short of its turn" in e.message for e in v.errors(ErrorKind.STOP, since=jam_t))
        allowed = max(cfg.motion.settle_s, *seen.values()) + cfg.moving_poll_interval_s
        assert stop.time_s - jam_t <= allowed, (stop.time_s - jam_t, allowed)
