"""Review 53 (cold review of d2618151, ``Motion.carried``): parts.py rule 8 now takes only a
turn "carried over a lost link" for the turn a tracking start found; "a turn the bridge saw
begin from rest with the link up is a hand as ever". A turn the bridge never saw begin is
neither: the bridge restarted (a crash, a host that rebooted: the end's own stop never went)
while a Rotor-EZ turned, and the controller finishes the old turn by itself, its target gone
with the process, as after a replug (review 50). The new session's first reading finds the
rotor where it is (motion.py rule 4's start-up, no ``lost_turning`` to carry), the next shows
it move, and ``carried`` is never set: ``track sun`` then ends at once "turned by hand" and the
rotor turns on to the old target. At 635b0cd5 (before d2618151) the same start stopped the turn
and turned the rotor to the sun, as after a replug.
What a user notices: after ``track sun`` the antenna turns on some 120 degrees away from the
sun and stays there; tracking is off, blamed on a hand nobody put on the panel."""

from __future__ import annotations

from bridge.session.session import RotatorSession
from bridge.sky import Body
from tests.engine.test_follow import STATION, bearing
from tests.engine.test_review46_track_start_mid_turn import turning_away_from_the_sun
from tests.engine.test_session_tracking import off_deg
from tests.engine.virtual import VirtualRotator
from tests.integration.test_pointing_bridge import angle_between
from tests.support.sky import sun_altaz


def restarted_mid_turn(v: VirtualRotator, within_s: float = 10) -> None:
    """The bridge's process gone mid-turn (no end, no stop) and started again: the controller
    answers and the old turn is seen going on (``within_s``: a limit, not a deadline)."""
    v.link_down(None)
    v.run_for(1.0)  # (not a deadline)
    v.session = RotatorSession(v.cfg)  # the bridge started again
    v._do(v.session.start(v.now))
    v.link_up()
    v.run_until(lambda h: h.status.available, within_s, "the controller answers again")
    v.run_until(lambda h: h.status.moving, within_s, "the old turn seen going on")


def test_a_tracking_start_right_after_a_restart_mid_turn_turns_the_rotor_to_the_body() -> None:
    with turning_away_from_the_sun() as (v, lat, lon):
        restarted_mid_turn(v)
        assert v.truth().is_moving  # (it finishes its old turn by itself)
        v.track(Body.sun())
        v.run_for(60.0)  # (the old target is some 15 s on; the sun's some 25 s back)
        sun = sun_altaz(lat, lon, v.wall())[0]
        assert v.status.tracking_ended is None  # observed: "turned by hand"
        assert off_deg(v.truth().az_deg, sun) <= 1.5 + 3.0  # observed: 120 degrees off


def test_a_follow_start_right_after_a_restart_mid_turn_turns_the_rotor_to_the_partner() -> None:
    """Following takes the same ``Before`` (follow.py rule 1): the partner's grid takes the
    old turn's place after a replug (review 50), not after a restart."""
    partner = bearing("PM95")
    away = partner - 120.0 if partner > 180.0 else partner + 120.0  # never across north
    with VirtualRotator("rotorez", emulator={"start_az_deg": round(partner)}, follow=STATION) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.run_until(lambda h: h.status.state is not None and not h.status.moving, 30, "at rest")
        v.run_for(6.0)  # the Rotor-EZ's brake delay after its start is over
        v.target(round(away))
        v.run_until(lambda h: angle_between(h.truth().az_deg, partner) >= 15.0, 30, "turning")
        v.run_for(0.1)  # (between two polls: a query torn by the unplug is another story)
        restarted_mid_turn(v)
        v.follow(True)
        v.heard("JA1ABC", "PM95")
        v.run_for(60.0)  # (the old target is some 15 s on: not a deadline)
        assert v.status.following_ended is None  # observed: "turned by hand"
        assert angle_between(v.truth().az_deg, partner) <= 3.0  # observed: 120 degrees off
