"""Review 123: a position sensor at rest that reads right one time in five (the rest garbled,
no two agreeing) is asked at more than the moving rate for good: a GS-232B so failing is asked
about 500 times a minute, where a clean one is asked 60 and the parent of review 103's
follow-up asked the same failing one 100.

controller.py rule 9 (review 103's follow-up, f23b2118): readings at rest that go on disagreeing
are "asked at the moving rate, not at once, until the first unwatched stop below, then at the
usual polls (...; not for good, the polling load review 105 found)". The first unwatched stop
comes at FIRST_UNWATCHED_READINGS (8) in a row that confirmed none, and a reading taken starts
the count again (``_reading``): a sensor that reads right every fifth answer never reaches
eight, so it never has that stop, and its readings are asked at the moving rate, with the
doubt's at-once asks on top, as long as it goes on failing. No stop is owed (it is watched every
fifth reading); the load is review 105's (Low), come back by another way. The review 116 guard
(test_review116_failed_sensor_at_rest_load) has a sensor that never reads right.

In virtual time: the emulated GS-232B at rest at 150, confirmed on a clean line; then each
``1`` it sends reaches the host as the next of ``2``, ``3``, ``4``, ``0``, but for every fifth
answer, which comes through whole, for good.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable

import pytest

from tests.engine.garblers import garbled_at_rest
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
QUERY = b"C\r"
ONLINE_S = 30.0  # a clean start (virtual time)
SETTLE_S = 120.0  # two minutes of it first (virtual time)
COUNT_S = 60.0  # the minute counted (virtual time)
MOVING_POLL_S = 0.2  # moving_poll_interval_s's default (a setting, not a deadline)
RIGHT_EVERY = 5  # one answer in this many read right


def right_now_and_then() -> Callable[[bytes, float], bytes]:
    digits = itertools.cycle(b"2340")
    answers = [0]

    def sensor(data: bytes, now: float) -> bytes:
        if b"1" not in data:
            return data
        answers[0] += 1
        if answers[0] % RIGHT_EVERY == 0:
            return data
        return data.replace(b"1", bytes([next(digits)]))

    return sensor


@pytest.mark.xfail(
    strict=True,
    reason="review 123: a sensor at rest that reads right one time in five is asked about 500 "
    "times a minute for good (clean: 60; before f23b2118: 100)",
)
def test_a_sensor_reading_right_now_and_then_is_not_asked_at_the_moving_rate_for_good(
    rig: Rig,
) -> None:
    v = rig("gs232b-az", emulator={"start_az_deg": 150.0})
    t = garbled_at_rest(v, right_now_and_then(), ONLINE_S, COUNT_S, SETTLE_S)
    v.run_for(COUNT_S)
    asked = v.sent(since=t).count(QUERY)
    assert v.status.available and v.status.bearing_deg == 150.0  # (watched: every fifth agrees)
    assert not v.frames("stop", since=t)  # (no stop owed to it)
    assert asked <= COUNT_S / MOVING_POLL_S / 2, asked  # (not the moving rate's 300, or more)
