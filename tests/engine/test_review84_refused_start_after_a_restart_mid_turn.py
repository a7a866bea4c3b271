"""Review 84 (429ed454: parts.py rule 10, ``StartHalt.owed``): a start refused right after a
replug mid-turn now halts the turn the controller goes on with, once the next readings show it
move. The same start right after a restart of the bridge mid-turn does not: a new session knows
of no lost turn (``lost_turning`` is a replug's), so at the restart's first reading the refusal
finds nothing ``turning`` and owes nothing, the second reading (0.2 s on, on a Rotor-EZ) shows
the controller finishing the turn the bridge before it sent, and the refusal is never judged
again (follow.py rule 5). R/error says the follow start was refused, while the rotor turns on
some 100 degrees to the old target (observed 84 -> 182), and following ends "turned by hand"
(nobody touched the panel): review 70's case with a restart in place of the replug. Not new in
429ed454 (the same before it; its rule 10 text leaves "a restart's turn" out on purpose). Review
73's hand before a Rot2Prog's second reading, 6 s on, is another case: here the second reading
comes 0.2 s on, before any hand could be told from the old turn."""

from __future__ import annotations

from bridge.core.model import ErrorKind
from bridge.session.session import RotatorSession
from tests.engine.test_attack19_follow_start_refused_grid import follower_by_a_keep_out
from tests.engine.test_attack19_track_start_refused_wait import (
    rotorez_under_a_kept_out_pass,
)
from tests.engine.test_review70_refused_start_after_replug import (
    a_follow_start_refused_after,
    a_track_started_after,
)
from tests.engine.virtual import VirtualRotator
from tests.integration.test_pointing_bridge import angle_between


def restarted_mid_turn(v: VirtualRotator) -> None:
    """The bridge started again while the rotor turns (a new session, the link down for a
    second); the controller answers the new one, finishing its old turn by itself."""
    v.run_for(0.1)  # (between two polls: not a deadline)
    v.link_down(None)
    v.run_for(1.0)  # (the bridge down: not a deadline)
    # the bridge started again, with what its state file kept of the turn (a DCU-1's, sent and
    # not seen over: runtime/kept.py rule 13)
    v.session = RotatorSession(v.cfg, turn_kept=v.status.turn_kept)
    v._do(v.session.start(v.now))
    v.link_up()
    v.run_until(lambda h: h.status.available, 10, "the controller answers the new bridge")
    assert v.truth().is_moving  # (it finishes its old turn by itself)


def test_a_refused_follow_start_right_after_a_restart_mid_turn_holds_the_rotor() -> None:
    with follower_by_a_keep_out("rotorez") as v:
        t, here = a_follow_start_refused_after(v, restarted_mid_turn)
        # held where it was (a stop and the Rotor-EZ's coast), as after a replug: 84 -> 182
        assert angle_between(v.truth().az_deg, here) <= 15.0, (here, v.truth().az_deg)
        # taken, and waiting for a grid it may turn to: observed ended "turned by hand", though
        # no hand touched the panel (the old turn's readings taken for one)
        assert v.status.following is not None, v.status.following_ended


def test_a_track_start_refused_right_after_a_restart_mid_turn_holds_the_rotor() -> None:
    """The same with tracking's wait for the pass refused (review 70's second case)."""
    with rotorez_under_a_kept_out_pass() as v:
        t, here = a_track_started_after(v, restarted_mid_turn)
        [refused] = v.errors(ErrorKind.REFUSED, since=t)
        assert "keep-out" in refused.message
        # held where it was (a stop and the Rotor-EZ's coast): observed 238 -> 340
        assert abs(v.truth().az_deg - here) <= 15.0, (here, v.truth().az_deg)
        assert v.status.tracking is not None  # taken, and holding (observed: ended)
