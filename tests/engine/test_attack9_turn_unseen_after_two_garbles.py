"""Attack 9: a rotor at rest turned by a hand at the panel (or by a command a flipped bit made)
is doubted on its first reading that shows the move and asked again at once
(session/controller.py rule 9); a reading asked again agrees 'within doubt_deg plus twice what
the rotor turns between them'. When the answer to that ask comes garbled and so does the
re-poll's (link.py rule 11: a garbled answer to a re-poll waits for the next poll), the doubt
loses its window (``_given_up``: ``at_once`` False), and every reading after it, at the idle
rate, must agree with the one before within ``doubt_deg`` alone: a rotor turning at 6 degrees
a second never does. Two noisy replies in a row, and the whole turn goes unseen: the bearing
shows the rotor idle where it stood until it rests again, a lock ON does not fight the turn,
and no limit is watched on the way. The lock now fights such a turn by itself, whatever the
doubt believes: a reading at rest doubted under the lock sends its stop again (stops.py rule
7)."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState
from tests.engine.test_session_doubt import at_rest, locked_at_rest
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


def garble_after_the_first_move(
    v: VirtualRotator, rest: float, count: int = 2, every: int = 0
) -> list[float]:
    """One noise byte at the head of each of the ``count`` Rotor-EZ replies (``;ddd``) that
    follow the first one more than 3 degrees from ``rest`` (with ``every``: of all of them, for
    good, all but every ``every``-th); returns the list each instant goes into."""
    when: list[float] = []
    digits = bytearray()
    armed = [False]
    seen = [0]

    def garble(data: bytes, now: float) -> bytes:
        out = bytearray()
        for b in data:
            out.append(b)
            if b == ord(";"):
                digits.clear()
                if armed[0]:
                    seen[0] += 1
                    if (seen[0] % every != 0) if every else len(when) < count:
                        when.append(now)
                        out += b"#"  # (a byte no board sends: the reply is not trusted)
            elif chr(b).isdigit() and len(digits) < 3:
                digits.append(b)
                if len(digits) == 3 and abs(int(digits) - rest) > 3:
                    armed[0] = True
        return bytes(out)

    v.to_host = garble
    return when


@pytest.mark.parametrize("model", ["rotorez", "rotorcard"])
def test_a_turn_by_hand_on_a_locked_rotor_is_fought_after_two_garbled_replies(
    rig: Rig, model: str
) -> None:
    v, rest = locked_at_rest(rig, model)
    t = v.now
    garbled = garble_after_the_first_move(v, rest)
    v.manual_rotate(300.0)  # a hand at the panel, the rotor locked
    v.run_for(40)
    assert len(garbled) == 2
    # what the lock does to a turn by hand when no reply is lost (rotorez.py's board stops on
    # ';'): it is fought within a few degrees (158.6 and 155 without the two noise bytes)
    assert v.truth().az_deg < rest + 20
    assert MotionState.MOVING in {s.state for s in v.published(since=t)}


@pytest.mark.parametrize("model", ["rotorez", "rotorcard"])
def test_a_turn_by_hand_on_a_locked_rotor_is_fought_when_every_ask_comes_garbled(
    rig: Rig, model: str
) -> None:
    """Five replies in six come garbled, so each reading between them is further on than
    ``doubt_deg`` from the one before (the rotor turns) and is asked again, and that ask comes
    garbled, its re-poll and the polls after too: the lock must still fight the turn."""
    v, rest = locked_at_rest(rig, model)
    t = v.now
    garbled = garble_after_the_first_move(v, rest, every=6)
    v.manual_rotate(300.0)  # a hand at the panel, the rotor locked
    v.run_for(40)
    assert len(garbled) >= 6
    assert v.truth().az_deg < rest + 40
    assert MotionState.MOVING in {s.state for s in v.published(since=t)}


def test_a_flipped_bit_at_rest_whose_ask_comes_garbled_twice_then_another_is_never_shown(
    rig: Rig,
) -> None:
    """The other side of the same rule: line noise, not a hand. The reading at rest (1xx) is
    read 3xx, the ask at once and its re-poll come garbled, the poll after (at the moving rate)
    is read 2xx: disagreeing with the doubted one, it is asked again at once, and the true
    reading then shows both were noise. Only the bearing at rest is ever published."""
    v = at_rest(rig, "rotorez")
    rest = v.status.bearing_deg
    assert rest is not None
    plan = iter(["3", "#", "#", "2"])
    done: list[str] = []
    head = [False]

    def noisy(data: bytes, now: float) -> bytes:
        out = bytearray()
        for b in data:
            if head[0] and chr(b).isdigit():
                head[0] = False
                what = next(plan, None)
                if what is not None:
                    done.append(what)
                    if what == "#":
                        out += b"#"
                    else:
                        b = ord(what)
            elif b == ord(";"):
                head[0] = True
            out.append(b)
        return bytes(out)

    v.to_host = noisy
    t = v.now
    v.run_until(lambda h: len(done) == 4, 60, "the four noisy replies")
    v.run_for(20)
    assert {s.bearing_deg for s in v.published(since=t)} - {None} == {rest}
    assert {s.state for s in v.published(since=t)} == {MotionState.IDLE}
