"""Review 103, follow-up: a line that goes bad while the rotor rests (after its readings were
confirmed) leaves a turn nobody asked for unwatched, and it runs past ``az_min_deg``.

controller.py rule 9 stops a rotor whose connection's first readings go on disagreeing
(``_unwatched_stop``: the bridge cannot watch it). Readings at rest that go on disagreeing
inside a session (a line gone bad, a failing position sensor) get no such stop: a reading back
where the rotor stood is taken, any other is doubted and compared with the one doubted before
(within ``doubt_deg`` alone at the usual polls), and a line that garbles every answer
differently never has two agree. A turn that starts then (a hand at the panel, or a poll the
bad line garbled into a jog: why an Easycomm box's ``unasked_moves`` is "stop") is never
confirmed, so rule 10 never sees it: an Easycomm at rest at 150, on a clean line stopped within
a second (at 144, "the rotor turned with no command from the bridge"), runs on to 5, 55 degrees
past ``az_min_deg`` 60, with no stop and no stop error.

Not fixed with review 100's stop: the same stop at each FIRST_UNWATCHED_READINGS readings at rest
in a row that disagree passes this test (stopped at 108-114, also on a GS-232B), but breaks a
deliberate rule, test_lock_fights_by_itself.py's "the same noise without the lock writes no
stop" (a failing sensor at rest whose readings are never back where it stood, stops.py rule 7,
review 40): which of the two holds is a maintainer's decision; at the usual idle polls such a
stop would also come late on a slow line (a Rot2Prog's 9.3 s: eight readings in 74 s).

Fixed, the maintainers' decision (limits hold): readings at rest that go on disagreeing get
the same stop, FIRST_UNWATCHED_READINGS in a row, said on R/error ("8 readings in a row at rest do
not agree ..."), and are asked at the moving rate until it: the hand's turn is stopped about a
second and a quarter in, at about 143 (test_lock_fights_by_itself.py's rule superseded).

In virtual time: the emulated Easycomm II box at rest at 150 (``az_min_deg`` 60), confirmed on a
clean line; then every position answer reaches the host off by 0, +60 or -60 degrees in turn
(review 100's line); three seconds on, a hand turns the rotor down to 5 at the box's speed.
"""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import ErrorKind
from tests.engine.garblers import every_answer_off, limited, lowest_az
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REST_DEG = 150.0
AZ_MIN_DEG = 60.0
OFFSETS = [0.0, 60.0, -60.0]
CONFIRMED_S = 5.0  # the start's readings on a clean line (not a deadline)
GONE_BAD_S = 3.0  # the bad line at rest before the hand (virtual time)
WATCH_S = 40.0  # 145 degrees at 6 deg/s, with room (virtual time)


def test_a_hand_turn_on_a_line_gone_bad_at_rest_is_stopped_before_the_limit(rig: Rig) -> None:
    v = limited(rig, "easycomm2", REST_DEG, AZ_MIN_DEG)
    v.link_up()
    v.run_for(CONFIRMED_S)
    assert v.status.available and v.status.bearing_deg == REST_DEG
    v.to_host = every_answer_off(OFFSETS)
    v.run_for(GONE_BAD_S)
    t = v.now
    v.manual_rotate(5.0)  # (a hand at the panel: a turn nobody asked for, towards the limit)
    lowest = lowest_az(v, t + WATCH_S, REST_DEG)
    said = [e.message for e in v.errors(since=t) if e.kind == ErrorKind.STOP]
    assert lowest >= AZ_MIN_DEG, (
        f"turned unstopped from {REST_DEG:g} down to {lowest:g}, past az_min_deg "
        f"{AZ_MIN_DEG:g}; stops written after the hand: {len(v.frames('stop', since=t))}; "
        f"said {said}"
    )
    assert any("readings in a row at rest do not agree" in m for m in said), said  # (told)
