"""Review 100: two of a connection's first three answers one bit off, and a rotor turning when
the bridge starts runs past ``az_min_deg`` unstopped.

controller.py rule 9 (``_doubts_first``, a8a074df and 80801409): a connection's first reading is
taken once the next agrees, asked at once, within ``doubt_deg`` and twice the nominal speed
times the time between; after DOUBTS_TOLD (3) first readings in a row that disagree, the rest
are asked "at the usual polls, within ``doubt_deg`` alone". At the usual polls (one a second
here) a rotor turning at its nominal 6 deg/s is 6 degrees on from the last reading, more than
``doubt_deg`` (5): no two ever agree while it turns, and until two agree the controller is "not
answering" and no turn nobody asked for is judged (rule 10). An Easycomm box (``unasked_moves``
"stop" by default: rule 10 stops a turn it was on when the bridge started, "a restart
mid-turn?") turning to 5 when the bridge opens its port, the first two position answers each
one bit off (``AZ146.9`` read ``AZ346.9``, then ``AZ246.8``): the rotor runs on from 147 past
the configured ``az_min_deg`` 60 to 5, nothing stopped, no bearing shown, and R/error says only
"3 first readings in a row disagree". Before the change the first (wrong) reading was taken,
the next showed the turn, and rule 10 stopped it at 144 within a second.

In virtual time: the emulated Easycomm II box given ``AZ5.0 EL0.0`` before the bridge opens the
port (a turn it goes on with across a restart); its first two position answers reach the host
one bit off, the rest as sent.
"""

from __future__ import annotations

from collections.abc import Callable

from tests.engine.garblers import first_answers_one_bit_off, limited, lowest_az, turning_down
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
START_DEG = 150.0
AZ_MIN_DEG = 60.0
FLIPS = [b"3", b"2"]  # the hundreds' 1 (0x31) read as 3 (0x33), then as 2 (0x32): one bit each
WATCH_S = 40  # 145 degrees at 6 deg/s, with room


def test_a_turn_at_the_start_is_stopped_before_the_limit_when_two_first_answers_are_off(
    rig: Rig,
) -> None:
    v = limited(rig, "easycomm2", START_DEG, AZ_MIN_DEG)
    turning_down(v, 0.5)
    t = v.now
    v.to_host = first_answers_one_bit_off(FLIPS)
    v.link_up()
    lowest = lowest_az(v, t + WATCH_S, START_DEG)
    said = [e.message for e in v.errors(since=t)]
    assert lowest >= AZ_MIN_DEG, (
        f"turned unstopped from {START_DEG:g} down to {lowest:g}, past az_min_deg "
        f"{AZ_MIN_DEG:g}; stops {[f.data for f in v.frames('stop', since=t)]}; said {said}"
    )
    assert v.frames("stop", since=t)
