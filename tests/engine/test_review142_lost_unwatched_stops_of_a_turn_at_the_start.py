"""Review 142: a turn under way at the start whose first readings never agree, its first two
unwatched stops lost on the line, runs past ``az_min_deg``: 1b8194c1 writes the next only eight
readings at one a second later.

controller.py rule 9: a connection's first readings that confirmed none get the unwatched stop at
each FIRST_UNWATCHED_READINGS (8) of them. No reading is taken, so nothing shows whether a stop
took (stops.py rule 2 checks a stop by the readings after it): the next unwatched stop is what
sends it again. Before 1b8194c1 those readings were asked at the moving rate, and a lost stop
was followed by another 1.6 s later (this test passes at 1b8194c1^, the turn stopped near 121).
1b8194c1 asks them once a second after the first unwatched stop (UNWATCHED_POLL_S): the next
comes 7 s later, and with two lost, an Easycomm II turning from 150 at 6 deg/s runs to about 52,
past ``az_min_deg`` 60 (one lost: stopped at 96, where 1b8194c1^ stopped it at 131).

In virtual time: the emulated Easycomm II at 150 (``az_min_deg`` 60) sent to 5 before the
bridge opens its port (garblers.py ``turning_at_the_start``); every answer's azimuth off by 0,
+60 or -60 degrees in turn (review 100's line); the first two stop frames lost on the way.
"""

from __future__ import annotations

from collections.abc import Callable

from tests.engine.garblers import every_answer_off, stopped_before_the_limit, turning_at_the_start
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
STOP = b"SA SE\n"  # the Easycomm II stop (easycomm.py)
LOST = 2  # stop frames lost on the noisy line


def test_a_turn_at_the_start_whose_unwatched_stops_are_lost_is_stopped_before_the_limit(
    rig: Rig,
) -> None:
    v = turning_at_the_start(rig, "easycomm2", b"AZ5.0 EL0.0\n")
    v.drop_writes(STOP, LOST)
    stopped_before_the_limit(v, every_answer_off([0.0, 60.0, -60.0]))
