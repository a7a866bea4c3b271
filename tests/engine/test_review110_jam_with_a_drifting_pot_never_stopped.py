"""Review 110 (attacking bbafe67a, motion.py rule 2: "a carried axis that creeps inside
noise_deg is not yet at rest"): each reading of a carried turn's axis further from where it last
moved than any since restarts that axis's own time (``az_crept_deg``, ``az_moved_t``), however
slowly it creeps, and a move beyond ``noise_deg`` starts the creep over from zero. So a pot
reading that drifts a tenth at a time (a stalled motor heating, its current on the pot's
ground), a tenth every 1.2 s, keeps a jammed carried turn 'moving' for ever: 0.08 deg/s, 70
times slower than the RC2800's 6 deg/s, slower than any turn rule 6 allows for. An RC2800
(noise_deg 0.5, read in tenths) whose turn was carried over a replug jams with its motor
driving: controller.py rule 13's stop ("in case its motor still drives") never goes, and
R/status shows it moving a minute on. Before bbafe67a the same readings were at rest 1.7 s after
the jam and the stop went (a creep of 0.6 degrees takes 7.2 s, rule 2's settle_s is 1.5)."""

from __future__ import annotations

import re
from collections.abc import Callable

from bridge.core.model import ErrorKind
from bridge.session import motion as mo
from tests.engine.carried import at_rest, jammed_after_a_carried_turn, replugged
from tests.engine.garblers import rc2800_drifting_from
from tests.engine.virtual import VirtualRotator

DRIFT_DEG = 0.1  # a count of the RC2800's readings
DRIFT_EVERY_S = 1.2  # 0.08 deg/s: no turn of a 6 deg/s rotor
WATCHED_S = 60.0


def drifting_from(since: float) -> Callable[[bytes, float], bytes]:
    """The box's lines as they reach the host, each bearing a tenth more every DRIFT_EVERY_S
    since ``since``."""
    return rc2800_drifting_from(since, DRIFT_EVERY_S, DRIFT_DEG)


def test_a_jammed_carried_turn_read_drifting_inside_noise_is_stopped() -> None:
    with VirtualRotator("rc2800-az", emulator={"start_az_deg": 10}) as v:
        cfg = v.cfg.motion
        own_s = max(cfg.settle_s, mo.axis_seen_s(cfg)["azimuth"])
        assert DRIFT_EVERY_S < own_s  # (the set-up: the drift restarts the axis's own time)
        assert DRIFT_DEG / DRIFT_EVERY_S < cfg.nominal_speed_deg_s / 50  # (no turn)
        jam_t = jammed_after_a_carried_turn(v, drifting_from)
        v.run_for(WATCHED_S)
        # observed: no stop in a minute, R/status 'moving' at 76.7 (jammed at 71.8)
        [stop, *_] = [f for f in v.frames(since=jam_t) if f.outcome == "stop"] or [None]
        assert stop is not None, "no stop to a jammed rotor whose motor drives"
        allowed = own_s + v.cfg.moving_poll_interval_s + DRIFT_EVERY_S
        assert stop.time_s - jam_t <= allowed, (stop.time_s - jam_t, allowed)
        assert any("short of its turn" in e.message for e in v.errors(ErrorKind.STOP, since=jam_t))
        assert not v.status.moving


def drifting_degrees_from(since: float) -> Callable[[bytes, float], bytes]:
    """A GS-232B's lines as they reach the host, the azimuth a whole degree (a count of its
    readings) more every DRIFT_EVERY_S since ``since``."""
    line = bytearray()

    def drift(data: bytes, now: float) -> bytes:
        line.extend(data)
        if not data.endswith(b"\r"):
            return b""
        whole = bytes(line)
        line.clear()
        counts = int((now - since) // DRIFT_EVERY_S)
        return re.sub(
            rb"AZ=(\d+)", lambda m: b"AZ=%03d" % (int(m.group(1)) + counts), whole, count=1
        )

    return drift


def test_a_jammed_carried_turn_read_in_whole_degrees_drifting_is_stopped() -> None:
    """The same on a box read in whole degrees (noise_deg 2): each count of the drift is a
    reading's whole step, a first one as sudden as a hand's first degree (motion.py rule 2
    counts it), the next slower than any turn (0.83 deg/s; the slowest 4): it rests between
    rule 1's moves. On bbafe67a: moving for ever, no stop."""
    with VirtualRotator("gs232b", emulator={"start_az_deg": 62, "start_el_deg": 0}) as v:
        cfg = v.cfg.motion
        own_s = max(cfg.settle_s, mo.axis_seen_s(cfg)["azimuth"])
        at_rest(v)
        v.target(250)
        v.run_until(lambda h: h.truth().az_deg >= 80.0, 60, "the azimuth turning")
        replugged(v)
        v.run_for(3.0)  # (the carried turn followed: not a deadline)
        assert v.truth().is_moving and v.status.moving
        jam_t = v.now
        v.jam()  # its motor driving
        v.to_host = drifting_degrees_from(jam_t)
        v.run_for(WATCHED_S)
        [stop, *_] = [f for f in v.frames(since=jam_t) if f.outcome == "stop"] or [None]
        assert stop is not None, "no stop to a jammed rotor whose motor drives"
        allowed = own_s + v.cfg.moving_poll_interval_s + 2 * DRIFT_EVERY_S
        assert stop.time_s - jam_t <= allowed, (stop.time_s - jam_t, allowed)
        assert any("short of its turn" in e.message for e in v.errors(ErrorKind.STOP, since=jam_t))
