"""Home Assistant discovery for a rotator of two boxes (homeassistant/ rule 7, entities.py):
one device, its version entity and ``sw_version`` its ``R/version`` (its boxes' versions
joined, azimuth first), the entity named for the boxes whose versions it shows."""

from __future__ import annotations

import json
from typing import Any

import pytest

from bridge.interfaces.homeassistant import Identity, RotatorInfo, all_configs
from bridge.interfaces.mqtt.topics import Topics
from bridge.protocols.axes import Axis
from bridge.settings import settings_from
from tests.ha_rules import validate

VERSION = "homeassistant/sensor/rotorbridge_rotor_r_sky/version/config"
BEARING = "homeassistant/sensor/rotorbridge_rotor_r_sky/bearing/config"


def discovery(az: str, el: str, version: str | None = None) -> dict[str, dict[str, Any]]:
    """The discovery messages of one rotator of two boxes, configured as a user would."""
    document = {
        "rotators": [
            {
                "id": "sky",
                "azimuth": {"model": az, "port": "/dev/ttyAZ"},
                "elevation": {"model": el, "port": "/dev/ttyEL"},
            }
        ]
    }
    r = settings_from(document, environ={}).rotators[0]
    topics = Topics("rotor", {"sky": "rotor"})
    info = RotatorInfo.of(
        "sky",
        "Sky",
        r.spec,
        topics.rotator("sky"),
        r.pointing,
        has_station=False,
        nudge_step_deg=r.nudge_step_deg,
        boxes=tuple(r.axis_spec(axis) for axis in Axis),
        version=version,
    )
    msgs = all_configs("homeassistant", Identity("rotor"), topics, [info])
    return {t: json.loads(p) for t, p in msgs.items()}


@pytest.mark.parametrize(
    ("az", "el", "name"),
    [
        ("rotorez", "satel", "Controller versions (azimuth / elevation)"),
        ("rotorez", "gs232b", "Azimuth controller version"),
        ("rt21", "satel", "Elevation controller version"),
        ("easycomm3-az", "easycomm3", "Controller versions (azimuth / elevation)"),
    ],
)
def test_a_rotator_of_two_boxes_has_a_version_entity_named_for_the_boxes_it_shows(
    az: str, el: str, name: str
) -> None:
    msgs = discovery(az, el, version="1.4S / SatEL")
    version = msgs[VERSION]
    assert version["name"] == name
    assert version["state_topic"] == "rotor/version"
    assert version["entity_category"] == "diagnostic"
    # the device's firmware is R/version's text, on every entity of the one device
    assert {m["device"].get("sw_version") for m in msgs.values() if "_r_sky" in m["unique_id"]} == {
        "1.4S / SatEL"
    }
    for topic, payload in msgs.items():
        assert validate(topic, payload) == []


def test_two_boxes_neither_of_which_reports_a_version_have_no_version_entity() -> None:
    msgs = discovery("rt21", "gs232b")
    assert VERSION not in msgs and "sw_version" not in msgs[BEARING]["device"]


def test_a_single_controllers_version_entity_keeps_its_name() -> None:
    document = {"rotators": [{"id": "sky", "model": "rotorez", "port": "/dev/ttyAZ"}]}
    r = settings_from(document, environ={}).rotators[0]
    topics = Topics("rotor", {"sky": "rotor"})
    info = RotatorInfo.of(
        "sky", "Sky", r.spec, topics.rotator("sky"), r.pointing,
        has_station=False, nudge_step_deg=r.nudge_step_deg,
    )  # fmt: skip
    msgs = all_configs("homeassistant", Identity("rotor"), topics, [info])
    assert json.loads(msgs[VERSION])["name"] == "Controller version"
