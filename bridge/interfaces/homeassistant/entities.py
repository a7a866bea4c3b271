"""Home Assistant MQTT discovery, the entity table: pure data and the builders that turn the
settings and the model's capabilities into discovery messages. No thread, no lock, no clock:
publisher.py keeps them current on the broker.

Single-component discovery (``<prefix>/<platform>/<node_id>/<object_id>/config``, retained,
QoS 1): it works on every Home Assistant version and is what zigbee2mqtt uses. A rotator's
entities are rows of a data table (ENTITIES, and each registered feature's rows in their
places: bridge/feature.py rule 5), each naming what it needs: a ModelSpec capability or a
configured feature (presets, park, the station, a registered feature's name); every topic,
discovery topics included, comes from bridge.interfaces.mqtt.topics.

Rules (numbered for all of homeassistant/; 4, 5 and 9 are publisher.py's, whose 6 is
another):
1. One device per rotator (manufacturer and model from the model spec, the controller's firmware
   as ``sw_version``, ``via_device`` the bridge), one per group (GROUP_ENTITIES: its
   target, its stop, its bearing and state from ``G/status``) and one bridge device. An
   entity exists only if
   the model can do it: no bearing for a DCU-1, options only where the controller has them; and
   only where configured: the preset select with presets, park with a park position, the
   locator, long path and distance with the station's position, for a bearing that is an
   azimuth (an elevation rotor on its own refuses every place: info.py ``RotatorInfo.of``).
2. Entities that describe the rotator are available only while both the bridge and the rotator
   are online (``availability_mode: all``). Entities that must work while the rotator is
   unreachable (the stop, the safety lock, the connection state, the last error) follow the
   bridge only.
3. Target numbers take min/max/step from the rotator's limits, never Home Assistant's 1..100;
   the azimuth's are true bearings (Pointing.target_range: an offset shifts them). Each range
   holds every value its state template shows (a number drops a state outside its range): 0..360
   for the azimuth, -90..180 and the controller's whole range for the elevation.
6. A controller setting's entity comes from its declaration (protocols/base.py ``Setting``): a
   bool is a switch (ON/OFF), a number a number (its min, max, step and unit), a choice a
   select (its names); all on R/option/<name> with R/option/<name>/state, in the config
   category.
7. A rotator of two boxes (runtime/composite.py) is one device: its ``sw_version`` and its
   version entity are its ``R/version``, its boxes' versions joined, azimuth first, and the
   entity's name says whose they are ("Controller versions (azimuth / elevation)", or the one
   box's that reports one: "Elevation controller version"). No box is a device or an entity
   of its own: a box has no topic of its own to show.
8. Every entity's unique id is its device's node id and its object id, ``<node>_<object>``,
   both of ``[a-zA-Z0-9_-]``: two rotators can make one of them (``sat``'s
   ``track_elevation`` and ``sat_track``'s ``elevation``, both
   ``rotorbridge_rotor_r_sat_track_elevation``), and Home Assistant took whichever came first
   and dropped the other with a line in its own log, the bridge saying nothing (an attack
   pass). Of two such entities the one of the rotator with the longer id gets
   ``<node>:<object>``, which no plain one can be (``unshared``, said in the log at start);
   the other, and every entity of a configuration without such a pair, keeps its id, so
   Home Assistant's history and settings stay with it.
10. The entity id an entity asks for (``default_entity_id``) is ``<platform>.<slug>_<suffix>``:
   the slug its device's id as Home Assistant writes it (core/text.py ``entity_slug``: no '_'
   at either end), the suffix its object id unless its row names another (``suffix``). No
   suffix of a platform ends in '_' and another suffix of that platform (the bridge's, a
   rotator's or a group's): then two devices whose slugs differ never ask for one entity id
   (``a_X`` = ``b_Y`` with ``a`` the shorter makes ``b`` ``a_Z`` and ``X`` ``Z_Y``, which ends
   in ``_Y``; an empty slug, a group's, asks for ``X`` alone, the same), and the settings'
   check that no two slugs are one is the whole check. ``sat``'s tracked elevation and
   ``sat_track``'s elevation both asked for ``sensor.sat_track_elevation`` (an attack pass:
   Home Assistant gave the second ``_2``, and a card written from docs/homeassistant.md showed
   the other antenna's value); the tracked elevation's suffix is ``track_el``. No
   configuration is refused for it, and no entity Home Assistant has is renamed: it honours
   the id asked for only when it first creates an entity (its unique id, rule 8, is as it
   was), so only a new one gets the new id.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import partial
from typing import Protocol

from bridge import __version__
from bridge.core.model import MotionState
from bridge.core.text import entity_slug
from bridge.feature import registered
from bridge.interfaces.homeassistant.info import GroupInfo, Identity, RotatorInfo
from bridge.interfaces.mqtt.topics import DiscoveryTopics, Topics
from bridge.protocols.base import Setting, SettingKind

ORIGIN = {"name": "rotor-bridge", "sw_version": __version__}
STATES = [s.value for s in MotionState]


def _entity_id(platform: str, named: str, suffix: str) -> str:
    """Rule 10: the entity id asked for, ``named``'s slug (core/text.py entity_slug), then the
    suffix; the suffix alone where the slug is empty (a group id of '-' and '_' only, which the
    settings take: a review found ``button._stop`` asked for, an id Home Assistant does not
    write)."""
    slug = entity_slug(named)
    return f"{platform}.{slug}_{suffix}" if slug else f"{platform}.{suffix}"


def _entity(
    platform: str,
    node: str,
    object_id: str,
    named: str,
    name: str | None,
    device: dict[str, object],
    availability: list[dict[str, str]] | None,
    **config: object,
) -> tuple[tuple[str, str, str], dict[str, object]]:
    """((platform, node, object_id), payload); availability None: the entity has none. The entity
    id asked for ends with the object id (a row's own suffix: ``rotator_configs``)."""
    payload: dict[str, object] = {
        "name": name,
        "unique_id": f"{node}_{object_id}",
        "default_entity_id": _entity_id(platform, named, object_id),
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
    named: Callable[[RotatorInfo], str] | None = None  # a name that depends on the rotator
    suffix: str | None = None  # rule 10: the entity id's end, where not the object id

    def expand(self, info: RotatorInfo) -> list[Entity]:
        if self.needs is not None and not info.has(self.needs):
            return []
        return [self if self.named is None else replace(self, name=self.named(info))]


def feature_entities() -> tuple[tuple[str | None, Entity], ...]:
    """The registered features' rows (bridge/feature.py), in the registry's order, each with
    the object id of the row it follows (None: after all the others)."""
    return tuple(
        (
            e.after,
            Entity(
                e.platform,
                e.object_id,
                e.name,
                e.config,
                e.needs,
                e.bridge_only,
                suffix=e.suffix,
            ),
        )
        for f in registered()
        for e in f.entities
    )


def rows() -> list[Entity | EachOption]:
    """ENTITIES with the features' rows in their places (bridge/feature.py rule 5): right after
    the row each names, a row of the table or of a feature, those after one row in the
    registry's order; a row that names no row follows them all."""
    features = feature_entities()
    named = {row.object_id for row in ENTITIES if isinstance(row, Entity)}
    named |= {e.object_id for _, e in features}
    out: list[Entity | EachOption] = []
    placed: set[int] = set()

    def place(row: Entity | EachOption) -> None:
        out.append(row)
        if isinstance(row, Entity):
            for i, (after, e) in enumerate(features):
                if after == row.object_id and i not in placed:
                    placed.add(i)
                    place(e)

    for row in ENTITIES:
        place(row)
    for anywhere in (False, True):  # the rows that name none, then a cycle's
        for i, (after, e) in enumerate(features):
            if i not in placed and (anywhere or after not in named):
                placed.add(i)
                place(e)
    return out


class OptionConfig(Protocol):
    """A setting entity's config: the setting is passed by its declaration (EachOption)."""

    def __call__(self, info: RotatorInfo, /, setting: Setting) -> dict[str, object]: ...


# rule 6: the platform of each kind of setting
SETTING_PLATFORMS = {
    SettingKind.BOOL: "switch",
    SettingKind.NUMBER: "number",
    SettingKind.CHOICE: "select",
}


@dataclass(frozen=True)
class EachOption:
    """One entity per controller setting (``spec.settings``), of the platform its kind has
    (rule 6), labelled by its declaration."""

    config: OptionConfig

    def expand(self, info: RotatorInfo) -> list[Entity]:
        return [
            Entity(
                SETTING_PLATFORMS[setting.kind],
                f"option_{setting.name}",
                setting.label,
                partial(self.config, setting=setting),
            )
            for setting in info.spec.settings
        ]


def _setting_config(r: RotatorInfo, setting: Setting) -> dict[str, object]:
    """Rule 6: the keys of a setting's entity."""
    name = setting.name
    keys: dict[str, object] = {
        "command_topic": r.topics.option(name),
        "state_topic": r.topics.option_state(name),
    }
    if setting.kind is SettingKind.BOOL:
        keys.update(SWITCH)
    elif setting.kind is SettingKind.NUMBER:
        keys.update(min=setting.minimum, max=setting.maximum, step=setting.step, mode="box")
        if setting.unit:
            keys["unit_of_measurement"] = setting.unit
    else:
        keys["options"] = list(setting.choices)
    icon = "mdi:speedometer" if setting.speed_factors else "mdi:cog"
    return {**keys, "entity_category": "config", "icon": icon}


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
# the release button names Home Assistant as who released (it sends no MQTT 5 user property)


def _version_name(info: RotatorInfo) -> str:
    """Rule 7: the version entity's name; a rotator of two boxes names the box or boxes whose
    versions it shows, in their order (``1.4S / SatEL``)."""
    boxes = info.versioned_boxes
    if len(boxes) == 1:
        return f"{boxes[0].capitalize()} controller version"
    return f"Controller versions ({' / '.join(boxes)})" if boxes else "Controller version"


DEGREES = {"unit_of_measurement": "°"}
# rule 3: every elevation a status may show (protocols/easycomm.py and rc2800.py read from -90;
# a model's own range, a SPID's -20..210, widens it)
EL_SHOWN = (-90.0, 180.0)
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
        # (the range holds every true bearing the status shows, 0..360, and every target the
        # rotator takes: a number drops a state outside it, a review: a south-centred 450° rotor's
        # 180..630 dropped 90)
        "min": min(r.az_min_deg, 0.0), "max": max(r.az_max_deg, 360.0), **TARGET_BOX,
        "icon": "mdi:compass-outline"}),
    Entity("sensor", "elevation", "Elevation", needs="has_elevation", config=lambda r: {
        "state_topic": r.topics.elevation, "state_class": "measurement", **DEGREES,
        "suggested_display_precision": 1, "icon": "mdi:angle-acute"}),
    Entity("number", "target_elevation", "Target elevation", needs="has_elevation",
           config=lambda r: {
        "command_topic": r.topics.target_elevation, "state_topic": r.topics.status,
        "value_template": _current_or("target_elevation", "elevation"),
        # (the range holds every elevation the status shows, as the azimuth's: a rotor resting
        # at 0 below el_min_deg = 10 was dropped, the number stuck at unknown with an error in
        # Home Assistant's log at every status; an Easycomm or RC2800 reads down to -90, a rotor
        # parked at -0.5, a SPID to 210)
        "min": min(r.el_min_deg, r.spec.el_min_deg, EL_SHOWN[0]),
        "max": max(r.el_max_deg, r.spec.el_max_deg, EL_SHOWN[1]), **TARGET_BOX}),
    # rule 2: a stop is never refused (one for a rotator that does not answer is owed and sent
    # first when it answers again), so its button stays while the bridge runs
    Entity("button", "stop", "Stop", bridge_only=True, config=lambda r: {
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
    # (the DX cluster's spot select: features/dxcluster, after the distance)
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
    Entity("sensor", "version", "Controller version", needs="has_version", named=_version_name,
           config=lambda r: {
        "state_topic": r.topics.version, **DIAGNOSTIC, "icon": "mdi:chip"}),
    EachOption(config=_setting_config),  # rule 6
    Entity("switch", "lock", "Safety lock", bridge_only=True, config=lambda r: {
        "command_topic": r.topics.lock, "state_topic": r.topics.lock_state, **SWITCH,
        "icon": "mdi:lock"}),
    Entity("sensor", "last_error", "Last error", bridge_only=True, config=lambda r: {
        "state_topic": r.topics.status, **DIAGNOSTIC, "icon": "mdi:alert-circle-outline",
        "value_template": "{{ (value_json.last_error or 'none')[:250] }}"}),
    # who sent the last command (the control lease's holder and release: features/control/)
    Entity("sensor", "last_operator", "Last operator", config=lambda r: {
        "state_topic": r.topics.status, **DIAGNOSTIC, "icon": "mdi:account-arrow-right",
        "value_template": "{{ value_json.last_operator or 'none' }}"}),
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
    out: Configs = {}
    for row in rows():
        for e in row.expand(r):
            avail = bridge_only if e.bridge_only else both
            where, payload = _entity(
                e.platform, node, e.object_id, r.rotator_id, e.name, device, avail, **e.config(r)
            )
            if e.object_id in r.shared_ids:  # rule 8
                payload["unique_id"] = f"{node}:{e.object_id}"
            if e.suffix is not None:  # rule 10
                payload["default_entity_id"] = _entity_id(e.platform, r.rotator_id, e.suffix)
            out[where] = payload
    return out


def unshared(ident: Identity, rotators: list[RotatorInfo]) -> list[RotatorInfo]:
    """Rule 8: the rotators, each with the object ids of its entities whose plain unique id
    an entity of the same platform of a rotator with a shorter id has (their lengths differ:
    ``<node>_<object>`` of two ids of one length is one only for one id)."""
    first: dict[tuple[str, str], tuple[int, str]] = {}  # (platform, unique id) -> its owner
    for r in rotators:
        node = ident.rotator_node(r.rotator_id)
        for row in rows():
            for e in row.expand(r):
                key = (e.platform, f"{node}_{e.object_id}")
                owner = first.get(key)
                if owner is None or owner[0] > len(r.rotator_id):
                    first[key] = (len(r.rotator_id), r.rotator_id)
    out = []
    for r in rotators:
        node = ident.rotator_node(r.rotator_id)
        shared = frozenset(
            e.object_id
            for row in rows()
            for e in row.expand(r)
            if first[(e.platform, f"{node}_{e.object_id}")][1] != r.rotator_id
        )
        out.append(replace(r, shared_ids=shared) if shared else r)
    return out


# a group's device (rule 1): the rotator's builders, on the group's topics (GroupTopics)
GroupRow = tuple[str, str, str | None, bool, Callable[[GroupInfo], dict[str, object]]]
GROUP_ENTITIES: tuple[GroupRow, ...] = (  # platform, object id, name, the stop?, config
    ("number", "target_azimuth", "Target azimuth", False, lambda g: {
        "command_topic": g.topics.target, "state_topic": g.topics.status,
        "value_template": "{{ value_json.bearing if value_json.bearing is not none else 'None' }}",
        "min": 0, "max": 360, **TARGET_BOX, "icon": "mdi:compass-outline"}),
    ("button", "stop", "Stop", True, lambda g: {
        "command_topic": g.topics.stop, "payload_press": "STOP", "icon": "mdi:stop-circle"}),
    ("sensor", "bearing", "Bearing", False, lambda g: {
        "state_topic": g.topics.status, **DEGREES, "state_class": "measurement_angle",
        "value_template": "{{ value_json.bearing if value_json.bearing is not none else 'None' }}",
        "suggested_display_precision": 0, "icon": "mdi:compass"}),
    ("sensor", "state", "State", False, lambda g: {
        "state_topic": g.topics.status, "device_class": "enum", "options": STATES,
        "value_template": "{{ value_json.state }}", "icon": "mdi:rotate-3d-variant"}),
    ("binary_sensor", "moving", "Moving", False, lambda g: {
        "state_topic": g.topics.status, "device_class": "moving",
        "value_template": "{{ 'ON' if value_json.moving else 'OFF' }}",
        "json_attributes_topic": g.topics.status}),  # each member's bearing and the refusals
)  # fmt: skip


def group_configs(ident: Identity, topics: Topics, g: GroupInfo) -> Configs:
    """The entities of one group's device; the stop follows the bridge only (rule 2: it must
    work whatever its members say)."""
    node = ident.group_node(g.group_id)
    device: dict[str, object] = {
        "identifiers": [node],
        "name": g.name,
        "manufacturer": "rotor-bridge",
        "model": f"Group of {len(g.members)} rotators ({', '.join(g.members)})",
        "via_device": ident.bridge_node,
    }
    both = [{"topic": topics.bridge_state}, {"topic": g.topics.availability}]
    bridge_only = [{"topic": topics.bridge_state}]
    out: Configs = {}
    for platform, object_id, name, stop, config in GROUP_ENTITIES:
        avail = bridge_only if stop else both
        where, payload = _entity(
            platform, node, object_id, g.group_id, name, device, avail, **config(g)
        )
        out[where] = payload
    return out


def all_configs(
    prefix: str,
    ident: Identity,
    topics: Topics,
    rotators: list[RotatorInfo],
    groups: tuple[GroupInfo, ...] = (),
) -> dict[str, str]:
    """Every discovery message: full topic -> JSON payload (stable key order)."""
    configs = bridge_configs(ident, topics)
    for r in rotators:
        configs.update(rotator_configs(ident, topics, r))
    for g in groups:
        configs.update(group_configs(ident, topics, g))
    return _messages(prefix, configs)


def rotator_messages(
    prefix: str, ident: Identity, topics: Topics, r: RotatorInfo
) -> dict[str, str]:
    """One rotator's discovery messages, as ``all_configs`` has them (its version came: the
    other rotators' and the bridge's are as they were)."""
    return _messages(prefix, rotator_configs(ident, topics, r))


def _messages(prefix: str, configs: Configs) -> dict[str, str]:
    disc = DiscoveryTopics(prefix)
    return {disc.config(*where): json.dumps(p, sort_keys=True) for where, p in configs.items()}
