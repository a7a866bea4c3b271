"""``[[groups]]`` (settings/groups.py, settings/ ``_groups``): what a file says becomes the
group the service turns, and every mistake is one line naming its key."""

from __future__ import annotations

from typing import Any

import pytest

from bridge.app import group_of
from bridge.interfaces.mqtt.groups import Group, Member
from bridge.settings import ConfigError, settings_from

ROTATORS = [
    {"id": "upper", "model": "rotorez", "port": "/dev/ttyUSB0"},
    {"id": "lower", "model": "rotorez", "port": "/dev/ttyUSB1"},
]


def load(*groups: dict[str, Any]) -> Any:
    return settings_from({"rotators": [dict(r) for r in ROTATORS], "groups": list(groups)}, {})


def test_a_group_as_the_issue_names_it_and_with_offsets_and_limits() -> None:
    s = load({"id": "stack", "name": "Stack", "rotators": ["upper", "lower"]})
    assert s.group_topic(s.groups[0]) == "rotor/stack"
    assert group_of(s.groups[0]) == Group("stack", "Stack", (Member("upper"), Member("lower")))
    s = load(
        {
            "id": "stack",
            "rotators": ["upper", "lower"],
            "offsets": {"lower": 180},
            "limits": {"upper": [20, 340]},
        }
    )
    assert group_of(s.groups[0]) == Group(
        "stack", "stack", (Member("upper", 0.0, (20.0, 340.0)), Member("lower", 180.0))
    )
    assert load().groups == []


def test_a_rotator_may_be_in_two_groups() -> None:
    both = ["upper", "lower"]
    s = load({"id": "stack", "rotators": both}, {"id": "all", "rotators": both})
    assert [g.id for g in s.groups] == ["stack", "all"]


@pytest.mark.parametrize(
    ("group", "said"),
    [
        ({"rotators": ["upper", "nope"]}, "groups[0].rotators: 'nope' is no rotator's id"),
        ({"rotators": ["upper", "upper"]}, "rotator 'upper' is named twice"),
        ({"rotators": ["upper"]}, "at least two rotators"),
        ({"id": "upper"}, "groups[0].id: 'upper' would share its topic rotor/upper"),
        ({"id": "bridge"}, "groups[0].id: 'bridge' is a word of the bridge's own topics:"),
        ({"id": "track"}, "'track' is a word of the bridge's own topics (the tracking feature's)"),
        ({"id": "spots"}, "'spots' is a word of the bridge's own topics (the dxcluster feature's)"),
        ({"id": "a/b"}, "groups.0.id: must be 1 to 32 lower-case letters"),
        ({"id": "stack\n"}, "groups.0.id: must be 1 to 32 lower-case letters"),
        ({"offsets": {"lowr": 180}}, "offsets.lowr names no member of the group"),
        ({"offsets": {"lower": 360}}, "lower = 360: an offset is 0 to 360"),
        ({"limits": {"upper": [300, 20]}}, "upper = [300, 20]: limits are true bearings"),
        ({"limts": {}}, "groups[0].limts"),
        ({"name": "Stack\n\x1b[31m"}, "groups[0].name: holds U+000A, which MQTT does not carry"),
        ({"name": ""}, "groups[0].name: must be 1..64 characters without blanks at either end"),
    ],
)
def test_every_mistake_names_its_key(group: dict[str, Any], said: str) -> None:
    table = {"id": "stack", "rotators": ["upper", "lower"], **group}
    with pytest.raises(ConfigError) as err:
        load(table)
    assert said.replace("groups.0.", "groups[0].") in str(err.value)


@pytest.mark.parametrize("model", ["prosistel-el", "prosistel-el-a"])  # unit E, or unit A
def test_a_box_made_for_an_elevation_rotor_alone_is_no_member(model: str) -> None:
    """An attack pass: a group of a yagi's Rotor-EZ and its Prosistel elevation box took
    ``G/target 80`` and tilted the elevation rotor to 80 (that box's bearing is its
    elevation). Such a box is refused as a member; an az/el rotator of two boxes is not."""
    rotators = [
        *ROTATORS,
        {"id": "tilt", "model": model, "port": "/dev/ttyUSB2"},
        {
            "id": "sat",
            "azimuth": {"model": "rotorez", "port": "/dev/ttyUSB3"},
            "elevation": {"model": model, "port": "/dev/ttyUSB4"},
        },
    ]
    tower = {"id": "tower", "rotators": ["upper", "tilt"]}
    with pytest.raises(ConfigError) as err:
        settings_from({"rotators": rotators, "groups": [tower]}, {})
    assert (
        f"groups[0].rotators: 'tilt' is a {model} box, whose bearing is an elevation: a "
        "group turns its members in azimuth; leave it out"
    ) in str(err.value)
    both = {"id": "both", "rotators": ["upper", "sat"]}
    assert settings_from({"rotators": rotators, "groups": [both]}, {}).groups[0].id == "both"


@pytest.mark.parametrize("gid", ["Stack", "STACK", "Tower"])
def test_a_group_id_with_capitals_is_refused_as_a_rotator_id_is(gid: str) -> None:
    """An attack pass: a group "Tower" beside a rotator "tower" passed, and its discovery
    asked for number.Tower_target_azimuth, no entity id, which Home Assistant lower-cases to
    the rotator's own number.tower_target_azimuth."""
    with pytest.raises(ConfigError) as err:
        load({"id": gid, "rotators": ["upper", "lower"]})
    assert "groups[0].id: must be 1 to 32 lower-case letters, digits, - or _" in str(err.value)
    assert load({"id": gid.lower(), "rotators": ["upper", "lower"]}).groups[0].id == gid.lower()


def test_a_group_id_used_twice_is_refused() -> None:
    g = {"id": "stack", "rotators": ["upper", "lower"]}
    with pytest.raises(ConfigError, match="group id 'stack' is used twice"):
        load(g, g)


@pytest.mark.parametrize("rid", ["upper\n", "bridge\n"])
def test_a_rotator_id_ending_in_a_newline_is_refused(rid: str) -> None:
    """A newline is no letter of a topic level: ``$`` matched before a final one, so a TOML
    ``id = "bridge\\n"`` passed as a slug (and as not 'bridge') into every topic of it."""
    rotators = [{**ROTATORS[0], "id": rid}, ROTATORS[1]]
    with pytest.raises(ConfigError, match=r"rotators\[0\]\.id: .*short slug"):
        settings_from({"rotators": rotators}, {})


AT_BASE = {"topic": "rotor"}


@pytest.mark.parametrize(
    ("upper", "lower", "said"),
    [
        # rotor/bridge/state is the bridge's own (every entity's availability): the rotator's
        # "moving" went there
        (
            {"topic": "rotor/bridge"},
            {},
            "rotators[0].topic: its topic rotor/bridge lies under "
            "rotor (of the bridge), where 'bridge' is a word of the bridge's own topics",
        ),
        (
            {"topic": "rotor/spots"},
            {},
            "rotators[0].topic: its topic rotor/spots lies under rotor (of the bridge)",
        ),
        # under a rotator at the base topic: rotor/target/elevation, the one's reading and the
        # other's command
        (
            {"id": "target"},
            AT_BASE,
            "rotators[0].id: its topic rotor/target lies under rotor (of rotator 'lower')",
        ),
        (
            {"topic": "rotor/option/x"},
            AT_BASE,
            "where 'option' is a word of the bridge's own topics",
        ),
    ],
)
def test_a_rotators_topic_takes_no_word_of_the_topics_it_lies_under(
    upper: dict[str, Any], lower: dict[str, Any], said: str
) -> None:
    rotators = [{**ROTATORS[0], **upper}, {**ROTATORS[1], **lower}]
    with pytest.raises(ConfigError) as err:
        settings_from({"rotators": rotators}, {})
    assert said in str(err.value)


def test_a_rotators_topic_may_lie_under_another_by_a_word_of_its_own() -> None:
    rotators = [{**ROTATORS[0], "topic": "shack/2m"}, {**ROTATORS[1], "topic": "shack"}]
    s = settings_from({"rotators": rotators}, {})
    assert [s.rotator_topic(r) for r in s.rotators] == ["shack/2m", "shack"]


@pytest.mark.parametrize(
    ("upper", "said"),
    [
        # its R/status on Home Assistant's birth topic, its readings among the discovery's
        (
            {"topic": "homeassistant"},
            "rotators[0].topic: its topic homeassistant lies under "
            "homeassistant.discovery_prefix homeassistant",
        ),
        ({"topic": "homeassistant/tower"}, "lies under homeassistant.discovery_prefix"),
        (
            {"topic": "ha"},
            "rotators[0].topic: homeassistant.status_topic ha/status lies under its topic ha",
        ),
    ],
)
def test_a_rotators_topic_keeps_off_home_assistants(upper: dict[str, Any], said: str) -> None:
    rotators = [{**ROTATORS[0], **upper}, ROTATORS[1]]
    ha = {"status_topic": "ha/status"} if upper["topic"] == "ha" else {}
    with pytest.raises(ConfigError) as err:
        settings_from({"rotators": rotators, "homeassistant": {"enabled": True, **ha}}, {})
    assert said in str(err.value)
    settings_from({"rotators": rotators, "homeassistant": {**ha, "enabled": False}}, {})
