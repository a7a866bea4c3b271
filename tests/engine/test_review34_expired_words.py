"""COLD REVIEW 34 (7d371f02), fixed since (EXPIRED_TAKEN): session.py rule 13 drops a
stamped target taken from the mailbox past its expiry, whatever held it up, and always said
"its expiry passed while it waited for the order of a STOP or lock". A target judged fresh by
service.py rule 9 at 4.99 s of its 5 s expiry (a slow link: what the stamps are for), taken by
the lines thread a few milliseconds later, with no STOP or lock anywhere, is dropped (past its
expiry: rightly) with words that blamed a STOP or lock that never came; the operator looks for
a STOP in the audit trail and on the other front ends, and finds none.
"""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState, Target
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


def test_a_target_taken_past_its_expiry_with_no_halt_does_not_blame_a_stop(rig: Rig) -> None:
    v = rig("rotorez")
    v.run_until_state(MotionState.IDLE, 30)
    t = v.now
    v.mailbox.put(Target(300.0, not_after_s=t - 0.005))  # read at 4.99 s, taken 15 ms later
    v._take()
    v.run_for(10)
    said = [e.message for e in v.errors(since=t)]
    assert said, "dropped unsaid"
    assert not [m for m in said if "STOP" in m], (
        f"no STOP or lock came, yet the drop is said to have waited for one: {said}"
    )
