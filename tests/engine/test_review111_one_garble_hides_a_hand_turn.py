"""Review 111: one flipped bit in the first answer of a hand turn hides the whole turn: the
rotor is shown idle where it stood while it runs past ``az_min_deg`` to its end.

controller.py rule 9 at rest: a reading off where the rotor stands is doubted and asked again at
once; the next is taken if it agrees with the doubted one (within ``doubt_deg`` and what the
rotor turns between the two, asked at once); if not, the one after is asked at the usual poll
and compared with the one before it "within ``doubt_deg`` alone" (turned: 0, as it was not
asked at once). An Easycomm box turning at its nominal 6 deg/s, polled at its idle rate of a
second, is 6 degrees on at each poll, more than ``doubt_deg`` (5): once one garble has broken
the at-once pair, no two of its readings ever agree again while it turns. The bridge shows it
idle at 150 ("3 readings in a row at rest disagree ... the bearing shown is the last two
readings agreed on"), rule 10 never sees the turn nobody asked for (on a clean line it stops it
within a second, at 144), and it runs on from 150 past ``az_min_deg`` 60 to 5; the stop comes
once it rests there. One garble, on a line otherwise clean, at the rotor's own nominal speed.

In virtual time: the emulated Easycomm II (azimuth) at rest at 150 (``az_min_deg`` 60),
confirmed on a clean line; a hand turns it down to 5 at the box's speed, and the first answer
after that whose bearing is off where it stood reaches the host with its hundreds digit ``1``
read ``3`` (0x31 read 0x33: one bit); every other answer as sent.

Fixed (rule 9): readings at rest that disagree are asked at the moving rate until the first
unwatched stop, and a turn is told by its line as at the start (FIRST_TURN_READINGS on one
steady line, ``_steady``). Here the moving rate's readings, 1.2 degrees apart, agree: the turn is
confirmed and rule 10 stops it ("the rotor turned with no command from the bridge", at about
143, a second and a quarter in; by its line alone, at the idle polls, at about 126, four
seconds in). A rotor stepping further than ``doubt_deg`` a moving poll (the same box at
30 deg/s) is told by its line: the second test.
"""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import ErrorKind
from tests.engine.garblers import first_turning_answer_one_bit_off, limited, lowest_az
from tests.engine.virtual import Sent, VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
AZ_MIN_DEG = 60.0
HAND_TO_DEG = 5.0
POLL = b"AZ EL\n"
CONFIRMED_S = 5.0  # the start's readings on a clean line (not a deadline)
POLLED_S = 5.0  # until a poll goes out (virtual time: one a second)
WATCH_S = 40.0  # 145 degrees at 6 deg/s, with room (virtual time)
STEP_S = 0.1  # a step of virtual time to see the lowest bearing: not a deadline
FAST_DEG_S = 30.0  # 6 degrees a moving poll (0.2 s): more than doubt_deg
EARLY_DEG = 30.0  # four readings on its line, the stop and the coast: well short of the limit
UNASKED = "the rotor turned with no command from the bridge"


def test_one_garbled_answer_does_not_hide_a_hand_turn_past_the_limit(rig: Rig) -> None:
    v = limited(rig, "easycomm2-az", REST_DEG, AZ_MIN_DEG)
    v.link_up()
    v.run_for(CONFIRMED_S)
    assert v.status.available and v.status.bearing_deg == REST_DEG  # (confirmed, clean line)
    v.run_until(lambda h: h.writes[-1] == Sent(h.now, POLL), POLLED_S, "a poll just written")
    v.to_host = first_turning_answer_one_bit_off(f"{REST_DEG:.1f}")
    t = v.now
    v.manual_rotate(HAND_TO_DEG)  # (a hand at the panel, towards the limit)
    lowest = lowest_az(v, t + WATCH_S, REST_DEG, STEP_S)
    stops = [round(f.time_s - t, 2) for f in v.frames("stop", since=t)]
    assert lowest >= AZ_MIN_DEG, (
        f"turned unstopped from {REST_DEG:g} down to {lowest:g}, past az_min_deg "
        f"{AZ_MIN_DEG:g}; stops written {stops} s into the turn"
    )
    said = [e.message for e in v.errors(ErrorKind.STOP, since=t)]
    assert said and all(UNASKED in m for m in said), said  # (rule 10's, not the unwatched)


def test_a_fast_hand_turn_after_one_garble_is_told_by_its_line(rig: Rig) -> None:
    """The same box turning at 30 deg/s (and so configured): 6 degrees a moving poll, more
    than ``doubt_deg``, so no two readings agree; four on one steady line are its turn, and
    rule 10 stops it early, not the unwatched stop eight readings on."""
    v = rig(
        "easycomm2-az",
        emulator={"start_az_deg": REST_DEG, "az_speed_deg_s": FAST_DEG_S},
        settings={"az_min_deg": AZ_MIN_DEG, "az_speed_deg_s": FAST_DEG_S},
        connect=False,
    )
    v.link_up()
    v.run_for(CONFIRMED_S)
    assert v.status.available and v.status.bearing_deg == REST_DEG  # (confirmed, clean line)
    v.run_until(lambda h: h.writes[-1] == Sent(h.now, POLL), POLLED_S, "a poll just written")
    v.to_host = first_turning_answer_one_bit_off(f"{REST_DEG:.1f}")
    t = v.now
    v.manual_rotate(HAND_TO_DEG)  # (a hand at the panel, towards the limit)
    lowest = lowest_az(v, t + WATCH_S, REST_DEG, STEP_S)
    said = [e.message for e in v.errors(ErrorKind.STOP, since=t)]
    assert said and all(UNASKED in m for m in said), said  # (rule 10's, not the unwatched)
    assert lowest >= REST_DEG - EARLY_DEG, (lowest, said)
