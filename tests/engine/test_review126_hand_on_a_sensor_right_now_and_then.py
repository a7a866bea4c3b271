"""Review 126: a Rot2Prog at rest on a line that reads one answer in five right (review 123's
sensor, the others far off) is asked at its idle rate once the moving rate's spell is spent
(``_rest_spell_on``, 726b34d5); a hand at the panel that turns it then has its first unwatched
stop only some forty seconds later, and runs past ``az_min_deg``. At 726b34d5^ (the spell
renewed by each reading taken) the same hand was stopped some four seconds in.

controller.py rule 9: readings at rest that go on disagreeing are asked at the moving rate till
the first unwatched stop, "not for more than FIRST_UNWATCHED_READINGS of them counted since the
last as many readings taken in a row" (review 123: the load of a sensor right one answer in
five). The sensor right now and then is watched (every fifth reading taken) and owes no stop;
but once a hand turns the rotor its right readings disagree too, the count runs on, and the
eight that bring the first unwatched stop are asked at the idle rate (a Rot2Prog's: seconds
apart), the spell long spent and not renewed (no eight taken in a row).

In virtual time: the emulated Rot2Prog at rest at 150 (``az_min_deg`` 120), confirmed on a
clean line; then each position frame reaches the host off by +60, -60, +100, -100 and 0 in
turn, for good; ten minutes on, a hand turns the rotor down to 5.
"""

from __future__ import annotations

from collections.abc import Callable

from tests.engine.garblers import (
    confirmed_at_rest,
    every_answer_off,
    every_frame_off,
    lowest_az,
)
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
AZ_MIN_DEG = 120.0
HAND_DEG = 5.0
OFFSETS = [60.0, -60.0, 100.0, -100.0, 0.0]  # one frame in five right
CONFIRMED_S = 30.0  # the start's readings on a clean line (virtual time, not a deadline)
RIGHT_NOW_AND_THEN_S = 600.0  # ten minutes of the failing sensor at rest (virtual time)
WATCH_S = 120.0  # the hand's turn (virtual time)


def test_a_hand_turn_on_a_sensor_right_now_and_then_is_stopped_before_the_limit(
    rig: Rig,
) -> None:
    v = confirmed_at_rest(rig, "rot2prog", REST_DEG, AZ_MIN_DEG, CONFIRMED_S)
    v.to_host = every_frame_off(OFFSETS)
    v.run_for(RIGHT_NOW_AND_THEN_S)
    assert v.truth().az_deg == REST_DEG  # (at rest all along)
    t = v.now
    v.manual_rotate(HAND_DEG)  # (a hand at the panel: a turn nobody asked for, to the limit)
    lowest = lowest_az(v, t + WATCH_S, REST_DEG)
    stops = [round(f.time_s - t, 1) for f in v.frames("stop", since=t)]
    assert lowest >= AZ_MIN_DEG, (lowest, stops)


EASYCOMM_AZ_MIN_DEG = 120.0
REVIEW_103_LINE = [0.0, 60.0, -60.0]  # every answer off by 0, +60 or -60 in turn
GONE_BAD_S = 3.0  # the bad line at rest before the hand (virtual time): review 103's
HAND_WATCH_S = 40.0  # 145 degrees at 6 deg/s, with room (virtual time)


def test_a_hand_turn_three_seconds_into_review_103s_line_is_stopped_within_seconds(
    rig: Rig,
) -> None:
    """The same spell spent on review 103's own line (an Easycomm II, every answer off by 0,
    +60 or -60 in turn, a hand three seconds after the line went bad): the readings taken
    between (every third) start the count again, never eight taken in a row, and the spell of
    eight disagreeing at the moving rate is spent before the hand comes. Its first unwatched
    stop comes 7 s in, at 108, 42 degrees down; at 726b34d5^, 1.2 s in, at 143 (review 103's
    "about a second and a quarter in, at about 143")."""
    v = confirmed_at_rest(rig, "easycomm2", REST_DEG, EASYCOMM_AZ_MIN_DEG, CONFIRMED_S)
    v.to_host = every_answer_off(REVIEW_103_LINE)
    v.run_for(GONE_BAD_S)
    t = v.now
    v.manual_rotate(HAND_DEG)  # (a hand at the panel: a turn nobody asked for, to the limit)
    lowest = lowest_az(v, t + HAND_WATCH_S, REST_DEG)
    stops = [round(f.time_s - t, 1) for f in v.frames("stop", since=t)]
    assert lowest >= EASYCOMM_AZ_MIN_DEG, (lowest, stops)
