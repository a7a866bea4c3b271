"""Review 113: the unwatched stop written just before the port failed is sent again on the
reconnect (stops.py rule 3) and that copy stays checked for good: a hand at the panel ten
minutes later, the line long sound, is stopped, and nothing says why.

Commit bd07c40d lets controller.py rule 9's unwatched stop go once a reading shows the rotor
still (``_release_check``, as a released lock's): only the frame ``_unwatched_stop`` itself
writes is marked (``_unwatched_stopping``). A stop written less than STOP_UNSURE_S before the
port failed is owed and written first on the next connect (``_send_owed``), as an ordinary
stop: a newer ``stop_sent_t`` that ``_release_check`` takes for "a newer stop, rule 2 as ever",
so the check review 107 removed is back, armed until the next target. A flaky adapter, the
very one 34623a6f counts the unwatched stop across, drops just after a stop often enough. On a
GS-232B (``unasked_moves`` "follow") the hand's turn to 250 is cut a few degrees in.

In virtual time: review 107's start (the emulated GS-232B at rest at 150, readings of a failing
sensor that never agree); the port drops the moment the unwatched stop is written and is back
a second later with the line sound; ten minutes on, a hand turns the rotor to 250.

Fixed: the owed copy of rule 9's unwatched stop is let go as the unwatched stop itself
(controller.py ``_let_go``: ``_released_owed`` at the drop).
"""

from __future__ import annotations

from collections.abc import Callable

from tests.engine.test_review105_first_readings_polled_at_the_moving_rate_forever import failing
from tests.engine.test_review107_unwatched_stop_checked_for_good import (
    HAND_DEG,
    REST_DEG,
    hand_turn_after,
)
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
GARBLED_S = 10.0  # for the unwatched stop to be written (virtual time)
DOWN_S = 1.0  # the drop (virtual time, not a deadline)


def test_an_unwatched_stop_owed_across_a_drop_lets_a_later_hand_turn_be(rig: Rig) -> None:
    v = rig("gs232b", emulator={"start_az_deg": REST_DEG}, connect=False)
    v.to_host = failing()
    v.link_up()
    v.run_until(lambda h: h.frames("stop"), GARBLED_S, "the unwatched stop written")
    v.link_down()  # (within STOP_UNSURE_S of the stop: it is owed)
    v.to_host = None
    v.run_for(DOWN_S)
    t = v.now
    v.link_up()
    stops, said = hand_turn_after(v)
    assert v.frames("stop", since=t), "no stop owed on the reconnect"  # (the premise)
    assert stops == [] and v.truth().az_deg == HAND_DEG, (
        f"the hand turn from {REST_DEG:g} to {HAND_DEG:g} stopped at {v.truth().az_deg:.0f} "
        f"by stops written {[round(s, 2) for s in stops]} s into it; said: {said}"
    )
