"""Review 145 (cold review of 1998b9a5): the connections that carry stops keep alive every 2 s
(connection.py rule 6, STOP_KEEPALIVE_S), and paho gives a connection the same keep-alive to be
answered in: the CONNACK of an attempt (TCP and TLS handshakes counted: paho starts the clock
before them), and each PINGRESP. A broker, or a path, that takes 2 s or more to answer keeps
the stop lane, the lock lane and the stop express off for good, silently for the lanes; a STOP
then waits behind whatever the main connection has to read first (the backlog the lanes exist
to go around: lane.py).

Real parts: mosquitto, the bridge in-process, an emulated Rotor-EZ on a pty, a paho client at the
broker's own port as the dashboard, and an MQTT-aware proxy (tests/support/mqtt_proxy.py) on the
bridge's path that slows the broker's answers.

Fixed: the CONNECT says the keep-alive asked for; a stop's carrier pings every 2 s once
accepted (connection.py rule 6, paho_client.py ``ping_within``)."""

from __future__ import annotations

import contextlib
import socket
import threading
import time
from pathlib import Path

from tests.support import Probe
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt_proxy import SUBACK, MqttProxy, _packets, _Stream
from tests.support.rig import Rig
from tests.support.tap import near_deg
from tests.support.waiting import slow, wait_until

CONNACK = 2  # MQTT packet type
TARGET = "300"  # from 10 deg at 2 deg/s: 145 s under way, past every deadline below
SHORT_DEG = 20.0  # a stopped rotor is this far from its target at least
PROMPT_S = 10.0  # a STOP reaches the controller within this (it takes well under a second)


class SlowPath(MqttProxy):
    """The proxy, with the broker's CONNACKs handed on ``accept_s`` late (a broker whose login
    check takes that long, or a path with that much round trip under TCP, TLS and CONNECT), and
    what the broker sends one client id held (``backlog``: its connection has that much to read
    before anything new)."""

    def __init__(self, backend: int, accept_s: float) -> None:
        self.accept_s = accept_s
        self.backlogged: set[str] = set()
        self.released = threading.Event()
        super().__init__(backend)

    def backlog(self, client_id: str) -> None:
        self.backlogged.add(client_id)

    def _down(self, s: _Stream) -> None:
        buf = bytearray()
        with contextlib.suppress(OSError):
            while data := s.server.recv(65536):
                if s.dead:
                    continue
                if s.client_id in self.backlogged:
                    self.released.wait()
                buf += data
                for packet in _packets(buf):
                    if packet[0] >> 4 == CONNACK:
                        time.sleep(self.accept_s)
                    s.client.sendall(packet)
                    if packet[0] >> 4 == SUBACK:
                        self.subacks[s.client_id] = self.subacks.get(s.client_id, 0) + 1
        with contextlib.suppress(OSError):
            s.client.shutdown(socket.SHUT_WR)

    def close(self) -> None:
        self.released.set()
        super().close()


def stop_behind_a_backlog(tmp_path: Path, accept_s: float) -> None:
    """A broker that accepts a connection ``accept_s`` after its CONNECT; the rotor turning, the
    main connection has a backlog to read (held at the proxy) when the operator presses STOP:
    the stop lane carries it, and the rotor stops short of its target within PROMPT_S."""
    broker = Mosquitto(tmp_path / "broker").start()
    proxy = SlowPath(broker.port, accept_s)
    probe = Probe(broker.port, "rotor/#")  # a dashboard on the broker's own port
    try:
        with Rig(tmp_path, proxy, probe) as rig:
            emu = rig.add("tower", "rotorez", emu={"start_az_deg": 10, "speed_deg_s": 2.0})
            app = rig.start()
            rig.ready("tower", timeout_s=slow(30))
            # the lane's time to come up (it does not, after the change: the assertion says)
            with contextlib.suppress(AssertionError, TimeoutError):
                wait_until(app.lane.connected.is_set, slow(15), "the stop lane up")
            probe.publish("rotor/target", TARGET)  # a long turn
            emu.wait_for(lambda s: s.is_moving, slow(10))
            proxy.backlog(rig.settings.mqtt.effective_client_id())  # the main one's reading
            assert probe.publish("rotor/stop", "")  # the operator's STOP, at the broker
            with contextlib.suppress(AssertionError, TimeoutError):
                emu.wait_for(lambda s: not s.is_moving, slow(PROMPT_S))
            s = emu.state()
            assert not s.is_moving and not near_deg(s.az_deg, float(TARGET), SHORT_DEG), (
                f"a STOP pressed while the main connection had a backlog to read, the broker "
                f"accepting connections {accept_s:g} s after their CONNECT, did not stop the "
                f"rotor: it turns on ({s.az_deg:.0f} deg); the stop lane up: "
                f"{app.lane.connected.is_set()}, SUBACKs: {proxy.subacks}"
            )
    finally:
        probe.close()
        proxy.close()
        broker.stop()


def test_a_stop_behind_a_backlog_takes_the_lane_of_a_broker_that_accepts_at_once(
    tmp_path: Path,
) -> None:
    """The control: the same, the broker answering at once."""
    stop_behind_a_backlog(tmp_path, 0.0)


def test_a_stop_behind_a_backlog_takes_the_lane_of_a_broker_slow_to_accept(
    tmp_path: Path,
) -> None:
    stop_behind_a_backlog(tmp_path, 2.5)
