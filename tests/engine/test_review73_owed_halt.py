"""Review 73 (d609655e, parts.py rule 10: ``StartHalt.owed``). A refused follow start right
after a replug owes its halt to the turn carried over the lost link "until a reading shows it
move", and takes the first move any reading shows for that turn. But after a replug the
carried turn is assumed until readings show the rotor still long enough for rule 2's rest
(motion.py rule 4), not dropped at the first reading that shows no move (review 54's rule is
the restart's only). A hand at the panel in that window, the rotor at rest since long before
the replug and every reading since the replug showing it still, is taken for the carried turn:
the owed halt stops it a few degrees into its turn. Before d609655e the hand's turn went
where the hand sent it (both then and now following goes on, the turn taken for the carried
one by ``Before``: not asserted here)."""

from __future__ import annotations

from bridge.core.model import ErrorKind
from tests.engine.test_attack19_follow_start_refused_grid import PARTNER, follower_by_a_keep_out
from tests.engine.test_review70_refused_start_after_replug import (
    rotorez_turning_away_from_the_partner,
)
from tests.engine.virtual import VirtualRotator
from tests.integration.test_pointing_bridge import angle_between


def test_a_hand_at_the_panel_right_after_a_replug_at_rest_is_not_the_owed_halts_turn() -> None:
    with follower_by_a_keep_out("rotorez") as v:
        rotorez_turning_away_from_the_partner(v)
        # observed: a stop frame 0.2 s into the hand's turn, the rotor left at 178 (not 102)
        a_hand_at_the_panel_right_after_a_replug_at_rest(v)


def a_hand_at_the_panel_right_after_a_replug_at_rest(v: VirtualRotator) -> None:
    """``v`` turning away from PARTNER, unplugged: the old turn over, at rest long before the
    replug; replugged, a follow start refused; a hand at the panel a second later turns the
    rotor to PARTNER + 60: the bridge sends it no stop and the hand's turn ends there."""
    v.link_down()
    v.run_until(lambda h: not h.truth().is_moving, 60, "the old turn over, unplugged")
    v.run_for(10.0)  # at rest, unplugged, long before the replug (not a deadline)
    rest = v.truth().az_deg
    v.link_up()
    v.run_until(lambda h: h.status.available, 10, "the controller answers again")
    t = v.now
    v.follow(True)
    v.heard("JA1ABC", "PM95")
    v.run_until(lambda h: bool(h.errors(ErrorKind.REFUSED, since=t)), 10, "refused")
    v.run_for(1.0)  # five polls, each reading the rotor still (not a deadline)
    assert v.truth().az_deg == rest and not v.truth().is_moving  # (never moved since)
    hand_to = round(PARTNER + 60.0)  # (never through the sector)
    v.manual_rotate(hand_to)  # a hand at the panel
    v.run_until(lambda h: h.status.moving, 10, "the bridge sees the hand's turn")
    v.run_until(lambda h: not h.truth().is_moving, 90, "the hand's turn over")
    assert {f.outcome for f in v.frames(since=t)} == {"query"}, v.frames(since=t)
    assert angle_between(v.truth().az_deg, hand_to) <= 1.0, (hand_to, v.truth().az_deg)
