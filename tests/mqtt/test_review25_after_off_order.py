"""COLD REVIEW 25 (f68d30a8), finding R25-2: FAILS at f68d30a8.

halts.py ``after_off`` (lastword.py rule 13, f68d30a8): a move the main connection reads after
a lock OFF that waits under a lane hold is kept in halts.py, to run after that OFF when the
marker comes back. Only what ``turns_rotor`` calls a move is kept (service.py ``_command``:
``since`` is None for the rest); a tracking OFF or a following OFF is no move, so it is handed
on at once, *before* the start read ahead of it. When the marker comes back the kept start
runs, after the OFF: the order the user published is inverted, and the rotor tracks the sun
(follows the QSO) although the last word on that topic was "off". Published, in order, within
one marker round trip (a script, or a user who changes their mind): lock ON (the lane carries
it out first), lock OFF, track sun, track off. Expected: not tracking. Got: tracking.
"""

from __future__ import annotations

from tests.mqtt.test_review22_lost_lane_copy import markers_back
from tests.mqtt.test_service import service


def _last(calls: list[tuple[object, ...]], kind: str) -> tuple[object, ...]:
    return [c for c in calls if c[0] == kind][-1]


def test_r25_2_track_off_after_track_start_behind_a_waiting_lock_off_stays_off() -> None:
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    tower.can_track = True
    pub.take()
    svc.on_lane_message("rotor/lock", b"ON", False)  # the lane first: carried out, on hold
    svc.on_message("rotor/lock", b"ON", False)  # its copy on the main connection
    svc.on_message("rotor/lock", b"OFF", False)  # waits for the marker (rule 13)
    svc.on_message("rotor/track", b"sun", False)  # kept behind the OFF
    svc.on_message("rotor/track", b"off", False)  # the last word on tracking
    markers_back(svc, pub)
    last = _last(tower.calls, "track")
    assert last[1] == "off", (
        "track sun then track off, published in that order after a lock OFF: the rotator "
        f"was left tracking the sun (the OFF went first, the start after it): {tower.calls}"
    )


def test_r25_2_follow_off_after_follow_on_behind_a_waiting_lock_off_stays_off() -> None:
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    tower.can_follow = True
    pub.take()
    svc.on_lane_message("rotor/lock", b"ON", False)
    svc.on_message("rotor/lock", b"ON", False)
    svc.on_message("rotor/lock", b"OFF", False)
    svc.on_message("rotor/follow", b"wsjtx", False)
    svc.on_message("rotor/follow", b"off", False)  # the last word on following
    markers_back(svc, pub)
    last = _last(tower.calls, "follow")
    assert last[1] is False, (
        "follow wsjtx then follow off, published in that order after a lock OFF: the "
        f"rotator was left following (the OFF went first, the start after it): {tower.calls}"
    )
