"""Review 103: the one stop a connection's unconfirmed first readings get for a limit is spent
by a garble at rest, and a turn that then runs past the limit goes unstopped.

controller.py rule 9 (``_first_past_limit``, commit e9e2e51a) sends a stop when a first reading
not yet confirmed by another is, if true, past a limit, once a connection. A line that garbles
the answers (review 100's: every answer off by one of a few offsets in turn, no two agree) can
put its first garble past the limit while the rotor stands well inside it: that stop is sent
to a rotor at rest (harmless) and the once is used up. A turn that starts after it (a hand at
the panel; on a clean line the bridge stops a turn nobody asked for within a second) runs on,
unwatched, past ``az_min_deg`` to its end: no second stop is sent while the readings go on
disagreeing, though they keep saying the rotor is past the limit. (That stop was reverted; now
first readings that go on disagreeing get a stop at each FIRST_UNWATCHED_READINGS in a row, so
a turn begun after the first such stop gets one too.)

In virtual time: the emulated Easycomm II box at rest at 150 (``az_min_deg`` 60); every
position answer reaches the host off by -100, +60 or 0 degrees in turn (the first reads 50, past
the limit); three seconds after the start a hand turns the rotor down to 5 at the box's speed.
"""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import ErrorKind
from tests.engine.garblers import every_answer_off, limited, lowest_az
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
AZ_MIN_DEG = 60.0
OFFSETS = [-100.0, 60.0, 0.0]  # the first answer reads 50: past az_min_deg, the rotor is not
SETTLED_S = 3.0  # the start's first readings, at rest (not a deadline)
WATCH_S = 40.0  # 145 degrees at 6 deg/s, with room (virtual time)


def test_a_turn_past_the_limit_after_a_garble_spent_the_first_stop_is_stopped(rig: Rig) -> None:
    v = limited(rig, "easycomm2", REST_DEG, AZ_MIN_DEG)
    v.to_host = every_answer_off(OFFSETS)
    v.link_up()
    v.run_for(SETTLED_S)
    assert v.truth().az_deg == REST_DEG and not v.truth().is_moving
    t = v.now
    v.manual_rotate(5.0)  # (a hand at the panel: a turn nobody asked for, towards the limit)
    lowest = lowest_az(v, t + WATCH_S, REST_DEG)
    errors = v.errors()
    assert lowest >= AZ_MIN_DEG, (
        f"turned unstopped from {REST_DEG:g} down to {lowest:g}, past az_min_deg "
        f"{AZ_MIN_DEG:g}; stops written at {[round(f.time_s, 2) for f in v.frames('stop')]}; "
        f"said {[e.message for e in errors if e.kind == ErrorKind.STOP]}"
    )
