"""Review 52 (cold review of 7447112e, tracking.py rule 5): "a start whose first target is
refused holds the rotor where it is: a turn under way ... is stopped". Not on a DCU-1: it
reports no position, its motion is ``unknown`` (motion.py rule 6) while it carries out the
turn the bridge sent it, and ``_turning`` asks for MOVING. ``track sun`` with the sun in a
keep-out sector, said "...; holding", leaves the DCU-1 turning on to the older target, 120
degrees from the sun: review 50's finding 3 as it was, on the one model that cannot be seen.
The DCU-1 takes a stop (``;``) mid-turn, as the Rotor-EZ the fix was proven on does."""

from __future__ import annotations

from bridge.core.model import ErrorKind
from bridge.sky import Body, Sky
from tests.engine.test_session_tracking import SUN_EPOCH, off_deg, sun_up_somewhere
from tests.engine.virtual import VirtualRotator
from tests.support.sky import sun_altaz


def test_a_dcu1_turning_when_a_refused_tracking_start_comes_is_stopped() -> None:
    wall = SUN_EPOCH
    lat, lon = sun_up_somewhere(wall, 20.0, 50.0)
    sun_az = sun_altaz(lat, lon, wall)[0]
    away = sun_az - 120.0 if sun_az > 180.0 else sun_az + 120.0  # never across north
    sector = [round(sun_az) - 10, round(sun_az) + 10]  # the sun in it for the whole test
    toward = 20.0 if away > sun_az else -20.0  # (never through the sector)
    emulator = {"start_az_deg": round(sun_az + toward)}
    settings = {"keep_out": [sector]}
    with VirtualRotator(
        "dcu1", sky=Sky(lat, lon), wall_epoch_s=wall, emulator=emulator, settings=settings
    ) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.run_for(6.0)  # (its brake delay after the start is over)
        v.target(round(away))
        v.run_until(lambda h: off_deg(h.truth().az_deg, sun_az) >= 30.0, 30, "turning away")
        t, here = v.now, v.truth().az_deg
        v.track(Body.sun())
        v.run_for(60.0)  # (the old target is some 15 s on: not a deadline)
        assert v.status.tracking is not None  # taken, and holding
        [refused] = v.errors(ErrorKind.REFUSED, since=t)
        assert "keep-out" in refused.message and "holding" in refused.message
        assert v.frames("stop", since=t) != []  # observed: nothing sent
        assert off_deg(v.truth().az_deg, here) <= 15.0  # observed: on to the old target
