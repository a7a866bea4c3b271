"""Review 118: review 113's torn-answer count (link.py rule 11) needs two torn answers in a
row ON ONE CONNECTION (``Link._torn`` starts False with each Link), while controller.py rule 9
counts first readings across a replug until a reading is taken (review 107: "a flaky
adapter's connections of seven readings each never reached eight"). A receive line that
garbles every byte, its line ends too, on an adapter that resets every couple of seconds (the
same fault: a failing level shifter or the rotor motor's interference on the cable) gives each
connection a torn answer or two: the first of each connection is never counted, and the turn
under way at the start runs past ``az_min_deg``. Connections of 2 s, reopened after the
worker's 0.5 s ``reconnect_min_s``: a GS-232B turning from 150 to 5 is stopped only at 24,
36 degrees past az_min_deg 60 (connections of 1.5 s: never stopped, it runs to 5). The same
line on one connection is stopped at 95 (review 113's fix).

In virtual time: the emulated GS-232B turning from 150 to 5 when the bridge starts; every
byte it sends reaches the host XORed with 0x5A; the port fails every UP_S and reopens
DOWN_S later.
"""

from __future__ import annotations

from collections.abc import Callable

from tests.engine.garblers import (
    AZ_MIN_DEG,
    START_DEG,
    WATCH_S,
    opened_through,
    turning_at_the_start,
)
from tests.engine.resetting import lowest_az_resetting
from tests.engine.test_review113_every_byte_garbled_unwatched import torn
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
UP_S = 2.0  # each connection lasts this long (virtual time)


def test_a_garbled_turn_on_a_resetting_adapter_is_stopped_before_the_limit(rig: Rig) -> None:
    v = turning_at_the_start(rig, "gs232b", b"M005\r")
    t = opened_through(v, torn)
    lowest = lowest_az_resetting(v, t + WATCH_S, START_DEG, UP_S)
    stops = v.frames("stop", since=t)
    assert lowest >= AZ_MIN_DEG, (
        f"turned from {START_DEG:g} down to {lowest:g}, past az_min_deg {AZ_MIN_DEG:g}; "
        f"first stop frame at {stops[0].time_s - t if stops else None}"
    )
