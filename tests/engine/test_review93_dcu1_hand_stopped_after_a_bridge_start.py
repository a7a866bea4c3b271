"""Review 93 (2f8a7d47, motion.py rule 6, parts.py rule 10): a DCU-1 at a bridge's first connect
is taken as possibly finishing the old bridge's turn for the whole range's assumed time (some
90 s), and a start refused in that time halts it, at the cost, the commit says, of "a stop to a
box at rest, which does nothing". But a DCU-1 reports no position, so the bridge cannot tell
that turn from a person's on the front panel: for some 90 s after every bridge start, even
one at rest with no turn ever sent (the first start here), a follow (or track) start refused
sends ``AS1;`` and stops the operator's own turn a few degrees in (observed: the hand's turn
from 62 to 182 stopped at 74, R/error saying only that the start was refused). Before
2f8a7d47 the same refusal sent nothing (only a turn lost over a replug counted)."""

from __future__ import annotations

from bridge.core.model import ErrorKind
from tests.engine.test_attack19_follow_start_refused_grid import PARTNER, follower_by_a_keep_out
from tests.integration.test_pointing_bridge import angle_between


def test_a_dcu1_turned_by_hand_after_a_bridge_start_at_rest_is_not_stopped_by_a_refusal() -> None:
    with follower_by_a_keep_out("dcu1") as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.run_for(30.0)  # the bridge up half a minute, no turn of any bridge's ever sent
        to = round(PARTNER + 140.0)  # (never through the sector)
        v.manual_rotate(to)  # the operator turns it on the front panel
        v.run_for(2.0)  # (the hand's turn under way: not a deadline)
        assert v.truth().is_moving
        t = v.now
        v.follow(True)
        v.heard("JA1ABC", "PM95")
        v.run_for(60.0)  # (the hand's turn some 20 s on: not a deadline)
        [refused] = v.errors(ErrorKind.REFUSED, since=t)
        assert "keep-out" in refused.message
        # the operator's turn goes on to where they turned it: observed stopped at 74, AS1; sent
        assert "stop" not in {f.outcome for f in v.frames(since=t)}
        assert angle_between(v.truth().az_deg, to) <= 2.0, (to, v.truth().az_deg)
