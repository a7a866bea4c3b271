"""Review 100: while a connection's first readings are not yet confirmed, a turn nobody watches
must not run past a limit.

controller.py rule 9 (``_doubts_first``) takes no first reading until two agree (or three lie on
one steady turn); until then no move, limit or turn nobody asked for is judged from it (rules 10
and 13). A line that garbles every answer differently keeps a rotor turning when the bridge
starts unconfirmed for as long as it goes on, and the turn runs on, unwatched, past
``az_min_deg``. First readings that go on disagreeing (FIRST_UNWATCHED_READINGS in a row, more
than a healthy start ever needs) now mean the bridge cannot watch the rotor: it is stopped (a
stop is always safe), and R/error says so. (A stop for one unconfirmed reading past a limit,
e9e2e51a, was tried first and reverted: review 103 found it stopped healthy starts outside a
limit.)

In virtual time: the emulated Easycomm II box turning from 150 to 5 when the bridge opens its
port (``az_min_deg`` 60); every position answer reaches the host off by 0, +60 or -60 degrees
in turn: no two agree, and no three lie on a turn a rotor can make.
"""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import ErrorKind
from tests.engine.garblers import every_answer_off, limited, lowest_az, turning_down
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
START_DEG = 150.0
AZ_MIN_DEG = 60.0
OFFSETS = [0.0, 60.0, -60.0]
WATCH_S = 40  # 145 degrees at 6 deg/s, with room


def test_a_turn_whose_first_readings_never_agree_is_stopped_before_the_limit(rig: Rig) -> None:
    v = limited(rig, "easycomm2", START_DEG, AZ_MIN_DEG)
    turning_down(v, 0.5)
    t = v.now
    v.to_host = every_answer_off(OFFSETS)
    v.link_up()
    lowest = lowest_az(v, t + WATCH_S, START_DEG)
    errors = v.errors(since=t)
    assert lowest >= AZ_MIN_DEG, (
        f"turned unstopped from {START_DEG:g} down to {lowest:g}, past az_min_deg "
        f"{AZ_MIN_DEG:g}; said {[e.message for e in errors]}"
    )
    assert v.frames("stop", since=t)
    said = [e.message for e in errors if e.kind == ErrorKind.STOP]
    assert any("do not agree" in m and "stopped" in m for m in said), errors
