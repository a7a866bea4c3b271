"""Review 73 (d609655e, parts.py rule 10: ``StartHalt.owed``): review 70's refused start right
after a replug mid-turn, on a DCU-1. Its turn is never seen (no readings: motion.py rule 6), so
it is never ``carried`` and nothing is owed; and ``turning`` counts a blind turn only while the
bridge's own target is out, which the unplug dropped ("the controller may finish it by itself
(unseen, not stopped)", the log says). So a follow start whose first grid is refused right
after the replug halts nothing, and the DCU-1 turns on some 90 degrees to the target from
before the unplug under 'refused'. Without the replug the same refusal stops the turn (two
stop frames at once), and after d609655e a Rotor-EZ's is stopped once a reading shows it."""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import ErrorKind
from tests.engine.test_attack19_follow_start_refused_grid import (
    follower_by_a_keep_out,
    turning_away_from_the_partner,
)
from tests.engine.test_review70_refused_start_after_replug import replugged_mid_turn
from tests.engine.virtual import VirtualRotator
from tests.integration.test_pointing_bridge import angle_between


def test_a_dcu1s_refused_follow_start_right_after_a_replug_mid_turn_holds_the_rotor() -> None:
    # held where it was: observed 92 -> 182, no stop frame
    a_dcu1s_refused_follow_start_holds_the_rotor(replugged_mid_turn)


def a_dcu1s_refused_follow_start_holds_the_rotor(
    interrupted: Callable[[VirtualRotator], None],
) -> None:
    """A DCU-1 turning away from PARTNER, ``interrupted`` mid-turn (a replug, a restart); a
    follow start refused at once for the keep-out: it must stop the rotor where it was."""
    with follower_by_a_keep_out("dcu1") as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        turning_away_from_the_partner(v)
        interrupted(v)
        t, here = v.now, v.truth().az_deg
        v.follow(True)
        v.heard("JA1ABC", "PM95")
        v.run_for(60.0)  # (the old target is some 20 s on: not a deadline)
        [refused] = v.errors(ErrorKind.REFUSED, since=t)
        assert "keep-out" in refused.message
        assert v.status.following is not None  # taken, and waiting for a grid it may turn to
        assert "stop" in {f.outcome for f in v.frames(since=t)}
        assert angle_between(v.truth().az_deg, here) <= 15.0, (here, v.truth().az_deg)
