"""A rotor that turns back on its way to its target, on a controller whose azimuth wraps
(motion.py rule 5, ``turned back``): stopped at once where a poll garbled into a jog sends it
the other way, and never for a turn that only looks so (the way round a stop, a new target
across it mid-turn, one corrupt reading). Easycomm in virtual time unless said; the reviews'
and attack passes' cases, each a test."""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState, Target
from tests.engine.virtual import VirtualRotator, settled_at

Rig = Callable[..., VirtualRotator]
IDLE = MotionState.IDLE
FAST = {"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0}
JOG = (b"AZ EL\n", b"AZ ML\n")  # E (0x45) read as M (0x4D): "jog left", on until stopped


def resting(rig: Rig, az: float, **settings: object) -> VirtualRotator:
    v = rig("easycomm2", emulator={"start_az_deg": az, "start_el_deg": 20, **FAST}, **settings)
    v.run_until_state(IDLE, 30)
    v.run_for(10)
    return v


def flip_once(v: VirtualRotator, seen: bytes, instead: bytes) -> list[float]:
    """One reply byte changed on its way to the host: the byte that ends ``seen`` becomes
    ``instead``'s last; returns the list the instant goes into."""
    tail, when = b"", []

    def flip(data: bytes, now: float) -> bytes:
        nonlocal tail
        out = bytearray()
        for b in data:
            tail = (tail + bytes([b]))[-8:]
            if not when and tail.endswith(seen):
                b = instead[-1]
                when.append(now)
            out.append(b)
        return bytes(out)

    v.to_host = flip
    return when


def jogged_back(v: VirtualRotator, past: float) -> float:
    """Sent 300, a poll garbled into a jog once the rotor is past ``past``; until the turn back
    is told. Returns when the poll was garbled."""
    v.target(300, 20)
    v.run_until(lambda h: h.truth().az_deg > past, 30, "on its way")
    t = v.now
    v.garble_writes(*JOG)
    v.run_until(lambda h: h.errors("stalled", since=t) != [], 20, "the turn back told")
    return t


def test_a_target_sent_again_after_a_turn_back_arrives(rig: Rig) -> None:
    v = resting(rig, 200)
    jogged_back(v, 240)
    v.run_for(10)
    t = v.now
    v.target(300, 20)
    v.run_until(settled_at(300, 20), 60, "at 300")
    assert v.errors(since=t) == []


def test_a_jog_in_the_first_degrees_of_a_turn_is_stopped(rig: Rig) -> None:
    """An attack pass: 4 degrees into the turn (two movements that closed in) a jog ran the rotor
    back to its end stop, the first form of the rule waiting for 10 degrees of closing in."""
    v = resting(rig, 200)
    jogged_back(v, 204)
    v.run_for(5)
    assert not v.truth().is_moving and v.truth().az_deg > 185


def test_a_new_target_across_the_stop_mid_turn_is_no_turn_back(rig: Rig) -> None:
    """An attack pass: an RC2800 at 12 degrees a second on its way to 300 is sent 20 at 270 and
    turns back down the long way at once; the reading on its way and the one before showed it
    still going up, 9.7 degrees closer to 20 round the circle: stopped as a turn back at 257.6.
    The watch of a target sent mid-turn starts after the settle time."""
    v = rig("rc2800", emulator={"start_az_deg": 200, "az_speed_deg_s": 12.0})
    v.run_until_state(IDLE, 30)
    v.target(300)
    v.run_until(lambda h: h.truth().az_deg >= 270, 30, "at 270")
    t = v.now
    v.target(20)
    v.run_until(lambda h: h.errors(since=t) != [] or settled_at(20)(h), 60, "at 20")
    assert v.errors(since=t) == [] and v.truth().az_deg == 20


def test_one_flipped_digit_on_the_long_way_round_is_no_turn_back(rig: Rig) -> None:
    """An attack pass: 10 to 350 goes up the long way (away from 350 round the circle first);
    one reply ``AZ113.x`` read as ``AZ103.x`` ('1' read as '0', one bit) closed in on 350 by
    8.8 degrees in one reading and armed the rule's first form: the two true readings after it
    were a turn back, the turn stopped at 113. One movement that closes in is nothing."""
    v = resting(rig, 10)
    v.target(350, 20)
    v.run_until(lambda h: h.truth().az_deg > 105, 30, "on its way")
    t = v.now
    when = flip_once(v, b"AZ11", b"AZ10")
    v.run_until(lambda h: h.errors(since=t) != [] or settled_at(350, 20)(h), 90, "at 350")
    assert when and v.errors(since=t) == [] and v.truth().az_deg == 350


def test_the_error_gives_the_bearing_the_user_sees(rig: Rig) -> None:
    """An attack pass: with ``az_offset_deg`` 30 the error said 'now at 231.1' where R/bearing
    said 261.1 (the pass's and the stall's words did so too: stops.py ``verdict``'s ``shown``)."""
    v = resting(rig, 200, settings={"az_offset_deg": 30})
    v.aim(Target(330, 20))
    v.run_until(lambda h: h.truth().az_deg > 240, 30, "on its way")
    t = v.now
    v.garble_writes(*JOG)
    v.run_until(lambda h: h.errors("stalled", since=t) != [], 20, "the turn back told")
    [said] = v.errors("stalled", since=t)
    assert f"now at {v.status.bearing_deg:g}°" in said.message, said.message
