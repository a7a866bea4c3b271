"""Review 112: a broker that refuses new connections because it is overloaded ("server busy",
a connection quota or rate limit reached) has its refusal taken as the answer that proves the
bridge's path dead (paho_client.py rule 12: "any CONNACK, an acceptance or a refusal"), and
the bridge ends the connections it had for ones the broker will not take.

An overloaded broker (EMQX, HiveMQ, a cloud broker's quota) passes what it routes late and
answers a new connection at once with a refusal (MQTT 5 0x89 server busy, 0x97 quota exceeded,
0x9F connection rate exceeded; 3.1.1's 3, server unavailable). The main connection is silent
(its heartbeat stuck in the broker's backlog), the probe is refused at once: "answered", the
verdict is a dead path, and the main connection, both lanes and the express are ended. Their
new connections are refused as the probe was, and the STOP the broker had already put on the
old ones (QoS 1, unacknowledged) goes with their sessions: when the broker catches up nothing
of the bridge is there to have it, and the rotor turns on. Kept, the connections would have
had it then. A refusal for load says the broker lives, not that the bridge's path is dead.

The overload is the test's proxy's: the streams open at its start pass nothing until it ends
(then all of it, in order: the broker's backlog delivered), and a new connection is answered
by a CONNACK refusing it as busy, as the broker's own front would.
"""

from __future__ import annotations

import contextlib
from pathlib import Path

from tests.faults.behind_a_proxy import bridge_behind
from tests.faults.test_review112_stop_lost_on_a_stalled_path import StallProxy, stop_through_a_stall
from tests.support.mqtt_proxy import CONNECT, _client_id, _packets, _Stream
from tests.support.tap import near_deg

BUSY_S = 15.0  # the overload's length: past the verdict, well within the keep-alive
PROMPT_S = 10.0  # a STOP reaches the controller within this once the broker caught up
SHORT_DEG = 20.0  # a stopped rotor is this far from its target at least (not an arrival)
SERVER_BUSY_5 = b"\x20\x03\x00\x89\x00"  # CONNACK, MQTT 5: 0x89 server busy
SERVER_UNAVAILABLE_311 = b"\x20\x02\x00\x03"  # CONNACK, 3.1.1: 3 server unavailable


class BusyProxy(StallProxy):
    """``stall`` as StallProxy's, and while stalled a new connection is refused as busy."""

    busy = False

    def stall(self) -> None:
        super().stall()
        self.busy = True

    def unstall(self) -> None:
        self.busy = False
        super().unstall()

    def _up(self, s: _Stream) -> None:
        if self.busy:  # a connection made during the overload: refused, nothing forwarded
            buf = bytearray()
            with contextlib.suppress(OSError):
                while data := s.client.recv(65536):
                    buf += data
                    for packet in _packets(buf):
                        if packet[0] >> 4 == CONNECT:
                            s.client_id = _client_id(packet)
                            v5 = b"MQTT\x05" in packet[:16]
                            s.client.sendall(SERVER_BUSY_5 if v5 else SERVER_UNAVAILABLE_311)
                            s.client.close()
                            s.server.close()
                            return
            return
        super()._up(s)

    def _down(self, s: _Stream) -> None:
        if self.busy:
            return  # (its server side closed by ``_up``)
        super()._down(s)


def test_a_stop_an_overloaded_broker_held_reaches_the_rotor_when_it_catches_up(
    tmp_path: Path,
) -> None:
    with bridge_behind(tmp_path, BusyProxy) as b:
        app = b.app
        # the broker overloaded (its backlog, new connections refused) as the STOP is taken
        s = stop_through_a_stall(b, BUSY_S, PROMPT_S)
        assert not s.is_moving and not near_deg(s.az_deg, 300, SHORT_DEG), (
            f"a STOP the broker took during a {BUSY_S:g} s overload (new connections "
            f"refused as busy) did not stop the rotor once it caught up: it turns on "
            f"({s.az_deg:.0f} deg); connections remade for a 'dead path': "
            f"{app.client.redials}"
        )
