"""Home Assistant MQTT discovery, the entity table: pure data and the builders that turn the
settings and the model's capabilities into discovery messages. No thread, no lock, no clock:
publisher.py keeps them current on the broker.

Single-component discovery (``<prefix>/<platform>/<node_id>/<object_id>/config``, retained,
QoS 1): it works on every Home Assistant version and is what zigbee2mqtt uses. A rotator's
entities are rows of a data table (ENTITIES), each naming what it needs: a ModelSpec capability
or a configured feature (presets, park, the station); every topic, discovery topics included,
comes from bridge.mqtt.topics.

Rules (numbered for all of homeassistant/; 4 and 5 are publisher.py's):
1. One device per rotator (manufacturer and model from the model spec, the controller's firmware
   as ``sw_version``, ``via_device`` the bridge) and one bridge device. An entity exists only if
   the model can do it: no bearing for a DCU-1, options only where the controller has them; and
   only where configured: the preset select with presets, park with a park position, the
   locator, long path and distance with the station's position.
2. Entities that describe the rotator are available only while both the bridge and the rotator
   are online (``availability_mode: all``). Entities that must work while the rotator is
   unreachable (the safety lock, the connection state, the last error) follow the bridge only.
3. Target numbers take min/max/step from the rotator's limits, never Home Assistant's 1..100;
   the azimuth's are true bearings (Pointing.target_range: an offset shifts them).
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import partial
from typing import Protocol

from bridge import __version__
from bridge.model import MotionState
from bridge.mqtt.topics import DiscoveryTopics, RotatorTopics, Topics
from bridge.pointing import Pointing
from bridge.protocols.base import ModelSpec

ORIGIN = {"name": "rotor-bridge", "sw_version": __version__}
STATES = [s.value for s in MotionState]
_UNSAFE = re.compile(r"[^a-zA-Z0-9_-]")


@dataclass(frozen=True)
class RotatorInfo:
    """What discovery needs to know about one rotator."""

    rotator_id: str
    name: str
    spec: ModelSpec
    topics: RotatorTopics
    az_min_deg: float  # the range of azimuth targets, true bearings (rule 3)
    az_max_deg: float
    el_min_deg: float = 0.0
    el_max_deg: float = 0.0
    version: str | None = None
    presets: tuple[str, ...] = ()  # names, in the configuration's order
    has_park: bool = False
    has_station: bool = False  # the station's position: targets by locator
    nudge_step_deg: float = 10.0
    track_options: tuple[str, ...] = ()  # off, sun, moon and the TLE file's satellites
    can_follow: bool = False  # [wsjtx] and a station: R/follow (engine/follow.py)
    has_wind: bool = False  # a wind_topic (engine/wind.py)

    @classmethod
    def of(
        cls,
        rotator_id: str,
        name: str,
        spec: ModelSpec,
        topics: RotatorTopics,
        pointing: Pointing,
        *,
        has_station: bool,
        nudge_step_deg: float,
        satellites: tuple[str, ...] = (),
        can_follow: bool = False,
        has_wind: bool = False,
    ) -> RotatorInfo:
        """From the rotator's pointing (limits, offset, presets, park) and the settings."""
        az_min, az_max = pointing.target_range()
        return cls(
            rotator_id,
            name,
            spec,
            topics,
            az_min,
            az_max,
            pointing.el_min_deg,
            pointing.el_max_deg,
            presets=tuple(pointing.presets),
            has_park=pointing.park is not None,
            has_station=has_station,
            nudge_step_deg=nudge_step_deg,
            track_options=(
                track_options(satellites) if has_station and spec.can_report_position else ()
            ),
            can_follow=can_follow,
            has_wind=has_wind,
        )

    def with_satellites(self, satellites: tuple[str, ...]) -> RotatorInfo:
        """This rotator with the TLE file's names as they are now (if it can track at all)."""
        return (
            replace(self, track_options=track_options(satellites)) if self.track_options else self
        )

    def has(self, need: str) -> bool:
        """An ENTITIES row's need: a field of this info (configured), else a model capability."""
        where = self if need in self.__dataclass_fields__ else self.spec
        return bool(getattr(where, need))


@dataclass(frozen=True)
class Identity:
    """Ids derived from the base topic, so two bridges on one broker do not collide."""

    base_topic: str

    @property
    def bridge_node(self) -> str:
        return "rotorbridge_" + _UNSAFE.sub("_", self.base_topic)

    def rotator_node(self, rotator_id: str) -> str:
        return f"{self.bridge_node}_r_{rotator_id}"

    def owns(self, node_id: str) -> bool:
        return node_id == self.bridge_node or node_id.startswith(self.bridge_node + "_r_")


def _entity(
    platform: str,
    node: str,
    object_id: str,
    entity_slug: str,
    name: str | None,
    device: dict[str, object],
    availability: list[dict[str, str]] | None,
    **config: object,
) -> tuple[tuple[str, str, str], dict[str, object]]:
    """((platform, node, object_id), payload); availability None: the entity has none."""
    payload: dict[str, object] = {
        "name": name,
        "unique_id": f"{node}_{object_id}",
        "default_entity_id": f"{platform}.{entity_slug}_{object_id}",
        "device": device,
        "origin": ORIGIN,
        "qos": 1,
        **config,
    }
    if availability is not None:
        payload.update(availability=availability, availability_mode="all")
    return (platform, node, object_id), payload


Configs = dict[tuple[str, str, str], dict[str, object]]


def bridge_configs(ident: Identity, topics: Topics) -> Configs:
    """The bridge device and its connection-state entity (no availability of its own)."""
    device: dict[str, object] = {
        "identifiers": [ident.bridge_node],
        "name": f"Rotor bridge ({topics.base})",
        "manufacturer": "rotor-bridge",
        "model": "Bridge",
        "sw_version": __version__,
    }
    where, payload = _entity(
        "binary_sensor",
        ident.bridge_node,
        "connection",
        ident.bridge_node,
        "Connection state",
        device,
        None,
        state_topic=topics.bridge_state,
        payload_on="online",
        payload_off="offline",
        device_class="connectivity",
        entity_category="diagnostic",
    )
    return {where: payload}


# -- the entity table ----------------------------------------------------------------------------
@dataclass(frozen=True)
class Entity:
    """One entity of a rotator device; ``config`` gives the platform-specific keys."""

    platform: str
    object_id: str
    name: str | None
    config: Callable[[RotatorInfo], dict[str, object]]
    needs: str | None = None  # RotatorInfo.has (rule 1): without it, no entity
    bridge_only: bool = False  # rule 2: available while the rotator is unreachable

    def expand(self, info: RotatorInfo) -> list[Entity]:
        return [self] if self.needs is None or info.has(self.needs) else []


class OptionConfig(Protocol):
    """An option entity's config: the option is passed by name (EachOption binds it)."""

    def __call__(self, info: RotatorInfo, /, option: str) -> dict[str, object]: ...


@dataclass(frozen=True)
class EachOption:
    """One entity per controller option (``spec.options``), labelled by ``spec.option_labels``."""

    platform: str
    config: OptionConfig

    def expand(self, info: RotatorInfo) -> list[Entity]:
        spec = info.spec
        return [
            Entity(
                self.platform,
                f"option_{name}",
                spec.option_labels.get(name, name.title()),
                partial(self.config, option=name),
            )
            for name in spec.options
        ]


def _current_or(field: str, fallback: str) -> str:
    """A template for a target number: the active target, else where the rotor is."""
    return (
        f"{{{{ value_json.{field} if value_json.{field} is not none else (value_json.{fallback} "
        f"if value_json.{fallback} is not none else 'None') }}}}"
    )


def _nudge(info: RotatorInfo, sign: str) -> str:
    """A nudge button's payload: ``+10``, ``-2.5`` (the step without a trailing .0)."""
    return f"{sign}{info.nudge_step_deg:g}"


# a 2, 4, 6 or 8 character Maidenhead locator, either case (as geo.is_locator): Home Assistant
# checks it with Python's re and its dashboard with an HTML pattern, so no inline flags
LOCATOR_PATTERN = "^[A-Ra-r]{2}([0-9]{2}([A-Xa-x]{2}([0-9]{2})?)?)?$"
# sent as {"locator": ...}: a bare two-letter field on the target topic is refused (it is more
# often a preset's name sent to the wrong topic); the pattern keeps the JSON well formed
LOCATOR_TEMPLATE = '{"locator": "{{ value }}"}'
# the preset select is a menu of places to go: every status shows it with none chosen, because
# Home Assistant's dashboard sends nothing when the option it shows is picked again
NO_OPTION = "{{ 'None' }}"
DISTANCE = (
    "{{ value_json.target_info.distance_km if value_json.target_info is defined else 'None' }}"
)
MAX_SATELLITES = 100  # in the track select: a whole Celestrak "active" file has thousands


def track_options(satellites: tuple[str, ...]) -> tuple[str, ...]:
    """The track select's options: off, the sun, the moon, the first satellites by name."""
    return ("off", "sun", "moon", *satellites[:MAX_SATELLITES])


def _tracked(field: str) -> str:
    """A template for a field of the status's tracking block (unknown while not tracking)."""
    return (
        f"{{{{ value_json.tracking.{field} if value_json.tracking is defined and "
        f"value_json.tracking.{field} is defined else 'None' }}}}"
    )


DEGREES = {"unit_of_measurement": "°"}
SWITCH = {"payload_on": "ON", "payload_off": "OFF"}
TARGET_BOX = {"step": 1, "mode": "box", **DEGREES}
DIAGNOSTIC = {"entity_category": "diagnostic"}

# in the order they are published; every topic comes from RotatorTopics (r.topics)
ENTITIES: tuple[Entity | EachOption, ...] = (
    Entity("sensor", "bearing", "Bearing", needs="can_report_position", config=lambda r: {
        "state_topic": r.topics.bearing, "state_class": "measurement_angle", **DEGREES,
        "suggested_display_precision": 0, "icon": "mdi:compass"}),
    Entity("number", "target_azimuth", "Target azimuth", config=lambda r: {
        "command_topic": r.topics.target, "state_topic": r.topics.status,
        "value_template": _current_or("target", "bearing"),
        "min": r.az_min_deg, "max": r.az_max_deg, **TARGET_BOX, "icon": "mdi:compass-outline"}),
    Entity("sensor", "elevation", "Elevation", needs="has_elevation", config=lambda r: {
        "state_topic": r.topics.elevation, "state_class": "measurement", **DEGREES,
        "suggested_display_precision": 1, "icon": "mdi:angle-acute"}),
    Entity("number", "target_elevation", "Target elevation", needs="has_elevation",
           config=lambda r: {
        "command_topic": r.topics.target_elevation, "state_topic": r.topics.status,
        "value_template": _current_or("target_elevation", "elevation"),
        "min": r.el_min_deg, "max": r.el_max_deg, **TARGET_BOX}),
    Entity("button", "stop", "Stop", config=lambda r: {
        "command_topic": r.topics.stop, "payload_press": "STOP", "icon": "mdi:stop-circle"}),
    Entity("select", "preset", "Preset", needs="presets", config=lambda r: {
        "command_topic": r.topics.preset, "options": list(r.presets),
        "state_topic": r.topics.status, "value_template": NO_OPTION, "icon": "mdi:star"}),
    Entity("button", "park", "Park", needs="has_park", config=lambda r: {
        "command_topic": r.topics.park, "payload_press": "PARK", "icon": "mdi:parking"}),
    Entity("button", "nudge_ccw", "Nudge counter-clockwise", needs="can_report_position",
           config=lambda r: {
        "command_topic": r.topics.nudge, "payload_press": _nudge(r, "-"),
        "icon": "mdi:rotate-left"}),
    Entity("button", "nudge_cw", "Nudge clockwise", needs="can_report_position",
           config=lambda r: {
        "command_topic": r.topics.nudge, "payload_press": _nudge(r, "+"),
        "icon": "mdi:rotate-right"}),
    Entity("text", "locator", "Locator", needs="has_station", config=lambda r: {
        "command_topic": r.topics.target, "command_template": LOCATOR_TEMPLATE, "mode": "text",
        "min": 2, "max": 8, "pattern": LOCATOR_PATTERN, "icon": "mdi:map-search"}),
    Entity("button", "long_path", "Long path", needs="has_station", config=lambda r: {
        "command_topic": r.topics.target, "payload_press": '{"path": "long"}',
        "icon": "mdi:earth"}),
    Entity("sensor", "distance", "Distance", needs="has_station", config=lambda r: {
        "state_topic": r.topics.status, "value_template": DISTANCE, "unit_of_measurement": "km",
        "device_class": "distance", "state_class": "measurement",
        "suggested_display_precision": 0, "icon": "mdi:map-marker-distance"}),
    Entity("select", "track", "Track", needs="track_options", config=lambda r: {
        "command_topic": r.topics.track, "state_topic": r.topics.tracking,
        "options": list(r.track_options), "icon": "mdi:satellite-variant"}),
    Entity("sensor", "track_azimuth", "Tracked azimuth", needs="track_options",
           config=lambda r: {
        "state_topic": r.topics.status, "value_template": _tracked("azimuth"), **DEGREES,
        "state_class": "measurement_angle", "suggested_display_precision": 1,
        "icon": "mdi:compass-rose"}),
    Entity("sensor", "track_elevation", "Tracked elevation", needs="track_options",
           config=lambda r: {
        "state_topic": r.topics.status, "value_template": _tracked("elevation"), **DEGREES,
        "state_class": "measurement", "suggested_display_precision": 1,
        "icon": "mdi:angle-acute"}),
    Entity("sensor", "next_aos", "Next AOS", needs="track_options", config=lambda r: {
        "state_topic": r.topics.status, "value_template": _tracked("aos"),
        "device_class": "timestamp", "icon": "mdi:clock-start"}),
    Entity("switch", "follow", "Follow WSJT-X", needs="can_follow", config=lambda r: {
        "command_topic": r.topics.follow, "state_topic": r.topics.follow_state,
        "payload_on": "wsjtx", "payload_off": "off", "state_on": "wsjtx", "state_off": "off",
        "icon": "mdi:account-arrow-right"}),
    Entity("sensor", "followed", "Followed station", needs="can_follow", config=lambda r: {
        "state_topic": r.topics.status, "icon": "mdi:account-voice",
        "value_template": "{{ value_json.following.call if value_json.following is defined "
                          "and value_json.following.call else 'None' }}"}),
    Entity("sensor", "wind", "Wind", needs="has_wind", config=lambda r: {
        "state_topic": r.topics.status, "unit_of_measurement": "km/h",
        "device_class": "wind_speed", "state_class": "measurement",
        "value_template": "{{ value_json.wind.speed_kmh if value_json.wind is defined and "
                          "value_json.wind.speed_kmh is not none else 'None' }}"}),
    Entity("binary_sensor", "storm", "Parked for the storm", needs="has_wind",
           config=lambda r: {
        "state_topic": r.topics.status, "icon": "mdi:weather-windy",
        "value_template": "{{ 'ON' if value_json.wind is defined and value_json.wind.storm "
                          "else 'OFF' }}"}),
    Entity("sensor", "state", "State", config=lambda r: {
        "state_topic": r.topics.state, "device_class": "enum", "options": STATES,
        "icon": "mdi:rotate-3d-variant"}),
    Entity("binary_sensor", "moving", "Moving", config=lambda r: {
        "state_topic": r.topics.status, "device_class": "moving",
        "value_template": "{{ 'ON' if value_json.moving else 'OFF' }}"}),
    Entity("binary_sensor", "connected", "Controller connected", bridge_only=True,
           config=lambda r: {
        "state_topic": r.topics.availability, "payload_on": "online", "payload_off": "offline",
        "device_class": "connectivity", **DIAGNOSTIC}),
    Entity("sensor", "version", "Controller version", needs="has_version", config=lambda r: {
        "state_topic": r.topics.version, **DIAGNOSTIC, "icon": "mdi:chip"}),
    EachOption("switch", config=lambda r, option: {
        "command_topic": r.topics.option(option), "state_topic": r.topics.option_state(option),
        **SWITCH, "entity_category": "config", "icon": "mdi:cog"}),
    Entity("switch", "lock", "Safety lock", bridge_only=True, config=lambda r: {
        "command_topic": r.topics.lock, "state_topic": r.topics.lock_state, **SWITCH,
        "icon": "mdi:lock"}),
    Entity("sensor", "last_error", "Last error", bridge_only=True, config=lambda r: {
        "state_topic": r.topics.status, **DIAGNOSTIC, "icon": "mdi:alert-circle-outline",
        "value_template": "{{ (value_json.last_error or 'none')[:250] }}"}),
)  # fmt: skip


def rotator_configs(ident: Identity, topics: Topics, r: RotatorInfo) -> Configs:
    """The entities of one rotator device: the rows of ENTITIES it has what they need for."""
    spec = r.spec
    node = ident.rotator_node(r.rotator_id)
    device: dict[str, object] = {
        "identifiers": [node],
        "name": r.name,
        "manufacturer": spec.manufacturer,
        "model": spec.display_name,
        "via_device": ident.bridge_node,
    }
    if r.version:
        device["sw_version"] = r.version
    both = [{"topic": topics.bridge_state}, {"topic": r.topics.availability}]
    bridge_only = [{"topic": topics.bridge_state}]
    slug = r.rotator_id.replace("-", "_")
    out: Configs = {}
    for row in ENTITIES:
        for e in row.expand(r):
            avail = bridge_only if e.bridge_only else both
            where, payload = _entity(
                e.platform, node, e.object_id, slug, e.name, device, avail, **e.config(r)
            )
            out[where] = payload
    return out


def all_configs(
    prefix: str, ident: Identity, topics: Topics, rotators: list[RotatorInfo]
) -> dict[str, str]:
    """Every discovery message: full topic -> JSON payload (stable key order)."""
    configs = bridge_configs(ident, topics)
    for r in rotators:
        configs.update(rotator_configs(ident, topics, r))
    disc = DiscoveryTopics(prefix)
    return {disc.config(*where): json.dumps(p, sort_keys=True) for where, p in configs.items()}
