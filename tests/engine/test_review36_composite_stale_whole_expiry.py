"""Review 36 of 87595d8e (runtime/composite.py rule 8, ``Composition.expires_as``): a half
waiting in its box when a hold ends is judged by the rotator's whole target, the sooner of its
two halves' expiries. ``aimed`` takes the whole with the other box's half while that box still
``holds`` it, waiting or TURNING to it, and it is judged when the batch is split, before the
batch's own STOP reaches the boxes. So: a stamped azimuth 300 (5 s expiry) turns; the stop
lane's STOP and the same sender's elevation 40 (60 s expiry, read after the STOP's copy) come
in one batch; the azimuth box still turns to 300 when ``aimed`` looks, so the elevation's
whole target takes the 300's 5 s expiry, though the STOP then ends that turn. At the hold's
end, 6 s on, the elevation box drops its 40 "its expiry passed while it waited for the order
of a STOP", a minute before its own expiry. One controller (a GS-232B) takes the same
commands and turns the elevation to 40 (the STOP dropped the 300 first: nothing to combine
with), as the composite did before 87595d8e."""

from __future__ import annotations

import pytest

from bridge.core.model import Source, Stop, Target
from bridge.protocols.axes import Axis
from tests.engine.test_composite import FAST, online
from tests.engine.virtual import VirtualRotator
from tests.engine.virtual_composite import VirtualComposite


def test_one_controller_turns_the_elevation_sent_after_a_stop_of_a_stamped_turn() -> None:
    """The reference: the STOP ends the 300, the elevation 40 goes at the hold's end."""
    with VirtualRotator("gs232b", emulator=FAST[Axis.ELEVATION]) as v:
        v.run_for(5.0)
        t = v.now
        v.mailbox.put(Target(300.0, None, not_after_s=t + 5.0))
        v._take()
        v.run_for(1.0)
        assert v.truth().is_moving
        v.mailbox.put(Stop(Source.MQTT), hold=1)  # the lane's STOP, its hold 1
        v.mailbox.put(Target(None, 40.0, not_after_s=v.now + 60.0))  # after its copy
        v._take()
        v.run_for(6.0)
        v.mailbox.put_release(1)
        v._take()
        v.run_for(40.0)
        assert v.truth().el_deg == pytest.approx(40.0, abs=1.0)
        assert not [e for e in v.errors(since=t) if "expiry" in e.message]


def test_a_composite_turns_the_elevation_sent_after_a_stop_of_a_stamped_turn() -> None:
    with VirtualComposite("rt21", "gs232b", emulators=FAST) as v:
        v.run_until(online, 10, "both boxes answer")
        t = v.now

        def judged(target: Target) -> Target:
            return v.cfg.aim.judge(target, v.status.raw_bearing_deg)

        v.mailbox.put(judged(Target(300.0, None, not_after_s=t + 5.0)))
        v._take()
        v.run_for(1.0)
        assert v.az.truth().is_moving  # (turning to 300 when the STOP comes)
        v.mailbox.put(Stop(Source.MQTT), hold=1)  # the lane's STOP, its hold 1
        v.mailbox.put(judged(Target(None, 40.0, not_after_s=v.now + 60.0)))  # after its copy
        v._take()
        v.run_for(6.0)  # the marker back 6 s on: past the 300's expiry, not the 40's
        v.mailbox.put_release(1)
        v._take()
        v.run_for(40.0)
        said = [e.message for box in (v.az, v.el) for e in box.errors(since=t)]
        assert v.el.truth().el_deg == pytest.approx(40.0, abs=1.0), (
            "the elevation 40, its own expiry a minute off, was dropped at the hold's end as "
            f"expired, judged by the stopped azimuth turn's expiry: {said}"
        )
        assert not [m for m in said if "expiry" in m], said
