"""Review 107: a flaky adapter whose connections each end before their eighth reading keeps a
garbling start unwatched: the turn runs past ``az_min_deg`` to its end, never stopped.

controller.py rule 9 (``_unwatched_stop``, commits 025ee699 and 110b095c) stops a rotor once
FIRST_UNWATCHED_READINGS (eight) of a connection's first readings in a row confirmed none; the
count starts again at every connection (``link_up``). An adapter that drops every second or so
(a USB serial adapter hit by RF: the very line that garbles the answers) gives each connection
seven readings at most (two asked at once, then one a moving poll): none reaches eight, no stop
is ever written, and review 100's turn, begun before the start, runs from 150 past ``az_min_deg``
60 down to 5, as it did before these commits. With connections of a second and a half the same
line is stopped at 140. Nothing of the readings is confirmed across the drops either: the
rotor cannot be watched for the whole time, which is what the stop is for.

In virtual time: the emulated Easycomm II box turning from 150 to 5 when the bridge starts
(``az_min_deg`` 60); every position answer off by 0, +60 or -60 degrees in turn (review 100's
line); the port open for one second, out for one, and so on.
"""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import ErrorKind
from tests.engine.garblers import every_answer_off, limited, turning_down
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
START_DEG = 150.0
AZ_MIN_DEG = 60.0
OFFSETS = [0.0, 60.0, -60.0]
UP_S = 1.0  # each connection of the flaky adapter (virtual time)
DOWN_S = 1.0  # each drop (virtual time)
WATCH_S = 40.0  # 145 degrees at 6 deg/s, with room (virtual time)


def test_a_garbling_start_on_a_flaky_adapter_is_stopped_before_the_limit(rig: Rig) -> None:
    v = limited(rig, "easycomm2", START_DEG, AZ_MIN_DEG)
    turning_down(v, DOWN_S)
    v.to_host = every_answer_off(OFFSETS)
    t, lowest = v.now, START_DEG
    while v.now < t + WATCH_S:
        v.link_up()
        v.run_for(UP_S)
        v.link_down()
        v.run_for(DOWN_S)
        lowest = min(lowest, v.truth().az_deg)
    said = [e.message for e in v.errors(since=t) if e.kind == ErrorKind.STOP]
    assert lowest >= AZ_MIN_DEG, (
        f"turned unstopped from {START_DEG:g} down to {lowest:g}, past az_min_deg "
        f"{AZ_MIN_DEG:g}; stop frames written: {len(v.frames('stop', since=t))}; said: {said}"
    )
