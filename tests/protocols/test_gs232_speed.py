"""The GS-232's speed as a controller setting: one encoder in its codec, one spec entry
(protocols/gs232.py). Its bytes, what it refuses, and its Home Assistant select."""

from __future__ import annotations

import json

import pytest

from bridge.core.model import Origin, SetOption, Source
from bridge.interfaces.homeassistant import Identity, RotatorInfo, all_configs
from bridge.interfaces.mqtt import payloads as pl
from bridge.interfaces.mqtt.service import parse_command
from bridge.interfaces.mqtt.topics import Topics
from bridge.protocols import REGISTRY
from bridge.protocols.base import SendWhen, SettingKind
from tests.ha_rules import validate

GS232 = [name for name in REGISTRY if name.startswith("gs232")]
BY = Origin(Source.MQTT)


@pytest.mark.parametrize("model", GS232)
def test_every_gs232_model_has_the_speed_as_x1_to_x4(model: str) -> None:
    speed = REGISTRY[model].setting("speed")
    assert speed is not None and speed.kind is SettingKind.CHOICE
    assert [speed.encode(speed.read(n)) for n in "1234"] == [b"X1\r", b"X2\r", b"X3\r", b"X4\r"]
    assert speed.when is SendWhen.ANYTIME and speed.resend  # the box forgets it at power-off
    assert [speed.speed_factor(n) for n in "1234"] == [0.25, 0.5, 0.75, 1.0]


def test_r_option_speed_is_read_by_the_declaration_and_a_bad_value_refused() -> None:
    spec = REGISTRY["gs232b"]
    assert parse_command("option", "speed", b"2", BY, spec) == SetOption("speed", "2", origin=BY)
    for bad, words in [(b"9", "'9' is not one of 1, 2, 3, 4"), (b"ON", "'ON' is not one of")]:
        with pytest.raises(pl.PayloadError, match=words):
            parse_command("option", "speed", bad, BY, spec)


def test_the_speed_is_a_home_assistant_select() -> None:
    topics = Topics("rotor", {"tower": "rotor"})
    spec = REGISTRY["gs232b"]
    info = RotatorInfo("tower", "Tower", spec, topics.rotator("tower"), 0.0, 360.0, 0.0, 180.0)
    msgs = {
        t: json.loads(p) for t, p in all_configs("ha", Identity("rotor"), topics, [info]).items()
    }
    sel = msgs["ha/select/rotorbridge_rotor_r_tower/option_speed/config"]
    assert sel["options"] == ["1", "2", "3", "4"] and sel["entity_category"] == "config"
    assert (sel["command_topic"], sel["state_topic"]) == (
        "rotor/option/speed",
        "rotor/option/speed/state",
    )
    for topic, payload in msgs.items():
        assert validate(topic, payload, prefix="ha") == []


def test_r_info_says_what_the_speed_takes() -> None:
    """A client far from the station (Node-RED, the remote) learns the choices from R/info."""
    from bridge.interfaces.mqtt.payloads import info_json
    from bridge.pointing import Pointing

    spec = REGISTRY["gs232b"]
    doc = json.loads(info_json("Tower", spec, Pointing.of(spec), False))
    assert doc["options"] == ["speed"]
    assert doc["settings"] == [
        {
            "name": "speed",
            "label": "Speed (1 slowest, 4 fastest)",
            "kind": "choice",
            "choices": ["1", "2", "3", "4"],
        }
    ]
