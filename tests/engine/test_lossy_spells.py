"""A line that loses every reply for spells shorter than the silence timeout, a valid reply
getting through between them, in virtual time: the controller answers, so it is never called
silent, and a turn on such a line goes on to its target (controller.py rule 2, link.py rule 2:
the questions since the last valid reply must reach the silence's end, or one asked then
decides). A review: a GS-232B whose line lost 2.6 s of every 3.6 s went offline 3.2 s into a
turn, and the turn was stopped: the question that the line would have answered went out only
after the verdict, a reply time after the one before it, lost in the spell."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
FAMILIES = ["rotorez", "gs232b", "easycomm3", "rc2800", "prosistel", "rt21"]


def _spells(v: VirtualRotator, period_s: float, lost_s: float, phase_s: float) -> None:
    """From now on, every reply the controller sends in the first ``lost_s`` of every
    ``period_s`` (shifted by ``phase_s``) is lost on its way to the host."""
    start = v.now

    def host(data: bytes, now: float) -> bytes:
        return b"" if (now - start + phase_s) % period_s < lost_s else data

    v.to_host = host


def _first_query(v: VirtualRotator) -> bytes:
    asked = v.cfg.spec.codec_factory().encode_query()
    return asked[0] if isinstance(asked, list) else asked


def _stop_frames(v: VirtualRotator) -> list[bytes]:
    stop = v.cfg.spec.codec_factory().encode_stop()
    return stop if isinstance(stop, list) else [stop]


def _turn(v: VirtualRotator, period_s: float, lost_s: float, phase_s: float) -> tuple[float, float]:
    """``v`` online at rest, its line set losing replies in spells (``_spells``) as a
    170-degree turn is sent: the target, and when."""
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "ready")
    target = (v.truth().az_deg + 170) % 360
    _spells(v, period_s, lost_s, phase_s)
    v.target(target)
    return target, v.now


def _arrived(v: VirtualRotator, target: float, t: float) -> None:
    """Online throughout since ``t``, no stop sent, the rotor at rest at ``target``."""
    assert v.errors("serial", since=t) == []
    assert {s.available for s in v.published(since=t)} == {True}
    assert not [w for w in v.writes if w.t >= t and w.data in _stop_frames(v)]
    assert v.state is MotionState.IDLE and not v.truth().is_moving
    assert abs((v.truth().az_deg - target + 180) % 360 - 180) <= 3.0


@pytest.mark.parametrize(("model", "phase_s"), [("gs232b", 0.0), ("prosistel", 1.5)])
def test_a_turn_on_a_line_that_loses_replies_in_spells_goes_on_to_its_target(
    rig: Rig, model: str, phase_s: float
) -> None:
    """At the defaults (silence_timeout_s 3): every reply lost for 2.6 s of every 3.6 s from
    the moment a 170-degree turn is sent, a whole reply possible in the second between. The
    rotator stays online, no stop goes out, and the rotor arrives (before: offline 3.2 s into
    the turn on a GS-232B, 5.2 s on a Prosistel, and the turn stopped short)."""
    v = rig(model)
    target, t = _turn(v, 3.6, 2.6, phase_s)
    v.run_until(lambda h: h.state is MotionState.IDLE and not h.truth().is_moving, 60, "there")
    _arrived(v, target, t)


@pytest.mark.parametrize(
    ("model", "phase_s"),
    [("rotorez", 0.5), ("gs232b", 0.5), ("rc2800", 0.5), ("rc2800", 1.25), ("rc2800", 2.0)],
)
def test_a_line_that_loses_two_seconds_in_three_keeps_the_rotator_online(
    rig: Rig, model: str, phase_s: float
) -> None:
    """Every reply lost for 2 s of every 3 s, through a turn and a minute at rest after it: the
    rotator stays online (before: offline 35 s in, at rest, where a poll asked again off the
    grid of idle polls left the last stretch of the silence unasked). An az/el RC2800's poll is
    two frames 200 ms apart, and each second between the spells holds the elevation's answer to
    one poll and the azimuth's to the next: a reading of the two (rc2800.py rule 2; before:
    offline 3 s into the turn at every phase, and the turn stopped)."""
    v = rig(model)
    target, t = _turn(v, 3.0, 2.0, phase_s)
    v.run_until(lambda h: h.state is MotionState.IDLE and not h.truth().is_moving, 60, "there")
    v.run_for(60)
    _arrived(v, target, t)


@pytest.mark.parametrize("model", FAMILIES)
def test_a_controller_gone_silent_mid_turn_is_asked_to_the_end_of_its_silence(
    rig: Rig, model: str
) -> None:
    """Silent 2 s into a turn (its replies lost, it still hears): the questions since the last
    one it answered reach the whole silence timeout (before: the last went out a reply time
    before it ran out, and its loss was the verdict), and the offline, with its stop, comes
    within a reply time of the last question, as soon as that question's reply can no longer
    come whole."""
    v = rig(model)
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "ready")
    v.target((v.truth().az_deg + 170) % 360)
    v.run_until(lambda h: h.state is MotionState.MOVING, 10, "moving")
    v.run_for(2)
    heard_t = max(t for t, _ in v.received)
    v.set_silent(True)
    v.run_until(lambda h: not h.status.available, 15, "offline")
    off = v.now

    asked = [w.t for w in v.writes if w.data == _first_query(v)]
    answered_q = max(q for q in asked if q <= heard_t)  # the question the last reply answered
    last_q = max(q for q in asked if q < off)  # (not the poll that goes on after it)
    assert last_q - answered_q >= v.cfg.silence_timeout_s, (answered_q, last_q, off)
    assert off - last_q <= v.cfg.spec.reply_timeout_s + v.cfg.spec.axis_gap_s + 1e-9
    [why] = v.errors("serial", since=heard_t)
    assert "stopped answering (no valid reply for 3 s)" in why.message
    assert any(w.data in _stop_frames(v) for w in v.writes if off - 0.3 <= w.t <= off + 0.3)
