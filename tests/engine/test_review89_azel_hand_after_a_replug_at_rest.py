"""Review 89 (4ade0199, motion.py rule 4: ``carried_seen_s`` by the slowest axis): a refused
start right after a replug owes its halt to the turn lost with the port until readings for
``carried_seen_s`` show no move (``lost_still``; review 73: a hand at the panel a second after
a replug at rest must not be stopped for it). 4ade0199 times that by the slowest axis the
controller turns, so on an az/el GS-232B (elevation 2.5 deg/s) it grew from 0.9 s to 2.1 s for
every lost turn, an azimuth-only one included: the azimuth's own readings have shown it still
for its own time, yet a hand turning the azimuth at the panel a second after the refusal is
taken for the lost turn and stopped a few degrees into its turn (review 73's case, on a
GS-232B; before 4ade0199 the hand's turn went where the hand sent it)."""

from __future__ import annotations

from bridge.core.model import ErrorKind
from tests.engine.test_attack19_follow_start_refused_grid import (
    PARTNER,
    follower_by_a_keep_out,
    turning_away_from_the_partner,
)
from tests.integration.test_pointing_bridge import angle_between


def test_a_hand_at_a_gs232_azimuth_a_second_after_a_replug_at_rest_is_not_stopped() -> None:
    with follower_by_a_keep_out("gs232b") as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.run_until(lambda h: h.status.state is not None and not h.status.moving, 30, "at rest")
        turning_away_from_the_partner(v)  # an azimuth-only turn
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
        # observed: a stop frame a reading into the hand's turn, the rotor left near 179
        assert {f.outcome for f in v.frames(since=t)} == {"query"}, v.frames(since=t)
        assert angle_between(v.truth().az_deg, hand_to) <= 1.0, (hand_to, v.truth().az_deg)
