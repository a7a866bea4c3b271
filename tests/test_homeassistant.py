"""Discovery builders (pure) and the publisher's decisions, checked against HA's rules."""

from __future__ import annotations

import json
import threading

import pytest

from bridge.homeassistant import DiscoveryPublisher, Identity, RotatorInfo, all_configs
from bridge.model import RotatorStatus
from bridge.mqtt.topics import Topics
from bridge.protocols import REGISTRY
from tests.ha_rules import validate


def build(models: dict[str, str], base: str = "rotor", **kw) -> dict[str, dict]:
    roots = {rid: base if len(models) == 1 else f"{base}/{rid}" for rid in models}
    topics = Topics(base, roots)
    infos = [
        RotatorInfo(
            rid,
            rid.title(),
            REGISTRY[m],
            topics.rotator(rid),
            REGISTRY[m].az_min_deg,
            REGISTRY[m].az_max_deg,
            REGISTRY[m].el_min_deg,
            REGISTRY[m].el_max_deg,
            **kw,
        )
        for rid, m in models.items()
    ]
    return {
        t: json.loads(p)
        for t, p in all_configs("homeassistant", Identity(base), topics, infos).items()
    }


@pytest.mark.parametrize("model", ["rotorez", "rotorcard", "dcu1", "rot2prog", "rot1prog", "md01"])
def test_every_message_passes_home_assistants_rules(model: str) -> None:
    for topic, payload in build({"tower": model}).items():
        assert validate(topic, payload) == []


def test_rotorez_message_set_is_exact() -> None:
    node = "homeassistant/{}/rotorbridge_rotor_r_tower/{}/config"
    want = {
        node.format(*p)
        for p in [
            ("sensor", "bearing"),
            ("number", "target_azimuth"),
            ("button", "stop"),
            ("sensor", "state"),
            ("binary_sensor", "moving"),
            ("binary_sensor", "connected"),
            ("sensor", "version"),
            ("switch", "option_endpoint"),
            ("switch", "option_jam"),
            ("switch", "option_overshoot"),
            ("switch", "option_unstick"),
            ("switch", "lock"),
            ("sensor", "last_error"),
        ]
    }
    want.add("homeassistant/binary_sensor/rotorbridge_rotor/connection/config")
    assert set(build({"tower": "rotorez"})) == want


def test_entities_follow_capabilities() -> None:
    dcu = {t.split("/")[3] for t in build({"tower": "dcu1"})}
    assert (
        "bearing" not in dcu
        and "version" not in dcu
        and not any(o.startswith("option_") for o in dcu)
    )
    assert {"target_azimuth", "stop", "lock", "state"} <= dcu
    card = {t.split("/")[3] for t in build({"tower": "rotorcard"})}
    assert "bearing" in card and not any(o.startswith("option_") for o in card)


def test_device_blocks_and_availability() -> None:
    msgs = build({"tower": "rotorez"}, version="1.4S")
    bearing = msgs["homeassistant/sensor/rotorbridge_rotor_r_tower/bearing/config"]
    assert bearing["device"] == {
        "identifiers": ["rotorbridge_rotor_r_tower"],
        "name": "Tower",
        "manufacturer": "Idiom Press",
        "model": "Rotor-EZ",
        "sw_version": "1.4S",
        "via_device": "rotorbridge_rotor",
    }
    assert bearing["availability"] == [
        {"topic": "rotor/bridge/state"},
        {"topic": "rotor/availability"},
    ]
    assert bearing["availability_mode"] == "all"
    assert bearing["unit_of_measurement"] == "°" and bearing["state_class"] == "measurement_angle"
    assert bearing["default_entity_id"] == "sensor.tower_bearing"
    assert bearing["origin"]["name"] == "rotor-bridge"
    # must work while the rotator is unreachable: follow the bridge only
    for obj in ("lock", "connected", "last_error"):
        cfg = next(p for t, p in msgs.items() if t.split("/")[3] == obj)
        assert cfg["availability"] == [{"topic": "rotor/bridge/state"}], obj
    bridge = msgs["homeassistant/binary_sensor/rotorbridge_rotor/connection/config"]
    assert "availability" not in bridge and bridge["state_topic"] == "rotor/bridge/state"


def test_target_number_uses_the_rotator_limits_and_topics() -> None:
    topics = Topics("rotor", {"tower": "rotor"})
    info = RotatorInfo("tower", "Tower", REGISTRY["rotorez"], topics.rotator("tower"), 10, 350)
    msgs = {
        t: json.loads(p) for t, p in all_configs("ha", Identity("rotor"), topics, [info]).items()
    }
    num = msgs["ha/number/rotorbridge_rotor_r_tower/target_azimuth/config"]
    assert (num["min"], num["max"], num["step"]) == (10, 350, 1)
    assert num["command_topic"] == "rotor/target" and "retain" not in num
    sw = msgs["ha/switch/rotorbridge_rotor_r_tower/option_jam/config"]
    assert (sw["command_topic"], sw["state_topic"], sw["entity_category"]) == (
        "rotor/option/jam",
        "rotor/option/jam/state",
        "config",
    )


def test_several_rotators_have_distinct_ids() -> None:
    msgs = build({"tower": "rotorez", "yagi": "rotorcard"})
    uids = [p["unique_id"] for p in msgs.values()]
    assert len(uids) == len(set(uids))
    assert (
        msgs["homeassistant/switch/rotorbridge_rotor_r_yagi/lock/config"]["command_topic"]
        == "rotor/yagi/lock"
    )


class Recorder:
    def __init__(self) -> None:
        self.published: list[tuple[str, str]] = []
        self.cleared: list[str] = []
        self.republished = threading.Event()


def publisher(rec: Recorder, birth_delay_s: float = 0.0) -> DiscoveryPublisher:
    topics = Topics("rotor", {"tower": "rotor"})
    info = RotatorInfo("tower", "Tower", REGISTRY["rotorez"], topics.rotator("tower"), 0, 360)
    return DiscoveryPublisher(
        prefix="homeassistant",
        status_topic="homeassistant/status",
        topics=topics,
        rotators=[info],
        publish_retained=lambda t, p: rec.published.append((t, p)),
        clear_retained=rec.cleared.append,
        republish_state=rec.republished.set,
        birth_delay_s=birth_delay_s,
    )


def test_stale_configs_of_ours_are_cleared_and_others_left_alone() -> None:
    rec = Recorder()
    pub = publisher(rec)
    pub.publish_all()
    ours_gone = "homeassistant/sensor/rotorbridge_rotor_r_oldrotor/bearing/config"
    current = "homeassistant/sensor/rotorbridge_rotor_r_tower/bearing/config"
    foreign = "homeassistant/sensor/0x00124b/temperature/config"
    other_bridge = "homeassistant/sensor/rotorbridge_rotor2_r_x/bearing/config"
    for topic in (ours_gone, current, foreign, other_bridge):
        assert pub.on_message(topic, b'{"x":1}', True) is True
    assert rec.cleared == [ours_gone]
    assert pub.on_message(ours_gone, b"", True) is True  # our own clearing, echoed: nothing more
    assert rec.cleared == [ours_gone]
    assert pub.on_message("rotor/target", b"1", False) is False


def test_version_change_republishes_device_info_once() -> None:
    rec = Recorder()
    pub = publisher(rec)
    pub.publish_all()
    n = len(rec.published)
    pub.on_status("tower", RotatorStatus("tower", version="1.4S"))
    assert len(rec.published) == 2 * n
    assert '"sw_version": "1.4S"' in rec.published[-1][1]
    pub.on_status("tower", RotatorStatus("tower", version="1.4S"))
    assert len(rec.published) == 2 * n


def test_home_assistant_birth_schedules_a_state_republish() -> None:
    rec = Recorder()
    pub = publisher(rec, birth_delay_s=0.01)
    assert pub.on_message("homeassistant/status", b"offline", False) is True
    assert not rec.republished.wait(0.1)
    pub.on_message("homeassistant/status", b"online", False)
    assert rec.republished.wait(5)


def test_az_el_models_get_elevation_entities_with_their_limits() -> None:
    topics = Topics("rotor", {"sat": "rotor"})
    info = RotatorInfo("sat", "Sat", REGISTRY["rot2prog"], topics.rotator("sat"), -180, 540, 0, 90)
    msgs = {
        t: json.loads(p) for t, p in all_configs("ha", Identity("rotor"), topics, [info]).items()
    }
    el = msgs["ha/number/rotorbridge_rotor_r_sat/target_elevation/config"]
    assert (el["min"], el["max"], el["command_topic"]) == (0, 90, "rotor/target/elevation")
    assert (
        msgs["ha/sensor/rotorbridge_rotor_r_sat/elevation/config"]["state_topic"]
        == "rotor/elevation"
    )
    az = msgs["ha/number/rotorbridge_rotor_r_sat/target_azimuth/config"]
    assert (az["min"], az["max"]) == (-180, 540)
