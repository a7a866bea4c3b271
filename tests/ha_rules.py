"""Home Assistant's MQTT discovery rules, as the tests check them (from the HA docs for each
platform and from HA core's validation of discovery payloads).

select and text: the "MQTT Select" and "MQTT Text" pages (select.mqtt, text.mqtt) and HA core's
schemas for them: a select requires command_topic and a list of options; a text requires
command_topic, its min and max are lengths 0..255 with min <= max (HA's longest state is 255
characters; equal bounds are allowed since core PR #107738), mode is text or password and
pattern must be a valid regular expression."""

from __future__ import annotations

import re

COMMON = {
    "name",
    "unique_id",
    "default_entity_id",
    "device",
    "origin",
    "availability",
    "availability_mode",
    "availability_topic",
    "entity_category",
    "icon",
    "qos",
    "enabled_by_default",
    "json_attributes_topic",
    "encoding",
}
PLATFORM_KEYS = {
    "sensor": {
        "state_topic",
        "value_template",
        "unit_of_measurement",
        "device_class",
        "state_class",
        "suggested_display_precision",
        "options",
        "expire_after",
        "force_update",
    },
    "binary_sensor": {
        "state_topic",
        "value_template",
        "payload_on",
        "payload_off",
        "device_class",
        "expire_after",
        "off_delay",
    },
    "number": {
        "command_topic",
        "state_topic",
        "value_template",
        "command_template",
        "min",
        "max",
        "step",
        "mode",
        "unit_of_measurement",
        "device_class",
        "optimistic",
        "retain",
        "payload_reset",
    },
    "button": {"command_topic", "payload_press", "device_class", "retain"},
    "select": {
        "command_topic",
        "command_template",
        "options",
        "state_topic",
        "value_template",
        "optimistic",
        "retain",
    },
    "text": {
        "command_topic",
        "command_template",
        "state_topic",
        "value_template",
        "min",
        "max",
        "mode",
        "pattern",
        "retain",
    },
    "switch": {
        "command_topic",
        "state_topic",
        "payload_on",
        "payload_off",
        "state_on",
        "state_off",
        "optimistic",
        "retain",
        "device_class",
        "value_template",
    },
}
REQUIRED = {
    "sensor": {"state_topic"},
    "binary_sensor": {"state_topic"},
    "number": {"command_topic"},
    "button": {"command_topic"},
    "switch": {"command_topic"},
    "select": {"command_topic", "options"},
    "text": {"command_topic"},
}
TEXT_MAX = 255  # HA's longest state (MAX_LENGTH_STATE_STATE)
BINARY_CLASSES = {
    "battery",
    "cold",
    "connectivity",
    "door",
    "heat",
    "light",
    "lock",
    "moisture",
    "motion",
    "moving",
    "occupancy",
    "opening",
    "plug",
    "power",
    "presence",
    "problem",
    "running",
    "safety",
    "smoke",
    "sound",
    "tamper",
    "update",
    "vibration",
    "window",
    "gas",
    "garage_door",
    "battery_charging",
    "carbon_monoxide",
}
STATE_CLASSES = {"measurement", "measurement_angle", "total", "total_increasing"}
WRITABLE = {"number", "switch", "button", "select", "text"}
# an entity id's object id (HA core's valid_entity_id): lower-case letters, digits and '_', no
# '_' at either end and no '__' (its slugify writes what a config asks for so, and two ids that
# differ only there ask for one entity)
SLUG = re.compile(r"^(?!.*__)(?!_)[a-z0-9_]+(?<!_)$")
TOPIC_ID = re.compile(r"^[a-zA-Z0-9_-]+$")


def validate(topic: str, payload: dict, prefix: str = "homeassistant") -> list[str]:
    """Problems Home Assistant would have with one single-component discovery message."""
    errs: list[str] = []
    parts = topic.split("/")
    if len(parts) != 5 or parts[0] != prefix or parts[-1] != "config":
        return [f"{topic}: not <prefix>/<platform>/<node_id>/<object_id>/config"]
    platform, node, obj = parts[1], parts[2], parts[3]
    if platform not in PLATFORM_KEYS:
        return [f"{topic}: unexpected platform {platform}"]
    if not (TOPIC_ID.match(node) and TOPIC_ID.match(obj)):
        errs.append(f"{topic}: node_id/object_id may only use [a-zA-Z0-9_-]")
    unknown = set(payload) - COMMON - PLATFORM_KEYS[platform]
    if unknown:
        errs.append(f"{topic}: keys HA does not know for {platform}: {sorted(unknown)}")
    missing = REQUIRED[platform] - set(payload)
    if missing:
        errs.append(f"{topic}: missing required {sorted(missing)}")
    if not isinstance(payload.get("unique_id"), str) or not payload["unique_id"]:
        errs.append(f"{topic}: unique_id required")
    dei = payload.get("default_entity_id", "")
    if not (dei.startswith(platform + ".") and SLUG.match(dei.split(".", 1)[1])):
        errs.append(f"{topic}: default_entity_id {dei!r} is not '{platform}.<slug>'")
    dev = payload.get("device", {})
    if not dev.get("identifiers") and not dev.get("connections"):
        errs.append(f"{topic}: device needs identifiers or connections")
    if not payload.get("origin", {}).get("name"):
        errs.append(f"{topic}: origin.name required")
    if "availability" in payload and "availability_topic" in payload:
        errs.append(f"{topic}: availability and availability_topic are exclusive")
    for a in payload.get("availability", []):
        if (
            set(a) - {"topic", "payload_available", "payload_not_available", "value_template"}
            or "topic" not in a
        ):
            errs.append(f"{topic}: bad availability entry {a}")
    if payload.get("availability_mode", "latest") not in ("all", "any", "latest"):
        errs.append(f"{topic}: bad availability_mode")
    cat = payload.get("entity_category")
    if cat not in (None, "config", "diagnostic"):
        errs.append(f"{topic}: bad entity_category {cat}")
    if cat == "config" and platform not in WRITABLE:
        errs.append(f"{topic}: a read-only {platform} cannot be a config entity")
    if payload.get("qos", 0) not in (0, 1, 2):
        errs.append(f"{topic}: bad qos")
    if platform == "sensor":
        sc = payload.get("state_class")
        if sc is not None and sc not in STATE_CLASSES:
            errs.append(f"{topic}: bad state_class {sc}")
        if sc == "measurement_angle" and payload.get("unit_of_measurement") != "°":
            errs.append(f"{topic}: measurement_angle needs unit °")
        if payload.get("device_class") == "enum":
            if not isinstance(payload.get("options"), list) or not payload["options"]:
                errs.append(f"{topic}: enum sensor needs options")
            if "unit_of_measurement" in payload or "state_class" in payload:
                errs.append(f"{topic}: enum sensor has no unit or state_class")
        elif "options" in payload:
            errs.append(f"{topic}: options only with device_class enum")
    if platform == "binary_sensor" and payload.get("device_class") not in (None, *BINARY_CLASSES):
        errs.append(f"{topic}: bad binary_sensor device_class")
    if platform == "number":
        lo, hi, step = payload.get("min"), payload.get("max"), payload.get("step", 1)
        if lo is None or hi is None:
            errs.append(f"{topic}: number without explicit min/max gets HA's 1..100")
        elif not lo < hi:
            errs.append(f"{topic}: min must be below max")
        if not step >= 0.001:
            errs.append(f"{topic}: step must be >= 0.001")
        if payload.get("mode", "auto") not in ("auto", "box", "slider"):
            errs.append(f"{topic}: bad mode")
    if platform == "select":
        opts = payload.get("options")
        if not isinstance(opts, list) or not all(isinstance(o, str) for o in opts):
            errs.append(f"{topic}: select options must be a list of strings")
    if platform == "text":
        lo, hi = payload.get("min", 0), payload.get("max", TEXT_MAX)
        if not (isinstance(lo, int) and isinstance(hi, int) and 0 <= lo <= hi <= TEXT_MAX):
            errs.append(f"{topic}: text min/max must be lengths with 0 <= min <= max <= 255")
        if payload.get("mode", "text") not in ("text", "password"):
            errs.append(f"{topic}: text mode must be text or password")
        if "pattern" in payload:
            try:
                re.compile(payload["pattern"])
            except (re.error, TypeError):
                errs.append(f"{topic}: text pattern is not a regular expression")
    if payload.get("retain") is True and platform in WRITABLE:
        errs.append(f"{topic}: command must not be retained")
    return errs


def number_state(payload: dict, rendered: str) -> float | None | str:
    """What Home Assistant's MQTT number makes of its value_template's output (number.mqtt,
    HA core's ``MqttNumber._message_received``): ``payload_reset`` ("None" unless set) is
    unknown (None); a value outside min..max is dropped with an error in HA's log ("Invalid
    value for number...": the entity keeps what it showed before, unknown after a start),
    returned here as a string saying so, as is a payload that is no number."""
    if not rendered.strip():
        return "ignored: empty"
    if rendered == payload.get("payload_reset", "None"):
        return None
    try:
        value = float(rendered)
    except ValueError:
        return f"ignored: {rendered!r} is not a number"
    lo, hi = payload.get("min", 1), payload.get("max", 100)
    if not lo <= value <= hi:
        return f"dropped: {value:g} outside {lo:g}..{hi:g}"
    return value
