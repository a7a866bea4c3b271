"""Review 88, with real mosquitto and a Rotor-EZ on a real pty: a full broker (``max_connections``,
busy neighbours that reconnect as soon as a slot is free) and a client that connects once with
the bridge's main client id and stays (a copied configuration, someone's mosquitto_sub -i, a
hostile client).

Review 81 made the stop lane and the lock lane give their connections up (``drop``) and hold back
up to 30 s whenever the main connection is closed before its CONNACK (connection.py rule 6). A
broker at its limit closes every new socket before CONNACK: so once the main connection is
knocked off, its first try again tells the lanes that carry STOP to leave a broker they were
connected to, and the neighbours take the slots they free. With ``mqtt.stop_express = false`` the
bridge is then off the broker altogether: a STOP sent from a dashboard that is still connected
reaches no connection of the bridge, and the rotor turns on to its target. Before review 81
(b4654e62) the lanes kept their slots and the same STOP stopped the rotor (checked by hand).
"""

from __future__ import annotations

import contextlib
import itertools
import socket
from pathlib import Path

import paho.mqtt.client as paho
import pytest
from paho.mqtt.enums import CallbackAPIVersion

from bridge.interfaces.mqtt.lane import lane_client_id
from tests.support import Probe
from tests.support.mosquitto import Mosquitto
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until

# mosquitto 2.0 lets in one connection more than its max_connections: the probe, the bridge's
# three (main, stop lane, lock lane) and one more, the hostile copy's
LIMIT = "allow_anonymous true\nmax_connections 4\n"
NEIGHBOURS = 8  # busy clients that take any slot that frees (more than the bridge can free)
_ids = itertools.count()
TURNED_AWAY = "the MQTT broker closed the connection before accepting it"


def _taker(port: int, client_id: str) -> socket.socket:
    """An MQTT 3.1.1 connection with ``client_id`` (no keep-alive), held open: it takes the
    main connection's session over once, and goes when taken over in turn (no fight)."""
    cid = client_id.encode()
    body = b"\x00\x04MQTT\x04\x02\x00\x00" + len(cid).to_bytes(2, "big") + cid
    sock = socket.create_connection(("127.0.0.1", port))
    sock.sendall(bytes([0x10, len(body)]) + body)
    assert sock.recv(4) == b"\x20\x02\x00\x00", "the taker's CONNACK"
    return sock


def _neighbour(port: int, client_id: str) -> paho.Client:
    """A client that is back as soon as the broker lets it (a crash-looping device, a fleet)."""
    c = paho.Client(CallbackAPIVersion.VERSION2, client_id=client_id)
    c.reconnect_delay_set(0.05, 0.05)  # type: ignore[arg-type]
    c.connect_async("127.0.0.1", port, keepalive=30)
    c.loop_start()
    return c


def test_a_stop_still_stops_the_rotor_when_the_main_connection_is_turned_away_by_a_full_broker(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    broker = Mosquitto(tmp_path / "broker", extra_conf=LIMIT).start()
    probe = Probe(broker.port, "rotor/#")
    others: list[paho.Client] = []
    hostile: socket.socket | None = None
    try:
        with Rig(tmp_path, broker, probe) as rig:
            rig.express = False  # mqtt.stop_express: false: the stop lane carries the stops
            emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 2.0})
            app = rig.start()
            rig.ready("tower")
            left = f"Client {lane_client_id(rig.settings.mqtt)} closed its connection"
            wait_until(app.lane.connected.is_set, 10, "the stop lane up")
            wait_until(app.lock_lane.connected.is_set, 10, "the lock lane up")
            probe.publish("rotor/target", "300")  # a long turn (145 s)
            emu.wait_for(lambda s: s.is_moving, slow(10))
            # a client with the main connection's id knocks it off once (and never fights back)
            hostile = _taker(broker.port, rig.settings.mqtt.effective_client_id())
            wait_until(lambda: not app.client.connected.is_set(), 10, "main taken over")
            # ... and busy neighbours take every slot that frees from now on
            others += [
                _neighbour(broker.port, f"neighbour-{next(_ids)}") for _ in range(NEIGHBOURS)
            ]
            # the main connection's next try is turned away by the full broker (the bridge says
            # so) ...
            wait_until(lambda: TURNED_AWAY in caplog.text, 30, "the main connection's try again")
            # ... and the stop lane leaves its slot to it (review 81), the neighbours take it; a
            # bridge that keeps its stop lane goes on at once
            with contextlib.suppress(AssertionError, TimeoutError):
                wait_until(lambda: left in broker.log.read_text(errors="replace"), 5, "lane off")
            assert emu.state().is_moving
            probe.publish("rotor/stop", "")  # the operator's STOP (the probe is connected)
            try:
                emu.wait_for(lambda s: not s.is_moving, slow(10))
            except (AssertionError, TimeoutError):
                pass  # (said below)
            s = emu.state()
            assert not s.is_moving, (
                f"a STOP sent while the main connection is away did not stop the rotor: it "
                f"turns on ({s.az_deg:.0f} deg); the stop lane up: "
                f"{app.lane.connected.is_set()}, the lock lane: "
                f"{app.lock_lane.connected.is_set()}"
            )
    finally:
        if hostile is not None:
            hostile.close()
        for c in others:
            c.loop_stop()
            c.disconnect()
        probe.close()
        broker.stop()
