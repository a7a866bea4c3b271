"""Cold review 22: the main connection's copy of a lane halt is "the oldest one the lane read of
that rotator and kind still waiting" (lastword.py rule 9). Both connections take commands at
QoS 0 (lane.py rule 2, client.py rules 1 and 4), so the count can be wrong (a halt lost on the
lane, one lost on the main connection), and a halt the main connection takes for a copy must
still be carried out: not carrying it out (as one change of this stop did) left a rotator
unlocked under the last word published, a lock ON.
"""

from __future__ import annotations

from tests.mqtt.test_service import service


def test_a_lock_on_lost_on_the_lane_is_carried_out_by_the_main_connection() -> None:
    """Published: lock ON 1, then (the console unlocks the rotator, its OFF waiting on the
    hold) lock ON 2, both within the marker's round trip. The lane reads ON 1 and loses ON 2;
    the main connection loses ON 1 (QoS 0 on both, a reader that fell behind) and reads ON 2:
    taken for ON 1's copy, it must still be carried out as a full lock ON."""
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    pub.take()
    svc.on_lane_message("rotor/lock", b"ON", False)  # ON 1, carried out at once, on hold
    tower.calls.clear()
    svc.on_message("rotor/lock", b"ON", False)  # ON 2 (ON 1 lost on this connection)
    assert ("lock", True) in tower.calls, (
        f"a lock ON the lane never read was carried out by neither connection: {tower.calls}"
    )
