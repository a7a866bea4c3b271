"""Review 121: a stop carrier's kept session (interfaces/mqtt/connection.py rule 22) from the
bridge's earlier run comes back at its start when the broker turns down its first connect.

Rule 22 asks paho's MQTT_CLEAN_START_FIRST_ONLY so that "nothing of an earlier run is handed to
it". But paho ends its "first" at the first CONNACK it reads, accepted or not
(``_mqttv5_first_connect = False`` in ``_handle_connack``, before it looks at the reason). A
broker that answers the lane's first CONNECT with a refusal (MQTT 5's 0x89 "Server busy" or 0x88
"Server unavailable": a broker or its auth back-end starting up with the bridge, an overload
guard) has the next attempt made with clean start off, and the session the earlier run left
(30 s of expiry from its stop: the bridge's own restart, a service manager's restart) is
handed over with what it queued meanwhile: a lock ON published while the bridge was away
locks the rotator at the new run's start (R/lock/state ON, a target refused), though nobody
sent it to this run. Under a clean session (before rule 22, or with the first CONNECT
accepted) the word is not replayed (rule 1: commands sent while the bridge was away are not).

Real mosquitto, a proxy of the test's own between it and the bridge (tests/support/mqtt_proxy.py
with one turn-down: it answers the lock lane's next CONNECT with CONNACK 0x89 and closes); a
Rotor-EZ on a real pty; the operator on the broker's own port.
"""

from __future__ import annotations

import contextlib
import socket
import time
from pathlib import Path

from tests.support import Probe
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt_proxy import CONNECT, MqttProxy, _client_id, _packets, _Stream
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until

SERVER_BUSY = bytes([0x20, 3, 0x00, 0x89, 0x00])  # MQTT 5 CONNACK: no session, 0x89, no props
QUIET_S = 3.0  # how long after the lane is back a handed-over word has had its say
TURN_DEG = 40.0  # the target sent at the new run's start (the rotor at 10)


class BusyOnceProxy(MqttProxy):
    """An MqttProxy that turns down the next CONNECT of the client ids in ``busy``, once each
    (CONNACK 0x89, "Server busy", then closes), as a broker under load may."""

    def __init__(self, backend: int) -> None:
        self.busy: set[str] = set()
        self.turned_down: dict[str, int] = {}
        super().__init__(backend)

    def _up(self, s: _Stream) -> None:
        buf = bytearray()
        with contextlib.suppress(OSError):
            data = s.client.recv(65536)
            while data:
                buf += data
                for packet in _packets(buf):
                    if packet[0] >> 4 == CONNECT:
                        s.client_id = _client_id(packet)
                        if s.client_id in self.busy:
                            self.busy.discard(s.client_id)
                            self.turned_down[s.client_id] = 1 + self.turned_down.get(s.client_id, 0)
                            s.client.sendall(SERVER_BUSY)
                            for sock in (s.client, s.server):
                                with contextlib.suppress(OSError):
                                    sock.shutdown(socket.SHUT_RDWR)
                            return
                    s.server.sendall(packet)
                data = s.client.recv(65536)
        with contextlib.suppress(OSError):
            s.server.shutdown(socket.SHUT_WR)


def test_a_lock_on_sent_while_the_bridge_was_away_is_not_carried_out_at_its_start(
    tmp_path: Path,
) -> None:
    broker = Mosquitto(tmp_path / "broker").start()
    proxy = BusyOnceProxy(broker.port)
    probe = Probe(broker.port, "rotor/#")  # the operator, on the broker's own port
    try:
        with Rig(tmp_path, proxy, probe) as rig:
            emu = rig.add("tower", "rotorez", emu={"start_az_deg": 10, "speed_deg_s": 2.0})
            app = rig.start()
            rig.ready("tower")
            lane = app.lock_lane.client_id
            wait_until(lambda: proxy.subacks.get(lane, 0) > 0, slow(10), "the lock lane up")
            rig.stop()  # the bridge's earlier run ends (a restart, an upgrade)
            assert probe.publish("rotor/lock", "ON")  # sent while the bridge is away
            proxy.busy.add(lane)  # the broker busy for the new run's lock lane's first try
            before = proxy.subacks.get(lane, 0)
            mark = probe.mark()
            rig.start()
            rig.ready("tower")
            wait_until(lambda: proxy.turned_down.get(lane, 0) == 1, slow(10), "turned down")
            wait_until(lambda: proxy.subacks.get(lane, 0) > before, slow(10), "the lane back")
            time.sleep(QUIET_S)  # the handed-over word's moment (a quiet period)
            shown = [m.text for m in probe.messages[mark:] if m.topic == "rotor/lock/state"]
            assert probe.publish("rotor/target", f"{TURN_DEG:g}")
            try:
                moved = emu.wait_for(lambda s: s.is_moving, slow(5)).is_moving
            except TimeoutError:
                moved = False
            assert "ON" not in shown and moved, (
                f"a lock ON published while the bridge was away came back in its new run (the "
                f"lock lane's first CONNECT turned down, its next keeping the earlier run's "
                f"session): R/lock/state said {shown}; the target {TURN_DEG:g} turned the "
                f"rotor: {moved}"
            )
    finally:
        probe.close()
        proxy.close()
        broker.stop()
