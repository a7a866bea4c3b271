"""Review 121: a stop lane's kept session (interfaces/mqtt/connection.py rule 22) hands its old
copies over past its command SUBACK when there are more of them than the broker keeps in flight.

The lane drops a handed-over copy the main connection already had only while it is read
before the lane's command SUBACK (``_handed_over_had``). mosquitto sends a returning session at
most ``max_inflight_messages`` (20 by default) QoS 1 messages at once and the rest only as
PUBACKs come back; the lane's SUBSCRIBE goes out (in on_connect) ahead of those PUBACKs, so
the broker's SUBACK is read after the first 20 copies and before the others. With the path
dead under the stop lane alone, an operator who pressed STOP more than 20 times (a button
hammered while the rotor coasts, a script that repeats it) and then sent a new target sees the
rotor halt on its way to that target 5-10 s later: the 21st and later copies of the old STOP
are carried out as new. 1 or 18 presses: the target is reached (checked by hand). The lock
lane the same way: 26 lock words toggled while its path is dead, the last an OFF, and an old
ON copy past its SUBACK locks the rotator again (R/lock/state ON after the OFF, the next target
refused; with 2 words, 1f2e23a9's own test, nothing comes back). On a broker set to
``max_inflight_messages 1`` (mosquitto.conf's way to "guarantee in-order delivery") a STOP
pressed twice is enough: the second copy comes after the SUBACK (one press: the target is
reached, checked by hand).

Real mosquitto (its defaults), the test's proxy between it and the bridge (its ``blackhole`` of
the lane's client id), a Rotor-EZ on a real pty; the operator on the broker's own port.
"""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from tests.faults.behind_a_proxy import bridge_behind
from tests.support import Probe
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt_proxy import MqttProxy
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until

BACK_S = 15.0  # a stop carrier given up and made again (5-10 s, and its back-off) within this
AFTER_S = 3.0  # how long after the lane is back its copies have had their say (a quiet period)
NEW_DEG = 60.0  # the target sent after the STOPs
NEAR_DEG = 3.0
PRESSES = 24  # STOPs pressed while the lane's path is dead: more than mosquitto's 20 in flight


@pytest.mark.xfail(
    strict=True,
    reason="review 121: more than 20 STOPs pressed while the stop lane's path was dead, then a "
    "new target: the lane, back, carries out the old STOP copies read after its SUBACK and the "
    "rotor halts short of the newer target",
)
def test_many_stops_handed_over_do_not_stop_the_newer_target(tmp_path: Path) -> None:
    with bridge_behind(tmp_path, MqttProxy) as b:
        lane = b.app.lane.client_id
        before = b.proxy.subacks.get(lane, 0)
        b.probe.publish("rotor/target", "300")
        b.emu.wait_for(lambda s: s.is_moving, slow(10))
        b.proxy.blackhole(lane)  # the stop lane's path dies alone
        for _ in range(PRESSES):  # carried by the main connection, the express
            assert b.probe.publish("rotor/stop", "")
        b.emu.wait_for(lambda s: not s.is_moving, slow(5))
        assert b.probe.publish("rotor/target", f"{NEW_DEG:g}")  # the operator's last word
        b.emu.wait_for(lambda s: s.is_moving, slow(10))
        wait_until(lambda: b.proxy.subacks.get(lane, 0) > before, slow(BACK_S), "the lane back")
        time.sleep(AFTER_S)  # the handed-over copies' moment (a quiet period)
        s = b.emu.state()
        assert s.is_moving or abs(s.az_deg - NEW_DEG) < NEAR_DEG, (
            f"the stop lane came back with {PRESSES} kept copies of the STOP sent before the "
            f"target {NEW_DEG:g}; those past its SUBACK were carried out: the rotor stopped at "
            f"{s.az_deg:.0f} deg, short of it"
        )


WORDS = 13  # lock ON/OFF pairs sent while the lock lane's path is dead: 26 words, past 20
TURN_DEG = 40.0  # the target sent once the lock lane is back (the rotor at 10, 2 deg/s)


@pytest.mark.xfail(
    strict=True,
    reason="review 121: lock ON and OFF toggled 13 times while the lock lane's path was dead, "
    "the last word OFF: the lane, back, carries out an old ON copy read after its SUBACK; "
    "R/lock/state ON again and the next target is refused",
)
def test_many_lock_words_handed_over_do_not_undo_the_last_lock_off(tmp_path: Path) -> None:
    with bridge_behind(tmp_path, MqttProxy) as b:
        lane = b.app.lock_lane.client_id
        before = b.proxy.subacks.get(lane, 0)
        b.proxy.blackhole(lane)  # the lock lane's path dies alone
        start = b.probe.mark()
        for word in ("ON", "OFF") * WORDS:  # the operator's last word: OFF
            assert b.probe.publish("rotor/lock", word)
        b.probe.wait(
            lambda m: m.topic == "rotor/lock/state" and m.text == "OFF",
            what="R/lock/state OFF",
            start=start,
        )
        mark = b.probe.mark()
        wait_until(lambda: b.proxy.subacks.get(lane, 0) > before, slow(BACK_S), "the lane back")
        time.sleep(AFTER_S)  # the handed-over copies' moment (a quiet period)
        shown = [m.text for m in b.probe.messages[mark:] if m.topic == "rotor/lock/state"]
        assert b.probe.publish("rotor/target", f"{TURN_DEG:g}")
        try:
            moved = b.emu.wait_for(lambda s: s.is_moving, slow(5)).is_moving
        except TimeoutError:
            moved = False
        assert not shown and moved, (
            f"the lock lane came back with {2 * WORDS} kept copies of lock words all carried out "
            f"before, the last an OFF; those past its SUBACK were carried out: R/lock/state said "
            f"{shown} after the OFF, and the target {TURN_DEG:g} then turned the rotor: {moved}"
        )


IN_ORDER = "allow_anonymous true\nmax_inflight_messages 1"  # mosquitto.conf: "in-order delivery"


@pytest.mark.xfail(
    strict=True,
    reason="review 121: on a broker set to max_inflight_messages 1, STOP pressed twice while "
    "the stop lane's path was dead, then a new target: the lane, back, carries out the second "
    "old STOP copy (read after its SUBACK) and the rotor halts short of the target",
)
def test_a_double_stop_handed_over_does_not_stop_the_newer_target_in_order_broker(
    tmp_path: Path,
) -> None:
    broker = Mosquitto(tmp_path / "broker", extra_conf=IN_ORDER).start()
    proxy = MqttProxy(broker.port)
    probe = Probe(broker.port, "rotor/#")  # the operator, on the broker's own port
    try:
        with Rig(tmp_path, proxy, probe) as rig:
            rig.express = True
            emu = rig.add("tower", "rotorez", emu={"start_az_deg": 10, "speed_deg_s": 2.0})
            app = rig.start()
            rig.ready("tower")
            wait_until(app.lane.connected.is_set, slow(10), "the stop lane up")
            wait_until(app.express.up.is_set, slow(10), "the stop express up")
            lane = app.lane.client_id
            before = proxy.subacks.get(lane, 0)
            probe.publish("rotor/target", "300")
            emu.wait_for(lambda s: s.is_moving, slow(10))
            proxy.blackhole(lane)  # the stop lane's path dies alone
            for _ in range(2):  # STOP pressed twice (carried by the main connection, express)
                assert probe.publish("rotor/stop", "")
            emu.wait_for(lambda s: not s.is_moving, slow(5))
            assert probe.publish("rotor/target", f"{NEW_DEG:g}")  # the operator's last word
            emu.wait_for(lambda s: s.is_moving, slow(10))
            wait_until(lambda: proxy.subacks.get(lane, 0) > before, slow(BACK_S), "lane back")
            time.sleep(AFTER_S)  # the handed-over copies' moment (a quiet period)
            s = emu.state()
            assert s.is_moving or abs(s.az_deg - NEW_DEG) < NEAR_DEG, (
                f"the stop lane came back with 2 kept copies of the STOP sent before the target "
                f"{NEW_DEG:g} (max_inflight_messages 1: the second read after its SUBACK): the "
                f"rotor stopped at {s.az_deg:.0f} deg, short of it"
            )
    finally:
        probe.close()
        proxy.close()
        broker.stop()
