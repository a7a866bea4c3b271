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

from tests.engine.test_review73_dcu1_refused_start_after_replug import (
    a_dcu1s_refused_follow_start_holds_the_rotor,
)
from tests.engine.test_review84_refused_start_after_a_restart_mid_turn import restarted_mid_turn


def test_a_dcu1s_refused_follow_start_right_after_a_restart_mid_turn_holds_the_rotor() -> None:
    # held where it was: observed 87 -> 182, no stop frame
    a_dcu1s_refused_follow_start_holds_the_rotor(restarted_mid_turn)
