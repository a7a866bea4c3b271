"""`rotor-bridge demo` on the broker of a real installation (base topic `rotor`, Home Assistant
discovery on): the two must not know of each other. Before issue 13 the demo took the bridge's
client id, base topic and discovery node id: they kicked each other off the broker every second,
deleted each other's Home Assistant entities, and one publish on rotor/target turned both."""

from __future__ import annotations

import json
import re
import time
from pathlib import Path

from bridge.interfaces.homeassistant import Identity
from bridge.interfaces.mqtt.topics import DiscoveryTopics
from tests.demo_process import DemoProcess
from tests.support import Message, retained_snapshot
from tests.support.rig import Rig
from tests.support.waiting import slow

DISCOVERY = DiscoveryTopics("homeassistant")


def _node(topic: str) -> str | None:
    parsed = DISCOVERY.parse_config(topic)
    return None if parsed is None else parsed[1]


def _configs_of(ident: Identity, messages: list[Message]) -> list[Message]:
    return [m for m in messages if (node := _node(m.topic)) is not None and ident.owns(node)]


def test_a_demo_beside_a_real_bridge_leaves_it_alone(tmp_path: Path, rig: Rig) -> None:
    rig.mqtt_extra = {"client_id": None}  # the service's own default, as installed
    rig.add("tower", "rotorez")
    rig.start()
    rig.ready("tower")
    real = Identity("rotor")
    probe = rig.probe  # subscribed to '#' since before the bridge started
    assert _configs_of(real, probe.messages), "the real bridge published no discovery"

    # the environment of a shell set up for the service must not make the demo its twin
    service_env = {
        "ROTOR_BRIDGE_MQTT__BASE_TOPIC": "rotor",
        "ROTOR_BRIDGE_MQTT__CLIENT_ID": rig.settings.mqtt.effective_client_id(),
    }
    demo = DemoProcess(
        ["--mqtt-port", str(rig.broker.port), "--duration-s", "25", "--speed-deg-s", "60"],
        tmp_path / "tmp",
        env=service_env,
    )
    try:
        base = demo.base_topic()
        assert base.startswith("rotor-demo-")
        assert "the MQTT broker already running" in demo.output
        demo.wait_line(rf"turn:  mosquitto_pub -h 127\.0\.0\.1 -p {rig.broker.port} -t {base}/")
        probe.wait_value(f"{base}/availability", "online", timeout_s=20)
        probe.wait_value(f"{base}/state", "idle", timeout_s=20)  # past its brake delay
        mine = Identity(base)
        assert _configs_of(mine, probe.messages), "the demo published no discovery"

        # a publish on rotor/target turns the real rotor, and only it
        t0 = time.monotonic()
        probe.publish("rotor/target", "120")
        probe.wait_for("rotor/bearing", lambda m: abs(float(m.text) - 120) <= 3, timeout_s=15)
        probe.wait_value("rotor/state", "idle", timeout_s=15, after=t0)
        # ... and the demo's own topic turns the demo's rotor, and only it
        t1 = time.monotonic()
        probe.publish(f"{base}/target", "200")
        probe.wait_for(f"{base}/bearing", lambda m: abs(float(m.text) - 200) <= 3, timeout_s=15)
        demo_moves = [m for m in probe.on(f"{base}/state") if m.text == "moving"]
        assert demo_moves and all(m.t >= t1 for m in demo_moves), "rotor/target moved the demo"
        real_moves = [m for m in probe.on("rotor/state") if m.text == "moving"]
        assert real_moves and all(m.t < t1 for m in real_moves), "the demo's target moved rotor"

        assert demo.wait(slow(45)) == 0, demo.output  # --duration-s over
    finally:
        demo.close()

    # the real bridge was never disconnected: one "online" (its first connect), no "offline",
    # and the broker never closed one of its connections for another with its client id
    assert [m.text for m in probe.on("rotor/bridge/state")] == ["online"]
    log = rig.broker.log.read_text()
    assert "already connected, closing old connection" not in log, log[-3000:]
    # the demo came with client ids of its own (the stop lane's and the lock lane's too:
    # lastword.py rule 16), short enough for any broker
    ids = set(re.findall(r"New client connected from \S+ as (\S+) ", log))
    assert rig.settings.mqtt.effective_client_id() in ids
    own = {base, f"{base}-ui", f"{base}-stop", f"{base}-lock", f"{base}-fast"}
    assert {i for i in ids if i.startswith(base)} == own
    assert all(len(i) <= 23 for i in own)
    # none of its Home Assistant configs was cleared, and all are still there
    real_configs = _configs_of(real, probe.messages)
    assert [m.topic for m in real_configs if not m.payload] == []
    snap = retained_snapshot(rig.broker.port, "#")
    assert {m.topic for m in real_configs} <= set(snap)
    assert snap["rotor/bridge/state"] == b"online"
    assert snap["rotor/availability"] == b"online"
    assert abs(json.loads(snap["rotor/status"])["bearing"] - 120) <= 3
    # the demo took its own away: no retained topic of it, no Home Assistant config of it
    assert [t for t in snap if t.startswith(f"{base}/")] == []
    assert [t for t in snap if (node := _node(t)) and mine.owns(node)] == []
    assert list((tmp_path / "tmp").iterdir()) == []


def test_a_demo_told_to_take_a_live_bridges_base_topic_refuses(tmp_path: Path, rig: Rig) -> None:
    rig.add("tower", "rotorez")
    rig.start()
    rig.ready("tower")
    demo = DemoProcess(
        ["--mqtt-port", str(rig.broker.port), "--base-topic", "rotor", "--duration-s", "20"],
        tmp_path / "tmp",
    )
    try:
        assert demo.wait(slow(20)) == 2, demo.output
    finally:
        demo.close()
    assert "base topic 'rotor' belongs to a bridge (rotor/bridge/state is 'online')" in demo.output
    assert [m.text for m in rig.probe.on("rotor/bridge/state")] == ["online"]
    assert [
        m for m in rig.probe.messages if m.topic.startswith("homeassistant/") and not m.payload
    ] == []
    assert (
        retained_snapshot(rig.broker.port, "rotor/bridge/state")["rotor/bridge/state"] == b"online"
    )
    assert list((tmp_path / "tmp").iterdir()) == []


def test_a_demo_refuses_the_base_topic_of_a_stopped_bridge_too(tmp_path: Path, rig: Rig) -> None:
    """Stopped for maintenance, the bridge's Home Assistant devices are still its own: a demo on
    its base topic would clear them as stale (found by review)."""
    rig.add("tower", "rotorez")
    rig.start()
    rig.ready("tower")
    rig.stop()  # retained rotor/bridge/state is now "offline"; its discovery stays retained
    rig.probe.wait_value("rotor/bridge/state", "offline")
    demo = DemoProcess(
        ["--mqtt-port", str(rig.broker.port), "--base-topic", "rotor", "--duration-s", "20"],
        tmp_path / "tmp",
    )
    try:
        assert demo.wait(slow(20)) == 2, demo.output
    finally:
        demo.close()
    assert "(rotor/bridge/state is 'offline')" in demo.output
    assert [
        m for m in rig.probe.messages if m.topic.startswith("homeassistant/") and not m.payload
    ] == []
