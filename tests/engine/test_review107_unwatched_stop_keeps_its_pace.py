"""Review 107 (a guard): first readings that go on disagreeing for minutes still get their
stop within FIRST_UNWATCHED_READINGS of a turn's start, not at the idle rate.

controller.py rule 9 stops a rotor whose connection's first readings confirmed none at each
FIRST_UNWATCHED_READINGS of them (commit 110b095c: a hand at the panel after the first such
stop, review 103, stopped at 143 on its way from 150 past ``az_min_deg`` 60). How far such a turn
runs is eight of those readings' spacing: at the moving rate about 1.6 s, ten degrees. Review
105 found those readings asked at the moving rate for good, and a change that asks them at the
idle rate after a while (10 s: eight are 80 s, a whole turn) would keep review 103's test green,
whose hand turns three seconds after the start. This one turns the rotor three minutes after.

In virtual time: the emulated Easycomm II box at rest at 150 (``az_min_deg`` 60); every position
answer off by 0, +60 or -60 degrees in turn (review 100's line) from the start; three minutes
on, a hand turns the rotor down to 5 at the box's speed.
"""

from __future__ import annotations

from collections.abc import Callable

from tests.engine.garblers import every_answer_off, limited, lowest_az
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
AZ_MIN_DEG = 60.0
OFFSETS = [0.0, 60.0, -60.0]
GARBLED_S = 180.0  # three minutes of disagreeing first readings (virtual time)
WATCH_S = 40.0  # 145 degrees at 6 deg/s, with room (virtual time)
STEP_S = 0.1  # a step of virtual time to see the lowest bearing: not a deadline


def test_a_hand_turn_minutes_into_a_garbling_start_is_stopped_before_the_limit(
    rig: Rig,
) -> None:
    v = limited(rig, "easycomm2", REST_DEG, AZ_MIN_DEG)
    v.to_host = every_answer_off(OFFSETS)
    v.link_up()
    v.run_for(GARBLED_S)
    assert v.truth().az_deg == REST_DEG and not v.status.available  # (still unconfirmed)
    t = v.now
    v.manual_rotate(5.0)  # (a hand at the panel, towards the limit)
    lowest = lowest_az(v, t + WATCH_S, REST_DEG, STEP_S)
    stops = [round(f.time_s - t, 2) for f in v.frames("stop", since=t)]
    assert lowest >= AZ_MIN_DEG, (
        f"turned unstopped from {REST_DEG:g} down to {lowest:g}, past az_min_deg "
        f"{AZ_MIN_DEG:g}; stops written {stops} s into the turn"
    )
