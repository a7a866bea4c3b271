"""Review 145 (cold review of 1998b9a5): the stop and lock lanes keep alive every 2 s
(connection.py rule 6), so a broker drops them after 3 s in which nothing of theirs came (1.5
keep-alives): a bridge host whose uplink stalls that long (Wi-Fi), a bridge held that long. Under
MQTT 3.1.1 the broker just closes the socket, and connection.py rule 7 counts such a drop (the
broker's port still listening) as evidence of another client with the lane's client id: three
in a row, within STABLE_S of each other, and B/bridge/info says a client-id fight that does not
exist, while the lane backs off TAKEOVER_FIRST_S. With the setting's keep-alive (30 s) the same
stalls dropped nothing.

Real parts: nats-server (MQTT 3.1.1), the bridge in-process, an emulated Rotor-EZ on a pty, a
paho client at the broker's own port, and the MQTT-aware proxy (tests/support/mqtt_proxy.py) on
the bridge's path, holding what the stop lane's connection sends (``hold``) for STALL_S (a new
connection passes).

Fixed: the CONNECT says the keep-alive asked for; a stop's carrier pings every 2 s once
accepted (connection.py rule 6, paho_client.py ``ping_within``)."""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest

from bridge.interfaces.mqtt.lane import lane_client_id
from tests.support import Probe, retained_snapshot
from tests.support.brokers import Nats, find_nats
from tests.support.mqtt_proxy import MqttProxy
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until

STALLS = 3  # connection.py FLAP_COUNT
STALL_S = 4.0  # each stall of the lane's uplink: past the broker's 1.5 keep-alives of 2 s
INFO = "rotor/bridge/info"


def test_stalls_of_the_stop_lanes_uplink_say_no_client_id_fight(tmp_path: Path) -> None:
    if find_nats() is None:
        pytest.fail("nats-server is not installed (tests/run installs Debian's nats-server)")
    broker = Nats(tmp_path / "nats")
    broker.start()
    proxy = MqttProxy(broker.port)
    probe = Probe(broker.port)  # a dashboard on the broker's own port
    try:
        with Rig(tmp_path, proxy, probe) as rig:
            rig.add("tower", "rotorez", emu={"start_az_deg": 10})
            app = rig.start()
            rig.ready("tower", timeout_s=slow(40))
            lane = lane_client_id(rig.settings.mqtt)
            wait_until(lambda: proxy.subacks.get(lane, 0) > 0, slow(20), "the stop lane up")
            for _ in range(STALLS):
                wait_until(app.lane.connected.is_set, slow(20), "the stop lane up")
                proxy.hold(lane)  # what it sends waits: its uplink stalls
                time.sleep(STALL_S)  # the stall: the scenario's timing, not a wait for the bridge
                proxy.release(lane)
            wait_until(app.lane.connected.is_set, slow(20), "the stop lane up")
            shown = json.loads(retained_snapshot(broker.port, INFO)[INFO])["problems"]
            assert not [p for p in shown if "client id" in p], (
                f"B/bridge/info after {STALLS} stalls of the stop lane's uplink: {shown}"
            )
    finally:
        probe.close()
        proxy.close()
        broker.stop()
