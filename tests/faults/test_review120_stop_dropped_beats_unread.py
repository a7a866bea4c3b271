"""Review 120: connection.py rule 22 drops a stop lane's handed-over copy when the main
connection "had it": its command topics without a break since the lane's previous connection
and ``broker_late()`` None, "so its own path is alive". But ``broker_late`` is None also when
no beat of the main connection ever came back (client.py rule 19: an ACL that denies the bridge
its heartbeat topic, a set-up the bridge supports and says once). On such a broker the main
connection is never late, so attack 32's own case (the path dead under every connection, a STOP
pressed 3 s after) has the stop lane come back with its session's copy of the STOP and drop it:
the main connection never read it (its path dead too, its keep-alive 30 s, its session clean),
and the rotor turns on to its target, as before attack 32's fix.

A Rot2Prog (no stop express), real mosquitto with an ACL file denying the heartbeat topic, the
test's proxy (tests/support/mqtt_proxy.py ``blackhole``) between it and the bridge; the operator
on the broker's own port.
"""

from __future__ import annotations

import contextlib
import time
from pathlib import Path

from bridge.interfaces.mqtt.connection import STOP_RECONNECT_MAX_S
from tests.support import Probe
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt_proxy import MqttProxy
from tests.support.rig import Rig
from tests.support.tap import near_deg
from tests.support.waiting import slow, wait_until

BEAT = "rotor/bridge/heartbeat"
KEEPALIVE_S = 30  # the bridge's default keep-alive (the main connection's)
TARGET = "190 0"  # a slow turn: 180 s at 1 deg/s, under way past every deadline below
PRESSED_S = STOP_RECONNECT_MAX_S + 1.0  # the STOP pressed this long after the path died
BACK_S = 15.0  # a stop lane gives its dead path up and is back within this (5-10 s, back-off)
PROMPT_S = 12.0  # the promise: a STOP after a path died reaches the rotor within ~12 s
SHORT_DEG = 20.0


def test_a_stop_after_the_path_died_reaches_the_rotor_when_the_beats_are_denied(
    tmp_path: Path,
) -> None:
    acl = tmp_path / "acl"
    acl.write_text(f"topic readwrite rotor/#\ntopic deny {BEAT}\n")
    # started as root, mosquitto would become user "mosquitto", who cannot read pytest's tmp
    broker = Mosquitto(
        tmp_path / "broker", extra_conf=f"allow_anonymous true\nacl_file {acl}\nuser root"
    ).start()
    proxy = MqttProxy(broker.port)
    probe = Probe(broker.port, "rotor/#")  # the operator, on the broker's own port
    try:
        with Rig(tmp_path, proxy, probe) as rig:
            rig.mqtt_extra = {"keepalive_s": KEEPALIVE_S}
            emu = rig.add("tower", "rot2prog", emu={"start_az_deg": 10, "az_speed_deg_s": 1.0})
            app = rig.start()
            rig.ready("tower")
            wait_until(app.lane.connected.is_set, slow(10), "the stop lane up")
            lane = app.lane.client_id
            before = proxy.subacks.get(lane, 0)
            probe.publish("rotor/target", TARGET)
            emu.wait_for(lambda s: s.is_moving, slow(10))
            proxy.blackhole()  # the path under every connection dies without a word
            # the user's hand: the scenario's timing (attack 32's), not a wait for the bridge
            time.sleep(PRESSED_S)
            assert app.client.broker_late() is None  # the beats never came back: never late
            assert probe.publish("rotor/stop", "")  # QoS 1: the lane's session keeps it
            wait_until(lambda: proxy.subacks.get(lane, 0) > before, slow(BACK_S), "lane back")
            with contextlib.suppress(AssertionError, TimeoutError):
                emu.wait_for(lambda s: not s.is_moving, slow(PROMPT_S))
            s = emu.state()
            assert not s.is_moving and not near_deg(s.az_deg, 190.0, SHORT_DEG), (
                f"a STOP pressed {PRESSED_S:g} s after the path died, on a broker that denies "
                f"the heartbeat topic, was handed over to the stop lane and dropped as a copy "
                f"the main connection had: the rotor turns on ({s.az_deg:.0f} deg); main "
                f"connection up: {app.client.connected.is_set()}"
            )
    finally:
        probe.close()
        proxy.close()
        broker.stop()
