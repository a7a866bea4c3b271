"""A reading at rest far from where the rotor stands is asked again before it is believed
(session/controller.py rule 9): one a flipped bit made well-formed is never published, never
taken as a move, and reported as junk; a move by hand is believed on the next reading."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import ErrorKind, MotionState, Target
from bridge.session.controller import DOUBT_MIN_DEG
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
# every model whose replies carry the bearing as ASCII digits (SPID's are raw bytes)
MODELS = ["rotorez", "rotorcard", "gs232b", "gs232a", "easycomm2", "rt21", "prosistel", "satel"]


def at_rest(rig: Rig, model: str) -> VirtualRotator:
    """At rest at 150 (settled), polled at its idle rate."""
    v = rig(model)
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, 60, "online")
    v.aim(Target(150.0, None))
    v.run_until(lambda h: h.state is MotionState.IDLE and h.now > 10, 200, "at 150")
    v.run_for(10)
    assert v.status.bearing_deg is not None and 100 <= v.status.bearing_deg < 200  # (overshoot)
    return v


def flip_next_hundreds(v: VirtualRotator) -> list[float]:
    """One bit flipped on the line in the next reply: its bearing's hundreds digit, 1 -> 3
    (0x31 -> 0x33): 150 reads 350. Returns the list the instant goes into."""
    when: list[float] = []
    before = bytearray(b"  ")  # the two bytes before (the device's output comes byte by byte)

    def flip(data: bytes, now: float) -> bytes:
        out = bytearray()
        for b in data:  # the first digit after the bearing's head
            if (
                not when
                and b == ord("1")
                and (before[-1] in b";=,Z" or before[-2:] in (b"= ", b"+0"))
            ):
                when.append(now)
                b = ord("3")
            before[:] = before[-1:] + bytes([b])
            out.append(b)
        return bytes(out)

    v.to_host = flip
    return when


@pytest.mark.parametrize("model", MODELS)
def test_a_flipped_bit_in_a_reading_at_rest_is_never_taken(rig: Rig, model: str) -> None:
    v = at_rest(rig, model)
    t, rest = v.now, v.status.bearing_deg
    sent = len(v.sent())
    flipped = flip_next_hundreds(v)
    v.run_until(lambda h: bool(flipped), 60, "the flipped reply")
    v.run_for(20)
    shown = {(s.bearing_deg, s.state) for s in v.published(since=t)}
    assert shown == {(rest, MotionState.IDLE)}
    assert v.status.bearing_deg == rest
    assert [e.kind for e in v.errors(since=t)] == [ErrorKind.PROTOCOL]  # junk, once
    query = v.cfg.spec.codec_factory().encode_query()
    assert set(v.sent()[sent:]) == set(query if isinstance(query, list) else [query])


@pytest.mark.parametrize("model", MODELS)
def test_a_move_by_hand_at_rest_is_believed_on_the_reading_after(rig: Rig, model: str) -> None:
    v = at_rest(rig, model)
    t = v.now
    v.manual_rotate(250.0)
    v.run_until(lambda h: h.truth().az_deg == 250.0 and not h.truth().is_moving, 120, "turned")
    v.run_for(10)
    assert v.status.bearing_deg is not None and abs(v.status.bearing_deg - 250.0) <= 1.0
    assert MotionState.MOVING in {s.state for s in v.published(since=t)}
    assert v.errors(since=t) == []


def test_a_reading_at_rest_said_twice_is_believed(rig: Rig) -> None:
    """A controller recalibrated at its panel (every reading from now on 200 degrees more)
    says its new bearing twice: believed on the second, no junk reported."""
    v = at_rest(rig, "gs232b")
    t = v.now
    v.to_host = lambda data, now: data.replace(b"1", b"3")  # 150 reads 350 from now on
    v.run_for(30)
    assert v.status.bearing_deg == 350.0
    assert v.errors(since=t) == []
    assert DOUBT_MIN_DEG < 200


def test_readings_at_rest_that_go_on_disagreeing_are_reported_and_polled_as_ever(
    rig: Rig,
) -> None:
    """A failing position sensor (each reading elsewhere): the bearing shown stays the last
    two readings agreed on, the readings are reported, and the line is polled at its idle
    rate, not at once after each."""
    v = at_rest(rig, "gs232b")
    rest, query = v.status.bearing_deg, b"C\r"
    t0 = v.now
    v.run_for(30)
    polls_before = v.sent(since=t0).count(query)
    digits = iter(b"2340" * 1000)  # 150 reads 250, 350, 450, 50, 250...

    def failing(data: bytes, now: float) -> bytes:
        return data.replace(b"1", bytes([next(digits)])) if b"1" in data else data

    v.to_host = failing
    t = v.now
    v.run_for(30)
    assert v.status.bearing_deg == rest and v.status.available
    assert {s.state for s in v.published(since=t)} <= {MotionState.IDLE}
    assert v.sent(since=t).count(query) <= polls_before + 1
    told = [e.message for e in v.errors(since=t)]
    assert any("readings in a row at rest disagree" in m for m in told), told
