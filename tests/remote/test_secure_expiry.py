"""A command whose expiry passes in a broker queue never moves the rotor.

The station's bridge keeps no session (clean start: interfaces/mqtt/connection.py rule 1), so
nothing waits for it in the station's broker. The queue a command really waits in is a relay's: a
broker on the operator's side, bridged to the station's (mosquitto's ``connection`` bridge, MQTT 5,
``topic rotor/# out 1``), whose link to the station is down while the command waits. The link
here goes through a gate this test opens when it wants (tests/support/remote.py's stalling
link, stalled from the start): shut, it takes each connection and closes it at once, so the
relay keeps its queue; open, it forwards bytes both ways.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import paho.mqtt.client as paho
import pytest
from paho.mqtt.enums import CallbackAPIVersion
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.properties import Properties

from bridge.emulators.rotorez_models import BEARING_OUTCOMES
from tests.support import wait_until
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt import end_paho
from tests.support.remote import StallingLink
from tests.support.rig import Rig


def relay_conf(gate: StallingLink) -> str:
    """The operator's broker, bridged to the station's through the gate."""
    return (
        "allow_anonymous true\n"
        "connection station\n"
        f"address 127.0.0.1:{gate.port}\n"
        "bridge_protocol_version mqttv50\n"
        "cleansession false\n"  # the relay keeps what is for the station while the link is down
        "restart_timeout 1\n"  # tries the link again every second
        "try_private false\n"
        "topic rotor/# out 1\n"
    )


@pytest.fixture
def relay(tmp_path: Path, station: Rig) -> Iterator[tuple[Mosquitto, StallingLink]]:
    gate = StallingLink(station.broker.port, flowing=False)
    broker = Mosquitto(tmp_path / "relay", extra_conf=relay_conf(gate)).start()
    yield broker, gate
    broker.stop()
    gate.close()


def publish(port: int, topic: str, payload: str, expiry_s: int | None) -> None:
    """QoS 1, acknowledged by the broker at ``port`` before this returns; MQTT 5, with a message
    expiry interval when ``expiry_s`` is given."""
    c = paho.Client(CallbackAPIVersion.VERSION2, client_id=f"op-{topic}", protocol=paho.MQTTv5)
    c.connect("127.0.0.1", port)
    c.loop_start()
    try:
        props: Any = None
        if expiry_s is not None:
            props = Properties(PacketTypes.PUBLISH)  # type: ignore[no-untyped-call]
            props.MessageExpiryInterval = expiry_s
        c.publish(topic, payload, qos=1, properties=props).wait_for_publish(5)
    finally:
        end_paho(c)


@pytest.mark.parametrize(
    ("expiry_s", "moves"),
    [(1, False), (60, True)],
    ids=["expired in the queue: never moves", "control, still alive: moves"],
)
def test_a_command_whose_expiry_passes_in_a_relay_queue_never_moves_the_rotor(
    station: Rig, relay: tuple[Mosquitto, StallingLink], expiry_s: int, moves: bool
) -> None:
    broker, gate = relay
    emu = station.emus["tower"]
    frames = len(emu.frames(*BEARING_OUTCOMES))
    wait_until(lambda: gate.turned_away >= 1, 10, "the relay trying its link")
    publish(broker.port, "rotor/target", "60", expiry_s)
    # The thing under test is time passing in the queue: a real wait past a 1 s expiry (and
    # well inside the control's 60 s); the link stays shut all along.
    expired = threading.Event()
    expired.wait(2.5)  # time passing, not a deadline
    # a marker without expiry, behind the target in the same queue (FIFO): when it reaches the
    # station's broker, the target would have been before it
    publish(broker.port, "rotor/relay/marker", "m", None)
    start = station.probe.mark()
    gate.recover()
    station.probe.wait(lambda m: m.topic == "rotor/relay/marker", 15, "the marker", start)
    targets = [m for m in station.probe.messages[start:] if m.topic == "rotor/target"]
    if moves:
        assert [m.payload for m in targets] == [b"60"]
        station.arrived("tower", 60)
    else:
        assert targets == []
        # what the bridge would do with one: nothing moved, no command source recorded
        assert len(emu.frames(*BEARING_OUTCOMES)) == frames
        assert abs(emu.state().az_deg - 10) <= 1
        assert station.status("tower").last_command_source is None
