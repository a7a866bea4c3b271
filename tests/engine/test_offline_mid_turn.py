"""A turn that loses its readings is stopped, at the latest when the rotator goes offline
(controller.py rule 2, stops.py rule 3): the bridge watches a turn's stall and its limits only
through readings, and an unsupervised turn does not go on. The stop goes in case the controller
still hears (its replies lost, or garbled on their way), and is owed again, the first frame
once it answers. (A review, every model at its defaults: a jammed rotor whose controller went
silent, or sent only garbage, mid-turn went offline at the silence timeout, 3 s, or at twice it,
6 s, with "it may still be turning" and no stop: the motor still drove against the jam 60 s
later on a Rotor-EZ, GS-232B, Easycomm, RC2800, Prosistel and RT-21.)"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
FAMILIES = ["rotorez", "gs232b", "easycomm3", "rc2800", "prosistel", "rt21"]


def _garbled(data: bytes, now: float) -> bytes:
    """Every digit the controller sends reaches the host as ``?``: no reply is valid."""
    return bytes(0x3F if 0x30 <= b <= 0x39 else b for b in data)


def _turning(v: VirtualRotator) -> tuple[float, float]:
    """``v`` online at rest, sent 170° round, 2 s into the turn: the target and the time."""
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "ready")
    target = (v.truth().az_deg + 170) % 360
    v.target(target)
    v.run_until(lambda h: h.state is MotionState.MOVING, 10, "moving")
    v.run_for(2)
    return target, v.now


def _stop_frames(v: VirtualRotator) -> list[bytes]:
    stop = v.cfg.spec.codec_factory().encode_stop()
    return stop if isinstance(stop, list) else [stop]


@pytest.mark.parametrize("fault", ["silent", "garbage"])
@pytest.mark.parametrize("model", FAMILIES)
def test_a_jammed_rotor_whose_readings_are_lost_mid_turn_is_stopped_going_offline(
    rig: Rig, model: str, fault: str
) -> None:
    """At the defaults (silence_timeout_s 3, stall_timeout_s 10): jammed mid-turn, its replies
    lost (it still hears) or all garbled; offline with a stop on the wire at that moment, and
    the motor off (before: offline at 3 s, or 6 s, no stop, the motor driving 60 s on)."""
    v = rig(model)
    _, t = _turning(v)
    if fault == "silent":
        v.set_silent(True)
    else:
        v.to_host = _garbled
    v.jam()
    v.run_until(lambda h: not h.status.available, 15, "offline")
    off = v.now
    v.run_for(1)

    [why] = v.errors("serial", since=t)
    assert "a stop sent, in case it still hears" in why.message.lower(), why.message
    assert "may still be turning" not in why.message
    stops = [w.t for w in v.writes if w.t >= t and w.data in _stop_frames(v)]
    assert stops and off - 0.3 <= stops[0] <= off + 0.3, (off, stops)  # at the offline
    assert v.errors("stalled", since=t) == []  # (no stall: no readings showed one)
    assert not v.truth().is_moving  # (the truth: the motor is off)


@pytest.mark.parametrize("model", FAMILIES)
def test_a_turn_whose_replies_are_lost_is_stopped_short_going_offline(rig: Rig, model: str) -> None:
    """Not jammed, its replies lost (it hears): the turn it heard is stopped at the offline,
    short of its target, since the bridge can no longer watch it (the price: a legitimate turn
    cut short, sent again once the controller answers; before: it ran on to its target
    unwatched, 26 s after the silence)."""
    v = rig(model)
    target, t = _turning(v)
    v.set_silent(True)
    v.run_until(lambda h: not h.status.available, 15, "offline")
    v.run_for(2)

    assert not v.truth().is_moving
    assert abs((v.truth().az_deg - target + 180) % 360 - 180) > 30  # (stopped well short)
    assert any(w.data in _stop_frames(v) for w in v.writes if w.t >= t)


@pytest.mark.parametrize("model", ["gs232b", "rotorez"])
def test_the_stop_sent_going_offline_mid_turn_is_owed_until_it_answers(
    rig: Rig, model: str
) -> None:
    """Deaf and silent both (the stop at the offline lost on the line), the motor driving the
    jam: the stop stays owed (stops.py rule 3) and is the first frame after the first reading
    once the controller answers again; the motor is off then."""
    v = rig(model)
    _, t = _turning(v)
    v.set_silent(True)
    v.set_deaf(True)
    v.jam()
    v.run_until(lambda h: not h.status.available, 15, "offline")
    v.run_for(20)
    assert v.truth().is_moving  # (nothing reached it: the motor drives on)
    back = v.now
    v.set_deaf(False)
    v.set_silent(False)
    v.run_until(lambda h: h.status.available, 30, "online again")
    v.run_for(1)

    assert any(w.data in _stop_frames(v) for w in v.writes if w.t >= back)
    assert not v.truth().is_moving
