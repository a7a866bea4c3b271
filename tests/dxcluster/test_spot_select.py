"""Home Assistant's spot select (features/dxcluster, interfaces/homeassistant/info.py): there with
[dxcluster] and a station only, the newest spots' calls as options (bounded, never none), sending
the call form of R/target, and following the spots when the client hands new calls."""

from __future__ import annotations

import json

from bridge.interfaces.homeassistant import DiscoveryPublisher, Identity, RotatorInfo, all_configs
from bridge.interfaces.homeassistant.info import MAX_SPOTS, NO_SPOTS
from bridge.interfaces.mqtt.payloads import parse_aim
from bridge.interfaces.mqtt.topics import Topics
from bridge.settings import RotatorSettings
from tests.ha_rules import validate

TOPIC = "homeassistant/select/rotorbridge_rotor_r_tower/spot/config"


def info(dxcluster: bool, station: bool = True) -> RotatorInfo:
    cfg = RotatorSettings(id="tower", model="rotorez", port="/dev/ttyUSB0")
    topics = Topics("rotor", {"tower": "rotor"})
    return RotatorInfo.of(
        "tower", "Tower", cfg.spec, topics.rotator("tower"), cfg.pointing,
        has_station=station, nudge_step_deg=cfg.nudge_step_deg,
        features=frozenset({"dxcluster"} if dxcluster else ()),
    )  # fmt: skip


def configs(r: RotatorInfo) -> dict[str, dict[str, object]]:
    topics = Topics("rotor", {"tower": "rotor"})
    msgs = all_configs("homeassistant", Identity("rotor"), topics, [r])
    return {t: json.loads(p) for t, p in msgs.items()}


def test_the_select_is_there_only_with_the_cluster_and_a_station() -> None:
    assert TOPIC not in configs(info(False))
    assert TOPIC not in configs(info(True, station=False))
    sel = configs(info(True))[TOPIC]
    assert sel["options"] == [NO_SPOTS]  # Home Assistant needs one option at least
    assert sel["command_topic"] == "rotor/target"
    assert validate(TOPIC, sel) == []


def test_its_options_are_bounded_and_it_sends_the_call_form() -> None:
    calls = tuple(f"JA1A{i:02d}" for i in range(MAX_SPOTS + 15))
    sel = configs(info(True).with_spot_calls(calls))[TOPIC]
    assert sel["options"] == list(calls[:MAX_SPOTS])
    assert validate(TOPIC, sel) == []
    template = str(sel["command_template"])
    sent = template.replace("{{ value }}", "JA1A00").encode()  # what Home Assistant renders
    assert parse_aim(sent).call == "JA1A00"  # type: ignore[union-attr]
    assert info(False).with_spot_calls(calls).spot_options == ()  # no select, none added


def test_the_publisher_follows_the_calls_it_is_handed() -> None:
    sent: list[tuple[str, str]] = []
    topics = Topics("rotor", {"tower": "rotor"})
    pub = DiscoveryPublisher(
        prefix="homeassistant",
        status_topic="homeassistant/status",
        topics=topics,
        rotators=[info(True)],
        publish_retained=lambda t, p: sent.append((t, p)),
        clear_retained=lambda t: None,
        republish_state=lambda: None,
        birth_delay_s=0.0,
    )
    pub.publish_all()
    sent.clear()
    pub.set_spot_calls(("JA1ABC", "VK2XYZ"))
    pub.set_spot_calls(("JA1ABC", "VK2XYZ"))  # unchanged: nothing more
    options = [json.loads(p)["options"] for t, p in sent if t == TOPIC]
    assert options == [["JA1ABC", "VK2XYZ"]]
