"""A tracking or following start is the user's newest command: the turn under way to an older
target is handled as for any newest target (session/tracking.py rule 3, session/follow.py rule
2, session/targets.py), on each controller by its own rules. A Rotor-EZ (review 46,
tests/engine/test_review46_track_start_mid_turn.py) is stopped and turned after its brake delay;
a SatEL's slew is stopped (a stop, the one input it takes while it slews) and the body slewed
to once it is still; a GS-232B is re-targeted on the fly, never stopped. What a user notices:
after ``track`` (or ``follow``) the rotor turns no further away from where it was asked to
point."""

from __future__ import annotations

from bridge.emulators.satel import Outcome as SatelOutcome
from bridge.sky import Body, Sky
from tests.engine.test_follow import STATION, bearing
from tests.engine.test_session_tracking import SUN_EPOCH, off_deg, sun_up_somewhere
from tests.engine.virtual import VirtualRotator
from tests.support.sky import sun_altaz

# the Rotor-EZ's frames of a bearing it did not take (its brake delay, or a turn under way)
IGNORED = ("ignored: brake delay", "ignored: re-target while turning (stopped)")


def away_from(az_deg: float) -> float:
    """A bearing 120 degrees from ``az_deg``, never across north (a 0..360 rotor's stop)."""
    return az_deg - 120.0 if az_deg > 180.0 else az_deg + 120.0


def slewing(v: VirtualRotator) -> bool:
    return bool(v.device.state(v.now).slewing)


def test_a_tracking_start_stops_a_satel_slewing_away_and_slews_to_the_body() -> None:
    wall = SUN_EPOCH
    lat, lon = sun_up_somewhere(wall, 20.0, 50.0)
    sun_az, sun_el = sun_altaz(lat, lon, wall)
    emulator = {"start_az_deg": round(sun_az), "start_el_deg": round(sun_el)}
    with VirtualRotator("satel", sky=Sky(lat, lon), wall_epoch_s=wall, emulator=emulator) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.run_until(lambda h: h.status.state is not None and not h.status.moving, 30, "at rest")
        v.target(round(away_from(sun_az)), round(sun_el))
        v.run_until(lambda h: off_deg(h.truth().az_deg, sun_az) >= 15.0, 30, "slewing away")
        assert slewing(v)
        t = v.now
        v.track(Body.sun())
        farthest = 0.0
        for _ in range(60):  # a minute: the old target is some 15 s of slewing away
            v.run_for(1.0)
            sun = sun_altaz(lat, lon, v.wall())[0]
            farthest = max(farthest, off_deg(v.truth().az_deg, sun))
        assert farthest <= 30.0, f"slewed on {farthest:.0f} degrees from the sun after track"
        sun_now = sun_altaz(lat, lon, v.wall())
        assert off_deg(v.truth().az_deg, sun_now[0]) <= 7.0  # (a step and its lag, as a pass)
        # the slew was stopped (its one input), and nothing else was sent into any slew
        assert [f.data for f in v.frames(since=t) if f.data != b"z"][0] == b"s"
        assert v.device.misuse_frames() == []
        assert len(v.frames(SatelOutcome.SLEW, since=t)) >= 1
        assert v.errors() == []


def test_a_tracking_start_re_targets_a_gs232b_on_the_fly() -> None:
    """A GS-232B takes a new bearing while it turns (protocols: re-target on the fly): the
    start's first step goes at once, without a stop."""
    wall = SUN_EPOCH
    lat, lon = sun_up_somewhere(wall, 20.0, 50.0)
    sun_az, sun_el = sun_altaz(lat, lon, wall)
    speeds = {"az_speed_deg_s": 2.0, "el_speed_deg_s": 1.0}
    emulator = {**speeds, "start_az_deg": round(sun_az), "start_el_deg": round(sun_el)}
    with VirtualRotator(
        "gs232b", sky=Sky(lat, lon), wall_epoch_s=wall, emulator=emulator, settings=speeds
    ) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.run_until(lambda h: h.status.state is not None and not h.status.moving, 30, "at rest")
        v.target(away_from(sun_az), sun_el)
        v.run_until(lambda h: off_deg(h.truth().az_deg, sun_az) >= 15.0, 30, "turning away")
        t = v.now
        v.track(Body.sun())
        v.run_for(30.0)
        assert v.frames("stop", since=t) == []  # re-targeted, never stopped
        assert v.frames("move", since=t)
        sun = sun_altaz(lat, lon, v.wall())[0]
        assert off_deg(v.truth().az_deg, sun) <= 1.5 + 3.0
        assert v.errors() == []


def test_a_following_start_stops_a_rotor_ez_turning_away_from_the_partner() -> None:
    """follow.py rule 2: as a tracking start, the partner's bearing is the newest target: the
    turn to the older one is stopped, and the partner's sent after the brake delay."""
    partner = bearing("PM95")  # JA, from Berlin: some 40 degrees
    emulator = {"start_az_deg": round(partner)}
    with VirtualRotator("rotorez", emulator=emulator, follow=STATION) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.run_until(lambda h: h.status.state is not None and not h.status.moving, 30, "at rest")
        v.run_for(6.0)  # the Rotor-EZ's brake delay after its start is over
        v.target(away_from(partner))
        v.run_until(lambda h: off_deg(h.truth().az_deg, partner) >= 15.0, 30, "turning away")
        v.heard("JA1ABC", "PM95")
        v.follow(True)
        farthest = 0.0
        for _ in range(60):  # a minute: the old target is some 20 s of turning away
            v.run_for(1.0)
            farthest = max(farthest, off_deg(v.truth().az_deg, partner))
        assert farthest <= 30.0, f"turned on {farthest:.0f} degrees from the partner"
        assert off_deg(v.truth().az_deg, partner) <= 3.0
        assert v.frames(*IGNORED) == []
        assert v.errors() == []
