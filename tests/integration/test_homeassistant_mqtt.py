"""Home Assistant discovery through a real broker: what HA would receive, and how it reacts."""

from __future__ import annotations

import json
import logging
import math
import re
import time
from pathlib import Path

import pytest

from bridge import emulators
from bridge.interfaces.homeassistant.publisher import ROUND_MIN_S
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


def _rounds(ha: Probe) -> dict[str, list[object]]:
    """Each discovery config sent live (not a replay) since the probe subscribed: the device's
    ``sw_version`` in each, in order."""
    sent: dict[str, list[object]] = {}
    for m in ha.messages:
        if m.topic.startswith(f"{PREFIX}/") and m.topic.endswith("/config") and not m.retain:
            sent.setdefault(m.topic, []).append(json.loads(m.payload)["device"].get("sw_version"))
    return sent


def _restarted(rig: Rig, ha: Probe) -> None:
    """The bridge started again and ready; every config it published for the controller's
    answer has reached ``ha``: a refusal it published after (QoS 1, as the configs are) came.
    What the last run sent is taken first: none of it passes for this run's."""
    t = rig.probe.caught_up()
    ha.caught_up()
    ha.messages.clear()
    rig.start()
    rig.ready("tower", after=t)
    rig.probe.publish("rotor/target", "999")
    ha.wait_for("rotor/error")


def test_a_restart_with_the_same_firmware_sends_each_config_once(rig: Rig) -> None:
    """The version the controller reported last is kept (runtime/kept.py rule 11): a restart
    sent each config twice, first without ``sw_version``, then again when the controller
    answered; now once, with it. Another firmware sends them again at once, with the new one
    (never the kept one after it)."""
    emu = rig.add("tower")
    rig.start()
    rig.ready("tower")
    bearing = f"{PREFIX}/sensor/rotorbridge_rotor_r_tower/bearing/config"
    wait_until(lambda: configs(rig.broker.port)[bearing]["device"].get("sw_version") == "1.4S", 10)
    rig.stop()
    ha = Probe(rig.broker.port, f"{PREFIX}/#|rotor/error|rotor/version")
    try:
        _restarted(rig, ha)
        sent = _rounds(ha)
        assert sent[bearing] == ["1.4S"]
        assert all(len(versions) == 1 for versions in sent.values()), sent
        assert [m.text for m in ha.on("rotor/version") if not m.retain] == ["1.4S"]
        rig.stop()
        with emu.lock:  # the controller's firmware updated while the bridge was down
            emu.device.version, emu.device.banner = "1.5S", b"C2000 IDIOM V1.5S "
        _restarted(rig, ha)
        sent = _rounds(ha)
        ours = {t: v for t, v in sent.items() if "_r_tower/" in t}
        # the kept version's round, then the new one's; or the new one's alone when the
        # controller answered before the bridge reached the broker (a loaded host)
        assert ours and all(v in (["1.4S", "1.5S"], ["1.5S"]) for v in ours.values()), ours
        assert all(len(v) == 1 for t, v in sent.items() if t not in ours), sent
        assert configs(rig.broker.port)[bearing]["device"]["sw_version"] == "1.5S"
    finally:
        ha.close()


def test_the_kept_version_is_said_while_the_controller_is_unplugged_and_never_another_models(
    rig: Rig,
) -> None:
    """Unplugged at the start, the controller cannot say its version: the configs and
    ``R/version`` say the one it reported last. Its model changed in the configuration (the
    controller swapped), nothing is claimed for it: ``R/version`` is cleared, no ``sw_version``."""
    emu = rig.add("tower")
    rig.start()
    rig.ready("tower")
    bearing = f"{PREFIX}/sensor/rotorbridge_rotor_r_tower/bearing/config"
    wait_until(lambda: configs(rig.broker.port)[bearing]["device"].get("sw_version") == "1.4S", 10)
    rig.stop()
    emu.unplug()
    ha = Probe(rig.broker.port, f"{PREFIX}/#|rotor/version")
    try:
        rig.start()
        ha.wait_for(bearing, lambda m: not m.retain)
        assert _rounds(ha)[bearing] == ["1.4S"]
        assert rig.retained()["rotor/version"] == b"1.4S"
        rig.stop()
        rig.rotators[0]["model"] = "rotorcard"  # another controller, not plugged in yet
        ha.caught_up()  # (the first run's configs, all of them, before the clear)
        ha.messages.clear()
        rig.start()
        ha.wait_for("rotor/version", lambda m: not m.retain and m.payload == b"")
        assert "rotor/version" not in rig.retained()
        m = ha.wait_for(bearing, lambda m: not m.retain)
        assert "sw_version" not in json.loads(m.payload)["device"]
    finally:
        ha.close()


def test_a_controller_flooding_versions_costs_home_assistant_a_round_a_hold(rig: Rig) -> None:
    """homeassistant/ rule 9 through the broker: an Easycomm III box sending ``VE<n>`` lines
    on its own (its version is taken whenever it comes) had its rotator's every config sent
    again for each (200 lines, over 4000 configs); now a round at once and the latest when
    the hold ends, and the state file keeps the latest (runtime/kept.py rule 11)."""
    emu = rig.add("tower", model="easycomm3", emu={"version": "1.0"})
    rig.start()
    rig.ready("tower")
    rig.probe.wait_value("rotor/version", "1.0")
    bearing = f"{PREFIX}/sensor/rotorbridge_rotor_r_tower/bearing/config"
    ha = Probe(rig.broker.port, f"{PREFIX}/#")
    try:
        t = time.monotonic()
        for i in range(60):  # each one taken (its R/version came) before the next is sent
            line = f"VE{i}\n".encode()  # (behind a reply on the line: inject broke into one)
            emu.call(lambda device, now, line=line: device.transmit(line, now))
            rig.probe.wait_value("rotor/version", str(i))
        # a round at once (the start's, then the first of the flood's) and one a hold at most
        most = 2 + math.ceil((time.monotonic() - t) / ROUND_MIN_S)
        ha.wait_for(bearing, lambda m: not m.retain and b'"59"' in m.payload, timeout_s=10)
        sent = _rounds(ha)
        assert len(sent[bearing]) <= most and sent[bearing][-1] == "59", sent[bearing]
        assert all(len(v) <= most for v in sent.values()), {t: len(v) for t, v in sent.items()}
        rig.stop()  # (its writer done: every save queued is written)
        kept = json.loads((rig.tmp / "state.json").read_text())["rotators"]["tower"]
        assert kept["version"] == {"model": "easycomm3", "text": "59"}
    finally:
        ha.close()
