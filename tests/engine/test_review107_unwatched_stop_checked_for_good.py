"""Review 107: the stop a garbled start gets stays checked for good: a hand at the panel ten
minutes later, the line long sound, is stopped, and nothing says why.

controller.py rule 9 (``_unwatched_stop``, commit 025ee699) sends "a stop as any" when a
connection's first readings go on disagreeing. stops.py rule 2 checks a stop to a rotor the
bridge took for at rest "until the next target or until the move after it ended", and names the
price for an operator's STOP: "a move by hand long after such a stop is stopped once too" (the
lock's release lets its stop go, ``lock_released``). Nobody pressed STOP here: the bridge sent
it to a rotor at rest whose readings it could not trust, the line came right seconds later and
every reading since showed the rotor where it stood. Yet the check stays armed: on a GS-232B
(``unasked_moves`` "follow": a turn by hand is the operator's) a hand at the panel ten minutes
later is stopped six degrees into its turn, and R/error says nothing. After a clean start the
same turn is followed to its end.

In virtual time: the emulated GS-232B at rest at 150; for its first three seconds each ``1`` it
sends reaches the host as the next of ``2``, ``3``, ``4``, ``0`` (review 105's failing sensor: no
two readings agree), then the line is sound; ten minutes on, a hand turns the rotor to 250.
"""

from __future__ import annotations

from collections.abc import Callable

from tests.engine.test_review105_first_readings_polled_at_the_moving_rate_forever import failing
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
HAND_DEG = 250.0
GARBLED_S = 3.0  # the start's readings disagree: the unwatched stop written (virtual time)
ONLINE_S = 10.0  # the sound line's readings agree (virtual time)
QUIET_S = 600.0  # ten minutes at rest, every reading sound (virtual time)
TURN_S = 40.0  # 100 degrees at the emulator's 6 deg/s, with room (virtual time)


def hand_turn_after(v: VirtualRotator) -> tuple[list[float], list[str]]:
    """Ten minutes at rest, then a hand turn: the stops written at it, and what was said."""
    v.run_until(lambda h: h.status.available, ONLINE_S, "the sound line's readings agree")
    v.run_for(QUIET_S)
    assert v.status.bearing_deg == REST_DEG and not v.truth().is_moving
    t = v.now
    v.manual_rotate(HAND_DEG)  # (the operator at the panel)
    v.run_for(TURN_S)
    return [f.time_s - t for f in v.frames("stop", since=t)], [e.message for e in v.errors(since=t)]


def test_after_a_clean_start_a_hand_turn_is_followed(rig: Rig) -> None:
    v = rig("gs232b", emulator={"start_az_deg": REST_DEG})
    stops, said = hand_turn_after(v)
    assert stops == [] and v.truth().az_deg == HAND_DEG, (stops, said)


def test_after_a_garbled_start_a_hand_turn_much_later_is_followed(rig: Rig) -> None:
    v = rig("gs232b", emulator={"start_az_deg": REST_DEG}, connect=False)
    v.to_host = failing()
    v.link_up()
    v.run_for(GARBLED_S)
    assert v.frames("stop"), "the garbled start got no unwatched stop"  # (the premise)
    v.to_host = None
    stops, said = hand_turn_after(v)
    assert stops == [] and v.truth().az_deg == HAND_DEG, (
        f"the hand turn from {REST_DEG:g} to {HAND_DEG:g} stopped at {v.truth().az_deg:.0f} "
        f"by stops written {[round(s, 2) for s in stops]} s into it; said: {said}"
    )
