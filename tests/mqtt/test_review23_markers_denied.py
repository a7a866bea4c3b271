"""A guard: 0785d896 did what is said below, and was reverted (6129c849).

Cold review 23: lastword.py rule 7 since 0785d896. While the main connection cannot read its
markers (the fence topic denied and its hello never back: an ACL on B/bridge/#), a lane halt is
carried out at once and holds nothing. Whatever the main connection then reads for that
rotator is carried out in its order, so what was published before the STOP (or the lock ON)
and is still in the main connection's backlog runs after it: the operator sees the rotor stop
(R/status stopped, R/lock/state ON) and then start again on its own, towards a target older
than the STOP, for as long as the main connection takes to reach its copy of the STOP (the
backlog the lane exists for: seconds). With that copy lost (QoS 0 on both connections, a broker
dropping messages for a reader behind a flood) it is never stopped again, and a lock OFF
published before the lock ON leaves the rotator unlocked under a lock ON the bridge read and
said. The bridge knew of the halt first and still let the older words through.

A simple safer choice exists in this mode (nothing could end a marker-held wait): refuse the
main connection's moves and lock OFF for that rotator until the main connection reads a halt
of that rotator and kind (its copy, by count), bounded by a clock (LONG_HOLD_S, said on
B/bridge/info) so that a lost copy, or a copy read first, holds nothing for ever. A clock
that ends a wait is what rule 5 forbids while a marker can end it; here the choice is between
a bounded wait and none.
"""

from __future__ import annotations

from bridge.core.model import Target
from tests.mqtt.test_service import service


def test_with_markers_denied_a_target_published_before_a_lane_stop_does_not_run_after_it() -> None:
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    svc.markers_denied()  # the fence topic denied, the hello not back (rule 7)
    pub.take()
    # published: target 300 (the main connection behind a backlog has not read it yet), STOP
    svc.on_lane_message("rotor/stop", b"", False)  # the STOP, carried out at once
    tower.calls.clear()
    svc.on_message("rotor/target", b"300", False)  # published before the STOP, read after it
    sent = [c for c in tower.calls if c[0] == "submit" and isinstance(c[1], Target)]
    assert not sent, (
        "with the markers denied, a target published before the lane's STOP went to the "
        f"controller after it (the rotor starts again on its own): {tower.calls}"
    )


def test_with_markers_denied_a_lock_off_published_before_a_lane_lock_on_does_not_unlock() -> None:
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    svc.markers_denied()
    pub.take()
    # published: lock OFF, lock ON (the last word). The lane reads the ON; the main connection
    # reads the OFF, and loses the ON (QoS 0, a reader behind a flood)
    svc.on_lane_message("rotor/lock", b"ON", False)
    tower.calls.clear()
    svc.on_message("rotor/lock", b"OFF", False)
    unlocked = [c for c in tower.calls if c[:2] == ("lock", False)]
    assert not unlocked, (
        "with the markers denied, a lock OFF published before the lane's lock ON unlocked the "
        f"rotator after it: {tower.calls}"
    )
