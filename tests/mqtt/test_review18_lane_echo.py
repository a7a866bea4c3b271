"""Cold review 18: lastword.py rule 4 against rule 9.

Rule 9 knows that, once the lane's subscription is acknowledged, the main connection may still
read halts published *before* that subscription (it is behind: a backlog) until the marker sent
at the SUBACK comes back, and refuses to take such a halt for the copy of a lane halt. Rule 4's
note ("the lane's copy, if the lane has one, comes before the lane marker") asks only whether
the SUBACK came (``_lane_sub == NOT_YET``). A halt the main connection reads from before the
lane's subscription therefore notes an echo the lane will never read, and the lane's next real
STOP for that rotator (published before the lane marker is back) is dropped as that echo: it is
left to the main connection, behind the very backlog the lane exists to bypass.
"""

from __future__ import annotations

from bridge.interfaces.mqtt.lastword import LastWord


def test_a_halt_from_before_the_lanes_subscription_notes_no_echo_that_eats_a_new_lane_stop() -> (
    None
):
    w = LastWord(token="t")
    w.lane_connected()  # the lane alone reconnected (the main connection stays up, behind)
    sync = w.lane_subscribed(0.0)  # its SUBACK: a marker goes out on the main connection
    assert sync is not None
    # the main connection, still reading its backlog, reads a STOP published while the lane
    # was down (the lane will never have a copy of it); the marker ``sync`` is not back yet
    w.main_halt("a", "stop")  # (carried out, in order: rule 1)
    # the operator's new STOP, read on the lane a moment later: carried out at once
    assert w.lane_halt("a", "stop", 0.5) is not None, "the lane's new STOP was dropped as an echo"


def test_the_lanes_new_stop_after_it_reconnected_is_carried_out_at_once_through_the_service() -> (
    None
):
    """The same through the service (service.py rule 5, halts.py): the lane reconnects while
    the main connection reads a backlog; the main connection reads a STOP published while the
    lane was down; the operator's next STOP comes on the lane and must be carried out at once
    (with its hold), not left to the main connection behind its backlog."""
    from bridge.core.model import Source, Stop
    from tests.mqtt.test_service import service

    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    svc.lane_connected()
    svc.lane_subscribed()  # its SUBACK (its marker goes out on the main connection)
    pub.take()
    svc.on_message("rotor/stop", b"", False)  # from before the lane's subscription, read late
    tower.calls.clear()
    svc.on_lane_message("rotor/stop", b"", False)  # the operator's new STOP, on the lane
    assert [c for c in tower.calls if c[0] == "submit"] == [
        ("submit", Stop(Source.MQTT), "stop", 2)
    ], tower.calls
