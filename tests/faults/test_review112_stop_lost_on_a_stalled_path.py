"""Review 112: a STOP the broker sent into a path that stalls, not dies, is thrown away by the
dead-path redial (interfaces/mqtt/client.py rule 21, heartbeat.py rule 12).

The redial's premise is that a path which stalls and delivers later answers no probe either,
so the connections are kept and what the broker holds for them arrives when it runs on (the
frozen broker's case, attack 32's second test). But the probe is a *new* flow: a stateful
firewall or NAT failing over to its standby (its connection table synced a few seconds later),
a load balancer draining a node, a congested middlebox that queues the old flows: the streams
open now stall and deliver later, while a new connection passes at once. The probe is
answered, the main connection's quiet goes on past it, and all three stop carriers are remade
with clean sessions: the STOP the broker had already put on the stalled streams (QoS 1, not yet
acknowledged) is discarded with the old sessions at the takeover, and what the stall delivers
later meets closed sockets. Left alone, the connections would have had the STOP when the stall
ended (their keep-alive, 30 s, outlasts it), as they do for a frozen broker.

The stall is the test's own proxy's (``StallProxy``, a ``MqttProxy`` that keeps what either
side sends on the streams open at ``stall`` and delivers it, in order, at ``unstall``; the
streams made meanwhile pass). The operator's STOP goes in at the broker's own port.
"""

from __future__ import annotations

import contextlib
import socket
import time
from pathlib import Path
from typing import TypeVar

from bridge.emulators.base import RotatorState
from tests.faults.behind_a_proxy import Behind, bridge_behind
from tests.support.mqtt_proxy import CONNECT, SUBACK, MqttProxy, _client_id, _packets, _Stream
from tests.support.tap import near_deg
from tests.support.waiting import slow

STALL_S = 15.0  # the stall's length: past the redial (DEAD_PATH_S), well within the keep-alive
PROMPT_S = 10.0  # a STOP reaches the controller within this once the stall ends
SHORT_DEG = 20.0  # a stopped rotor is this far from its target at least (not an arrival)


class StallProxy(MqttProxy):
    """``stall``: what either side sends on the streams open now is kept, an end (FIN) too,
    until ``unstall`` delivers it in order; streams made meanwhile pass."""

    def __init__(self, backend: int) -> None:
        self._kept: dict[int, dict[str, bytearray | None]] = {}
        self._ended: dict[int, set[str]] = {}
        super().__init__(backend)

    def stall(self) -> None:
        for s in list(self._streams):
            with s.lock:
                self._kept[id(s)] = {"up": bytearray(), "down": bytearray()}
                self._ended[id(s)] = set()

    def unstall(self) -> None:
        for s in list(self._streams):
            with s.lock:
                kept = self._kept.pop(id(s), None)
                ended = self._ended.pop(id(s), set())
            if kept is None:
                continue
            for way, sock in (("up", s.server), ("down", s.client)):
                with contextlib.suppress(OSError):
                    data = kept[way]
                    if data:
                        sock.sendall(data)
                    if way in ended:
                        sock.shutdown(socket.SHUT_WR)

    def _keep(self, s: _Stream, way: str, data: bytes) -> bool:
        with s.lock:
            kept = self._kept.get(id(s))
            if kept is None:
                return False
            buf = kept[way]
            assert buf is not None
            buf += data
            return True

    def _end(self, s: _Stream, way: str, sock: socket.socket) -> None:
        with s.lock:
            if id(s) in self._ended:
                self._ended[id(s)].add(way)
                return
        with contextlib.suppress(OSError):
            sock.shutdown(socket.SHUT_WR)

    def _up(self, s: _Stream) -> None:
        buf = bytearray()
        with contextlib.suppress(OSError):
            while data := s.client.recv(65536):
                buf += data
                for packet in _packets(buf):
                    if packet[0] >> 4 == CONNECT:
                        s.client_id = _client_id(packet)
                    if not self._keep(s, "up", packet):
                        s.server.sendall(packet)
        self._end(s, "up", s.server)

    def _down(self, s: _Stream) -> None:
        buf = bytearray()
        with contextlib.suppress(OSError):
            while data := s.server.recv(65536):
                buf += data
                for packet in _packets(buf):
                    if not self._keep(s, "down", packet):
                        s.client.sendall(packet)
                    if packet[0] >> 4 == SUBACK:
                        self.subacks[s.client_id] = self.subacks.get(s.client_id, 0) + 1
        self._end(s, "down", s.client)


S = TypeVar("S", bound=StallProxy)


def stop_through_a_stall(b: Behind[S], fault_s: float, prompt_s: float) -> RotatorState:
    """The tower on a long turn (to 300, 145 s); the proxy's ``stall`` for ``fault_s``, the
    operator's STOP taken by the broker (its PUBACK seen) at its start; then ``unstall``. The
    rotor as it is once stopped, or ``prompt_s`` on."""
    b.probe.publish("rotor/target", "300")  # a long turn (145 s)
    b.emu.wait_for(lambda s: s.is_moving, slow(10))
    b.proxy.stall()
    try:
        assert b.probe.publish("rotor/stop", "")  # the operator's STOP, taken
        time.sleep(fault_s)  # the fault's length (not a deadline)
    finally:
        b.proxy.unstall()
    with contextlib.suppress(AssertionError, TimeoutError):
        b.emu.wait_for(lambda s: not s.is_moving, slow(prompt_s))
    return b.emu.state()


def test_a_stop_held_by_a_stalled_path_reaches_the_rotor_when_it_delivers(
    tmp_path: Path,
) -> None:
    with bridge_behind(tmp_path, StallProxy) as b:
        app = b.app
        # the streams open now stall (new ones pass); the operator's STOP, taken by the
        # broker, sent on into the stalled streams of every stop carrier
        s = stop_through_a_stall(b, STALL_S, PROMPT_S)
        assert not s.is_moving and not near_deg(s.az_deg, 300, SHORT_DEG), (
            f"a STOP the broker took during a {STALL_S:g} s stall of the bridge's path did "
            f"not stop the rotor once the stall ended: it turns on ({s.az_deg:.0f} deg); "
            f"connections remade for a 'dead path': {app.client.redials}"
        )
