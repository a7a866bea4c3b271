"""Home Assistant discovery through a real broker: what HA would receive, and how it reacts."""

from __future__ import annotations

import json
import logging
import re
import time
from pathlib import Path

import pytest

from bridge import emulators
from bridge.interfaces.mqtt import client as mqtt_client
from bridge.interfaces.mqtt.look import CLEARS_SAID_AT_ONCE
from tests.ha_rules import validate
from tests.integration.test_process import start_bridge, write_config
from tests.support import Probe, retained_snapshot, wait_until
from tests.support.mosquitto import Mosquitto
from tests.support.rig import Rig
from tests.support.waiting import slow

PREFIX = "homeassistant"


def configs(port: int) -> dict[str, dict]:
    snap = retained_snapshot(port, f"{PREFIX}/#")
    return {t: json.loads(p) for t, p in snap.items() if t.endswith("/config") and p}


def test_discovery_is_retained_valid_and_not_repeated(rig: Rig) -> None:
    ha = Probe(rig.broker.port, f"{PREFIX}/#")
    emu = rig.add("tower", emu={"start_az_deg": 10})
    rig.start()
    rig.ready("tower")
    msgs = configs(rig.broker.port)
    assert (
        len(msgs) == 29
    )  # with the nudge buttons, rotor health (it reports its bearing) and control
    for topic, payload in msgs.items():
        assert validate(topic, payload) == []
    # the controller's firmware arrived and became the device's sw_version
    bearing = msgs[f"{PREFIX}/sensor/rotorbridge_rotor_r_tower/bearing/config"]
    assert bearing["device"]["sw_version"] == "1.4S"
    # a move changes states, not discovery: no config is published again
    seen = {t: len(ha.on(t)) for t in msgs}
    rig.probe.publish("rotor/target", "60")
    emu.wait_for(lambda s: abs(s.az_deg - 60) <= 3 and not s.is_moving, 15)
    rig.probe.wait_value("rotor/state", "idle", timeout_s=10)
    assert {t: len(ha.on(t)) for t in msgs} == seen
    # retained: configs() read them from a fresh subscription; QoS 1 on the way out
    assert all(m.qos == 1 for t in msgs for m in ha.on(t))
    ha.close()


def test_number_entity_command_turns_the_rotor(rig: Rig) -> None:
    emu = rig.add("tower", emu={"start_az_deg": 10})
    rig.start()
    rig.ready("tower")
    num = configs(rig.broker.port)[
        f"{PREFIX}/number/rotorbridge_rotor_r_tower/target_azimuth/config"
    ]
    rig.probe.publish(num["command_topic"], "120.0")  # HA's number sends the value as text
    emu.wait_for(lambda s: abs(s.az_deg - 120) <= 3 and not s.is_moving, 15)
    stop = configs(rig.broker.port)[f"{PREFIX}/button/rotorbridge_rotor_r_tower/stop/config"]
    assert stop["command_topic"] == "rotor/stop"


def test_home_assistant_birth_brings_the_state_again(rig: Rig) -> None:
    rig.add("tower")
    rig.start()
    rig.ready("tower")
    t = time.monotonic()
    rig.probe.publish(f"{PREFIX}/status", "online")  # HA's birth message (not retained)
    for topic in ("rotor/availability", "rotor/state", "rotor/bridge/state", "rotor/status"):
        rig.probe.wait_for(topic, after=t, timeout_s=20)


def test_home_assistant_birth_brings_every_discovery_config_again(rig: Rig) -> None:
    """A broker that replays retained messages only to exact-topic subscriptions (RabbitMQ)
    gives Home Assistant's ``homeassistant/#`` no config after its restart: the bridge sends
    every one again on the birth message, whatever the broker replays."""
    rig.add("tower")
    rig.start()
    rig.ready("tower")
    known = configs(rig.broker.port)
    ha = Probe(rig.broker.port, f"{PREFIX}/#")  # MQTT 3.1.1: retain flag set = a replay
    try:
        rig.probe.publish(f"{PREFIX}/status", "online")  # HA's birth message (not retained)
        for topic, payload in known.items():
            m = ha.wait_for(topic, lambda m: not m.retain)
            assert json.loads(m.payload) == payload
        assert all(m.qos == 1 for t in known for m in ha.on(t) if not m.retain)
    finally:
        ha.close()


def test_removed_rotator_entities_are_cleared(rig: Rig) -> None:
    rig.add("tower")
    rig.add("yagi", model="rotorcard")
    rig.start()
    rig.ready("tower")
    before = configs(rig.broker.port)
    assert any("_r_yagi/" in t for t in before)
    rig.stop()
    rig.rotators = [r for r in rig.rotators if r["id"] == "tower"]
    rig.start()
    wait_until(
        lambda: not any("_r_yagi/" in t for t in configs(rig.broker.port)),
        15,
        "yagi's configs cleared",
    )
    after = configs(rig.broker.port)
    assert any("_r_tower/" in t for t in after)


def test_a_flood_of_foreign_configs_under_the_bridges_node_ids_is_a_few_log_lines(
    rig: Rig, caplog: pytest.LogCaptureFixture, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A client publishing thousands of configs under the bridge's node ids (hostile, or a
    flow gone wrong) wrote two log lines for each: "clearing stale ..." and "... left alone"."""
    monkeypatch.setattr(mqtt_client, "FOREIGN_LOG_S", 1.0)  # the minute between summaries
    rig.add("tower")
    rig.start()
    rig.ready("tower")
    client = rig.app.client if rig.app is not None else None
    assert client is not None
    wait_until(lambda: time.monotonic() - client.connected_at > 1.0, 5, "the first look done")
    node = f"{PREFIX}/sensor/rotorbridge_rotor_r_tower"
    # configs like ours, following this bridge's state (one that follows another bridge's is
    # left alone without a word: publisher.py rule 4)
    junk = b'{"name": "x", "availability": [{"topic": "rotor/bridge/state"}]}'
    flood = 3000
    hostile = Probe(rig.broker.port, "", max_inflight=1000)
    caplog.set_level(logging.INFO)
    caplog.clear()
    try:
        began = time.monotonic()
        for i in range(flood):  # QoS 0 throughout: the broker keeps their order to the bridge
            hostile.client.publish(f"{node}/junk{i}/config", junk, qos=0)
        hostile.client.publish(f"{PREFIX}/status", b"online", qos=0)  # then a marker
        wait_until(lambda: "Home Assistant came online" in caplog.text, 20, "the flood taken")
        took = time.monotonic() - began
        said = [r for r in caplog.records if "junk" in r.getMessage()]
        # a few at once, then one a "minute" (a second here) while the flood lasts: a loaded
        # machine said 7 lines where 5 were asserted
        most = CLEARS_SAID_AT_ONCE + 1 + int(took / mqtt_client.FOREIGN_LOG_S)
        assert 1 <= len(said) <= most, (took, [r.getMessage() for r in said])
        assert "left alone" in said[0].getMessage()
        # a minute later (here: a second) the next one says how many were not logged
        time.sleep(1.1)
        hostile.publish(f"{node}/late/config", junk)
        line = wait_until(
            lambda: next((r for r in caplog.records if "/late/" in r.getMessage()), None), 5
        ).getMessage()
        # every config is either said or counted in a later line (under load the flood can
        # outlast the second, and a line in the middle carries the count since the one before)
        more = re.compile(r"(\d+) more like it not logged")
        counted = [int(m.group(1)) for r in said[1:] if (m := more.search(r.getMessage()))]
        assert more.search(line), line
        assert sum(counted) + int(more.search(line).group(1)) == flood - len(said), line
    finally:
        hostile.close()


def test_discovery_can_be_turned_off(rig: Rig) -> None:
    rig.add("tower")
    from bridge.app import App

    settings = rig.settings.model_copy(
        update={"homeassistant": rig.settings.homeassistant.model_copy(update={"enabled": False})}
    )
    rig.app = App(settings)
    rig.app.start()
    rig.ready("tower")
    assert configs(rig.broker.port) == {}


def test_discovery_turned_off_clears_what_a_run_with_it_on_left(rig: Rig) -> None:
    """Discovery turned off after a run with it on left every config retained: Home Assistant
    kept the bridge's devices for good, each entity unavailable. They are cleared now; a config
    under one of our node ids that follows another bridge's state is left alone
    (homeassistant/publisher.py rules 4 and 6)."""
    rig.add("tower")
    rig.start()
    rig.ready("tower")
    before = configs(rig.broker.port)
    assert len(before) > 20
    foreign = f"{PREFIX}/sensor/rotorbridge_rotor_r_tower/theirs/config"
    theirs = {"name": "x", "availability": [{"topic": "elsewhere/bridge/state"}]}
    rig.probe.publish(foreign, json.dumps(theirs), retain=True)
    rig.stop()
    rig.sections["homeassistant"] = {"enabled": False}
    rig.start()
    rig.ready("tower")
    wait_until(lambda: set(configs(rig.broker.port)) == {foreign}, slow(15), "configs cleared")
    assert configs(rig.broker.port)[foreign] == theirs


def test_killed_bridge_makes_every_entity_unavailable(tmp_path: Path) -> None:
    broker = Mosquitto(tmp_path / "broker").start()
    emu = emulators.start("rotorez", link=str(tmp_path / "tty"), brake_delay_s=1)
    proc = start_bridge(write_config(tmp_path, broker.port, tmp_path / "tty"), tmp_path / "log")
    try:
        probe = Probe(broker.port, "rotor/#")
        probe.wait_value("rotor/availability", "online", timeout_s=20)
        msgs = configs(broker.port)
        assert msgs
        proc.kill()
        proc.wait(slow(5))
        wait_until(
            lambda: retained_snapshot(broker.port, "rotor/#")["rotor/bridge/state"] == b"offline",
            10,
        )
        # HA marks an entity unavailable when any of its availability topics says offline
        # (mode all); every rotator entity lists the bridge state
        for topic, payload in msgs.items():
            topics = [a["topic"] for a in payload.get("availability", [])]
            assert (
                "rotor/bridge/state" in topics or payload["state_topic"] == "rotor/bridge/state"
            ), topic
        probe.close()
    finally:
        if proc.poll() is None:
            proc.kill()
        broker.stop()
        emu.close()
