"""Review 120: connection.py rule 22's drop reads ``broker_late() is None`` as "the main
connection's path is alive", but ``broker_late`` is None on every new main connection until one
of its own beats has come back (client.py rule 19, heartbeat.py ``Echo.connected``): a main
connection whose path died right after its SUBACK (a link that flaps: re-made, then gone again
without a word) is never late, for its whole keep-alive (30 to 60 s). A stop lane accepted after
that SUBACK, its own path dead too, comes back with its kept session's copy of a STOP the main
connection never read, and drops it: the rotor turns on to its target. No ACL is needed (the
ACL case: test_review120_stop_dropped_beats_unread.py).

A Rot2Prog (no stop express), real mosquitto, the test's proxy (tests/support/mqtt_proxy.py)
with one more fault: a connection that goes dead right after the broker's first SUBACK to it;
the operator on the broker's own port.
"""

from __future__ import annotations

import contextlib
import socket
from pathlib import Path

from tests.support import Probe
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt_proxy import SUBACK, MqttProxy, _packets, _Stream
from tests.support.rig import Rig
from tests.support.tap import near_deg
from tests.support.waiting import slow, wait_until

KEEPALIVE_S = 30  # the bridge's default keep-alive (the main connection's)
TARGET = "190 0"  # a slow turn: 180 s at 1 deg/s, under way past every deadline below
BACK_S = 15.0  # a connection dropped or given up comes back within this
PROMPT_S = 12.0  # the promise: a STOP after a path died reaches the rotor within ~12 s
SHORT_DEG = 20.0


class Flapping(MqttProxy):
    """The proxy; a client id's next connection goes dead right after its first SUBACK."""

    def __init__(self, backend: int) -> None:
        super().__init__(backend)
        self.dies: set[str] = set()

    def _down(self, s: _Stream) -> None:
        buf = bytearray()
        with contextlib.suppress(OSError):
            while data := s.server.recv(65536):
                if s.dead:
                    continue
                buf += data
                for packet in _packets(buf):
                    s.client.sendall(packet)
                    if packet[0] >> 4 == SUBACK:
                        self.subacks[s.client_id] = self.subacks.get(s.client_id, 0) + 1
                        if s.client_id in self.dies:
                            self.dies.discard(s.client_id)
                            s.dead = True  # the path gone right after its SUBACK
                            break
        with contextlib.suppress(OSError):
            s.client.shutdown(socket.SHUT_WR)


def test_a_stop_is_not_dropped_for_a_main_connection_that_never_heard_a_beat(
    tmp_path: Path,
) -> None:
    broker = Mosquitto(tmp_path / "broker").start()
    proxy = Flapping(broker.port)
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
            probe.publish("rotor/target", TARGET)
            emu.wait_for(lambda s: s.is_moving, slow(10))
            # the link flaps: the main connection is re-made, and its new path dies at once
            subscribed = app.client.subscribed_since
            proxy.dies.add(main)
            proxy.drop(main)
            wait_until(
                lambda: app.client.subscribed_since not in (None, subscribed),
                slow(BACK_S),
                "the main connection subscribed again",
            )
            assert main not in proxy.dies  # its path dead since its SUBACK
            # the stop lane is re-made after it, and its path dies too
            count = proxy.subacks.get(lane, 0)
            proxy.drop(lane)
            wait_until(lambda: proxy.subacks.get(lane, 0) > count, slow(BACK_S), "lane back")
            proxy.blackhole(lane)
            assert app.client.broker_late() is None  # no beat back: never late
            assert probe.publish("rotor/stop", "")  # QoS 1: the lane's session keeps it
            count = proxy.subacks.get(lane, 0)
            wait_until(lambda: proxy.subacks.get(lane, 0) > count, slow(BACK_S), "lane back")
            with contextlib.suppress(AssertionError, TimeoutError):
                emu.wait_for(lambda s: not s.is_moving, slow(PROMPT_S))
            s = emu.state()
            assert not s.is_moving and not near_deg(s.az_deg, 190.0, SHORT_DEG), (
                f"a STOP pressed after the paths died, the main connection's right after its "
                f"SUBACK (no beat of it back: never late), was dropped by the stop lane as a "
                f"copy the main connection had: the rotor turns on ({s.az_deg:.0f} deg)"
            )
    finally:
        probe.close()
        proxy.close()
        broker.stop()
