"""Review 93 (4f62f1b3, motion.py rule 4): "a move only on axes decided still is a turn begun
since, not known to be the lost one": the owed halt of a refused start is dropped at once. A
move there is one reading past ``noise_deg``, and one garbled reading makes it: review 89's
GS-232B az/el, its elevation at 2.0 deg/s, unplugged mid elevation-only turn and plugged back
in, a follow start refused at once (owed the halt: review 84); the azimuth is decided still at
its own 1.07 s, the elevation's move shows only later (whole degrees, 2 degrees of noise), and
one reading in between has a flipped bit in the azimuth's units ("AZ=066" for 062: 0x32 read
as 0x36). That reading is taken for a hand's turn begun since, the halt is dropped, no stop goes
out, R/error says only that the start was refused, and the elevation turns on 25 -> 85 to the
target from before the unplug. The same glitch a reading sooner (before the azimuth is decided)
is taken for the lost turn and halts it; with no glitch the elevation is halted too (review 89's
replug test). A glitch on the elevation of an azimuth turn (an RC2800's) is the same case."""

from __future__ import annotations

import itertools

from bridge.core.model import ErrorKind, MotionState
from tests.engine.test_review73_restart_hand import _restarted_at_rest
from tests.engine.test_review84_elevation_carried_turn import START_AZ
from tests.engine.test_review89_restart_mid_slow_elevation_turn import (
    following_right_after_a_replug_mid_the_elevation_turn,
    gs232_with_a_slow_elevation_by_a_keep_out,
)
from tests.engine.virtual import VirtualRotator

AZ_SEEN_S = 1.15  # past the azimuth's own axis_seen_s (1.07 s), before the elevation's (2.12 s)


def flipped_bit_in_the_azimuth(v: VirtualRotator, after_s: float) -> list[float]:
    """The first reading ``after_s`` from now reaches the host with its azimuth's units digit
    '2' read as '6' (one flipped bit), once; the list returned gets the instant it did."""
    start, when, tail = v.now, [], bytearray()
    prefix = f"AZ={START_AZ:03d}".encode()[:-1]
    assert f"{START_AZ:03d}".endswith("2")  # (the digit flipped)

    def glitch(data: bytes, now: float) -> bytes:
        before = bytes(tail)
        tail.extend(data)
        del tail[: -len(prefix)]
        if not when and now >= start + after_s and before.endswith(prefix) and data == b"2":
            when.append(now)
            return b"6"
        return data

    v.to_host = glitch
    return when


def test_one_garbled_reading_of_a_decided_axis_does_not_drop_the_halt_of_a_lost_turn() -> None:
    with gs232_with_a_slow_elevation_by_a_keep_out() as v:
        t, here = following_right_after_a_replug_mid_the_elevation_turn(v)
        glitched = flipped_bit_in_the_azimuth(v, AZ_SEEN_S)
        v.run_for(60.0)  # (the old target is some 30 s on: not a deadline)
        assert glitched
        [refused] = v.errors(ErrorKind.REFUSED, since=t)
        assert "keep-out" in refused.message
        # held where it was (a stop and its coast): observed 25 -> 85, no stop frame
        assert "stop" in {f.outcome for f in v.frames(since=t)}
        assert abs(v.truth().el_deg - here) <= 10.0, (here, v.truth().el_deg)


def test_a_hand_at_a_decided_azimuth_while_a_halt_is_owed_is_one_move_shown_moving() -> None:
    """The fix's other side: while a refused start's halt is owed, a move only on decided axes
    is a hand's turn once the next reading confirms it, and the reading held back till then
    shows nothing (03af385a held it everywhere and showed its bearing at rest: one 'idle'
    status with the hand's bearing before 'moving'). A bridge just started by the GS-232B at
    rest, a follow start refused at once (owed the halt: review 89), a hand at the azimuth
    past its own time, before the elevation's: one move, never stopped, ended where the hand
    sent it."""
    with gs232_with_a_slow_elevation_by_a_keep_out() as v:
        _restarted_at_rest(v)
        t = v.now
        v.follow(True)
        v.heard("JA1ABC", "PM95")
        v.run_for(AZ_SEEN_S)  # (the azimuth decided still, the elevation not: not a deadline)
        assert [e.kind for e in v.errors(since=t)] == [ErrorKind.REFUSED]
        assert v.truth().az_deg == START_AZ and not v.truth().is_moving  # (never moved)
        hand_t, hand_to = v.now, START_AZ + 120  # (away from the keep-out sector)
        v.manual_rotate(hand_to)  # a hand at the panel
        v.run_until(lambda h: h.status.moving, 10, "the bridge sees the hand's turn")
        v.run_until(lambda h: not h.truth().is_moving, 90, "the hand's turn over")
        v.run_for(5.0)  # (its rest told: not a deadline)
        states = [s.state for s in v.published(since=hand_t)]
        assert [k for k, _ in itertools.groupby(states)] == [MotionState.MOVING, MotionState.IDLE]
        assert "stop" not in {f.outcome for f in v.frames(since=t)}
        assert abs(v.truth().az_deg - hand_to) <= 1.0, (hand_to, v.truth().az_deg)
