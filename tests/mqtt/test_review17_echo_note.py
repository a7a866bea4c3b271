"""Cold review 17: rule 4's echo note against a lane subscription the main connection has not
read past yet (lastword.py rules 4 and 9)."""

from __future__ import annotations

from bridge.interfaces.mqtt.lastword import LastWord


def test_a_halt_main_reads_before_passing_the_lanes_subscription_makes_no_echo_note() -> None:
    """The lane reconnects while the main connection reads a backlog. STOP#1 was published
    before the broker took the lane's new SUBSCRIBE, so the lane will never get a copy of it;
    the lane's SUBACK comes (lane_subscribed: its marker goes out on the main connection, not
    back yet). The main connection then reads STOP#1: nothing says the lane will get a copy of
    it (rule 9 reasons exactly so and counts no copy until the main connection passed that
    marker), yet rule 4 notes an echo. The operator's STOP#2, read by the (idle) lane right
    after, is taken for that echo and not carried out on the lane: it waits for the main
    connection to read through its backlog (rule 4's own words: "the lane's next real stop of
    that kind, taken for the echo, then waited for the main connection's copy, behind whatever
    it is reading")."""
    w = LastWord(token="t")
    w.lane_connected()
    w.lane_subscribed(0.0)  # its marker is out; the main connection has not read past it
    w.main_halt("a", "stop")  # STOP#1, maybe published before the lane subscribed
    second = w.lane_halt("a", "stop", 0.1)  # STOP#2 on the lane: a real, newer stop
    assert second is not None, "the lane's real STOP was dropped as the echo of an older one"


def test_the_lanes_stop_after_its_resubscribe_is_carried_out_through_the_service() -> None:
    """The same through the MQTT service: after the lane's new subscription is acknowledged
    (its marker out on the main connection, not read back), the main connection reads a STOP
    that may predate that subscription, then the lane reads an operator's new STOP. The lane's
    STOP must reach the rotator at once (with its hold); it is dropped as an echo."""
    from tests.mqtt.test_service import service

    svc, pub, rots = service({"tower": "rotorez"})
    tower = rots["tower"]
    svc.lane_connected()
    svc.lane_subscribed()
    pub.take()
    svc.on_message("rotor/stop", b"", False)  # STOP#1, read late from a backlog
    pub.take()
    svc.on_lane_message("rotor/stop", b"", False)  # STOP#2, new: never on the lane before
    stops = [c for c in tower.calls if c[0] == "submit" and c[2] == "stop"]
    assert len(stops) == 2, tower.calls
