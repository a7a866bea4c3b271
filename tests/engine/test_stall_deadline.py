"""A jammed rotor is stopped at its stall deadline, not a moving poll after it (motion.py rule
3, controller.py rule 2; a review of 1ed8e54: a stall told only by a reading, or by time while
a question is out unanswered, waited at the deadline for the next moving poll's reading, and
the motor drove against the jam up to ``moving_poll_interval_s`` longer than before: 2 s more
for a GS-232B polled every 2 s while turning). Review 36 (of eb203674, motion.py rule 3's
question time): a reply landing on the deadline itself, answering the poll sent just before
it, decides nothing, and nothing asked at once: a Rotor-EZ, a RotorCard or an RT-21 polled
every 2 s stalled 2 s late; the reading now asks at once (controller.py ``_reading``)."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


@pytest.mark.parametrize(
    "model", ["gs232b", "easycomm3", "prosistel", "rotorez", "rotorcard", "rt21"]
)
@pytest.mark.parametrize("poll_s", [0.2, 2.0])
def test_a_jammed_rotor_is_stopped_at_its_stall_deadline(
    rig: Rig, model: str, poll_s: float
) -> None:
    settings = {"moving_poll_interval_s": poll_s, "idle_poll_interval_s": max(poll_s, 1.0)}
    settings["settle_s"] = 2 * poll_s + 0.5
    v = rig(model, settings=settings)
    v.run_until(lambda v: v.state is MotionState.IDLE and v.status.available, 60, "ready")
    v.target((v.truth().az_deg + 170) % 360)
    v.run_for(6)
    v.jam()
    ctl = v.session.controller
    progress_t = ctl.motion.progress_t
    while not v.errors("stalled"):  # the stall deadline as the motion machine keeps it
        progress_t = ctl.motion.progress_t if ctl.motion.progress_t is not None else progress_t
        v.run_for(0.01)
        assert v.now < 60
    assert progress_t is not None
    deadline = progress_t + v.cfg.motion.stall_timeout_s
    link = ctl.link
    assert link is not None
    # asked at the deadline, read a reply time later (a poll already out then: its reply)
    assert v.now <= deadline + 2 * link.reply_timeout_s + 0.05, (v.now, deadline)
    v.run_for(1)
    assert not v.truth().is_moving
