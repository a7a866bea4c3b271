"""A group's Home Assistant device (interfaces/homeassistant/entities.py rule 1, GROUP_ENTITIES):
its target number and stop button publish on the group's own topics, its sensors read
``G/status``, every config passes Home Assistant's discovery rules, and the bridge owns the
group's node (stale configs of a group removed from the file are deleted like a rotator's)."""

from __future__ import annotations

import json

from bridge.interfaces.homeassistant.entities import all_configs
from bridge.interfaces.homeassistant.info import GroupInfo, Identity
from bridge.interfaces.mqtt.topics import Topics
from tests.ha_rules import validate

TOPICS = Topics("rotor", {"upper": "rotor/upper", "lower": "rotor/lower"}, {"stack": "rotor/stack"})
STACK = GroupInfo("stack", "Stacked yagis", TOPICS.group("stack"), ("upper", "lower"))


def test_a_group_is_a_device_with_its_target_its_stop_and_its_state() -> None:
    ident = Identity("rotor")
    configs = all_configs("homeassistant", ident, TOPICS, [], (STACK,))
    node = ident.group_node("stack")
    mine = {t: json.loads(p) for t, p in configs.items() if f"/{node}/" in t}
    for topic, payload in mine.items():
        assert validate(topic, payload) == [], topic
    target = mine[f"homeassistant/number/{node}/target_azimuth/config"]
    stop = mine[f"homeassistant/button/{node}/stop/config"]
    assert target["command_topic"] == "rotor/stack/target" and target["max"] == 360
    assert stop["command_topic"] == "rotor/stack/stop"
    assert stop["availability"] == [{"topic": "rotor/bridge/state"}]  # a stop: always
    assert {"topic": "rotor/stack/availability"} in target["availability"]
    assert target["device"]["name"] == "Stacked yagis"
    state = mine[f"homeassistant/sensor/{node}/state/config"]
    assert state["state_topic"] == "rotor/stack/status"
    assert ident.owns(node)


def test_a_group_whose_id_is_only_dashes_and_underscores_asks_for_entity_ids_ha_writes() -> None:
    """The settings take a group id of '-' and '_' only (settings/groups.py: [a-z0-9_-]); its
    slug is empty (core/text.py entity_slug), and the entity ids asked for were
    ``button._stop`` and ``number._target_azimuth``, which no entity id may be (a leading '_':
    Home Assistant's valid_entity_id). A review of 9f5dd5a."""
    for gid in ("-", "_", "_-_"):
        topics = Topics("rotor", {"upper": "rotor/upper", "lower": "rotor/lower"}, {gid: "rotor/g"})
        group = GroupInfo(gid, "G", topics.group(gid), ("upper", "lower"))
        configs = all_configs("homeassistant", Identity("rotor"), topics, [], (group,))
        for topic, payload in configs.items():
            assert validate(topic, json.loads(payload)) == [], (gid, topic)
