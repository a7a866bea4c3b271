"""Review 116's fix, its price: a position sensor failed for good at rest is stopped again each
time a turn at nominal speed would have gone UNWATCHED_TURN_DEG (controller.py rule 9), the
reading that brings it asked then; the rest of its readings at the usual polls. Never at the
moving rate for good (review 105's load): a GS-232B so failed is asked about 110 times a
minute (80 at its idle rate, the rest the stops' checks and the clock's readings), where the
moving rate would be about 300.

In virtual time: the emulated GS-232B at rest at 150, confirmed on a clean line; then each
``1`` it sends reaches the host as the next of ``2``, ``3``, ``4``, ``0`` (no two agree, no four
make a turn), for good.
"""

from __future__ import annotations

from collections.abc import Callable

from tests.engine.garblers import garbled_at_rest
from tests.engine.test_review105_first_readings_polled_at_the_moving_rate_forever import failing
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
QUERY = b"C\r"
ONLINE_S = 30.0  # a clean start (virtual time)
SETTLE_S = 120.0  # two minutes of it first (virtual time)
COUNT_S = 60.0  # the minute counted (virtual time)
MOVING_POLL_S = 0.2  # moving_poll_interval_s's default (a setting, not a deadline)


def test_a_sensor_failed_for_good_at_rest_is_stopped_but_not_asked_at_the_moving_rate(
    rig: Rig,
) -> None:
    v = rig("gs232b-az", emulator={"start_az_deg": 150.0})
    t = garbled_at_rest(v, failing(), ONLINE_S, COUNT_S, SETTLE_S)
    v.run_for(COUNT_S)
    asked = v.sent(since=t).count(QUERY)
    stops = v.frames("stop", since=t)
    assert stops  # (the rotor cannot be watched: stopped again while it goes on)
    assert asked <= COUNT_S / MOVING_POLL_S / 2, asked  # (not the moving rate's 300)
    assert not v.truth().is_moving
