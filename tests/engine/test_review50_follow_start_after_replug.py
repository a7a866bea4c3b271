"""Review 50 (cold review of the tracking start mid-turn), the follow start beside it: right
after a replug mid-turn the controller finishes its old turn by itself (its target dropped
with the port: session/motion.py rule 4), and ``R/follow on`` then ended following at once
as ``turned by hand`` (parts.py ``turned_by_hand``: before a first bearing, any turn with no
target was a hand), nobody at the front panel. The partner's grid, heard fresh, is the newest
word: it takes that turn's place as an ``R/target`` would (stopped first on a Rotor-EZ, then
its brake delay). What a user notices: following off, blamed on a hand, and the antenna 120
degrees from the partner, at a target nobody stands for any more."""

from __future__ import annotations

from bridge.core.model import MotionState
from tests.engine.test_follow import STATION, bearing
from tests.engine.virtual import VirtualRotator
from tests.integration.test_pointing_bridge import angle_between


def test_a_follow_start_right_after_a_replug_mid_turn_turns_the_rotor_to_the_partner() -> None:
    partner = bearing("PM95")
    away = partner - 120.0 if partner > 180.0 else partner + 120.0  # never across north
    emulator = {"start_az_deg": round(partner)}
    with VirtualRotator("rotorez", emulator=emulator, follow=STATION) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.run_until(lambda h: h.status.state is not None and not h.status.moving, 30, "at rest")
        v.run_for(6.0)  # the Rotor-EZ's brake delay after its start is over
        v.target(round(away))
        v.run_until(lambda h: angle_between(h.truth().az_deg, partner) >= 15.0, 30, "turning")
        v.run_for(0.1)  # (between two polls: a query torn by the unplug is another story)
        v.link_down()
        v.run_for(2.0)  # (the adapter out: not a deadline)
        v.link_up()
        v.run_until(lambda h: h.status.available, 10, "the controller answers again")
        assert v.truth().is_moving  # (it finishes its old turn by itself)
        v.follow(True)
        v.heard("JA1ABC", "PM95")
        v.run_for(60.0)  # (the old target is some 15 s on: not a deadline)
        assert v.status.following_ended is None  # before: "turned by hand"
        assert v.status.following is not None and v.status.following.grid == "PM95"
        assert v.state is MotionState.IDLE
        assert angle_between(v.truth().az_deg, partner) <= 3.0  # before: 120 degrees off
