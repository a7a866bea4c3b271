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

from bridge.sky import Body, Sky
from tests.engine.test_session_tracking import SUN_EPOCH, off_deg, sun_up_somewhere
from tests.engine.virtual import VirtualRotator
from tests.support.sky import sun_altaz


def test_a_tracking_start_right_after_a_replug_mid_turn_turns_the_rotor_to_the_body() -> None:
    wall = SUN_EPOCH
    lat, lon = sun_up_somewhere(wall, 20.0, 50.0)
    sun_az = sun_altaz(lat, lon, wall)[0]
    away = sun_az - 120.0 if sun_az > 180.0 else sun_az + 120.0  # never across north
    emulator = {"start_az_deg": round(sun_az)}
    with VirtualRotator("rotorez", sky=Sky(lat, lon), wall_epoch_s=wall, emulator=emulator) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.run_until(lambda h: h.status.state is not None and not h.status.moving, 30, "at rest")
        v.run_for(6.0)  # the Rotor-EZ's brake delay after its start is over
        v.target(round(away))
        v.run_until(lambda h: off_deg(h.truth().az_deg, sun_az) >= 15.0, 30, "turning away")
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
