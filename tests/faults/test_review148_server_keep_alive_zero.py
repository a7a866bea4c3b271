"""Review 148 (cold review of 1998b9a5 and 1d44d710): a stop's carrier, once accepted, takes
the keep-alive paho now holds down to 2 s (paho_client.py ``ping_within``: the smaller of the
two). Under MQTT 5 paho holds the broker's Server Keep Alive there when the CONNACK has one
(MQTT 5, 3.2.2.3.14: the client MUST use it), and 0 is a value a broker may send (keep-alive
off: moquette's ``server_keep_alive``, a broker that wants no pings). The smaller of 0 and 2 is
0: paho then never pings, the stop lane, the lock lane and the stop express never find a dead
path, and connection.py rule 6's STOP_DEAD_PATH_S does not hold (attack 32's 30-60 s became
for ever).

Real parts: mosquitto, the bridge in-process, an emulated Rotor-EZ (with its stop express) on a
pty, a paho client at the broker's own port as the dashboard, and the MQTT-aware proxy on the
bridge's path, which adds a Server Keep Alive of 0 to every MQTT 5 CONNACK it hands on (the
broker's word) and then turns the path dead (``blackhole``).

Fixed: paho_client.py ``ping_within`` pings under a Server Keep Alive of 0 too."""

from __future__ import annotations

import contextlib
import time
from pathlib import Path

from bridge.interfaces.mqtt.connection import STOP_DEAD_PATH_S
from tests.support import Probe
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt_proxy import MqttProxy, _Stream
from tests.support.rig import Rig
from tests.support.tap import near_deg
from tests.support.waiting import slow, wait_until

CONNACK = 2  # MQTT packet type
SERVER_KEEP_ALIVE = b"\x13\x00\x00"  # MQTT 5 property 0x13, two bytes: 0 (keep-alive off)
TARGET = "300"  # from 10 deg at 2 deg/s: 145 s under way, past every deadline below
SHORT_DEG = 20.0  # a stopped rotor is this far from its target at least
PROMPT_S = 10.0  # a STOP reaches the controller within this (it takes well under a second)


def _varint(n: int) -> bytes:
    out = bytearray()
    while True:
        b, n = n & 0x7F, n >> 7
        out.append(b | (0x80 if n else 0))
        if not n:
            return bytes(out)


def _with_keep_alive_off(connack: bytes) -> bytes:
    """An MQTT 5 CONNACK with a Server Keep Alive of 0 added (a 3.1.1 one as it came)."""
    i = 1
    while connack[i] & 0x80:
        i += 1
    body = connack[i + 1 :]
    if len(body) <= 2:  # MQTT 3.1.1: no properties
        return connack
    j, size, shift = 2, 0, 0
    while True:
        b = body[j]
        size |= (b & 0x7F) << shift
        shift += 7
        j += 1
        if not b & 0x80:
            break
    props = body[j : j + size] + SERVER_KEEP_ALIVE
    new_body = body[:2] + _varint(len(props)) + props + body[j + size :]
    return bytes([connack[0]]) + _varint(len(new_body)) + new_body


class KeepAliveOff(MqttProxy):
    """The proxy, the broker saying "keep-alive off" in every MQTT 5 CONNACK."""

    def on_packet(self, s: _Stream, packet: bytes, *, up: bool) -> bytes | None:
        if not up and packet[0] >> 4 == CONNACK:
            return _with_keep_alive_off(packet)
        return packet


def test_a_stop_after_a_dead_path_under_a_broker_that_turns_keep_alive_off(
    tmp_path: Path,
) -> None:
    broker = Mosquitto(tmp_path / "broker").start()
    proxy = KeepAliveOff(broker.port)
    probe = Probe(broker.port, "rotor/#")  # a dashboard on the broker's own port
    try:
        with Rig(tmp_path, proxy, probe) as rig:
            rig.express = True
            emu = rig.add("tower", "rotorez", emu={"start_az_deg": 10, "speed_deg_s": 2.0})
            app = rig.start()
            rig.ready("tower", timeout_s=slow(30))
            wait_until(app.lane.connected.is_set, slow(10), "the stop lane up")
            wait_until(app.express.up.is_set, slow(10), "the stop express up")
            probe.publish("rotor/target", TARGET)  # a long turn
            emu.wait_for(lambda s: s.is_moving, slow(10))
            proxy.blackhole()  # the path under all the bridge's connections dies without a word
            # the user's hand: the scenario's timing (attack 32's), not a wait for the bridge
            time.sleep(STOP_DEAD_PATH_S + 1.0)
            assert emu.state().is_moving
            assert probe.publish("rotor/stop", "")  # the operator's STOP, at the broker
            with contextlib.suppress(AssertionError, TimeoutError):
                emu.wait_for(lambda s: not s.is_moving, slow(PROMPT_S))
            s = emu.state()
            assert not s.is_moving and not near_deg(s.az_deg, float(TARGET), SHORT_DEG), (
                f"a STOP pressed {STOP_DEAD_PATH_S + 1.0:g} s after the path died, the broker "
                f"saying Server Keep Alive 0, did not stop the rotor: it turns on "
                f"({s.az_deg:.0f} deg); the stop lane up: {app.lane.connected.is_set()}"
            )
    finally:
        probe.close()
        proxy.close()
        broker.stop()
