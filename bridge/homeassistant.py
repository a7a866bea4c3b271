"""Home Assistant MQTT discovery: pure builders from settings and model capabilities to
discovery messages, and the publisher that keeps them current.

Single-component discovery (``<prefix>/<platform>/<node_id>/<object_id>/config``, retained,
QoS 1): it works on every Home Assistant version and is what zigbee2mqtt uses.

Rules:
1. One device per rotator (manufacturer and model from the model spec, the controller's firmware
   as ``sw_version``, ``via_device`` the bridge) and one bridge device. An entity exists only if
   the model can do it: no bearing for a DCU-1, options only where the controller has them.
2. Entities that describe the rotator are available only while both the bridge and the rotator
   are online (``availability_mode: all``). Entities that must work while the rotator is
   unreachable (the safety lock, the connection state, the last error) follow the bridge only.
3. Target numbers take min/max/step from the rotator's limits, never Home Assistant's 1..100.
4. Configs are published only when they changed. Configs under our node ids that we no longer
   generate (a rotator removed from the configuration) are cleared with an empty retained
   payload when the broker shows them to us.
5. On Home Assistant's birth message the retained state is published again after a delay, so
   Home Assistant, which ignores state that arrives before it has processed discovery, gets it.
"""

from __future__ import annotations

import json
import logging
import re
import threading
from collections.abc import Callable
from dataclasses import dataclass

from bridge import __version__
from bridge.model import MotionState, RotatorStatus
from bridge.mqtt.topics import RotatorTopics, Topics
from bridge.protocols.base import ModelSpec

log = logging.getLogger(__name__)

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
    az_min_deg: float
    az_max_deg: float
    el_min_deg: float = 0.0
    el_max_deg: float = 0.0
    version: str | None = None


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
    availability: list[dict[str, str]],
    **config: object,
) -> tuple[str, dict[str, object]]:
    payload: dict[str, object] = {
        "name": name,
        "unique_id": f"{node}_{object_id}",
        "default_entity_id": f"{platform}.{entity_slug}_{object_id}",
        "device": device,
        "origin": ORIGIN,
        "availability": availability,
        "availability_mode": "all",
        "qos": 1,
        **config,
    }
    return f"{platform}/{node}/{object_id}/config", payload


def bridge_configs(ident: Identity, topics: Topics) -> dict[str, dict[str, object]]:
    """The bridge device and its connection-state entity (no availability of its own)."""
    device = {
        "identifiers": [ident.bridge_node],
        "name": f"Rotor bridge ({topics.base})",
        "manufacturer": "rotor-bridge",
        "model": "Bridge",
        "sw_version": __version__,
    }
    topic, payload = _entity(
        "binary_sensor",
        ident.bridge_node,
        "connection",
        ident.bridge_node,
        "Connection state",
        device,
        [],
        state_topic=topics.bridge_state,
        payload_on="online",
        payload_off="offline",
        device_class="connectivity",
        entity_category="diagnostic",
    )
    del payload["availability"], payload["availability_mode"]
    return {topic: payload}


def rotator_configs(
    ident: Identity, topics: Topics, r: RotatorInfo
) -> dict[str, dict[str, object]]:
    spec, t = r.spec, r.topics
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
    both = [{"topic": topics.bridge_state}, {"topic": t.availability}]
    bridge_only = [{"topic": topics.bridge_state}]
    slug = r.rotator_id.replace("-", "_")
    out: dict[str, dict[str, object]] = {}

    def add(platform: str, object_id: str, name: str | None, avail: list, **cfg: object) -> None:
        topic, payload = _entity(platform, node, object_id, slug, name, device, avail, **cfg)
        out[topic] = payload

    if spec.can_report_position:
        add(
            "sensor",
            "bearing",
            "Bearing",
            both,
            state_topic=t.bearing,
            unit_of_measurement="°",
            state_class="measurement_angle",
            suggested_display_precision=0,
            icon="mdi:compass",
        )
    # the target number shows the active target, else where the rotor is
    add(
        "number",
        "target_azimuth",
        "Target azimuth",
        both,
        command_topic=t.target,
        state_topic=t.status,
        value_template="{{ value_json.target if value_json.target is not none "
        "else (value_json.bearing if value_json.bearing is not none else 'None') }}",
        min=r.az_min_deg,
        max=r.az_max_deg,
        step=1,
        mode="box",
        unit_of_measurement="°",
        icon="mdi:compass-outline",
    )
    if spec.has_elevation:
        add(
            "sensor",
            "elevation",
            "Elevation",
            both,
            state_topic=t.elevation,
            unit_of_measurement="°",
            state_class="measurement",
            suggested_display_precision=1,
            icon="mdi:angle-acute",
        )
        add(
            "number",
            "target_elevation",
            "Target elevation",
            both,
            command_topic=f"{t.target}/elevation",
            state_topic=t.status,
            value_template="{{ value_json.target_elevation if value_json.target_elevation is "
            "not none else (value_json.elevation if value_json.elevation is not none "
            "else 'None') }}",
            min=r.el_min_deg,
            max=r.el_max_deg,
            step=1,
            mode="box",
            unit_of_measurement="°",
        )
    add(
        "button",
        "stop",
        "Stop",
        both,
        command_topic=t.stop,
        payload_press="STOP",
        icon="mdi:stop-circle",
    )
    add(
        "sensor",
        "state",
        "State",
        both,
        state_topic=t.state,
        device_class="enum",
        options=STATES,
        icon="mdi:rotate-3d-variant",
    )
    add(
        "binary_sensor",
        "moving",
        "Moving",
        both,
        state_topic=t.status,
        value_template="{{ 'ON' if value_json.moving else 'OFF' }}",
        device_class="moving",
    )
    add(
        "binary_sensor",
        "connected",
        "Controller connected",
        bridge_only,
        state_topic=t.availability,
        payload_on="online",
        payload_off="offline",
        device_class="connectivity",
        entity_category="diagnostic",
    )
    if spec.has_version:
        add(
            "sensor",
            "version",
            "Controller version",
            both,
            state_topic=t.version,
            entity_category="diagnostic",
            icon="mdi:chip",
        )
    for name in spec.options:
        label = spec.option_labels.get(name, name.title())
        add(
            "switch",
            f"option_{name}",
            label,
            both,
            command_topic=t.option(name),
            state_topic=t.option_state(name),
            payload_on="ON",
            payload_off="OFF",
            entity_category="config",
            icon="mdi:cog",
        )
    add(
        "switch",
        "lock",
        "Safety lock",
        bridge_only,
        command_topic=t.lock,
        state_topic=t.lock_state,
        payload_on="ON",
        payload_off="OFF",
        icon="mdi:lock",
    )
    add(
        "sensor",
        "last_error",
        "Last error",
        bridge_only,
        state_topic=t.status,
        value_template="{{ (value_json.last_error or 'none')[:250] }}",
        entity_category="diagnostic",
        icon="mdi:alert-circle-outline",
    )
    return out


def all_configs(
    prefix: str, ident: Identity, topics: Topics, rotators: list[RotatorInfo]
) -> dict[str, str]:
    """Every discovery message: full topic -> JSON payload (stable key order)."""
    configs = bridge_configs(ident, topics)
    for r in rotators:
        configs.update(rotator_configs(ident, topics, r))
    return {f"{prefix}/{topic}": json.dumps(p, sort_keys=True) for topic, p in configs.items()}


def parse_config_topic(prefix: str, topic: str) -> tuple[str, str, str] | None:
    """(platform, node_id, object_id) of a discovery config topic under ``prefix``."""
    parts = topic.split("/")
    head = prefix.split("/")
    if len(parts) != len(head) + 4 or parts[: len(head)] != head or parts[-1] != "config":
        return None
    return parts[-4], parts[-3], parts[-2]


# -- the publisher -------------------------------------------------------------------------------
class DiscoveryPublisher:
    """Keeps the discovery messages current on the broker (see the module rules)."""

    def __init__(
        self,
        *,
        prefix: str,
        status_topic: str,
        topics: Topics,
        rotators: list[RotatorInfo],
        publish_retained: Callable[[str, str], None],
        clear_retained: Callable[[str], None],
        republish_state: Callable[[], None],
        birth_delay_s: float = 10.0,
    ) -> None:
        self.prefix = prefix
        self.status_topic = status_topic
        self._topics = topics
        self._ident = Identity(topics.base)
        self._rotators = {r.rotator_id: r for r in rotators}
        self._publish = publish_retained
        self._clear = clear_retained
        self._republish_state = republish_state
        self._birth_delay_s = birth_delay_s
        self._lock = threading.Lock()
        self._timer: threading.Timer | None = None
        self._current: dict[str, str] = {}

    @property
    def subscriptions(self) -> list[str]:
        return [self.status_topic, f"{self.prefix}/+/+/+/config"]

    def publish_all(self) -> None:
        # under the lock: workers call this concurrently (each controller's version arrives on
        # its own thread), and an older snapshot published last would stay retained
        with self._lock:
            configs = all_configs(
                self.prefix, self._ident, self._topics, list(self._rotators.values())
            )
            self._current = configs
            for topic, payload in configs.items():
                self._publish(topic, payload)  # the client skips what did not change

    def on_status(self, rotator_id: str, status: RotatorStatus) -> None:
        with self._lock:
            r = self._rotators.get(rotator_id)
            if r is None or not status.version or status.version == r.version:
                return
            self._rotators[rotator_id] = RotatorInfo(**{**r.__dict__, "version": status.version})
        self.publish_all()

    def on_message(self, topic: str, payload: bytes, retain: bool) -> bool:
        """Handle Home Assistant's birth and our own retained configs; True if it was ours."""
        if topic == self.status_topic:
            if payload.strip().lower() == b"online":
                self._schedule_republish()
            return True
        parsed = parse_config_topic(self.prefix, topic)
        if parsed is None:
            return False
        _, node, _ = parsed
        if not self._ident.owns(node) or not payload:
            return True
        with self._lock:
            stale = topic not in self._current
        if stale:
            log.info("clearing stale Home Assistant config %s", topic)
            self._clear(topic)
        return True

    def _schedule_republish(self) -> None:
        with self._lock:
            if self._timer is not None:
                self._timer.cancel()
            self._timer = threading.Timer(self._birth_delay_s, self._republish_state)
            self._timer.daemon = True
            self._timer.start()
        log.info("Home Assistant came online; state follows in %g s", self._birth_delay_s)

    def stop(self) -> None:
        with self._lock:
            if self._timer is not None:
                self._timer.cancel()
