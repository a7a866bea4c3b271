"""Review 46 (a cold run of ./demo): ``track sun`` typed while a Rotor-EZ was turning to a
long-path target some 300 degrees away left it turning there; the status said tracking sun
with the old target for most of a minute, and only once the rotor stood still at the old
target did tracking turn it back toward the sun. Rule 3 of session/tracking.py waits for an
idle rotor before each step on a controller that stops to re-target, which suits the steps of
a pass; but the first target of a tracking start is the user's newest command, and every
other newest command (an MQTT target, a preset, a nudge) stops a turning Rotor-EZ and turns it
to the new target after the brake delay. What a user notices: after ``track`` the rotor keeps
turning away from the body, as far as the old target, and then all the way back."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

from bridge.sky import Body, Sky
from tests.engine.test_session_tracking import SUN_EPOCH, off_deg, sun_up_somewhere
from tests.engine.virtual import VirtualRotator
from tests.support.sky import sun_altaz


@contextlib.contextmanager
def turning_away_from_the_sun(
    model: str = "rotorez",
) -> Iterator[tuple[VirtualRotator, float, float]]:
    """A rotor that stood on the sun turning 15 degrees or more away, to a target 120 degrees
    off it (never across north); with the station's latitude and longitude."""
    wall = SUN_EPOCH
    lat, lon = sun_up_somewhere(wall, 20.0, 50.0)
    sun_az = sun_altaz(lat, lon, wall)[0]
    away = sun_az - 120.0 if sun_az > 180.0 else sun_az + 120.0  # never across north
    emulator = {"start_az_deg": round(sun_az)}
    with VirtualRotator(model, sky=Sky(lat, lon), wall_epoch_s=wall, emulator=emulator) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.run_until(lambda h: h.status.state is not None and not h.status.moving, 30, "at rest")
        v.run_for(6.0)  # a Rotor-EZ's brake delay after its start is over
        v.target(round(away))
        v.run_until(lambda h: off_deg(h.truth().az_deg, sun_az) >= 15.0, 30, "turning away")
        yield v, lat, lon


def test_a_tracking_start_stops_a_rotor_ez_turning_away_from_the_body() -> None:
    with turning_away_from_the_sun() as (v, lat, lon):
        v.track(Body.sun())
        farthest = 0.0
        for _ in range(60):  # a minute: the old target is some 20 s of turning away
            v.run_for(1.0)
            sun = sun_altaz(lat, lon, v.wall())[0]
            farthest = max(farthest, off_deg(v.truth().az_deg, sun))
        assert farthest <= 30.0, f"turned on {farthest:.0f} degrees from the sun after track"
        assert off_deg(v.truth().az_deg, sun_altaz(lat, lon, v.wall())[0]) <= 1.5 + 3.0
        # stopped, then sent after its brake delay: never a bearing it ignores
        never = ("ignored: brake delay", "ignored: re-target while turning (stopped)")
        assert v.frames(*never) == []
