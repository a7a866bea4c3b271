"""Review 40: a doubted reading at rest whose answer is given up brings the next poll to the
moving rate (session/controller.py rule 9, ``_given_up``). Nothing ends that while no reading
comes: a controller that goes silent (switched off for the night, its cable pulled at the far
end), or whose line gives only garbage, right after one reading at rest that disagreed (a
flipped bit; a position sensor's last reading as its supply sagged) is polled at the moving
rate for good, online and offline, ten to twenty times what its idle rate asks of the line,
where the same silence or garbage without that reading is polled at the idle rate."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState, Target
from tests.engine.test_session_doubt import MODELS, flip_next_hundreds
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
IDLE_S = 10.0


def at_rest_polled_slowly(rig: Rig, model: str) -> VirtualRotator:
    v = rig(model, settings={"unasked_moves": "follow", "idle_poll_interval_s": IDLE_S})
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "online")
    v.aim(Target(150.0, None))
    v.run_until(lambda h: h.state is MotionState.IDLE and h.now > 10, 200, "at 150")
    v.run_for(3 * IDLE_S)
    return v


def silent_after(v: VirtualRotator, flip: bool, how: str) -> float:
    """The controller silent (``how``: or its line giving only garbage) from the poll after
    the next reply on (that reply flipped, 150 read as 350, if ``flip``); returns when."""
    flipped = flip_next_hundreds(v) if flip else []
    v.run_until(lambda h: bool(flipped) or not flip, 60, "the flipped reply")
    asked = len(v.sent())
    v.run_until(lambda h: len(h.sent()) > asked, 60, "the poll after it")
    if how == "silent":
        v.set_silent(True)
    else:
        v.to_host = lambda data, now: bytes(b ^ 0x80 for b in data)
    return v.now


@pytest.mark.parametrize("how", ["silent", "garbage"])
@pytest.mark.parametrize("model", MODELS)
def test_a_silent_controller_after_a_flipped_reading_is_polled_at_the_idle_rate(
    rig: Rig, model: str, how: str
) -> None:
    plain = at_rest_polled_slowly(rig, model)
    t = silent_after(plain, flip=False, how=how)
    plain.run_for(120)
    baseline = len(plain.sent(since=t + 60))
    # (the idle rate, offline too; each garbled answer asked again once: link.py rule 11)
    assert baseline <= 2 * 60 / IDLE_S + 2

    v = at_rest_polled_slowly(rig, model)
    t = silent_after(v, flip=True, how=how)
    v.run_for(120)
    assert not v.status.available
    assert v.status.bearing_deg != 350.0
    assert len(v.sent(since=t + 60)) <= baseline + 2
