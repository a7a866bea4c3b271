"""Review 53 (cold review of d2618151, ``Motion.carried``): parts.py rule 8 says "a turn the
bridge saw begin from rest with the link up is a hand as ever". ``link_down`` keeps only that
the rotor turned (``lost_turning``), not whose turn it was, and the first reading back marks any
such turn ``carried``: a hand at the panel that the bridge watched begin, still turning when the
adapter is replugged (a USB reset, a cable knocked), comes back as the controller finishing a
turn by itself. A ``track sun`` then takes it for the turn the start found: tracking stays on,
stops the hand's turn and turns the antenna to the sun (review 52's finding, across a replug).
What a user notices: the beam he is turning at the panel is stopped and turned away from him."""

from __future__ import annotations

from bridge.sky import Body
from tests.engine.test_review52_hand_before_track_start import beside_the_sun
from tests.engine.test_session_tracking import off_deg


def test_a_hand_turning_the_rotor_across_a_replug_ends_a_tracking_start() -> None:
    with beside_the_sun() as (v, sun_az, away, toward):
        v.manual_rotate(round(away))  # a hand at the panel
        v.run_until(lambda h: h.status.moving, 10, "the bridge sees the hand's turn")
        v.link_down()
        v.run_for(1.0)  # (the adapter out: not a deadline)
        v.link_up()
        v.run_until(lambda h: h.status.available, 10, "the controller answers again")
        v.run_until(lambda h: h.status.moving, 10, "the hand's turn seen going on")
        hand = v.now
        v.track(Body.sun())
        v.run_until(lambda h: not h.truth().is_moving, 90, "the rotor at rest")
        v.run_for(30.0)
        assert {f.outcome for f in v.frames(since=hand)} == {"query"}  # observed: a stop, the sun
        assert off_deg(v.truth().az_deg, round(away)) <= 1.0  # where the hand left it
        assert v.status.tracking is None and v.status.tracking_ended == "turned by hand"
