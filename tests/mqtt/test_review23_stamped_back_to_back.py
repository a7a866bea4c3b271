"""A guard: 0785d896 did what is said below, and was reverted (6129c849).

Cold review 23: the remote (``rotor-bridge remote``, remote.py) publishes every command
stamped with its send time (heartbeat.py rule 4); a hamlib client behind it (a logger, a
rotator panel) sends ``S`` then ``P`` back to back, so the station reads a STOP stamped t and
a target stamped t + 5 ms from the same sender. Since 0785d896 the lane's hold ends by its
marker alone and the target, read on the main connection before the marker, is refused as
"published before a STOP ... (or not known to be after it)". Its stamp says it was sent after
the STOP, by the sender of the STOP: it is known to be after it, and the bridge already reads
that stamp (service.py rule 9) to refuse the commands sent *before* a halt. The hamlib
client gets RPRT 0 for its P from the remote and the rotor does not turn.
"""

from __future__ import annotations

from bridge.core.model import Target
from bridge.interfaces.mqtt.heartbeat import Stamp
from tests.mqtt.test_service import NOW_UNIX, service


def test_a_target_stamped_after_the_lanes_stop_by_its_sender_is_carried_out() -> None:
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    pub.take()
    stop, target = Stamp.of(NOW_UNIX - 0.010, 5), Stamp.of(NOW_UNIX - 0.005, 5)
    svc.on_lane_message("rotor/stop", b"", False, stamp=stop)  # S, carried out at once
    svc.on_message("rotor/stop", b"", False, stamp=stop)  # its copy on the main connection
    svc.on_message("rotor/target", b"100", False, stamp=target)  # P, sent 5 ms after S
    sent = [c for c in tower.calls if c[0] == "submit" and isinstance(c[1], Target)]
    assert sent, f"a target stamped after the STOP by its sender was refused: {tower.calls}"
