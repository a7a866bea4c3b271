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

from tests.engine.test_attack19_follow_start_refused_grid import (
    follower_by_a_keep_out,
    turning_away_from_the_partner,
)
from tests.engine.test_review73_owed_halt import a_hand_at_the_panel_right_after_a_replug_at_rest


def test_a_hand_at_a_gs232_azimuth_a_second_after_a_replug_at_rest_is_not_stopped() -> None:
    with follower_by_a_keep_out("gs232b") as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.run_until(lambda h: h.status.state is not None and not h.status.moving, 30, "at rest")
        turning_away_from_the_partner(v)  # an azimuth-only turn
        # observed: a stop frame a reading into the hand's turn, the rotor left near 179
        a_hand_at_the_panel_right_after_a_replug_at_rest(v)
