"""The feature registry (bridge/feature.py, bridge/features/): every registered feature's
topics are in the topic table (subscribed, routed, owned), its command parsed by its
declaration, its block in R/status and its entities in discovery; and a toy feature, declared
here and registered for one test, gets all of that without a line in any other module."""

from __future__ import annotations

import importlib
import json
import re
from pathlib import Path

import pytest
from pydantic import BaseModel

import bridge.feature
from bridge.core.model import MotionState, Nudge, Origin, RotatorStatus, Source
from bridge.feature import (
    AppView,
    CommandTopic,
    EntityRow,
    Feature,
    RotatorView,
    StateTopic,
    StatusBlock,
    make_service,
    registered,
    session_parts,
)
from bridge.features import FEATURES
from bridge.interfaces.homeassistant import Identity, RotatorInfo, all_configs
from bridge.interfaces.mqtt import payloads as pl
from bridge.interfaces.mqtt.service import MqttService
from bridge.interfaces.mqtt.topics import RotatorTopics, Topics
from bridge.session.parts import Part, Wake
from bridge.settings import RotatorSettings, Settings
from bridge.settings.groups import reserved
from tests.mqtt.test_service import NOW_UNIX, RecordingPublisher, RecordingRotator

ROOT = Path(__file__).resolve().parents[1]


def core_topics(t: RotatorTopics) -> set[str]:
    """Every topic the table builds for a rotator without the registry (its properties)."""
    found = {
        getattr(t, n) for n in dir(RotatorTopics) if isinstance(getattr(RotatorTopics, n), property)
    }
    return found | {t.option("x"), t.option_state("x")}


def settings(**tables: object) -> Settings:
    rotator = {"id": "tower", "model": "rotorez", "port": "/dev/ttyUSB0"}
    return Settings(rotators=[rotator], **tables)  # type: ignore[arg-type]


def test_the_registry_is_the_features_tuple_in_its_order() -> None:
    assert registered() == FEATURES
    assert [f.name for f in FEATURES] == [
        "tracking", "follow", "wind", "health", "control", "dxcluster", "autopark", "bands",
    ]  # fmt: skip
    assert len({f.name for f in FEATURES}) == len(FEATURES)


@pytest.mark.parametrize("feature", FEATURES, ids=lambda f: f.name)
def test_a_features_topics_are_subscribed_routed_and_owned_never_on_the_stop_lane(
    feature: Feature,
) -> None:
    topics = Topics("B", {"r": "R"})
    t = topics.rotator("r")
    for command in feature.commands:
        topic = t.feature(command.suffix)
        assert topic in topics.subscriptions()
        assert topics.route(topic) == ("r", command.kind, None)
        assert topic not in topics.stop_lane()  # rule 1: the last word is no feature's
        assert topic not in core_topics(t)  # rule 3
    for state in feature.states:
        assert t.feature(state.suffix) in topics.owned()
        assert t.feature(state.suffix) not in core_topics(t)
    for x in (*feature.commands, *feature.states):
        assert x.suffix.split("/")[0] in reserved()  # rule 3: no group may take it
    for suffix in feature.base_topics:  # B/<suffix>: no group's nor rotator's id either
        assert topics.under_base(suffix) == f"B/{suffix}"
        assert suffix.split("/")[0] in reserved()


def test_no_two_features_share_a_topic_or_a_command_kind() -> None:
    suffixes = [x.suffix for f in FEATURES for x in (*f.commands, *f.states)]
    kinds = [c.kind for f in FEATURES for c in f.commands]
    assert len(set(suffixes)) == len(suffixes) and len(set(kinds)) == len(kinds)


@pytest.mark.parametrize("feature", FEATURES, ids=lambda f: f.name)
def test_a_features_entities_are_in_discovery_for_a_rotator_that_has_it(feature: Feature) -> None:
    cfg = RotatorSettings(id="tower", model="rot2prog", port="/dev/ttyUSB0")
    topics = Topics("rotor", {"tower": "rotor"})
    info = RotatorInfo.of(
        "tower", "Tower", cfg.spec, topics.rotator("tower"), cfg.pointing,
        has_station=True, nudge_step_deg=cfg.nudge_step_deg, can_follow=True,
        features=frozenset({feature.name}),
    )  # fmt: skip
    found = {t.split("/")[1] + "." + t.split("/")[3] for t in all_configs(
        "homeassistant", Identity("rotor"), topics, [info])}  # fmt: skip
    assert {f"{e.platform}.{e.object_id}" for e in feature.entities} <= found
    without = RotatorInfo.of(
        "tower", "Tower", cfg.spec, topics.rotator("tower"), cfg.pointing,
        has_station=False, nudge_step_deg=cfg.nudge_step_deg,
    )  # fmt: skip
    for e in feature.entities:  # an entity that needs the feature: not without it
        if e.needs == feature.name:
            assert without.has(e.needs) is False


@pytest.mark.parametrize("feature", FEATURES, ids=lambda f: f.name)
def test_a_features_docs_part_and_settings_are_real(feature: Feature) -> None:
    page, _, anchor = feature.docs.partition("#")
    text = (ROOT / page).read_text()
    if anchor:
        headings = {re.sub(r"[^a-z0-9 -]", "", h.lower()).replace(" ", "-")
                    for h in re.findall(r"^#+ (.+)$", text, re.M)}  # fmt: skip
        assert anchor in headings
    if feature.part is not None:  # its session part, run by the session's step
        assert isinstance(feature.part, Part) and feature.part in session_parts()
    if feature.rotator_settings is not None:  # a rotator's table includes its keys
        assert issubclass(RotatorSettings, feature.rotator_settings)
        heading = feature.settings_section[0]  # its keys' section in configuration.md
        assert f"### {heading}" in (ROOT / "docs" / "configuration.md").read_text()
    assert feature.name in (ROOT / "docs" / "architecture.md").read_text()


def test_the_dx_clusters_service_is_made_only_with_dxcluster_enabled() -> None:
    """Rule 4: off, its module is not even imported (tests/test_cli.py checks a whole start);
    its select sits where the entity table had it (rule 5)."""
    (dx,) = [f for f in FEATURES if f.name == "dxcluster"]
    off = AppView(settings(), None, (lambda doc: None,), None, lambda: 0.0)
    assert make_service(dx, off) is None
    assert dx.service is not None and dx.service_on is not None
    module, _, name = dx.service.partition(":")
    assert callable(getattr(importlib.import_module(module), name))
    assert [e.after for e in dx.entities] == ["track"]


def test_auto_park_is_on_for_a_rotator_that_parks_after_a_quiet_spell() -> None:
    (park,) = [f for f in FEATURES if f.name == "autopark"]
    never = RotatorSettings(id="tower", model="rotorez", port="/dev/ttyUSB0", park_az_deg=0)
    idle = RotatorSettings(
        id="tower", model="rotorez", port="/dev/ttyUSB0", park_az_deg=0, park_after_idle_s=60
    )
    assert (park.on_for(never), park.on_for(idle)) == (False, True)


def test_the_band_map_is_on_for_a_rotator_with_bands_and_documents_its_key() -> None:
    (bands,) = [f for f in FEATURES if f.name == "bands"]
    plain = RotatorSettings(id="tower", model="rotorez", port="/dev/ttyUSB0")
    banded = RotatorSettings(id="tower", model="rotorez", port="/dev/ttyUSB0", bands=["20m"])
    assert (bands.on_for(plain), bands.on_for(banded)) == (False, True)
    page = (ROOT / "docs" / "configuration.md").read_text()
    section = page.split("### Bands (per rotator)")[1].split("\n### ")[0]
    assert "**`bands`**" in section  # its key in its section, from its declaration


def test_wind_is_on_for_a_rotator_with_a_wind_topic_only() -> None:
    (wind,) = [f for f in FEATURES if f.name == "wind"]
    plain = RotatorSettings(id="tower", model="rotorez", port="/dev/ttyUSB0", park_az_deg=0)
    windy = RotatorSettings(
        id="tower", model="rotorez", port="/dev/ttyUSB0", park_az_deg=0,
        wind_topic="weather/wind", wind_park_above=60,
    )  # fmt: skip
    assert (wind.on_for(plain), wind.on_for(windy)) == (False, True)
    assert wind.replayed is not None and wind.replayed(windy) == "weather/wind"


# -- a toy feature, registered here only -----------------------------------------------------
def _toy_nudge(payload: bytes, by: Origin) -> Nudge:
    return Nudge(pl.parse_number(payload, "toy step"), 0.0, source=Source.MQTT, origin=by)


def _toy_state(status: RotatorStatus) -> str | None:
    return status.state.value if status.available else None


def _toy_entity(r: RotatorView) -> dict[str, object]:
    return {"command_topic": r.topics.feature("toy/go"), "state_topic": r.topics.status}


class ToyFields(BaseModel):
    toy: bool = False


TOY = Feature(
    name="toy",
    docs="docs/architecture.md#the-feature-registry",
    summary="a toy: nudges by the number sent",
    commands=(CommandTopic("toy/go", "toy", _toy_nudge),),
    states=(StateTopic("toy/state", _toy_state, lambda v: f"toy {v}"),),
    status=(StatusBlock("toy", _toy_state, lambda v: {"says": v}),),
    entities=(
        EntityRow("button", "toy", "Toy", _toy_entity, needs="toy"),
        EntityRow("button", "toy_near", "Toy by the stop", _toy_entity, needs="toy", after="stop"),
    ),
    configured=lambda r: isinstance(r, ToyFields) and r.toy,
    base_topics=("toys",),
    service="tests.test_features:ToyService",
    service_on=lambda settings: settings.web.enabled,  # any table's switch
)


class ToyService:
    """A feature's service: made from the app's view, publishing its base topic."""

    def __init__(self, view: AppView) -> None:
        (self.publish,) = view.publishers
        self.publish("made")

    def start(self) -> None: ...

    def stop(self) -> None: ...

    def with_discovery(self, publisher: object) -> None: ...


@pytest.fixture
def toy(monkeypatch: pytest.MonkeyPatch) -> Feature:
    monkeypatch.setattr(bridge.feature, "_loaded", (*FEATURES, TOY))
    return TOY


def test_a_toy_feature_gets_its_topics_command_state_status_and_entity(toy: Feature) -> None:
    topics = Topics("rotor", {"tower": "rotor"})
    assert "rotor/toy/go" in topics.subscriptions() and "rotor/toy/state" in topics.owned()
    assert "rotor/toy/go" not in topics.stop_lane()
    pub = RecordingPublisher()
    svc = MqttService(topics, pub, wall=lambda: NOW_UNIX)
    rot = RecordingRotator("tower", "rotorez")
    svc.attach(rot)
    pub.take()
    svc.on_message("rotor/toy/go", b"15", False)  # parsed by its declaration, judged as any
    assert rot.calls == [("nudge", 15.0, 0.0, Source.MQTT, "toy '15'")]
    svc.on_message("rotor/toy/go", b"far", False)  # its parser's error: refused, nothing moves
    assert rot.calls[-1][0] == "refused" and "toy step" in str(rot.calls[-1][1])
    svc.on_message("rotor/toy/go", b"15", True)  # retained: refused like any command
    assert rot.calls[-1][0] == "refused"
    svc.publish_status("tower", RotatorStatus("tower", MotionState.IDLE, 10.0, available=True))
    sent = {topic: payload for topic, payload, _ in pub.take()}
    assert sent["rotor/toy/state"] == "toy idle"
    assert json.loads(sent["rotor/status"])["toy"] == {"says": "idle"}
    cfg = RotatorSettings(id="tower", model="rotorez", port="/dev/ttyUSB0")
    info = RotatorInfo.of(
        "tower", "Tower", cfg.spec, topics.rotator("tower"), cfg.pointing,
        has_station=False, nudge_step_deg=cfg.nudge_step_deg, features=frozenset({"toy"}),
    )  # fmt: skip
    msgs = all_configs("homeassistant", Identity("rotor"), topics, [info])
    button = json.loads(msgs["homeassistant/button/rotorbridge_rotor_r_tower/toy/config"])
    assert button["command_topic"] == "rotor/toy/go"
    order = [t.split("/")[3] for t in msgs if t.split("/")[2].endswith("_r_tower")]
    assert order[order.index("stop") + 1] == "toy_near" and order[-1] == "toy"  # rule 5
    without = all_configs("homeassistant", Identity("rotor"), topics, [
        RotatorInfo.of("tower", "Tower", cfg.spec, topics.rotator("tower"), cfg.pointing,
                       has_station=False, nudge_step_deg=cfg.nudge_step_deg)])  # fmt: skip
    assert not any("/toy/" in topic for topic in without)


def test_a_toy_features_topic_words_are_no_groups_id(toy: Feature) -> None:
    """Rule 3, from its declaration alone: a group may take neither R/toy/... nor B/toys."""
    both = ["tower", "mast"]
    rotators = [{"id": r, "model": "rotorez", "port": f"/dev/{r}"} for r in both]
    for word in ("toy", "toys"):
        with pytest.raises(ValueError, match=f"'{word}' is a word of the bridge's own topics"):
            Settings(rotators=rotators, groups=[{"id": word, "rotators": both}])  # type: ignore[arg-type, list-item]
    Settings(rotators=rotators, groups=[{"id": "toyz", "rotators": both}])  # type: ignore[arg-type, list-item]


def test_a_toy_features_service_is_made_from_the_view_only_when_its_settings_say(
    toy: Feature,
) -> None:
    sent: list[str] = []
    view = AppView(settings(), None, (sent.append,), None, lambda: 0.0)
    assert make_service(toy, view) is None and sent == []  # off: nothing made
    on = AppView(settings(web={"enabled": True}), None, (sent.append,), None, lambda: 0.0)
    assert isinstance(make_service(toy, on), ToyService) and sent == ["made"]
    assert Topics("rotor", {}).under_base("toys") == "rotor/toys"


@pytest.mark.parametrize("suffix", ["bridge", "bridge/x", "spots", ""])
def test_a_feature_cannot_take_the_bridges_own_or_another_features_base_topic(
    suffix: str,
) -> None:
    thief = Feature("thief", "docs/architecture.md", "takes a topic", base_topics=(suffix,))
    with pytest.raises(ValueError, match="is taken"):
        Topics("rotor", {"tower": "rotor"}, features=(*FEATURES, thief))


def test_without_the_toy_its_topic_is_no_ones() -> None:
    topics = Topics("rotor", {"tower": "rotor"})
    assert topics.route("rotor/toy/go") is None
    assert "rotor/toy/go" not in topics.subscriptions()


@pytest.mark.parametrize("suffix", ["stop", "lock", "target", "option/speed", "health", ""])
def test_a_feature_cannot_take_a_core_topic_or_another_features(suffix: str) -> None:
    """Rule 3 (rule 1 above all: no feature answers on R/stop or R/lock)."""
    thief = Feature("thief", "docs/architecture.md", "takes a topic", commands=(
        CommandTopic(suffix, "thief", _toy_nudge),))  # fmt: skip
    with pytest.raises(ValueError, match="is taken"):
        Topics("rotor", {"tower": "rotor"}, features=(*FEATURES, thief))


@pytest.mark.parametrize(
    ("commands", "base"),
    [
        (("spots",), ()),  # R/spots is B/spots, the DX cluster's, with one rotator
        (("bridge/fence",), ()),  # the last word's markers (R is B with one rotator)
        (("bridge/state",), ()),
        ((), ("status",)),  # B/status is R/status with one rotator
        ((), ("lock",)),
        (("toy/+",), ()),  # a wildcard is no topic
        (("#",), ()),
        ((), ("toys/#",)),
        (("toy//go",), ()),
        (("toy/",), ()),
    ],
)
def test_a_features_topic_is_refused_where_a_rotators_topic_is_the_base_topic(
    commands: tuple[str, ...], base: tuple[str, ...]
) -> None:
    """Rule 3: with one rotator R is B, so a feature's R/<suffix> and B/<suffix> share one
    namespace with the core's and the bridge's own (B/bridge/...); a wildcard names no topic."""
    thief = Feature(
        "thief", "docs/architecture.md", "takes a topic",
        commands=tuple(CommandTopic(c, f"thief{i}", _toy_nudge) for i, c in enumerate(commands)),
        base_topics=base,
    )  # fmt: skip
    with pytest.raises(ValueError, match="is taken|is no topic"):
        Topics("rotor", {"tower": "rotor"}, features=(*FEATURES, thief))


# a rotator's discovery messages as the entity table published them before its features were
# packages (every row a rot2prog with a station, presets, park, tracking, WSJT-X, the wind, the
# DX cluster and the lease has): the order a client watching the discovery prefix sees
ORDER_BEFORE_THE_REGISTRY = [
    "bearing", "target_azimuth", "elevation", "target_elevation", "stop", "preset", "park",
    "nudge_ccw", "nudge_cw", "locator", "long_path", "distance", "track", "spot",
    "track_azimuth", "track_elevation", "next_aos", "follow", "followed", "wind", "storm",
    "state", "moving", "connected", "version", "lock", "last_error", "speed_cw", "speed_ccw",
    "speed_up", "speed_down", "start_delay", "coast", "odometer", "moves", "stalls", "motor_on",
    "health_problem", "health_reset", "control", "release_control", "last_operator",
]  # fmt: skip


def test_a_rotators_discovery_messages_come_in_the_order_they_always_did() -> None:
    """bridge/feature.py rule 5: each feature's entities sit where the table had them."""
    cfg = RotatorSettings(
        id="tower", model="rot2prog", port="/dev/ttyUSB0", presets={"EU": [45, 0]},
        park_az_deg=0, park_el_deg=0,
    )  # fmt: skip
    topics = Topics("rotor", {"tower": "rotor"})
    info = RotatorInfo.of(
        "tower", "Tower", cfg.spec, topics.rotator("tower"), cfg.pointing,
        has_station=True, nudge_step_deg=cfg.nudge_step_deg, satellites=("ISS",),
        can_follow=True, features=frozenset(f.name for f in FEATURES),
    )  # fmt: skip
    msgs = all_configs("homeassistant", Identity("rotor"), topics, [info])
    order = [t.split("/")[3] for t in msgs if t.split("/")[2].endswith("_r_tower")]
    shown = [oid for oid in ORDER_BEFORE_THE_REGISTRY if oid in order]  # (a rot2prog: no version)
    assert len(shown) >= len(ORDER_BEFORE_THE_REGISTRY) - 1
    assert [oid for oid in order if oid in ORDER_BEFORE_THE_REGISTRY] == shown


def test_a_state_published_after_the_status_keeps_its_needs_and_its_new_only() -> None:
    """bridge/feature.py StateTopic: ``needs`` and ``new_only`` hold after R/status as before."""
    late = Feature(
        "late", "docs/architecture.md", "a state after the status",
        states=(
            StateTopic("late/needs", lambda s: "x", str, needs="can_track", after_status=True),
            StateTopic("late/new", lambda s: s.version, str, new_only=True, after_status=True),
        ),
    )  # fmt: skip
    topics = Topics("rotor", {"tower": "rotor"}, features=(*FEATURES, late))
    pub = RecordingPublisher()
    svc = MqttService(topics, pub, wall=lambda: NOW_UNIX)
    svc.attach(RecordingRotator("tower", "rotorez"))  # it cannot track
    pub.take()
    version = "v1"
    for bearing in (10.0, 11.0):  # the same version object: new once
        svc.publish_status("tower", RotatorStatus("tower", bearing_deg=bearing, version=version))
    sent = [topic for topic, _, _ in pub.take()]
    assert "rotor/late/needs" not in sent and sent.count("rotor/late/new") == 1


@pytest.mark.parametrize("kind", ["target", "stop", "lock", "option", "nudge", "track"])
def test_a_features_command_cannot_take_a_core_commands_or_another_features_name(
    kind: str,
) -> None:
    """Rule 3: a command is parsed and routed by its name (``kind``): one named ``target``
    would parse every R/target by the feature's parser, one named ``stop`` be taken as a stop."""
    thief = Feature("thief", "docs/architecture.md", "takes a name", commands=(
        CommandTopic("thief/go", kind, _toy_nudge),))  # fmt: skip
    with pytest.raises(ValueError, match="is taken"):
        Topics("rotor", {"tower": "rotor"}, features=(*FEATURES, thief))


def test_a_part_that_takes_commands_must_bear_its_features_name() -> None:
    """bridge/feature.py rule 6: a FeatureCommand names the feature and is routed by the part's
    name, so a part named otherwise ("following" for "follow") would refuse every command."""

    def no_command(s: object, cmd: object, now: float) -> None:
        return None

    part = Part[object](
        "sweeping",
        Wake.STEP,
        True,
        lambda s: False,
        lambda s, scene: None,
        lambda s, now: None,
        command=no_command,
    )
    with pytest.raises(ValueError, match="'sweep'.*'sweeping'"):
        Feature("sweep", "docs/mqtt.md", "a toy", part=part)
    assert Feature("sweeping", "docs/mqtt.md", "a toy", part=part).part is part
    # a part without commands keeps the name its error events had (auto-park, following)
    silent = Part[object](
        "auto-park", Wake.STEP, True, lambda s: False, lambda s, scene: None, lambda s, now: None
    )
    assert Feature("autopark", "docs/mqtt.md", "a toy", part=silent).name == "autopark"


def test_a_station_feature_is_on_for_no_rotator_by_its_table() -> None:
    """An attack pass: without ``[dxcluster]`` every rotator got the DX cluster's "Turn to
    spot" select in Home Assistant (its one option "no spots yet", refused when picked): a
    feature of the station (a ``service``) is on only when the station's settings run it."""
    from bridge.features.dxcluster import FEATURE as DXCLUSTER
    from bridge.features.tracking import FEATURE as TRACKING
    from bridge.settings import RotatorSettings

    r = RotatorSettings.model_validate({"id": "hf", "model": "rotorez", "port": "/dev/ttyUSB0"})
    assert not DXCLUSTER.on_for(r)
    assert TRACKING.on_for(r)  # (a rotator's own, with no table to turn it on)
