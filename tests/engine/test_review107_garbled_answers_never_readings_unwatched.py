"""Review 107: a start whose every answer is garbled past parsing gets no unwatched stop: the
turn under way runs past ``az_min_deg`` to its end, as review 100's did.

controller.py rule 9's unwatched stop (commits 025ee699, 110b095c) counts first readings that
confirmed none: a reading garbled into another bearing counts, an answer garbled into no
reading at all does not. The harm is the same (the bridge cannot watch the rotor: no limit,
stall or turn nobody asked for is judged), and the controller hears (it answers every poll, so
a stop can reach it; rule 10 stops a turn on far less). But on a line that tears every answer
(here the decimal point of each ``AZ``/``EL`` value read as ``?``) nothing is counted: R/error
says the controller "answers only garbled replies: the wrong baud rate or model, or a noisy
line?", and the Easycomm turning at the start runs from 150 past ``az_min_deg`` 60 down to 5,
no stop written.

In virtual time: the emulated Easycomm II box turning from 150 to 5 when the bridge starts
(``az_min_deg`` 60); every ``.`` it sends reaches the host as ``?``.
"""

from __future__ import annotations

from collections.abc import Callable

from tests.engine.garblers import limited, lowest_az, turning_down
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
START_DEG = 150.0
AZ_MIN_DEG = 60.0
TURNING_S = 0.5  # the turn under way when the bridge starts (virtual time)
WATCH_S = 40.0  # 145 degrees at 6 deg/s, with room (virtual time)
STEP_S = 0.1  # a step of virtual time to see the lowest bearing: not a deadline


def torn(data: bytes, now: float) -> bytes:
    """Each answer's decimal points garbled: no value parses."""
    return data.replace(b".", b"?")


def test_a_turn_whose_answers_never_parse_is_stopped_before_the_limit(rig: Rig) -> None:
    v = limited(rig, "easycomm2", START_DEG, AZ_MIN_DEG)
    turning_down(v, TURNING_S)
    t = v.now
    v.to_host = torn
    v.link_up()
    lowest = lowest_az(v, t + WATCH_S, START_DEG, STEP_S)
    said = [e.message for e in v.errors(since=t)]
    assert lowest >= AZ_MIN_DEG, (
        f"turned unstopped from {START_DEG:g} down to {lowest:g}, past az_min_deg "
        f"{AZ_MIN_DEG:g}; stop frames: {len(v.frames('stop', since=t))}; said: {said}"
    )
