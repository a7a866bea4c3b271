"""Review 142: a connection's first readings that never agree are asked once a second after the
first unwatched stop (1b8194c1), and the next stop comes only at the eighth of them: a hand turn
at the panel after that stop runs eight seconds unstopped, 48 degrees at 6 deg/s, past
``az_min_deg``.

controller.py rule 9: FIRST_UNWATCHED_READINGS (8) first readings in a row that confirmed none
get the unwatched stop, "and so do each as many more while they go on (a hand at the panel after
the first such stop, review 103)". Before 1b8194c1 those readings were asked at the moving rate
(0.2 s): the next stop within 1.6 s, about 10 degrees of a hand's turn (this test passes at
1b8194c1^, the hand stopped at 146). 1b8194c1 asks them at
the usual polls, at least every UNWATCHED_POLL_S (1 s), but the count that brings the next stop
stays eight readings, with no clock bound (the readings at rest have one: UNWATCHED_TURN_DEG,
review 116, 20 degrees at the rotor's nominal speed). An Easycomm II at 6 deg/s, resting 30
degrees above ``az_min_deg``, turned by a hand a second after the first stop, is stopped again
6 s in (the stops go 7 s apart), at 114: 6 degrees past the limit.

In virtual time: the emulated Easycomm II at rest at 150 (``az_min_deg`` 120); every answer's
azimuth off by 0, +60 or -60 degrees in turn (review 100's line) from the start; the first
unwatched stop goes out; a second on, a hand turns the rotor down to 5 at its speed.
"""

from __future__ import annotations

from collections.abc import Callable

from tests.engine.garblers import every_answer_off, limited, lowest_az
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
AZ_MIN_DEG = 120.0
OFFSETS = [0.0, 60.0, -60.0]
FIRST_STOP_S = 60.0  # eight readings at the moving rate, with room (virtual time)
AFTER_S = 1.0  # the hand comes a second after the first unwatched stop (virtual time)
WATCH_S = 40.0  # 145 degrees at 6 deg/s, with room (virtual time)


def test_a_hand_turn_after_the_first_unwatched_stop_of_a_start_is_stopped_before_the_limit(
    rig: Rig,
) -> None:
    v = limited(rig, "easycomm2", REST_DEG, AZ_MIN_DEG)
    v.to_host = every_answer_off(OFFSETS)
    t0 = v.now
    v.link_up()
    v.run_until(lambda h: bool(h.frames("stop", since=t0)), FIRST_STOP_S, "the unwatched stop")
    v.run_for(AFTER_S)
    assert v.truth().az_deg == REST_DEG and not v.status.available  # (still unconfirmed)
    t = v.now
    v.manual_rotate(5.0)  # (a hand at the panel, towards the limit)
    lowest = lowest_az(v, t + WATCH_S, REST_DEG)
    stops = [round(f.time_s - t, 1) for f in v.frames("stop", since=t)]
    assert lowest >= AZ_MIN_DEG, (
        f"turned unstopped from {REST_DEG:g} down to {lowest:g}, past az_min_deg "
        f"{AZ_MIN_DEG:g}; stops written {stops} s into the turn"
    )
