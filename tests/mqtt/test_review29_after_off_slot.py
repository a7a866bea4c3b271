"""Cold review 29: halts.py keeps one move behind a lock OFF that waits under a lane hold
(``_after_off``, the newest; lastword.py rule 13), "as the mailbox keeps the newest target".
But ``service._command`` keeps a follow OFF there too, and the mailbox does not let a follow
OFF replace a target (session/mailbox.py ``put_follow``: "following off ends nothing else"):
published lock ON, lock OFF, target, follow off, the target is dropped at the marker without
a word, where read without a hold the same sequence unlocks and turns the rotor to it.
"""

from __future__ import annotations

from bridge.core.model import Target
from tests.mqtt.test_attack5_after_off import LockJudged
from tests.mqtt.test_review22_lost_lane_copy import markers_back
from tests.mqtt.test_service import service


def _sequence(lane_first: bool) -> LockJudged:
    svc, pub, _rots = service({"tower": "rotorez"})
    tower = LockJudged("tower", "rotorez")
    svc.attach(tower)
    pub.take()
    if lane_first:
        svc.on_lane_message("rotor/lock", b"ON", False)  # the lane first: carried, on hold
    svc.on_message("rotor/lock", b"ON", False)  # (its copy, counted, when the lane was first)
    svc.on_message("rotor/lock", b"OFF", False)
    svc.on_message("rotor/target", b"250", False)
    svc.on_message("rotor/follow", b"off", False)  # ends following: nothing else
    markers_back(svc, pub)
    return tower


def _moved(tower: LockJudged) -> list[float]:
    return [c[1].az_deg for c in tower.calls if c[0] == "submit" and isinstance(c[1], Target)]


def test_without_a_hold_the_target_before_a_follow_off_goes() -> None:
    tower = _sequence(lane_first=False)
    assert not tower.locked and _moved(tower) == [250.0], tower.calls


def test_a_follow_off_behind_a_waiting_lock_off_does_not_drop_the_target() -> None:
    tower = _sequence(lane_first=True)
    assert not tower.locked
    assert _moved(tower) == [250.0], f"the target was dropped without a word: {tower.calls}"
