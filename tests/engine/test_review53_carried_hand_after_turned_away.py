"""Review 53 (cold review of d2618151, ``Motion.carried``): the turn carried over a lost link is
no hand at a tracking start only while it is the controller finishing its old turn by itself
(motion.py rule 4, parts.py rule 8). ``carried`` is cleared at rest alone (``_at_rest``), not
when the bridge sends a target of its own into that turn (``commanded``): on a controller that
takes a new bearing while turning (a SPID) the flag rides along with the operator's new target,
and when a hand at the panel then turns the rotor away from that target (``turned away``, the
target dropped, the status blaming "the front panel") the hand's turn is "carried" still. A
``track sun`` in that moment takes the hand for the replugged turn: tracking stays on and its
first target turns the antenna back from where the hand is taking it. Without the replug before
it, the same hand ends tracking "turned by hand" and nothing is sent (review 52).
What a user notices: the beam he is turning at the panel is turned back to the sun."""

from __future__ import annotations

from bridge.sky import Body, Sky
from tests.engine.test_session_tracking import SUN_EPOCH, off_deg, sun_up_somewhere
from tests.engine.virtual import VirtualRotator
from tests.support.sky import sun_altaz


def test_a_hand_turning_a_spid_away_from_a_target_sent_after_a_replug_ends_tracking() -> None:
    wall = SUN_EPOCH
    lat, lon = sun_up_somewhere(wall, 20.0, 50.0)
    sun_az = sun_altaz(lat, lon, wall)[0]
    away = sun_az - 120.0 if sun_az > 180.0 else sun_az + 120.0  # never across north
    toward = 1.0 if away > sun_az else -1.0
    emulator = {"start_az_deg": round(sun_az)}
    with VirtualRotator("md01", sky=Sky(lat, lon), wall_epoch_s=wall, emulator=emulator) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.run_until(lambda h: h.status.state is not None and not h.status.moving, 30, "at rest")
        v.target(round(away))
        v.run_until(lambda h: off_deg(h.truth().az_deg, sun_az) >= 15.0, 30, "turning away")
        v.link_down()
        v.run_for(1.0)  # (the adapter out: not a deadline)
        v.link_up()
        v.run_until(lambda h: h.status.available, 10, "the controller answers again")
        v.run_until(lambda h: h.status.moving, 10, "its old turn followed by its readings")
        v.target(round(sun_az - 20.0 * toward))  # the operator's new bearing (SPID: at once)
        v.run_until(lambda h: h.status.target_az_deg is not None, 10, "the new target out")
        v.run_for(3.0)  # (it heads for it: not a deadline)
        v.manual_rotate(round(away))  # a hand at the panel, away from that target
        v.run_until(lambda h: h.status.target_az_deg is None, 60, "turned away: target dropped")
        hand = v.now
        v.track(Body.sun())
        v.run_until(lambda h: not h.truth().is_moving, 240, "the rotor at rest")
        v.run_for(30.0)
        assert v.frames("set", since=hand) == []  # observed: the sun's bearing
        assert off_deg(v.truth().az_deg, round(away)) <= 1.0  # where the hand left it
        assert v.status.tracking is None and v.status.tracking_ended == "turned by hand"
