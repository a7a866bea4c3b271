"""Review 142: a connection's first readings that never agree are asked once a second after the
first unwatched stop (1b8194c1), even where the user set a slower moving rate: the line's load
doubles against 1b8194c1^.

controller.py rule 9 (1b8194c1): past the first unwatched stop, such readings are asked "at the
usual polls but at least every UNWATCHED_POLL_S (1 s)". Before, they were asked at the moving
rate, and settings/rotator.py says of ``moving_poll_interval_s`` "how often a turning rotor is
asked": the fastest the bridge polls. A user who set it to 2 s (a slow serial server, a shared
line; ``idle_poll_interval_s`` 10 s) and whose GS-232B's sensor fails before the start now has it
asked some 80 times a minute, where 1b8194c1^ asked about 40 (this test passes there): the change
meant to lower review 105's load raises it here.

In virtual time: the emulated GS-232B at rest at 150, moving poll 2 s, idle poll 10 s; each ``1``
it sends reaches the host as the next of ``2``, ``3``, ``4``, ``0`` (review 105's failing sensor)
from the start; the queries of the third minute counted.
"""

from __future__ import annotations

from collections.abc import Callable

from tests.engine.test_review105_first_readings_polled_at_the_moving_rate_forever import (
    QUERY,
    failing,
)
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
MOVING_S = 2.0
SETTINGS = {"moving_poll_interval_s": MOVING_S, "idle_poll_interval_s": 10.0, "settle_s": 4.0}
SETTLE_S = 120.0  # two minutes of it, past the first unwatched stop (virtual time)
COUNT_S = 60.0  # the minute counted (virtual time)
ROOM = 1.5  # the moving rate's queries, with room for the stops' checks and at-once asks


def test_first_readings_that_never_agree_are_not_asked_faster_than_the_moving_rate(
    rig: Rig,
) -> None:
    v = rig("gs232b-az", emulator={"start_az_deg": 150.0}, settings=SETTINGS, connect=False)
    v.to_host = failing()
    v.link_up()
    v.run_for(SETTLE_S)
    t = v.now
    v.run_for(COUNT_S)
    asked = v.sent(since=t).count(QUERY)
    assert not v.status.available  # (no two agree: never confirmed)
    most = ROOM * COUNT_S / MOVING_S
    assert asked <= most, (
        f"asked {asked} times in a minute, more than {most:g} at a {MOVING_S:g} s moving rate"
    )
