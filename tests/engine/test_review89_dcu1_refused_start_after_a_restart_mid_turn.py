"""Review 89 (31e6aa00, parts.py rule 10 / motion.py rule 4): "a start refused before a just-started
bridge's readings have told whether the rotor turns owes the halt". A DCU-1 has no readings, so
they never tell; its link_up assumes the worst once (motion.py rule 6, ``busy_until_t``), but
``may_finish_blind`` counts only a turn lost with a port (``lost_turning``, a replug's), which a
new session never has. So review 84's case (the bridge restarted while the controller finishes
the old bridge's turn, a follow start refused at once) on a DCU-1: R/error says the start was
refused, no stop frame goes out, and the rotor turns on some 95 degrees to the old bridge's
target (observed 87 -> 182). After a replug the same refusal stops it (review 73's DCU-1 test),
and after a restart every model with readings is stopped (31e6aa00)."""

from __future__ import annotations

from bridge.core.model import ErrorKind
from tests.engine.test_attack19_follow_start_refused_grid import (
    follower_by_a_keep_out,
    turning_away_from_the_partner,
)
from tests.engine.test_review84_refused_start_after_a_restart_mid_turn import restarted_mid_turn
from tests.integration.test_pointing_bridge import angle_between


def test_a_dcu1s_refused_follow_start_right_after_a_restart_mid_turn_holds_the_rotor() -> None:
    with follower_by_a_keep_out("dcu1") as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        turning_away_from_the_partner(v)
        restarted_mid_turn(v)
        t, here = v.now, v.truth().az_deg
        v.follow(True)
        v.heard("JA1ABC", "PM95")
        v.run_for(60.0)  # (the old target is some 20 s on: not a deadline)
        [refused] = v.errors(ErrorKind.REFUSED, since=t)
        assert "keep-out" in refused.message
        assert v.status.following is not None  # taken, and waiting for a grid it may turn to
        # held where it was: observed 87 -> 182, no stop frame
        assert "stop" in {f.outcome for f in v.frames(since=t)}
        assert angle_between(v.truth().az_deg, here) <= 15.0, (here, v.truth().az_deg)
