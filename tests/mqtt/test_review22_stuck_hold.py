"""Cold review 22: a hold nothing can end, and since c2d46de1 every MQTT target refused under it.

lastword.py rule 7: when the broker does not let the main connection read its markers, "a
lane's halt holds until the main connection reads its own copy (rule 9), or drops". Rule 4:
when the lane cannot read *its* markers (``echoes`` False: an ACL denying the bridge's
``B/bridge/#`` to both users), no echo is noted. Rule 4 also says the two connections race
when both are idle: the main connection may read a STOP first. Then the lane's copy, read a
moment later, is carried out again as a new lane halt with a hold, and the only thing that can
end that hold (the main connection's copy) has already been read. No marker, no copy: the
rotator is held until the main connection drops. Before c2d46de1 its targets waited silently;
now every one, published seconds or hours after the STOP, is refused on R/error as "published
before a STOP ... send it again", and sending it again is refused the same way.

lastword.py rule 14 (the bound chosen): while neither connection can read the bridge's markers,
the lane carries out nothing; every stop and lock is carried out from the main connection, in
order. Stops lose the lane's speed, nothing else: no hold, so nothing to end.
"""

from __future__ import annotations

from bridge.core.model import Target
from bridge.interfaces.mqtt.halts import HELD
from tests.mqtt.test_service import service


def test_a_target_long_after_a_stop_is_not_refused_when_the_main_connection_won_the_race() -> None:
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    svc.markers_denied()  # the fence topic denied, the hello not back (rule 7)
    svc.lane_markers_denied()  # the lane's marker topic denied too (rule 4: no echo noted)
    pub.take()
    svc.on_message("rotor/stop", b"", False)  # the operator's STOP: the main connection first
    svc.on_lane_message("rotor/stop", b"", False)  # the lane's copy of it, a moment later
    tower.calls.clear()
    # a minute later, a new target (Home Assistant, Node-RED), and the same again
    svc.on_message("rotor/target", b"120", False)
    svc.on_message("rotor/target", b"120", False)
    refused = [c for c in tower.calls if c[0] == "refused"]
    sent = [c for c in tower.calls if c[0] == "submit" and isinstance(c[1], Target)]
    assert not refused and len(sent) == 2, (
        f"targets published after the STOP refused as older ({HELD!r}): {tower.calls}"
    )


def test_with_markers_denied_to_both_connections_every_halt_comes_from_the_main_one() -> None:
    """Rule 14: the lane's halt is not carried out alone (its copy, or the echo of one already
    carried out, could not be told apart, and its hold never ended); the main connection's
    copy of it, in order, stops the rotor and drops the target published before it."""
    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    svc.markers_denied()
    svc.lane_markers_denied()
    pub.take()
    svc.on_lane_message("rotor/stop", b"", False)  # the lane reads it first: nothing
    svc.on_lane_message("rotor/lock", b"ON", False)
    assert tower.calls == []
    svc.on_message("rotor/target", b"300", False)  # published before the STOP
    svc.on_message("rotor/stop", b"", False)  # the STOP, in order: drops it
    svc.on_message("rotor/lock", b"ON", False)
    svc.on_message("rotor/target", b"120", False)  # after the lock ON: the judge refuses it
    kinds = [c[0] if not isinstance(c[1], Target) else "target" for c in tower.calls]
    assert kinds == ["target", "submit", "lock", "target"], tower.calls
    assert not [c for c in tower.calls if c[0] == "refused"]
