"""Review 120: connection.py rule 22 drops a stop lane's handed-over copy when the main
connection "had it" (its command topics without a break since the lane's previous connection
was accepted, and ``broker_late`` None). Neither says the main connection's *path* carried the
word: a path that died under the main connection moments before the lane comes back leaves it
subscribed and not yet late (a beat must be out through 3 s of quiet), so the lane's copy of a
STOP pressed in between, which the main connection never read, is dropped. The main connection
notices its own dead path only at its keep-alive (30 s here) and comes back clean: the STOP is
lost, and the rotor turns on to its target.

A Rot2Prog (no stop express: the stop lane is its only stop carrier besides the main
connection), real mosquitto, the test's proxy (tests/support/mqtt_proxy.py ``blackhole``)
between it and the bridge; the operator on the broker's own port.
"""

from __future__ import annotations

import contextlib
from pathlib import Path

from tests.faults.behind_a_proxy import bridge_behind
from tests.support import Probe
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt_proxy import MqttProxy
from tests.support.rig import Rig
from tests.support.tap import near_deg
from tests.support.waiting import slow, wait_until

KEEPALIVE_S = 30  # the bridge's default keep-alive (the main connection's)
TARGET = "190 0"  # a slow turn: 180 s at 1 deg/s, under way past every deadline below
GONE_S = 15.0  # a stop lane gives its dead path up within this (5-10 s)
PROMPT_S = 12.0  # the promise: a STOP after a path died reaches the rotor within ~12 s
SHORT_DEG = 20.0


def test_a_stop_the_main_connection_never_read_is_not_dropped_as_its_copy(
    tmp_path: Path,
) -> None:
    broker = Mosquitto(tmp_path / "broker").start()
    proxy = MqttProxy(broker.port)
    probe = Probe(broker.port, "rotor/#")  # the operator, on the broker's own port
    try:
        with Rig(tmp_path, proxy, probe) as rig:
            rig.mqtt_extra = {"keepalive_s": KEEPALIVE_S}
            emu = rig.add("tower", "rot2prog", emu={"start_az_deg": 10, "az_speed_deg_s": 1.0})
            app = rig.start()
            rig.ready("tower")
            wait_until(app.lane.connected.is_set, slow(10), "the stop lane up")
            main = rig.settings.mqtt.effective_client_id()
            lane = app.lane.client_id
            before = proxy.subacks.get(lane, 0)
            probe.publish("rotor/target", TARGET)
            emu.wait_for(lambda s: s.is_moving, slow(10))
            proxy.blackhole(lane)  # the stop lane's path dies alone
            wait_until(lambda: not app.lane.connected.is_set(), slow(GONE_S), "the lane gone")
            # it connects again a second later, with its session; meanwhile the main
            # connection's path dies too (a link re-made), and the operator presses STOP
            proxy.blackhole(main)
            assert probe.publish("rotor/stop", "")  # QoS 1: the lane's session keeps it
            wait_until(lambda: proxy.subacks.get(lane, 0) > before, slow(GONE_S), "lane back")
            with contextlib.suppress(AssertionError, TimeoutError):
                emu.wait_for(lambda s: not s.is_moving, slow(PROMPT_S))
            s = emu.state()
            assert not s.is_moving and not near_deg(s.az_deg, 190.0, SHORT_DEG), (
                f"a STOP pressed while the stop lane was away, the main connection's path dead "
                f"a moment, was held in the lane's session and handed over, and dropped as a "
                f"copy the main connection had: the rotor turns on ({s.az_deg:.0f} deg); main "
                f"connection up: {app.client.connected.is_set()}"
            )
    finally:
        probe.close()
        proxy.close()
        broker.stop()


def test_a_lock_on_the_main_connection_never_read_is_not_dropped_as_its_copy(
    tmp_path: Path,
) -> None:
    """The same drop, the default set-up (a Rotor-EZ with its stop express, its path alive):
    the express writes the lock ON's stop frame but leaves the lock to the main connection,
    subscribed and vouched for (app.py ``_heard_only_by_express``), whose path is dead; the
    lock lane drops its handed-over copy as one the main connection had. The rotator is
    stopped and never locked (the bridge's own status: its R/lock/state goes out on the
    main connection, whose path is dead), and the next target from any front end turns it
    while someone is on the tower."""
    with bridge_behind(tmp_path, MqttProxy) as b:
        main = b.rig.settings.mqtt.effective_client_id()
        lane = b.app.lock_lane.client_id
        before = b.proxy.subacks.get(lane, 0)
        b.proxy.blackhole(lane)  # the lock lane's path dies alone
        wait_until(lambda: not b.app.lock_lane.connected.is_set(), slow(GONE_S), "lane gone")
        b.proxy.blackhole(main)  # ... and a moment later the main connection's
        assert b.probe.publish("rotor/lock", "ON")  # QoS 1: the lock lane's session keeps it
        wait_until(lambda: b.proxy.subacks.get(lane, 0) > before, slow(GONE_S), "lane back")
        with contextlib.suppress(AssertionError, TimeoutError):
            wait_until(lambda: b.rig.status("tower").locked, slow(PROMPT_S), "the lock ON")
        assert b.rig.status("tower").locked, (
            "a lock ON pressed while the lock lane was away, the main connection's path dead "
            "a moment, was handed over to the lane and dropped as a copy the main connection "
            "had; the stop express stopped the rotor but left the lock to the main connection: "
            f"the rotator is not locked (the emulator moving: {b.emu.state().is_moving})"
        )
