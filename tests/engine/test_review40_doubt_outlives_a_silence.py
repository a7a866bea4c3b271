"""Review 40: the first reading back after a silence, where the rotor stood still when its
readings were lost, is doubted against where it stood (session/controller.py rule 9). A doubt
open when the controller went silent outlives the silence, and every answer the silence lost
counts towards DOUBT_LOST_MOST: the first reading back, if not where the rotor stood, is taken
unchecked as "the rotor may be turning". One flipped bit at rest just before the silence (150
read as 350) and one in the first reply after it (150 read as 250): 250 is published as the
bearing and taken as a turn, where the same first reading back after the same silence without
the flip before it is doubted and never shown."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.test_session_doubt import MODELS, at_rest
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


def flip_next_hundreds_to(v: VirtualRotator, digit: bytes) -> list[float]:
    """As test_session_doubt.flip_next_hundreds, the hundreds digit 1 read as ``digit``."""
    when: list[float] = []
    before = bytearray(b"  ")

    def flip(data: bytes, now: float) -> bytes:
        out = bytearray()
        for b in data:
            if (
                not when
                and b == ord("1")
                and (before[-1] in b";=,Z" or before[-2:] in (b"= ", b"+0"))
            ):
                when.append(now)
                b = digit[0]
            before[:] = before[-1:] + bytes([b])
            out.append(b)
        return bytes(out)

    v.to_host = flip
    return when


def silence_then_a_flip(v: VirtualRotator, flip_before: bool) -> float:
    """The controller silent from the poll after the next reply (150 read as 350 if
    ``flip_before``) until it is offline and 10 s more; then back, its first reply read 250.
    Returns when the silence began."""
    flipped = flip_next_hundreds_to(v, b"3") if flip_before else []
    v.run_until(lambda h: bool(flipped) or not flip_before, 60, "the flipped reply")
    asked = len(v.sent())
    v.run_until(lambda h: len(h.sent()) > asked, 60, "the poll after it")
    v.set_silent(True)
    t = v.now
    v.run_until(lambda h: not h.status.available, 120, "offline")
    v.run_for(10)
    again = flip_next_hundreds_to(v, b"2")
    v.set_silent(False)
    v.run_until(lambda h: bool(again) and h.status.available, 120, "back, the flipped reply")
    v.run_for(20)
    return t


@pytest.mark.parametrize("model", [m for m in MODELS if m != "rt21"])
def test_the_first_reading_back_after_a_silence_is_doubted_whatever_came_before(
    rig: Rig, model: str
) -> None:
    plain = at_rest(rig, model)
    rest = plain.status.bearing_deg
    t = silence_then_a_flip(plain, flip_before=False)
    assert {s.bearing_deg for s in plain.published(since=t)} - {None} == {rest}

    v = at_rest(rig, model)
    rest = v.status.bearing_deg
    t = silence_then_a_flip(v, flip_before=True)
    assert {s.bearing_deg for s in v.published(since=t)} - {None} == {rest}
    assert v.status.bearing_deg == rest and v.state is MotionState.IDLE
