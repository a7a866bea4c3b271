"""Attack pass 6 on lastword.py rule 3: "A lock OFF from the lane is not carried out (it comes
in order on the main connection, rule 1), except while the main connection is down: then the
lane's word is the only one". It is the only one only if the lane is not behind the main
connection. The two connections read at their own pace (lastword.py's opening comment): a
neighbour who floods the stop topics (anyone may publish a STOP) keeps the lane busy, each
halt carried out with a marker, while the main connection, idle, reads ahead of it.

Published, in order: lock OFF, then lock ON (a climber is about to go up). The main connection
reads both and carries both out: the rotator is locked, R/lock/state says ON. Then the main
connection drops (a broker keepalive, a network blip, a neighbour's connect with its client
id). The lane, behind, now reads the OFF: carried out, as the only word, the rotator unlocked
under a climber. Its copy of the ON that follows is taken for the echo of the one the main
connection carried out first (rule 4's note, which a main connection's drop does not end) and
dropped: the rotator stays unlocked, although the last word published was ON.
"""

from __future__ import annotations

from tests.mqtt.test_review22_lost_lane_copy import controller, markers_back
from tests.mqtt.test_service import service


def test_a_lane_behind_the_main_connection_does_not_unlock_after_the_newer_lock_on() -> None:
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    pub.take()
    svc.lane_connected()  # the lane up and in step (lastword.py rule 9)
    svc.lane_subscribed()
    markers_back(svc, pub)
    svc.on_message("rotor/lock", b"OFF", False)  # the main connection, ahead of the lane
    svc.on_message("rotor/lock", b"ON", False)  # the last word: carried out, locked
    assert controller(tower.calls)[1] is True
    pub.up = pub.hears = False  # the main connection drops
    svc.main_gone()
    svc.on_lane_message("rotor/lock", b"OFF", False)  # the lane, behind: the older OFF
    unlocked_meanwhile = controller(tower.calls)[1] is False
    svc.on_lane_message("rotor/lock", b"ON", False)  # its copy of the ON
    _reached, locked = controller(tower.calls)
    assert not unlocked_meanwhile and locked is True, (
        "the lock OFF published before the lock ON unlocked the rotator after the main "
        f"connection had carried out that ON (locked at the end: {locked}): {tower.calls}"
    )
