"""Discovery builders (pure) and the publisher's decisions, checked against HA's rules."""

from __future__ import annotations

import dataclasses
import json
import logging
import re
import threading
import time
from collections.abc import Callable
from datetime import datetime

import pytest

from bridge.core import geo
from bridge.core.model import FollowingInfo, MotionState, RotatorStatus, TrackingInfo
from bridge.features.follow import follow_state
from bridge.features.tracking import tracking_state
from bridge.interfaces.homeassistant import (
    ENTITIES,
    MAX_SATELLITES,
    DiscoveryPublisher,
    Entity,
    Identity,
    RotatorInfo,
    all_configs,
)
from bridge.interfaces.homeassistant.publisher import ROUND_MIN_S
from bridge.interfaces.mqtt.payloads import parse_follow, parse_nudge, parse_track, status_json
from bridge.interfaces.mqtt.topics import Topics
from bridge.protocols import REGISTRY
from bridge.protocols.base import ModelSpec
from bridge.settings import RotatorSettings
from tests.ha_rules import number_state, validate
from tests.support.waiting import slow, wait_until


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
            ("button", "nudge_ccw"),
            ("button", "nudge_cw"),
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
            ("sensor", "speed_cw"),
            ("sensor", "speed_ccw"),
            ("sensor", "start_delay"),
            ("sensor", "coast"),
            ("sensor", "odometer"),
            ("sensor", "moves"),
            ("sensor", "stalls"),
            ("sensor", "motor_on"),
            ("binary_sensor", "health_problem"),
            ("button", "health_reset"),
            ("sensor", "control"),
            ("button", "release_control"),
            ("sensor", "last_operator"),
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
    # must work while the rotator is unreachable: follow the bridge only (the stop too: a stop
    # is never refused, one for a rotator that does not answer is owed and sent first when it
    # answers again; a button that went unavailable with the rotator left Home Assistant's user
    # no stop while the link flapped, and an automation's button.press skipped it silently)
    for obj in ("stop", "lock", "connected", "last_error"):
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
    # every true bearing the status shows is in range, whatever the limits (a number drops a
    # state outside it)
    assert (num["min"], num["max"], num["step"]) == (0, 360, 1)
    assert num["command_topic"] == "rotor/target" and "retain" not in num
    sw = msgs["ha/switch/rotorbridge_rotor_r_tower/option_jam/config"]
    assert (sw["command_topic"], sw["state_topic"], sw["entity_category"]) == (
        "rotor/option/jam",
        "rotor/option/jam/state",
        "config",
    )


@pytest.mark.parametrize("base", ["rotor", "home/rotor-1", "Shack/Rotor", "rotor_"])
@pytest.mark.parametrize("rid", ["tower", "tower-", "tow--er", "tow_-er", "2m_"])
def test_every_entity_id_asked_for_is_one_home_assistant_takes(base: str, rid: str) -> None:
    """An id the settings take ("tower-", "tow--er") or a base topic with '-', '/' or capitals
    asked for an entity id Home Assistant does not write ("sensor.tower__bearing",
    "binary_sensor.rotorbridge_home_rotor-1_connection"): it made "sensor.tower_bearing" of the
    first, the entity of a rotator "tower" beside it."""
    msgs = build({rid: "rot2prog"}, base=base)
    for topic, payload in msgs.items():
        assert validate(topic, payload) == [], topic


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
        self.rounds = 0  # states sent again
        self.again: list[tuple[str, str]] = []  # configs sent again on a birth
        self.sent_again = threading.Event()

    def republish(self) -> None:
        self.rounds += 1
        self.republished.set()

    def publish_again(self, topic: str, payload: str) -> None:
        self.again.append((topic, payload))
        self.sent_again.set()


def publisher(
    rec: Recorder,
    birth_delay_s: float = 0.0,
    info: RotatorInfo | None = None,
    clock: Callable[[], float] = time.monotonic,
) -> DiscoveryPublisher:
    topics = Topics("rotor", {"tower": "rotor"})
    info = info or RotatorInfo(
        "tower", "Tower", REGISTRY["rotorez"], topics.rotator("tower"), 0, 360
    )
    return DiscoveryPublisher(
        prefix="homeassistant",
        status_topic="homeassistant/status",
        topics=topics,
        rotators=[info],
        publish_retained=lambda t, p: rec.published.append((t, p)),
        clear_retained=rec.cleared.append,
        republish_state=rec.republish,
        birth_delay_s=birth_delay_s,
        publish_again=rec.publish_again,
        clock=clock,
    )


def test_stale_configs_of_ours_are_cleared_and_others_left_alone() -> None:
    rec = Recorder()
    pub = publisher(rec)
    pub.publish_all()
    ours_gone = "homeassistant/sensor/rotorbridge_rotor_r_oldrotor/bearing/config"
    current = "homeassistant/sensor/rotorbridge_rotor_r_tower/bearing/config"
    foreign = "homeassistant/sensor/0x00124b/temperature/config"
    other_bridge = "homeassistant/sensor/rotorbridge_rotor2_r_x/bearing/config"
    # a bridge whose base topic is "rotor/r/x": its node ids begin with ours, "rotorbridge_rotor_r_"
    # (it was cleared, its entities gone from Home Assistant each time it published them)
    under_ours = "homeassistant/sensor/rotorbridge_rotor_r_x_r_tower/bearing/config"
    ours = json.dumps({"availability": [{"topic": "rotor/bridge/state"}, {"topic": "rotor/x"}]})
    theirs = json.dumps({"availability": [{"topic": "rotor/r/x/bridge/state"}]})
    for topic in (ours_gone, current, foreign, other_bridge):
        assert pub.on_message(topic, ours.encode(), True) is True
    assert pub.on_message(under_ours, theirs.encode(), True) is True
    assert pub.on_message(under_ours, b"not json", True) is True
    # JSON nested past the parser's depth, retained by anyone: no config of ours, and no
    # RecursionError's traceback in the log at every connect
    assert pub.on_message(under_ours, b"[" * 100_000, True) is True
    assert pub.on_message(current, b'{"a":' * 100_000, True) is True
    # the bridge device's own config follows the bridge's state by its state topic
    old_bridge = "homeassistant/binary_sensor/rotorbridge_rotor/old/config"
    assert pub.on_message(old_bridge, b'{"state_topic": "rotor/bridge/state"}', True) is True
    assert rec.cleared == [ours_gone, old_bridge]
    assert pub.on_message(ours_gone, b"", True) is True  # our own clearing, echoed: nothing more
    assert rec.cleared == [ours_gone, old_bridge]
    assert pub.on_message("rotor/target", b"1", False) is False


def test_another_bridge_on_our_own_config_topics_is_said_once(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """Base topics "shack/rotor" and "shack_rotor" are one node id (rotorbridge_shack_rotor):
    two such bridges overwrite each other's configs, their entities flipping between them at
    each start and each birth, and nothing said why."""
    rec = Recorder()
    pub = publisher(rec)
    pub.publish_all()
    topic = "homeassistant/sensor/rotorbridge_rotor_r_tower/bearing/config"
    mine = dict(rec.published)[topic]
    caplog.set_level(logging.WARNING)
    assert pub.on_message(topic, mine.encode(), True) is True  # our own, echoed: nothing said
    twin = json.loads(mine)
    twin["availability"] = [{"topic": "ro/tor/bridge/state"}, {"topic": "ro/tor/availability"}]
    for _ in range(3):
        assert pub.on_message(topic, json.dumps(twin).encode(), True) is True
    said = [r for r in caplog.records if "another bridge" in r.getMessage()]
    assert len(said) == 1 and topic in said[0].getMessage()
    assert rec.cleared == []  # it is one of ours: nothing cleared


def test_version_change_republishes_device_info_once() -> None:
    rec = Recorder()
    pub = publisher(rec)
    pub.publish_all()
    n = len(rec.published)
    pub.on_status("tower", RotatorStatus("tower", version="1.4S"))
    assert '"sw_version": "1.4S"' in rec.published[-1][1]
    after = len(rec.published)
    pub.on_status("tower", RotatorStatus("tower", version="1.4S"))
    assert len(rec.published) == after and n < after <= 2 * n


def test_a_version_hands_on_only_its_rotators_configs_and_the_broker_gets_them_all() -> None:
    """With several rotators, a controller's version rebuilds its own rotator's configs only (all
    of them, once per rotator, was a tenth of a start-up's CPU); what the broker holds is
    every config with every version, as if all were built again."""
    topics = Topics("rotor", {"a": "rotor/a", "b": "rotor/b"})
    infos = [
        RotatorInfo(rid, rid.upper(), REGISTRY["rotorez"], topics.rotator(rid), 0, 360)
        for rid in ("a", "b")
    ]
    rec = Recorder()
    pub = DiscoveryPublisher(
        prefix="homeassistant",
        status_topic="homeassistant/status",
        topics=topics,
        rotators=infos,
        publish_retained=lambda t, p: rec.published.append((t, p)),
        clear_retained=rec.cleared.append,
        republish_state=rec.republished.set,
    )
    pub.publish_all()
    start = len(rec.published)
    pub.on_status("a", RotatorStatus("a", version="1.4S"))
    handed = [t for t, _ in rec.published[start:]]
    assert handed and all("_r_a" in t for t in handed)
    pub.on_status("b", RotatorStatus("b", version="2.0"))
    versioned = [
        dataclasses.replace(infos[0], version="1.4S"),
        dataclasses.replace(infos[1], version="2.0"),
    ]
    held = dict(rec.published)
    assert held == all_configs("homeassistant", Identity("rotor"), topics, versioned)
    current = "homeassistant/sensor/rotorbridge_rotor_r_b/bearing/config"
    assert pub.on_message(current, b'{"x":1}', True) and rec.cleared == []


def test_a_birth_sends_every_config_again_once_per_delay() -> None:
    rec = Recorder()
    pub = publisher(rec, birth_delay_s=30)  # the state waits longer than this test
    pub.publish_all()
    pub.on_message("homeassistant/status", b"online", False)
    wait_until(lambda: len(rec.again) == len(rec.published), 5, "every config again")
    assert rec.again == rec.published
    rec.sent_again.clear()
    pub.on_message("homeassistant/status", b"online", False)  # within the delay: no more
    assert not rec.sent_again.wait(0.2)  # a quiet period, not a deadline
    pub.stop()
    assert len(rec.again) == len(rec.published)


def test_a_flood_of_births_neither_pushes_the_state_back_nor_multiplies_it(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """Births while a round's delay runs start nothing at once: the state goes out the delay
    after the first of them, however long they go on (each used to start the delay again), and
    the births during it get one round of their own after it, said in one line that counts
    them."""
    caplog.set_level(logging.INFO)
    rec = Recorder()
    pub = publisher(rec, birth_delay_s=0.2)
    pub.publish_all()
    deadline = time.monotonic() + slow(10)
    births = 0
    while not rec.republished.is_set() and time.monotonic() < deadline:
        pub.on_message("homeassistant/status", b"online", False)
        births += 1
    assert rec.republished.is_set(), f"no state after {births} births"
    wait_until(lambda: rec.rounds == 2, slow(10), "the round of the births during the first")
    wait_until(lambda: len(rec.again) == 2 * len(rec.published), slow(5), "its configs")
    pub.stop()
    assert rec.rounds == 2
    said = [
        r.getMessage() for r in caplog.records if "Home Assistant came online" in r.getMessage()
    ]
    assert len(said) == 2 and f"({births - 1} more birth messages" in said[1], said


def test_a_home_assistant_that_restarts_during_a_round_gets_a_round_of_its_own() -> None:
    """A birth during another's delay (a forged one first, or two restarts close together):
    the later Home Assistant still gets every config and then the state, a round after it."""
    rec = Recorder()
    pub = publisher(rec, birth_delay_s=0.2)
    pub.publish_all()
    pub.on_message("homeassistant/status", b"online", False)
    pub.on_message("homeassistant/status", b"online", False)  # the real restart, meanwhile
    wait_until(lambda: rec.rounds == 2, slow(10), "a second round")
    wait_until(lambda: len(rec.again) == 2 * len(rec.published), slow(5), "configs twice")
    pub.stop()
    assert rec.rounds == 2


def test_with_no_birth_delay_a_flood_of_births_costs_one_round_per_interval() -> None:
    """``birth_delay_s = 0`` sends the state at once; a round (every config, the state) still
    comes at most once per ROUND_MIN_S: 500 births cost one, not 500 (10 MB of configs)."""
    now = [1000.0]
    rec = Recorder()
    pub = publisher(rec, birth_delay_s=0.0, clock=lambda: now[0])
    pub.publish_all()
    for _ in range(500):
        pub.on_message("homeassistant/status", b"online", False)
        wait_until(lambda: rec.rounds >= 1, slow(5), "the first round's state")
    wait_until(lambda: len(rec.again) == len(rec.published), slow(5), "every config again")
    assert rec.rounds == 1 and len(rec.again) == len(rec.published)
    now[0] += ROUND_MIN_S
    pub.on_message("homeassistant/status", b"online", False)
    wait_until(lambda: rec.rounds == 2, slow(5), "the next interval's round")
    wait_until(lambda: len(rec.again) == 2 * len(rec.published), slow(5), "its configs")
    pub.stop()


def test_home_assistant_birth_schedules_a_state_republish() -> None:
    rec = Recorder()
    pub = publisher(rec, birth_delay_s=0.01)
    assert pub.on_message("homeassistant/status", b"offline", False) is True
    assert not rec.republished.wait(0.1)  # a quiet period, not a deadline
    pub.on_message("homeassistant/status", b"online", False)
    assert rec.republished.wait(slow(5))


def test_az_el_models_get_elevation_entities_with_their_limits() -> None:
    topics = Topics("rotor", {"sat": "rotor"})
    info = RotatorInfo("sat", "Sat", REGISTRY["rot2prog"], topics.rotator("sat"), -180, 540, 0, 90)
    msgs = {
        t: json.loads(p) for t, p in all_configs("ha", Identity("rotor"), topics, [info]).items()
    }
    el = msgs["ha/number/rotorbridge_rotor_r_sat/target_elevation/config"]
    # every elevation the status shows, the controller's whole range among them, not the
    # limits 0..90 (test_the_target_elevation_shows_an_elevation_below_or_above_...)
    assert (el["min"], el["max"], el["command_topic"]) == (-90, 210, "rotor/target/elevation")
    assert (
        msgs["ha/sensor/rotorbridge_rotor_r_sat/elevation/config"]["state_topic"]
        == "rotor/elevation"
    )
    az = msgs["ha/number/rotorbridge_rotor_r_sat/target_azimuth/config"]
    assert (az["min"], az["max"]) == (-180, 540)


# -- pointing: presets, park, nudge, locator (issue 16) ------------------------------------------
POINTING = {"select": ["preset"], "button": ["park", "long_path"], "text": ["locator"]}
POINTING_IDS = {"preset", "park", "locator", "long_path", "distance"}


def from_settings(has_station: bool = False, **kw) -> dict[str, dict]:
    """Discovery for one rotator configured like a user would (settings -> Pointing -> info)."""
    cfg = RotatorSettings(id="tower", port="/dev/ttyUSB0", **{"model": "rotorez", **kw})
    topics = Topics("rotor", {"tower": "rotor"})
    info = RotatorInfo.of(
        "tower",
        "Tower",
        cfg.spec,
        topics.rotator("tower"),
        cfg.pointing,
        has_station=has_station,
        nudge_step_deg=cfg.nudge_step_deg,
    )
    msgs = all_configs("homeassistant", Identity("rotor"), topics, [info])
    return {t.split("/")[1] + "." + t.split("/")[3]: json.loads(p) for t, p in msgs.items()}


EVERYTHING = {"presets": {"W": 300, "EU": 45, "JA": 330}, "park_az_deg": 0}


@pytest.mark.parametrize("model", ["rotorez", "rotorcard", "dcu1", "rot2prog", "rot1prog", "md01"])
def test_pointing_entities_pass_home_assistants_rules(model: str) -> None:
    cfg = RotatorSettings(id="tower", model=model, port="/dev/null", **EVERYTHING)
    topics = Topics("rotor", {"tower": "rotor"})
    info = RotatorInfo.of(
        "tower", "Tower", cfg.spec, topics.rotator("tower"), cfg.pointing,
        has_station=True, nudge_step_deg=2.5,
    )  # fmt: skip
    msgs = all_configs("homeassistant", Identity("rotor"), topics, [info])
    assert POINTING_IDS <= {t.split("/")[3] for t in msgs}
    for topic, payload in msgs.items():
        assert validate(topic, json.loads(payload)) == []


def test_a_rotator_without_presets_park_or_station_gets_none_of_them() -> None:
    ids = {k.split(".")[1] for k in from_settings()}
    assert not POINTING_IDS & ids
    assert {"nudge_cw", "nudge_ccw"} <= ids  # a nudge needs nothing configured


@pytest.mark.parametrize(
    ("settings", "station", "wanted"),
    [
        ({"presets": {"EU": 45}}, False, {"select.preset"}),
        ({"park_az_deg": 90}, False, {"button.park"}),
        ({}, True, {"text.locator", "button.long_path", "sensor.distance"}),
        (EVERYTHING, True, {"select.preset", "button.park", "text.locator", "button.long_path",
                            "sensor.distance"}),
    ],
)  # fmt: skip
def test_each_pointing_entity_follows_its_configuration(
    settings: dict, station: bool, wanted: set[str]
) -> None:
    got = {k for k in from_settings(station, **settings) if k.split(".")[1] in POINTING_IDS}
    assert got == wanted


def test_preset_select_offers_the_presets_in_configuration_order() -> None:
    sel = from_settings(**EVERYTHING)["select.preset"]
    assert sel["options"] == ["W", "EU", "JA"]
    assert sel["command_topic"] == "rotor/preset" and "retain" not in sel
    # a menu of places: its state is always "none chosen", so the same preset can be picked again
    assert sel["state_topic"] == "rotor/status" and sel["value_template"] == "{{ 'None' }}"
    assert sel["availability"] == [{"topic": "rotor/bridge/state"}, {"topic": "rotor/availability"}]


def test_park_and_nudge_buttons_send_what_the_bridge_takes() -> None:
    msgs = from_settings(nudge_step_deg=2.5, **EVERYTHING)
    park = msgs["button.park"]
    assert (park["command_topic"], park["payload_press"]) == ("rotor/park", "PARK")
    cw, ccw = msgs["button.nudge_cw"], msgs["button.nudge_ccw"]
    assert cw["command_topic"] == ccw["command_topic"] == "rotor/nudge"
    assert (cw["payload_press"], ccw["payload_press"]) == ("+2.5", "-2.5")
    assert parse_nudge(cw["payload_press"].encode()) == (2.5, None)
    assert parse_nudge(ccw["payload_press"].encode()) == (-2.5, None)
    default = from_settings()  # nudge_step_deg 10: no trailing .0
    assert default["button.nudge_cw"]["payload_press"] == "+10"
    assert default["button.nudge_ccw"]["payload_press"] == "-10"


def test_no_nudge_buttons_without_a_bearing_to_nudge_from() -> None:
    ids = {k.split(".")[1] for k in from_settings(model="dcu1")}
    assert "target_azimuth" in ids and not {"nudge_cw", "nudge_ccw"} & ids


def test_locator_text_long_path_and_distance_topics() -> None:
    msgs = from_settings(has_station=True)
    loc = msgs["text.locator"]
    assert loc["command_topic"] == "rotor/target" and "state_topic" not in loc
    assert (loc["mode"], loc["min"], loc["max"]) == ("text", 2, 8)
    long_path = msgs["button.long_path"]
    assert long_path["command_topic"] == "rotor/target"
    assert json.loads(long_path["payload_press"]) == {"path": "long"}
    dist = msgs["sensor.distance"]
    assert dist["state_topic"] == "rotor/status"
    assert (dist["unit_of_measurement"], dist["device_class"], dist["state_class"]) == (
        "km",
        "distance",
        "measurement",
    )
    tpl = dist["value_template"]
    assert "value_json.target_info.distance_km" in tpl and "'None'" in tpl


@pytest.mark.parametrize(
    "text",
    ["JO", "jo", "JO62", "JO62qm", "jo62QM", "PM95vq12", "AA00aa00", "RR99xx99",
     "J", "JO6", "JO62q", "JO62qm1", "JO62qm123", "SO62", "JO62qy", "JOAA", "6262", "JO62qm 1",
     " JO62", "JO62qmab", ""],
)  # fmt: skip
def test_locator_pattern_accepts_what_the_bridge_takes_as_a_locator(text: str) -> None:
    pattern = from_settings(has_station=True)["text.locator"]["pattern"]
    takes = text == text.strip() and geo.is_locator(text)  # blanks: the dashboard refuses them
    assert (re.match(pattern, text) is not None) == takes  # Home Assistant checks with re.match
    assert (re.fullmatch(pattern, text) is not None) == takes  # its dashboard: the whole value


def test_target_azimuth_is_the_range_of_true_bearings() -> None:
    def az(**kw) -> tuple[float, float]:
        num = from_settings(**kw)["number.target_azimuth"]
        return num["min"], num["max"]

    # 0..360 always (the status shows true bearings: a number drops a state outside its range,
    # a review: 180..630 for a south-centred 450 degree Yaesu dropped 90), and the targets
    # beyond that a rotor that can pass 360 takes
    assert az() == (0, 360)
    assert az(az_min_deg=10, az_max_deg=350) == (0, 360)
    assert az(az_offset_deg=180) == (0, 360)  # a south-centred Rotor-EZ: every bearing
    assert az(az_offset_deg=180, az_min_deg=10, az_max_deg=350) == (0, 360)
    assert az(model="rot2prog", az_offset_deg=10) == (-170, 550)
    assert az(model="rot2prog", az_offset_deg=10, az_min_deg=0, az_max_deg=450) == (0, 460)
    assert az(model="rot2prog", az_min_deg=0, az_max_deg=450) == (0, 450)
    assert az(model="gs232b-450", az_offset_deg=180) == (0, 630)
    assert az(model="md01", az_min_deg=-180, az_max_deg=180) == (-180, 360)


def test_every_need_names_a_rotator_info_field_or_a_model_capability() -> None:
    names = {f.name for f in dataclasses.fields(RotatorInfo)}
    names |= {f.name for f in dataclasses.fields(ModelSpec)}
    needs = {row.needs for row in ENTITIES if isinstance(row, Entity) and row.needs}
    assert {"presets", "has_park", "has_station", "has_elevation"} <= needs <= names


def test_the_rules_catch_what_home_assistant_refuses_in_a_select_or_text() -> None:
    msgs = from_settings(has_station=True, **EVERYTHING)
    sel, text = msgs["select.preset"], msgs["text.locator"]
    node = "homeassistant/{}/rotorbridge_rotor_r_tower/{}/config"
    assert validate(node.format("select", "preset"), sel) == []
    assert validate(node.format("text", "locator"), text) == []
    # sent as JSON: a bare two-letter field on the target topic is refused (payloads.parse_aim)
    assert text["command_template"] == '{"locator": "{{ value }}"}'
    for bad_select in ({k: v for k, v in sel.items() if k != "options"}, {**sel, "options": "EU"}):
        assert validate(node.format("select", "preset"), bad_select)
    for change in ({"max": 256}, {"min": -1}, {"min": 9}, {"mode": "number"}, {"pattern": "(["}):
        assert validate(node.format("text", "locator"), {**text, **change}), change
    assert validate(node.format("text", "locator"), {**text, "min": 8}) == []  # min == max is fine


# -- tracking: the track select and the tracked body's sensors (issue 17) -------------------------
TRACKING_IDS = {"select.track", "sensor.track_azimuth", "sensor.track_elevation", "sensor.next_aos"}
SATELLITES = ("AO-7", "ISS (ZARYA)", "NOAA 19")  # as App passes them: TleCatalog.names(), sorted


def tracking_discovery(
    model: str = "md01", has_station: bool = True, satellites: tuple[str, ...] = SATELLITES
) -> dict[str, dict]:
    """Discovery for one rotator, as App builds it (the station, the TLE file's names)."""
    cfg = RotatorSettings(id="tower", model=model, port="/dev/ttyUSB0")
    topics = Topics("rotor", {"tower": "rotor"})
    info = RotatorInfo.of(
        "tower", "Tower", cfg.spec, topics.rotator("tower"), cfg.pointing,
        has_station=has_station, nudge_step_deg=cfg.nudge_step_deg, satellites=satellites,
    )  # fmt: skip
    msgs = all_configs("homeassistant", Identity("rotor"), topics, [info])
    return {t.split("/")[1] + "." + t.split("/")[3]: json.loads(p) for t, p in msgs.items()}


@pytest.mark.parametrize("model", ["rotorez", "rotorcard", "rot2prog", "rot1prog", "md01", "satel"])
def test_tracking_entities_pass_home_assistants_rules(model: str) -> None:
    msgs = tracking_discovery(model)
    assert TRACKING_IDS <= set(msgs)
    for key, payload in msgs.items():
        platform, obj = key.split(".")
        topic = f"homeassistant/{platform}/rotorbridge_rotor_r_tower/{obj}/config"
        assert validate(topic, payload) == [], key


@pytest.mark.parametrize(
    ("model", "station", "has_them"),
    [("md01", True, True), ("rotorez", True, True), ("md01", False, False),
     ("rotorez", False, False), ("dcu1", True, False), ("dcu1", False, False)],
)  # fmt: skip
def test_tracking_entities_need_a_station_and_a_controller_that_reports_where_it_points(
    model: str, station: bool, has_them: bool
) -> None:
    got = set(tracking_discovery(model, station)) & TRACKING_IDS
    assert got == (TRACKING_IDS if has_them else set())


def test_track_select_offers_off_sun_moon_and_the_tle_files_satellites() -> None:
    msgs = tracking_discovery()
    sel = msgs["select.track"]
    assert sel["options"] == ["off", "sun", "moon", "AO-7", "ISS (ZARYA)", "NOAA 19"]
    assert (sel["command_topic"], sel["state_topic"]) == ("rotor/track", "rotor/tracking")
    assert "retain" not in sel
    assert sel["availability"] == [{"topic": "rotor/bridge/state"}, {"topic": "rotor/availability"}]
    assert tracking_discovery(satellites=())["select.track"]["options"] == ["off", "sun", "moon"]
    # what R/tracking says is shown as itself when it is an option, else as none (a TLE sent
    # whole, a satellite past the file's first: HA logged an invalid option and kept "off")
    template = re.fullmatch(
        r"\{\{ value if value in (\[.*\]) else 'None' \}\}", sel["value_template"]
    )
    assert template is not None and json.loads(template.group(1)) == sel["options"]
    for body in (None, "sun", "moon", "ISS (ZARYA)"):
        tracking = None if body is None else TrackingInfo(body, "tracking")
        assert tracking_state(RotatorStatus("tower", tracking=tracking)) in sel["options"]


def test_track_select_is_capped_at_max_satellites_of_a_large_tle_file() -> None:
    names = tuple(f"SAT {i:04d}" for i in range(MAX_SATELLITES + 50))  # a Celestrak-sized file
    options = tracking_discovery(satellites=names)["select.track"]["options"]
    assert options == ["off", "sun", "moon", *names[:MAX_SATELLITES]]
    assert (
        validate(
            "homeassistant/select/rotorbridge_rotor_r_tower/track/config",
            tracking_discovery(satellites=names)["select.track"],
        )
        == []
    )


def test_track_select_offers_only_names_r_track_takes_as_themselves() -> None:
    """Attack 20: the select offered a TLE file's name of 79 characters, and R/track refused it
    at 64 ("a name of at most 64 printable characters"): a satellite the dashboard offered
    could not be tracked from it. A name is taken up to 255 (the longest state Home Assistant
    keeps); one R/track cannot take as itself is no option, and does not count among the
    first MAX_SATELLITES."""
    words = "AMSAT-OSCAR 7 (AO-7) - the oldest amateur satellite still heard, launched 1974"
    refused = ("N" * 256, "ISS\t(ZARYA)", '{"tle": ["A", "1 a", "2 b"]}')
    names = (words, "N" * 255, *refused, *(f"SAT {i:04d}" for i in range(MAX_SATELLITES)))
    options = tracking_discovery(satellites=names)["select.track"]["options"]
    assert options[3:5] == [words, "N" * 255]
    assert not set(refused) & set(options)
    assert len(options) == 3 + MAX_SATELLITES  # the refused ones leave room for others
    for option in options:
        assert parse_track(option.encode()) == (option, None), option


def test_tracked_body_sensors_read_the_status_and_say_what_they_measure() -> None:
    msgs = tracking_discovery()
    az, el, aos = (
        msgs["sensor.track_azimuth"],
        msgs["sensor.track_elevation"],
        msgs["sensor.next_aos"],
    )
    assert az["state_topic"] == el["state_topic"] == aos["state_topic"] == "rotor/status"
    assert (az["unit_of_measurement"], az["state_class"]) == ("°", "measurement_angle")
    assert (el["unit_of_measurement"], el["state_class"]) == ("°", "measurement")
    assert aos["device_class"] == "timestamp" and "unit_of_measurement" not in aos


# Home Assistant renders a value_template with Jinja2 against the JSON payload (value_json).
# Jinja2 is not among the test dependencies, so the few constructs these templates use are
# rendered here with Jinja's meaning: a dict's key read as an attribute (a name that is also a
# dict method would give the method: refused here), ``x is defined`` false only for a missing
# key (JSON null is defined), ``x is none`` and ``x is not none`` true and false for JSON null,
# an attribute of an undefined value an error, ``a if c else b`` and parentheses as in Python,
# and output as str() (None renders "None", which HA's MQTT sensor takes as
# unknown). A template using anything else fails the test rather than being guessed at.
_TOKENS = re.compile(r"\s*('[^']*'|[()]|[A-Za-z_]\w*(?:\.[A-Za-z_]\w*)*)")
_WORDS = {"if", "else", "and", "or", "not"}
_NONE_TESTS = (["is", "not", "none"], ["is", "none"])


class _Undefined:
    def __getattr__(self, name: str) -> object:
        raise AssertionError(f"jinja2.UndefinedError: undefined has no attribute {name!r}")


_UNDEFINED = _Undefined()


class _Json:
    def __init__(self, value: dict) -> None:
        self.value = value

    def __getattr__(self, name: str) -> object:
        assert not hasattr(dict, name), f"Jinja reads .{name} of a dict as its method"
        if name not in self.value:
            return _UNDEFINED
        found = self.value[name]
        return _Json(found) if isinstance(found, dict) else found

    def __bool__(self) -> bool:
        return bool(self.value)


def render(template: str, payload: str) -> str:
    body = re.fullmatch(r"\{\{(.*)\}\}", template)
    assert body is not None, f"not one {{{{ expression }}}}: {template!r}"
    rest, tokens = body.group(1).rstrip(), []
    while rest:
        m = _TOKENS.match(rest)
        assert m is not None, f"a construct this renderer does not know: {rest!r}"
        tokens.append(m.group(1))
        rest = rest[m.end() :]
    python = []
    i = 0
    while i < len(tokens):
        tok = tokens[i]
        if tokens[i + 1 : i + 3] == ["is", "defined"]:
            assert tok.startswith("value_json"), tok
            python.append(f"_defined({tok})")
            i += 3
            continue
        test = next((t for t in _NONE_TESTS if tokens[i + 1 : i + 1 + len(t)] == t), None)
        if test is not None:  # Jinja's test "none": JSON null
            assert tok.startswith("value_json"), tok
            python.append(f"{tok} {' '.join(test[:-1])} None")
            i += 1 + len(test)
            continue
        assert tok in _WORDS or tok in ("(", ")") or tok.startswith(("'", "value_json")), tok
        python.append(tok)
        i += 1
    names = {
        "value_json": _Json(json.loads(payload)),
        "_defined": lambda v: v is not _UNDEFINED,
        "__builtins__": {},
    }
    value = eval(" ".join(python), names)  # noqa: S307 - tokens checked above, no builtins
    return "" if value is _UNDEFINED else str(value)


def test_the_renderer_follows_jinja_on_what_these_templates_use() -> None:
    doc = json.dumps({"a": {"b": 1.5, "n": None}, "f": False})
    assert render("{{ value_json.a.b }}", doc) == "1.5"
    assert render("{{ value_json.a.n }}", doc) == "None"  # null renders as None
    assert render("{{ value_json.a.n if value_json.a.n is defined else 'x' }}", doc) == "None"
    assert render("{{ value_json.a.zz if value_json.a.zz is defined else 'x' }}", doc) == "x"
    assert render("{{ value_json.zz }}", doc) == ""  # undefined renders empty
    assert render("{{ 'ON' if value_json.f else 'OFF' }}", doc) == "OFF"
    assert render("{{ value_json.a.n if value_json.a.n is not none else 'x' }}", doc) == "x"
    assert render("{{ 'y' if value_json.a.n is none else 'x' }}", doc) == "y"
    assert render(
        "{{ value_json.a.n if value_json.a.n is not none else (value_json.a.b) }}", doc
    ) == ("1.5")
    with pytest.raises(AssertionError, match="UndefinedError"):
        render("{{ value_json.zz.b }}", doc)
    with pytest.raises(AssertionError, match="method"):
        render("{{ value_json.a.items }}", doc)
    with pytest.raises(AssertionError, match="does not know"):
        render("{{ value_json.a | float }}", doc)


def _status(tracking: TrackingInfo | None, ended: str | None = None) -> str:
    status = RotatorStatus("tower", tracking=tracking, tracking_ended=ended)
    return status_json(status, 1_780_000_000.0, has_elevation=True)


def test_tracked_body_templates_render_with_and_without_a_tracking_block() -> None:
    msgs = tracking_discovery()
    templates = {
        k: msgs[f"sensor.{k}"]["value_template"]
        for k in ("track_azimuth", "track_elevation", "next_aos")
    }
    aos_unix = 1_780_000_123.4

    def shown(status: str) -> dict[str, str]:
        return {k: render(t, status) for k, t in templates.items()}

    in_pass = TrackingInfo(
        "ISS (ZARYA)", "tracking", 123.4, 45.6, 130.0, 50.1,
        aos_unix=aos_unix, los_unix=aos_unix + 600, max_elevation_deg=61.2, aos_azimuth_deg=210.0,
    )  # fmt: skip
    got = shown(_status(in_pass))
    assert (got["track_azimuth"], got["track_elevation"]) == ("123.4", "45.6")
    aos = datetime.fromisoformat(got["next_aos"])  # HA's timestamp sensor: ISO 8601 with a zone
    assert aos.tzinfo is not None and aos.timestamp() == pytest.approx(aos_unix, abs=0.001)
    # not tracking (never, or ended): unknown, not 0 and not an error
    assert shown(_status(None)) == dict.fromkeys(templates, "None")
    assert shown(_status(None, ended="stop")) == dict.fromkeys(templates, "None")
    # tracking with no pass in sight: the body's position, no AOS
    no_pass = TrackingInfo("moon", "no pass", 300.5, -20.0, 300.7, -20.2)
    assert shown(_status(no_pass)) == {
        "track_azimuth": "300.5", "track_elevation": "-20.0", "next_aos": "None"
    }  # fmt: skip
    # just started: nothing computed yet (the block's positions are null)
    assert shown(_status(TrackingInfo("sun", "waiting"))) == dict.fromkeys(templates, "None")


def test_the_track_select_follows_the_tle_file_when_it_changes() -> None:
    """Review finding: the options were worked out once at start, so a satellite cron added
    could be tracked but not picked, and R/tracking showed an option HA did not have."""
    rec = Recorder()
    topics = Topics("rotor", {"tower": "rotor"})
    info = dataclasses.replace(
        RotatorInfo("tower", "Tower", REGISTRY["md01"], topics.rotator("tower"), -180, 540),
        track_options=("off", "sun", "moon", "ISS (ZARYA)"),
    )
    pub = publisher(rec, info=info)
    pub.publish_all()
    topic = "homeassistant/select/rotorbridge_rotor_r_tower/track/config"
    rec.published.clear()
    pub.set_satellites(("ISS (ZARYA)",))  # unchanged: nothing sent
    assert rec.published == [] or all(t != topic for t, _ in rec.published)
    pub.set_satellites(("ISS (ZARYA)", "NOAA 19"))
    options = [json.loads(p)["options"] for t, p in rec.published if t == topic]
    assert options == [["off", "sun", "moon", "ISS (ZARYA)", "NOAA 19"]]


# -- following WSJT-X (session/follow.py) ---------------------------------------------------------
def follow_discovery(can_follow: bool) -> dict[str, dict]:
    cfg = RotatorSettings(id="tower", model="rotorez", port="/dev/ttyUSB0")
    topics = Topics("rotor", {"tower": "rotor"})
    info = RotatorInfo.of(
        "tower", "Tower", cfg.spec, topics.rotator("tower"), cfg.pointing,
        has_station=True, nudge_step_deg=cfg.nudge_step_deg, can_follow=can_follow,
    )  # fmt: skip
    msgs = all_configs("homeassistant", Identity("rotor"), topics, [info])
    return {t.split("/")[1] + "." + t.split("/")[3]: json.loads(p) for t, p in msgs.items()}


def test_the_follow_switch_is_there_only_when_wsjtx_can_be_followed_and_passes_the_rules() -> None:
    assert {"switch.follow", "sensor.followed"}.isdisjoint(follow_discovery(False))
    msgs = follow_discovery(True)
    switch = msgs["switch.follow"]
    assert (switch["command_topic"], switch["state_topic"]) == (
        "rotor/follow",
        "rotor/follow/state",
    )
    # what R/follow/state says is the switch's on or off, and its on is what R/follow takes
    assert (switch["payload_on"], switch["state_on"]) == ("wsjtx", "wsjtx")
    assert (switch["payload_off"], switch["state_off"]) == ("off", "off")
    for following in (None, FollowingInfo("wsjtx")):
        state = follow_state(RotatorStatus("tower", following=following))
        assert state in (switch["state_on"], switch["state_off"])
    assert parse_follow(switch["payload_on"].encode()) == (True, False)
    assert parse_follow(switch["payload_off"].encode()) == (False, False)
    for key in ("switch.follow", "sensor.followed"):
        platform, obj = key.split(".")
        topic = f"homeassistant/{platform}/rotorbridge_rotor_r_tower/{obj}/config"
        assert validate(topic, msgs[key]) == [], key


def test_the_wind_entities_are_there_only_with_a_wind_topic_and_pass_the_rules() -> None:
    cfg = RotatorSettings(id="tower", model="rotorez", port="/dev/ttyUSB0")
    topics = Topics("rotor", {"tower": "rotor"})
    for has_wind in (False, True):
        info = RotatorInfo.of(
            "tower", "Tower", cfg.spec, topics.rotator("tower"), cfg.pointing,
            has_station=False, nudge_step_deg=cfg.nudge_step_deg,
            features=frozenset({"wind"} if has_wind else ()),
        )  # fmt: skip
        msgs = all_configs("homeassistant", Identity("rotor"), topics, [info])
        found = {t.split("/")[1] + "." + t.split("/")[3]: json.loads(p) for t, p in msgs.items()}
        wind = {"sensor.wind", "binary_sensor.storm"}
        assert (wind <= set(found)) is has_wind
        for key in wind & set(found):
            platform, obj = key.split(".")
            topic = f"homeassistant/{platform}/rotorbridge_rotor_r_tower/{obj}/config"
            assert validate(topic, found[key]) == [], key


def _number_shows(model: str, status: RotatorStatus, **limits: float) -> dict[str, object]:
    """What Home Assistant's target numbers show of ``status``, for a rotator configured with
    ``limits`` (ha_rules.number_state: a value outside the range is dropped)."""
    cfg = RotatorSettings(id="tower", model=model, port="/dev/null", **limits)
    topics = Topics("rotor", {"tower": "rotor"})
    info = RotatorInfo.of(
        "tower", "Tower", cfg.spec, topics.rotator("tower"), cfg.pointing,
        has_station=False, nudge_step_deg=10,
    )  # fmt: skip
    msgs = {
        t.split("/")[3]: json.loads(p)
        for t, p in all_configs("homeassistant", Identity("rotor"), topics, [info]).items()
    }
    doc = status_json(status, 1_780_000_000.0, has_elevation=cfg.spec.has_elevation)
    return {
        oid: number_state(msgs[oid], render(msgs[oid]["value_template"], doc))
        for oid in ("target_azimuth", "target_elevation")
        if oid in msgs
    }


@pytest.mark.parametrize("model", ["rot2prog", "md01", "gs232b", "easycomm3", "rc2800", "satel"])
def test_the_target_elevation_shows_an_elevation_below_or_above_the_configured_limits(
    model: str,
) -> None:
    """Found against a SPID emulator with el_min_deg = 10: the rotor rests at 0 until it is first
    turned, the status says elevation 0, and a number whose range was the configured 10..90
    dropped it (Home Assistant logs "Invalid value ... (range 10.0 - 90.0)" at every status and
    the entity stays unknown); the same above el_max_deg (a GS-232B limited to 90, as
    config/two-boxes.toml does, parked at 180 by its own controller); and below the model's own
    range, which an Easycomm's or an RC2800's codec reads (a rotor parked at -0.5)."""
    spec = REGISTRY[model]
    for el in (-0.5, spec.el_min_deg, 0.0, 5.0, 85.0, spec.el_max_deg):
        idle = RotatorStatus(
            "tower", MotionState.IDLE, bearing_deg=120.0, elevation_deg=el, available=True
        )
        shown = _number_shows(model, idle, el_min_deg=10, el_max_deg=80)
        assert shown == {"target_azimuth": 120.0, "target_elevation": el}, el
    # a target within the limits, as before
    moving = RotatorStatus(
        "tower", MotionState.MOVING, bearing_deg=120.0, elevation_deg=0.0,
        target_az_deg=200.0, target_el_deg=45.0, available=True,
    )  # fmt: skip
    assert _number_shows(model, moving, el_min_deg=10, el_max_deg=80) == {
        "target_azimuth": 200.0, "target_elevation": 45.0
    }  # fmt: skip


def _station_rotators(*ids: str) -> tuple[Topics, list[RotatorInfo]]:
    """Az/el rotators of a station (each with the track select and its sensors)."""
    topics = Topics("rotor", {rid: f"rotor/{rid}" for rid in ids})
    spec = REGISTRY["rot2prog"]
    infos = [
        RotatorInfo(
            rid,
            rid,
            spec,
            topics.rotator(rid),
            0,
            360,
            0,
            90,
            has_station=True,
            track_options=("off", "sun", "moon"),
        )  # fmt: skip
        for rid in ids
    ]
    return topics, infos


def test_two_rotators_never_give_two_entities_one_unique_id(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """homeassistant/ rule 8: ``sat``'s tracked elevation and ``sat_track``'s elevation were both
    ``rotorbridge_rotor_r_sat_track_elevation``: Home Assistant dropped one of them. The one of
    the longer id gets a form no plain id can have, said in the log; the other keeps its id."""
    topics, infos = _station_rotators("sat_track", "sat")
    rec = Recorder()
    with caplog.at_level(logging.WARNING):
        pub = DiscoveryPublisher(
            prefix="homeassistant",
            status_topic="homeassistant/status",
            topics=topics,
            rotators=infos,
            publish_retained=lambda t, p: rec.published.append((t, p)),
            clear_retained=rec.cleared.append,
            republish_state=rec.republished.set,
        )
    pub.publish_all()
    ids = [(t.split("/")[1], json.loads(p)["unique_id"]) for t, p in rec.published]
    assert len(ids) == len(set(ids))
    held = {t: json.loads(p) for t, p in rec.published}
    node = "homeassistant/sensor/rotorbridge_rotor_r_{}/{}/config"
    assert held[node.format("sat", "track_elevation")]["unique_id"] == (
        "rotorbridge_rotor_r_sat_track_elevation"
    )
    assert held[node.format("sat_track", "elevation")]["unique_id"] == (
        "rotorbridge_rotor_r_sat_track:elevation"
    )
    said = [r.getMessage() for r in caplog.records if "unique id" in r.getMessage()]
    assert len(said) == 1 and "'sat_track'" in said[0] and "'elevation'" in said[0]
    # a version that comes later rebuilds that rotator's configs with the same ids
    pub.on_status("sat_track", RotatorStatus("sat_track", version="2.0"))
    again = json.loads(dict(rec.published)[node.format("sat_track", "elevation")])
    assert again["unique_id"] == "rotorbridge_rotor_r_sat_track:elevation"
    # alone, a rotator of that name keeps the usual ids (Home Assistant's history with them)
    topics, alone = _station_rotators("sat_track")
    msgs = all_configs("homeassistant", Identity("rotor"), topics, alone)
    assert all(":" not in json.loads(p)["unique_id"] for p in msgs.values())


def test_a_controller_saying_a_new_version_in_every_line_costs_a_round_a_hold() -> None:
    """homeassistant/ rule 9: an Easycomm III's ``VE...`` is taken whenever it comes; a box
    saying another in every line had every config of its rotator rebuilt and sent each time.
    The first goes out at once, the rest are held, and the latest goes out when the hold
    ends."""
    rec = Recorder()
    pub = publisher(rec)
    pub.publish_all()
    bearing = "homeassistant/sensor/rotorbridge_rotor_r_tower/bearing/config"

    def versions() -> list[str | None]:
        return [json.loads(p)["device"].get("sw_version") for t, p in rec.published if t == bearing]

    for i in range(100):
        pub.on_status("tower", RotatorStatus("tower", version=f"V{i}"))
    assert versions() == [None, "V0"]
    wait_until(lambda: versions()[-1] == "V99", slow(ROUND_MIN_S + 5), "the latest version sent")
    assert versions() == [None, "V0", "V99"]
    pub.stop()
