"""The station's wall clock set back while commands stamped with its time are on their way
(interfaces/mqtt/heartbeat.py rule 6): real mosquitto, the station's bridge in this process on
an emulated Rotor-EZ and on a wall clock this test sets back, as a time server found after boot
does. The stamps are what a remote reckons from the heartbeats it heard before the step.

What the operator would see: a target the link held up for longer than its expiry never turns
the rotor, and one sent just now is carried out, not refused as "from the future"; also when
the station's bridge restarted after its wall clock was set back (heartbeat.py rule 7), where a
real remote link reckons the station's clock from the heartbeats; and the control lease ends
at the time R/control says on that clock, not 10 minutes later (runtime/operators.py rule 5)."""

from __future__ import annotations

import json
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
from bridge.interfaces.mqtt.remote import RemoteLink
from bridge.settings import MqttSettings
from tests.support import wait_until
from tests.support.rig import Rig
from tests.support.waiting import slow

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


HEARTBEAT, STATE = "rotor/bridge/heartbeat", "rotor/bridge/state"


@pytest.mark.parametrize("old_protocol", ["auto", "3.1.1"])
def test_a_station_bridge_restarted_on_a_clock_set_back_refuses_what_the_old_one_stamped(
    rig: Rig, stamper: Stamper, old_protocol: str
) -> None:
    """The station's wall clock set back 10 s, then its bridge restarted: the new process's
    clock starts 10 s behind the old one's. A target the remote stamped from the old process's
    beats, held up 12 s on the link (2 s old by the new clock), is refused and never turns the
    rotor; the remote's next move, stamped from the new process's first beat, is carried out
    at once (not refused as "ahead" while the old beats are remembered for a minute). Also
    when the old process spoke MQTT 3.1.1 (its beats named no process, heartbeat.py rule 7)
    and the new one MQTT 5."""
    emu = rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
    wall = SteppedWall()
    rig.mqtt_extra = {**rig.mqtt_extra, "protocol": old_protocol}
    rig.app = App(rig.settings, wall=wall)
    rig.app.start()
    rig.ready("tower")
    heard: list[tuple[str, bytes]] = []  # the bridge's state and beats, as the link heard them

    def hear(topic: str, payload: bytes, retain: bool) -> None:
        if not retain:
            heard.append((topic, payload))

    def new_beat() -> bool:  # a beat after the old process's ``offline``: the new process's
        gone = [i for i, m in enumerate(heard) if m == (STATE, b"offline")]
        return bool(gone) and any(t == HEARTBEAT for t, _ in heard[gone[0] :])

    link = RemoteLink(
        MqttSettings(host="127.0.0.1", port=rig.broker.port),
        "remote-test",
        [HEARTBEAT, STATE],
        hear,
        heartbeat=HEARTBEAT,
    )
    link.start()
    try:
        wait_until(lambda: link.up and heard, 10, "the remote hearing the station's heartbeat")
        before = link.station_clock.stamp(5)  # what the remote stamps now, before the restart
        reckoned_at = time.monotonic()
        assert before is not None
        wall.behind_s = 10.0  # the time server found ...
        rig.stop()
        t = time.monotonic()
        rig.mqtt_extra.pop("protocol")  # auto from now on: MQTT 5 with mosquitto
        rig.app = App(rig.settings, wall=wall)  # ... and the station's bridge restarted
        rig.app.start()
        rig.ready("tower", after=t)
        wait_until(new_beat, 10, "the new process's heartbeat at the remote")
        mark = rig.probe.mark()
        # stamped from the old process's beats, held up 12 s: 2 s old by the new process's clock
        old_clock_now = float(before.sent) + time.monotonic() - reckoned_at
        held = Stamp.of(old_clock_now - 12.0, 5, before.station)
        stamper.publish("rotor/target", "200", held)
        refused = rig.probe.wait(
            lambda m: m.topic == "rotor/error" and b"before it restarted" in m.payload,
            10,
            "the new process refusing what was stamped against the old one",
            mark,
        )
        assert b"200" in refused.payload
        link.send("rotor/target", '{"azimuth":120}', "DL1ABC", 5)  # the remote's next move
        rig.arrived("tower", 120)
        assert not [f for f in emu.frames(*BEARING_OUTCOMES) if b"200" in f.data]
        assert not [
            m
            for m in rig.probe.messages[mark:]
            if m.topic == "rotor/error" and b"ahead" in m.payload
        ]
    finally:
        link.stop()


def test_a_lease_ends_at_its_time_on_the_stations_clock_though_its_wall_clock_went_back(
    rig: Rig,
) -> None:
    """The control lease ends at the time ``R/control`` gives, on the clock the station's
    heartbeats carry (never set back), as the remote reads it (remote/rotator.py rule 6). On
    the raw wall clock, set back 10 minutes, the station held it 10 minutes past that end while
    its heartbeats said the end had passed: the remote answered another operator's move
    ``RPRT 0`` and the station refused it, naming a holder whose time was up."""
    # a kept lease (claims are a minute at least) ending soon, though not before the bridge
    # has started and said it (that takes longer on a busy machine: a lease over at the
    # start is ended there, and its holder never shown)
    ends_unix = time.time() + slow(4)
    lease = {"operator": "DL1ABC", "until": ends_unix}
    (rig.tmp / "state.json").write_text(json.dumps({"rotators": {"tower": {"lease": lease}}}))
    rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
    wall = SteppedWall()
    rig.app = App(rig.settings, wall=wall)
    rig.app.start()
    rig.ready("tower")
    probe = rig.probe
    held = probe.wait_for("rotor/control", lambda m: json.loads(m.text)["holder"] == "DL1ABC")
    wall.behind_s = 600.0  # the time server found: the wall clock goes back 10 minutes
    mark = probe.mark()
    beat = probe.wait(
        lambda m: m.topic == HEARTBEAT and parse_beat(m.payload) > ends_unix,
        15,
        "a heartbeat past the lease's end",
        mark,
    )
    assert parse_beat(beat.payload) > ends_unix  # the station's clock says it is over ...
    free = lambda m: json.loads(m.text)["holder"] is None  # noqa: E731
    probe.wait_for("rotor/control", free, 10, after=held.t)  # ... and so does R/control
    probe.publish("rotor/target", "120")  # anyone's move turns it
    rig.arrived("tower", 120)
