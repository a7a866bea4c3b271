"""COLD REVIEW 25 (f68d30a8), finding R25-4 (Low): FAILS at f68d30a8.

A lock OFF that waits under a lane hold (lastword.py rule 13) and is then superseded by a
lock ON the *main* connection reads after it (published after it: the user's own later word)
is reported on R/error with LOCK_OFF_OLDER: "lock OFF not carried out: a lock ON that may have
been published after it came on the stop connection; the lock stays ON (make sure nobody is
working on the tower before unlocking)". That lock ON did not come on the stop connection, and
it certainly was published after the OFF; with no hold up the same OFF then ON is carried out
in order and nothing is said. The user who toggled OFF then ON (a script, a double click)
reads a refusal and a tower warning for a sequence that did what they asked.
"""

from __future__ import annotations

from bridge.interfaces.mqtt.halts import LOCK_OFF_OLDER
from tests.mqtt.test_review22_lost_lane_copy import controller, markers_back
from tests.mqtt.test_service import service


def test_r25_4_a_waiting_lock_off_superseded_by_a_later_main_lock_on_is_not_refused() -> None:
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    pub.take()
    svc.on_lane_message("rotor/stop", b"", False)  # a STOP, the lane first: on hold
    svc.on_message("rotor/stop", b"", False)  # its copy
    svc.on_message("rotor/lock", b"OFF", False)  # waits for the marker (rule 13)
    svc.on_message("rotor/lock", b"ON", False)  # the user's later word, on the main connection
    markers_back(svc, pub)
    assert controller(tower.calls)[1] is True  # (the outcome is right: ON)
    said = [c for c in tower.calls if c[0] == "refused"]
    assert ("refused", LOCK_OFF_OLDER, "lock OFF") not in said, (
        "lock OFF then lock ON, both on the main connection, in order: the OFF was reported "
        f"as refused because of a lock ON 'on the stop connection': {said}"
    )
