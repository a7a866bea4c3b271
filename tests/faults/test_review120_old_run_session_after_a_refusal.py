"""Review 120: connection.py rule 22 promises a stop carrier "a clean start at its first connect
only (paho's MQTT_CLEAN_START_FIRST_ONLY: nothing of an earlier run is handed to it)". paho
2.2 ends its "first connect" at the first CONNACK it reads, a refusal too
(``_handle_connack``: ``_mqttv5_first_connect = False`` before the reason code is looked at).
A broker that refuses a lane's first attempt for a moment (a connection-rate limit, 0x9F, or a
quota, 0x97: the bridge opens four connections at once at its start) has the lane's next
attempt go out with ``clean_start`` false, and the session the previous run of the bridge left
(its expiry 30 s) is handed over: what was published on the lock or stop topics while the
bridge was down comes back at its start, and, the lane's first connection having no previous
one (``_handed_from`` None), nothing drops it. A lock ON published while the bridge was
restarting locks the rotator at the next run's start.

Real mosquitto behind the test's proxy, which plays the refusing broker once (a CONNACK with
0x9F to the lock lane's first CONNECT of the second run, as a broker's rate limit sends);
a Rotor-EZ on a real pty; the operator on the broker's own port.
"""

from __future__ import annotations

import contextlib
import socket
from pathlib import Path

from tests.support import Probe
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt_proxy import MqttProxy, _client_id, _packets, _Stream
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until

CONNECT = 1
RATE_EXCEEDED = bytes([0x20, 0x03, 0x00, 0x9F, 0x00])  # MQTT 5 CONNACK: connection rate
BACK_S = 15.0  # the lane refused once and connected again within this (its back-off: 2 s)
SHOWN_S = 5.0  # a lock word carried out is in the bridge's status within this


class RefusingOnce(MqttProxy):
    """The proxy, refusing one client id's next CONNECT itself, as a rate-limiting broker."""

    def __init__(self, backend: int) -> None:
        super().__init__(backend)
        self.refuse: str | None = None
        self.refused = 0

    def _up(self, s: _Stream) -> None:
        buf = bytearray()
        with contextlib.suppress(OSError):
            while data := s.client.recv(65536):
                buf += data
                for packet in _packets(buf):
                    if packet[0] >> 4 == CONNECT:
                        s.client_id = _client_id(packet)
                        if s.client_id == self.refuse:
                            self.refuse = None
                            self.refused += 1
                            s.client.sendall(RATE_EXCEEDED)
                            s.client.shutdown(socket.SHUT_RDWR)
                            s.server.close()
                            return
                    s.server.sendall(packet)
        with contextlib.suppress(OSError):
            s.server.shutdown(socket.SHUT_WR)


def test_nothing_of_the_previous_run_comes_back_after_a_refused_first_connect(
    tmp_path: Path,
) -> None:
    broker = Mosquitto(tmp_path / "broker").start()
    proxy = RefusingOnce(broker.port)
    probe = Probe(broker.port, "rotor/#")  # the operator, on the broker's own port
    try:
        with Rig(tmp_path, proxy, probe) as rig:
            rig.add("tower", "rotorez", emu={"start_az_deg": 10})
            app = rig.start()
            rig.ready("tower")
            wait_until(app.lock_lane.connected.is_set, slow(10), "the lock lane up")
            lane = app.lock_lane.client_id
            rig.stop()  # the bridge restarts (an upgrade): its lanes' sessions live 30 s
            assert probe.publish("rotor/lock", "ON")  # while it is down: nobody carries it
            proxy.refuse = lane
            app = rig.start()
            rig.ready("tower")
            wait_until(lambda: proxy.refused == 1, slow(BACK_S), "the lane refused once")
            wait_until(app.lock_lane.connected.is_set, slow(BACK_S), "the lock lane up")
            with contextlib.suppress(AssertionError, TimeoutError):
                wait_until(lambda: rig.status("tower").locked, slow(SHOWN_S), "an old lock ON")
            assert not rig.status("tower").locked, (
                "a lock ON published while the bridge was down came back at its next start, "
                "handed over by the previous run's session to a lock lane whose first connect "
                "the broker had refused once: the rotator is locked"
            )
    finally:
        probe.close()
        proxy.close()
        broker.stop()
