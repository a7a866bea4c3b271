"""The remote's link to the station's broker stalls without dropping (Wi-Fi, a mobile link): real
mosquitto, the station's bridge on an emulated Rotor-EZ, the remote in this process reaching the
broker through a TCP link this test stalls and recovers. Virtual-time proofs of the same rules
are in tests/remote/test_late_commands.py; this proves the wiring."""

from __future__ import annotations

import time

import paho.mqtt.client as paho
import pytest
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.properties import Properties

from bridge.emulators.rotorez_models import BEARING_OUTCOMES
from bridge.interfaces.mqtt.heartbeat import beat_payload, parse_beat
from bridge.interfaces.mqtt.remote import RemoteLink
from bridge.remote.run import Remote
from bridge.remote.settings import RemoteSettings
from bridge.settings import MqttSettings
from tests.support import Probe, wait_until
from tests.support.mosquitto import Mosquitto, free_port
from tests.support.remote import StallingLink, ask, remote_published
from tests.support.rig import Rig


def test_a_move_across_a_stalled_link_is_refused_and_never_turns_the_rotor_later(
    station: Rig, link: StallingLink, probe: Probe
) -> None:
    port = free_port()
    settings = RemoteSettings(
        operator="DL1ABC",
        mqtt={"host": "127.0.0.1", "port": link.port, "base_topic": "rotor"},
        endpoints=[{"rotator": "tower", "rotctld_port": port}],
        command_expiry_s=1,
    )
    remote = Remote(settings)
    remote.start()
    try:
        mqtt = remote.link
        assert mqtt is not None
        emu = station.emus["tower"]
        moves = len(emu.frames(*BEARING_OUTCOMES))
        link.stall()
        asked = time.time()
        # the broker never acknowledges it: an error, not RPRT 0 (the link is reset: -6)
        assert ask(port, b"P 200 0\n") == b"RPRT -6\n"
        assert mqtt.resets == 1 and not mqtt.up
        assert ask(port, b"P 210 0\n") == b"RPRT -6\n"  # refused at once while it reconnects
        # the stall lasts past the command's 1 s expiry; then the link delivers what it held
        wait_until(lambda: time.time() > asked + 2.5, 10, "the stall to last 2.5 s")
        errors = probe.mark()
        link.recover()
        refused = probe.wait(
            lambda m: m.topic == "rotor/error" and b"older than its 1 s expiry" in m.payload,
            20,
            "the station refusing the target the link held",
            errors,
        )
        assert b"set_pos" not in refused.payload and b"200" in refused.payload
        wait_until(lambda: mqtt.up, 30, "the remote connected again")
        wait_until(lambda: ask(port, b"P 120 0\n") == b"RPRT 0\n", 10, "a move taken again")
        station.arrived("tower", 120)
        assert not [f for f in emu.frames(*BEARING_OUTCOMES)[moves:] if b"200" in f.data]
        assert station.status("tower").bearing_deg == pytest.approx(120, abs=3.5)
    finally:
        remote.stop()


def test_the_station_bridge_beats_its_clock_not_retained(station: Rig, probe: Probe) -> None:
    """What the remote reads the station's life and clock from (interfaces/mqtt/heartbeat.py rule
    1)."""
    start = probe.mark()
    first = probe.wait(lambda m: m.topic == "rotor/bridge/heartbeat", 10, "a heartbeat", start)
    second = probe.wait(
        lambda m: m.topic == "rotor/bridge/heartbeat" and m is not first, 10, "the next", start
    )
    assert not first.retain and not second.retain
    assert parse_beat(first.payload) < parse_beat(second.payload)


def test_halts_unacknowledged_when_the_link_dropped_go_before_those_kept_after() -> None:
    """interfaces/mqtt/remote.py rule 6 (a full run on a busy machine found it): the stop sat
    unacknowledged when the connection dropped; a lock ON asked while it was down was kept at
    once; the close, handled after that, added the stop behind it, and the station got the
    lock first. Nothing decides it by a clock: the stop was sent first, and goes first."""
    link = RemoteLink(
        MqttSettings(host="127.0.0.1", port=1),
        "remote-test",
        [],
        lambda t, p, r: None,
        last_word=lambda topic, payload: True,
    )
    props = Properties(PacketTypes.PUBLISH)
    unacknowledged = paho.MQTTMessage(mid=7, topic=b"rotor/tower/stop")
    unacknowledged.payload, unacknowledged.properties = b"stop", props
    link._client.drop_out_messages = lambda: [unacknowledged]  # type: ignore[method-assign]
    with link._send_lock:
        link._keep("rotor/tower/lock", b"ON", props)  # asked while down: kept at once
        link._keep("rotor/tower/stop", b"stop", props)  # the same stop pressed again
        link._forget_unsent()  # the close, handled after it
    assert [(t, p) for t, p, _ in link._held] == [
        ("rotor/tower/stop", b"stop"),
        ("rotor/tower/lock", b"ON"),
    ]


def test_a_move_asked_after_a_halt_kept_for_the_stations_return_goes_after_it(
    broker: Mosquitto, probe: Probe
) -> None:
    """interfaces/mqtt/remote.py rule 6: a STOP sent while the station's bridge was not heard
    is sent again at its first heartbeat. The bridge, back on its broker after a flap, can
    take a move before that heartbeat (the remote still reckons its clock from the beats
    before the flap): the STOP, sent again at the heartbeat, went after the move it was asked
    before, and stopped it. The halts kept go before the later command instead."""
    beats: list[bytes] = []
    link = RemoteLink(
        MqttSettings(host="127.0.0.1", port=broker.port),
        "remote-kept-test",
        ["rotor/bridge/heartbeat"],
        lambda topic, payload, retain: beats.append(payload),
        last_word=lambda topic, payload: topic == "rotor/stop",
        heartbeat="rotor/bridge/heartbeat",
    )
    link.start()
    try:
        # subscribed, not only accepted: a beat (QoS 0) the broker takes before the link's
        # SUBSCRIBE is lost, and a loaded machine can run the test's publish first
        wait_until(lambda: link.subscribed_since is not None, 10, "the link subscribed")

        def beat() -> None:
            heard = len(beats)
            probe.publish("rotor/bridge/heartbeat", beat_payload(time.time()), qos=0)
            wait_until(lambda: len(beats) > heard, 10, "the beat heard")

        beat()
        log_from = broker.log.stat().st_size
        link.send("rotor/stop", "stop", "DL1ABC", 5, until_heard=True)  # to nobody, maybe
        # asked after it, a move (its check, rule 9, as remote/rotator.py sends every move)
        link.send("rotor/target", '{"azimuth":100}', "DL1ABC", 5, lambda: None)
        beat()  # the station's bridge heard again
        link.send("rotor/stop", "stop", "DL1ABC", 5)  # a marker behind anything sent again
        wait_until(lambda: len(remote_published(broker, log_from)) >= 4, 10, "the marker")
        # the stop, again before the target; nothing of it after the target but the marker
        assert remote_published(broker, log_from) == [b"stop", b"stop", b"target", b"stop"]
    finally:
        link.stop()
