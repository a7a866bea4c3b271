"""The station's wall clock set back while commands stamped with its time are on their way
(interfaces/mqtt/heartbeat.py rule 6): real mosquitto, the station's bridge in this process on
an emulated Rotor-EZ and on a wall clock this test sets back, as a time server found after boot
does. The stamps are what a remote reckons from the heartbeats it heard before the step.

What the operator would see: a target the link held up for longer than its expiry never turns
the rotor, and one sent just now is carried out, not refused as "from the future"."""

from __future__ import annotations

import time
from collections.abc import Iterator

import paho.mqtt.client as paho
import pytest
from paho.mqtt.enums import CallbackAPIVersion
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.properties import Properties

from bridge.app import App
from bridge.emulators.rotorez_models import BEARING_OUTCOMES
from bridge.interfaces.mqtt.heartbeat import Stamp, parse_beat
from tests.support.rig import Rig

STEP_S = 10.0  # the station's wall clock set back by this much


class SteppedWall:
    """The real wall clock, set back by ``step`` when the test says."""

    def __init__(self) -> None:
        self.behind_s = 0.0

    def __call__(self) -> float:
        return time.time() - self.behind_s


class Stamper:
    """An MQTT 5 client that stamps its commands as the remote does (heartbeat.py rule 4)."""

    def __init__(self, port: int) -> None:
        c = paho.Client(CallbackAPIVersion.VERSION2, client_id="stamper", protocol=paho.MQTTv5)
        c.connect("127.0.0.1", port)
        c.loop_start()
        self.client = c

    def publish(self, topic: str, payload: str, stamp: Stamp) -> None:
        props = Properties(PacketTypes.PUBLISH)  # type: ignore[no-untyped-call]
        props.UserProperty = stamp.properties()
        self.client.publish(topic, payload, qos=1, properties=props).wait_for_publish(5)

    def close(self) -> None:
        self.client.loop_stop()
        self.client.disconnect()


@pytest.fixture
def stamper(rig: Rig) -> Iterator[Stamper]:
    s = Stamper(rig.broker.port)
    yield s
    s.close()


def test_a_station_clock_set_back_neither_lets_a_held_up_target_turn_nor_refuses_a_fresh_one(
    rig: Rig, stamper: Stamper
) -> None:
    emu = rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
    wall = SteppedWall()
    rig.app = App(rig.settings, wall=wall)
    rig.app.start()
    rig.ready("tower")
    probe = rig.probe
    start = probe.mark()
    beat = probe.wait(lambda m: m.topic == "rotor/bridge/heartbeat", 10, "a heartbeat", start)
    assert parse_beat(beat.payload) == pytest.approx(time.time(), abs=5)  # the clock before
    reckoned = time.time()  # the station's clock as a remote reckons it from that beat
    wall.behind_s = STEP_S  # the time server found: the station's clock goes back
    mark = probe.mark()
    # held up 12 s with a 5 s expiry: by the clock after the step it looks 2 s old
    stamper.publish("rotor/target", "200", Stamp.of(reckoned - 12.0, 5))
    refused = probe.wait(
        lambda m: m.topic == "rotor/error" and b"older than its 5 s expiry" in m.payload,
        10,
        "the station refusing the target the link held up",
        mark,
    )
    assert b"200" in refused.payload
    # sent just now, reckoned from the beat before the step: carried out
    stamper.publish("rotor/target", "120", Stamp.of(time.time(), 5))
    rig.arrived("tower", 120)
    assert not [f for f in emu.frames(*BEARING_OUTCOMES) if b"200" in f.data]
    assert not [
        m for m in probe.messages[mark:] if m.topic == "rotor/error" and b"ahead" in m.payload
    ]
