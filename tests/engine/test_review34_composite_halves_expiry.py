"""COLD REVIEW 34 (7d371f02): a stamped target's two halves on a rotator of two boxes.

core/model.py ``combine`` (and session.py rule 13): "two halves of one sender's target expire
with the sooner of the two". On one controller the session keeps one sender's azimuth and
elevation, sent apart, as one target, and a hold that ends past the sooner expiry drops both:
the rotor stays where the STOP left it. On a rotator of two boxes (runtime/composite.py rule 2)
each half waits in its own box with its own expiry; the azimuth box drops its half at the
hold's end, said, and the elevation box sends its own: the elevation turns alone to the 40 of
a target whose azimuth was dropped (rule 8: "a target one box drops before it went out ... is
the rotator's whole target dropped: the other box drops its half too"; the drop for the expiry
is no ``drops``, so the other box is never told to ``forsake`` its half).
"""

from __future__ import annotations

import pytest

from bridge.core.model import Source, Stop, Target
from bridge.protocols.axes import Axis
from tests.engine.test_composite import FAST, online
from tests.engine.virtual import VirtualRotator
from tests.engine.virtual_composite import VirtualComposite

EXPIRY_S = 5.0  # the remote's command_expiry_s


def test_one_controller_drops_both_halves_of_a_sender_target_past_the_sooner_expiry() -> None:
    """The reference: one az/el controller (a GS-232B) keeps the two halves as one target."""
    with VirtualRotator("gs232b", emulator=FAST[Axis.ELEVATION]) as v:
        v.run_for(5.0)
        el_before = v.truth().el_deg
        t = v.now
        v.mailbox.put(Stop(Source.MQTT), hold=1)  # the lane's STOP, its hold 1
        v.mailbox.put(Target(300.0, None, not_after_s=t + EXPIRY_S))  # read after its copy
        v._take()
        v.run_for(3.0)
        v.mailbox.put(Target(None, 40.0, not_after_s=v.now + EXPIRY_S))  # the same sender's
        v._take()
        v.run_for(3.0)  # the marker back 6 s after the azimuth was sent: past its expiry
        v.mailbox.put_release(1)
        v._take()
        v.run_for(30.0)
        assert v.truth().el_deg == pytest.approx(el_before, abs=1.0)
        assert [e.message for e in v.errors(since=t) if "expiry passed" in e.message]


def test_a_composite_does_not_turn_one_axis_alone_for_a_target_whose_other_half_expired() -> None:
    with VirtualComposite("rt21", "gs232b", emulators=FAST) as v:
        v.run_until(online, 10, "both boxes answer")
        el_before = v.el.truth().el_deg
        az_before = v.az.truth().az_deg
        t = v.now

        def judged(target: Target) -> Target:
            return v.cfg.aim.judge(target, v.status.raw_bearing_deg)

        v.mailbox.put(Stop(Source.MQTT), hold=1)  # the lane's STOP, its hold 1
        v.mailbox.put(judged(Target(300.0, None, not_after_s=t + EXPIRY_S)))  # after its copy
        v._take()
        v.run_for(3.0)
        v.mailbox.put(judged(Target(None, 40.0, not_after_s=v.now + EXPIRY_S)))  # same sender
        v._take()
        v.run_for(3.0)  # the marker back 6 s after the azimuth was sent: past its expiry
        v.mailbox.put_release(1)
        v._take()
        v.run_for(30.0)
        said = [e.message for e in v.az.errors(since=t)]
        assert any("expiry passed" in m for m in said), said  # (the azimuth's half: dropped)
        assert v.az.truth().az_deg == pytest.approx(az_before, abs=1.0)
        assert v.el.truth().el_deg == pytest.approx(el_before, abs=1.0), (
            "the elevation box turned alone to 40 for a target whose azimuth half the other "
            f"box dropped as expired (one controller drops both): {v.el.truth()}"
        )


def _halves_under_a_hold(
    v: VirtualComposite, az_expiry_s: float, el_expiry_s: float, hold_s: float
) -> float:
    """The lane's STOP and its hold; the sender's azimuth, then 3 s later its elevation, each
    read after the STOP's copy with its own expiry; the marker back ``hold_s`` after the
    azimuth was sent. The time the azimuth was sent."""
    t = v.now

    def judged(target: Target) -> Target:
        return v.cfg.aim.judge(target, v.status.raw_bearing_deg)

    v.mailbox.put(Stop(Source.MQTT), hold=1)
    v.mailbox.put(judged(Target(300.0, None, not_after_s=t + az_expiry_s)))
    v._take()
    v.run_for(3.0)
    v.mailbox.put(judged(Target(None, 40.0, not_after_s=v.now + el_expiry_s)))
    v._take()
    v.run_for(hold_s - 3.0)
    v.mailbox.put_release(1)
    v._take()
    return t


def test_a_composite_turns_both_halves_when_the_hold_ends_within_the_sooner_expiry() -> None:
    """The marker back 4 s after the azimuth was sent, within both expiries: the whole target
    goes, both axes."""
    with VirtualComposite("rt21", "gs232b", emulators=FAST) as v:
        v.run_until(online, 10, "both boxes answer")
        t = _halves_under_a_hold(v, EXPIRY_S, EXPIRY_S, 4.0)
        v.run_for(60.0)
        assert v.az.truth().az_deg == pytest.approx(300.0, abs=2.0)
        assert v.el.truth().el_deg == pytest.approx(40.0, abs=2.0)
        assert not [e for box in (v.az, v.el) for e in box.errors(since=t) if "expiry" in e.message]


def test_a_composite_drops_the_earlier_half_too_when_the_later_half_expires_sooner() -> None:
    """The elevation, sent later, expires first (its sender's expiry shortened meanwhile): one
    controller drops the whole target at a hold's end past that expiry, so both boxes do,
    though the azimuth's own expiry has not passed."""
    with VirtualComposite("rt21", "gs232b", emulators=FAST) as v:
        v.run_until(online, 10, "both boxes answer")
        el_before, az_before = v.el.truth().el_deg, v.az.truth().az_deg
        t = _halves_under_a_hold(v, 30.0, 1.0, 6.0)  # (the elevation's: 4 s after it)
        v.run_for(30.0)
        assert v.az.truth().az_deg == pytest.approx(az_before, abs=1.0)
        assert v.el.truth().el_deg == pytest.approx(el_before, abs=1.0)
        said = [e.message for box in (v.az, v.el) for e in box.errors(since=t)]
        assert any("expiry passed" in m for m in said), said
