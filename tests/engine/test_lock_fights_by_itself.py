"""stops.py rule 7: while the lock holds, a reading at rest the doubt does not take (a hand at
the panel, or line noise) brings the lock's stop again. Its price on a noisy line: a stop frame
to a still rotor, at most one a poll and one a brake window, and the ``stop`` error said once,
not at every reading. Without the lock the same noise gets controller.py rule 9's unwatched
stop (review 103's follow-up, the maintainers' decision: the limits hold over a rotor the bridge
cannot watch), a stop each eight readings and said as rarely as the junk, never in the lock's
words."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.test_session_doubt import at_rest
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
LOCKS = "the lock's stop sent again"
UNWATCHED = "readings in a row at rest do not agree"


def noisy(v: VirtualRotator, digits: bytes) -> None:
    """Every Rotor-EZ reply (``;ddd``) read with its hundreds digit as the next of ``digits``
    in turn, for good (``1``: as the rotor at 1xx says it)."""
    head = [False]
    i = [0]

    def line(data: bytes, now: float) -> bytes:
        out = bytearray()
        for b in data:
            if b == ord(";"):
                head[0] = True
            elif head[0]:
                head[0] = False
                b = digits[i[0] % len(digits)]
                i[0] += 1
            out.append(b)
        return bytes(out)

    v.to_host = line


def stops_written(v: VirtualRotator, since: float) -> list[float]:
    return [w.t for w in v.writes if w.t >= since and w.data == b";"]


@pytest.mark.parametrize(
    "digits", [b"2340", b"13"], ids=["failing sensor", "every other reading flipped"]
)
def test_a_noisy_line_under_the_lock_gets_few_stops_and_one_word(rig: Rig, digits: bytes) -> None:
    v = at_rest(rig, "rotorez")
    rest = v.status.bearing_deg
    v.lock(True)
    v.run_for(5)
    t = v.now
    noisy(v, digits)
    v.run_for(60)
    stops = stops_written(v, t)
    assert stops  # (the lock fights what may be a turn)
    gaps = [b - a for a, b in zip(stops, stops[1:], strict=False)]
    assert all(gap >= 1.0 for gap in gaps), gaps  # one a brake window, a second at least
    said = [e for e in v.errors("stop", since=t) if LOCKS in e.message]
    assert 1 <= len(said) <= 2  # (once; again after junk_report_interval_s at the most)
    assert not v.truth().is_moving
    assert {s.bearing_deg for s in v.published(since=t)} - {None} == {rest}  # (rule 9 as ever)


def test_the_same_noise_without_the_lock_gets_the_unwatched_stop(rig: Rig) -> None:
    """Was "writes no stop": superseded by review 103's follow-up (the team's decision: a rotor
    at rest whose readings go on disagreeing cannot be watched, its limits included, and gets
    the first readings' unwatched stop; a stop to a still rotor costs nothing, and a failing
    sensor must be told)."""
    v = at_rest(rig, "rotorez")
    rest = v.status.bearing_deg
    t = v.now
    noisy(v, b"2340")
    v.run_for(60)
    stops = stops_written(v, t)
    assert stops  # (the rotor cannot be watched: stopped, and again while it goes on)
    gaps = [b - a for a, b in zip(stops, stops[1:], strict=False)]
    assert all(gap >= 1.0 for gap in gaps), gaps  # (a stop each eight readings, no flood)
    said = [e for e in v.errors("stop", since=t) if UNWATCHED in e.message]
    assert 1 <= len(said) <= 2  # (once; again after junk_report_interval_s at the most)
    assert not [e for e in v.errors(since=t) if LOCKS in e.message]
    assert not v.truth().is_moving
    assert {s.bearing_deg for s in v.published(since=t)} - {None} == {rest}  # (rule 9 as ever)


def test_a_turn_by_hand_after_the_lock_is_released_is_followed(rig: Rig) -> None:
    """The lock's release ends its own check: the operator's hand at the panel is theirs."""
    v = at_rest(rig, "rotorez")
    rest = v.status.bearing_deg
    assert rest is not None
    v.lock(True)
    v.run_for(5)
    v.lock(False)
    v.run_for(5)
    t = v.now
    v.manual_rotate(rest + 60)
    v.run_for(30)
    assert abs(v.truth().az_deg - (rest + 60)) < 1
    assert stops_written(v, t) == []
    assert MotionState.MOVING in {s.state for s in v.published(since=t)}
