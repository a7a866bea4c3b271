"""Review 50 (cold review of the tracking start mid-turn, d2067f87..f87b1948): a tracking start
is the user's newest command, and its first target goes "as any new target does, whatever the
rotor was doing" (docs/tracking.md, "Starting"). Not right after a replug: the port came back
while the controller finished its old turn by itself (its target dropped with the port: the
bridge follows the turn by its readings, session/motion.py rule 4), and ``track sun`` then
ended at once with ``tracking_ended: turned by hand``: a turn with no target and no stop of the
bridge's out, and no tracking target yet to measure from, is "any such turn" to
parts.py ``turned_by_hand``. Nobody touched the front panel. The same bearing sent on
``R/target`` at that moment stops the turn and turns the rotor there after the brake delay.
What a user notices: after ``track sun`` the rotor turns on some 120 degrees away from the sun,
to a target nobody stands for any more, and stays there; tracking is off, blamed on a hand."""

from __future__ import annotations

from bridge.sky import Body
from tests.engine.test_review46_track_start_mid_turn import turning_away_from_the_sun
from tests.engine.test_session_tracking import off_deg
from tests.support.sky import sun_altaz


def test_a_tracking_start_right_after_a_replug_mid_turn_turns_the_rotor_to_the_body() -> None:
    with turning_away_from_the_sun() as (v, lat, lon):
        v.link_down()
        v.run_for(2.0)  # (the adapter out: not a deadline)
        v.link_up()
        v.run_until(lambda h: h.status.available, 10, "the controller answers again")
        assert v.truth().is_moving  # (it finishes its old turn by itself)
        v.track(Body.sun())
        v.run_for(
            60.0
        )  # (the old target is some 15 s on; the sun's some 25 s back: not a deadline)
        sun = sun_altaz(lat, lon, v.wall())[0]
        assert v.status.tracking_ended is None  # observed: "turned by hand"
        assert off_deg(v.truth().az_deg, sun) <= 1.5 + 3.0  # observed: 120 degrees off
