"""Review 53 (cold review of d2618151, ``Motion.carried``): parts.py rule 8 says "a turn the
bridge saw begin from rest with the link up is a hand as ever". ``link_down`` keeps only that
the rotor turned (``lost_turning``), not whose turn it was, and the first reading back marks any
such turn ``carried``: a hand at the panel that the bridge watched begin, still turning when the
adapter is replugged (a USB reset, a cable knocked), comes back as the controller finishing a
turn by itself. A ``track sun`` then takes it for the turn the start found: tracking stays on,
stops the hand's turn and turns the antenna to the sun (review 52's finding, across a replug).
What a user notices: the beam he is turning at the panel is stopped and turned away from him."""

from __future__ import annotations

from bridge.sky import Body, Sky
from tests.engine.test_session_tracking import SUN_EPOCH, off_deg, sun_up_somewhere
from tests.engine.virtual import VirtualRotator
from tests.support.sky import sun_altaz


def test_a_hand_turning_the_rotor_across_a_replug_ends_a_tracking_start() -> None:
    wall = SUN_EPOCH
    lat, lon = sun_up_somewhere(wall, 20.0, 50.0)
    sun_az = sun_altaz(lat, lon, wall)[0]
    away = sun_az - 120.0 if sun_az > 180.0 else sun_az + 120.0  # never across north
    toward = 20.0 if away > sun_az else -20.0
    emulator = {"start_az_deg": round(sun_az + toward)}
    with VirtualRotator("rotorez", sky=Sky(lat, lon), wall_epoch_s=wall, emulator=emulator) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.run_until(lambda h: h.status.state is not None and not h.status.moving, 30, "at rest")
        v.run_for(6.0)  # the Rotor-EZ's brake delay after its start is over
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
