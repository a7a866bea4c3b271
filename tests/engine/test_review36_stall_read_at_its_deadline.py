"""Review 36 of eb203674 (motion.py rule 3): a reading whose question went out before the
stall's time decides no stall, and the controller is to be asked at once (``stall_due``) so
that its answer does, "a reply time later, not a poll later". Where the moving poll's reply is
read at the stall's deadline itself (the stall clock runs from a reading's time, the poll grid
from a question's, so a poll ``stall_timeout_s`` after the last progress is answered just as
the deadline comes: every time, with the defaults' whole seconds), nothing asks at once: the
reading set the controller's tick aside for the step (``_deadline``), the step's end put it at
``next_deadline``, which names no stall time already past, and ``stall_due`` is never looked
at. The stall waits for the next moving poll, and the motor drives against the jam a whole
moving poll longer than before the fix: 2 s for a Rotor-EZ, a RotorCard or an RT-21 polled
every 2 s while turning (told at the deadline before eb203674)."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


@pytest.mark.parametrize("model", ["rotorez", "rotorcard", "rt21"])
def test_a_jammed_rotor_is_stopped_at_its_stall_deadline_when_a_reply_lands_on_it(
    rig: Rig, model: str
) -> None:
    poll_s = 2.0
    settings = {"moving_poll_interval_s": poll_s, "idle_poll_interval_s": poll_s}
    settings["settle_s"] = 2 * poll_s + 0.5
    v = rig(model, settings=settings)
    v.run_until(lambda v: v.state is MotionState.IDLE and v.status.available, 60, "ready")
    v.target((v.truth().az_deg + 170) % 360)
    v.run_for(5)
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
    # asked at the deadline, read a reply time later (a poll already out then: its reply);
    # 2 s later, the next moving poll's, with eb203674
    assert v.now <= deadline + 2 * link.reply_timeout_s + 0.05, (v.now, deadline)
    v.run_for(1)
    assert not v.truth().is_moving
