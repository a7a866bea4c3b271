"""Inbound payloads parsed, outbound payloads rendered. Pure functions, no paho.

Inbound rules: UTF-8 text at most MAX_COMMAND_BYTES long; numbers are finite decimals; a target
is a bare azimuth (``123``, ``123.5``), ``az el`` (space or comma), or a JSON object
``{"azimuth": a, "elevation": e}``; switches are ON/OFF, 1/0, true/false in any case. Anything
else raises PayloadError with a message meant for the user.
"""

from __future__ import annotations

import json
import math
import re
from datetime import UTC, datetime

from bridge.model import RotatorStatus

MAX_COMMAND_BYTES = 256
_SPLIT = re.compile(r"[\s,;]+")
_NUMBER = re.compile(r"^[+-]?(\d+(\.\d*)?|\.\d+)([eE][+-]?\d+)?$")
_TRUE = {"on", "1", "true"}
_FALSE = {"off", "0", "false"}


class PayloadError(ValueError):
    pass


def _text(payload: bytes) -> str:
    if len(payload) > MAX_COMMAND_BYTES:
        raise PayloadError(f"payload too large ({len(payload)} bytes, at most {MAX_COMMAND_BYTES})")
    try:
        text = payload.decode("utf-8").strip()
    except UnicodeDecodeError:
        raise PayloadError("payload is not UTF-8 text") from None
    if not text:
        raise PayloadError("empty payload")
    return text


def _number(raw: object, what: str) -> float:
    if isinstance(raw, bool) or raw is None:
        raise PayloadError(f"{what} must be a number, got {json.dumps(raw)}")
    if isinstance(raw, int | float):
        value = float(raw)
    elif isinstance(raw, str) and _NUMBER.match(raw.strip()):
        value = float(raw)
    else:
        shown = raw if isinstance(raw, str) else json.dumps(raw)
        raise PayloadError(f"{what} must be a number, got {str(shown)[:40]!r}")
    if not math.isfinite(value):
        raise PayloadError(f"{what} must be a finite number")
    return value


def parse_target(payload: bytes) -> tuple[float, float | None]:
    """(azimuth, elevation or None). Limits are checked later, in one place (the rotator)."""
    text = _text(payload)
    if text.startswith("{"):
        try:
            obj = json.loads(text, parse_constant=lambda c: c)  # NaN/Infinity stay strings
        except json.JSONDecodeError as exc:
            raise PayloadError(f"bad JSON: {exc.msg}") from None
        if not isinstance(obj, dict):
            raise PayloadError("JSON target must be an object")
        unknown = set(obj) - {"azimuth", "elevation", "az", "el"}
        if unknown:
            raise PayloadError(f"unknown key(s) in target: {', '.join(sorted(unknown))}")
        az_raw = obj.get("azimuth", obj.get("az"))
        el_raw = obj.get("elevation", obj.get("el"))
        if az_raw is None:
            raise PayloadError('JSON target needs "azimuth"')
        az = _number(az_raw, "azimuth")
        return az, None if el_raw is None else _number(el_raw, "elevation")
    parts = [p for p in _SPLIT.split(text) if p]
    if not parts or len(parts) > 2:
        raise PayloadError(f"target must be 'azimuth' or 'azimuth elevation', got {text[:40]!r}")
    az = _number(parts[0], "azimuth")
    el = _number(parts[1], "elevation") if len(parts) == 2 else None
    return az, el


def parse_number(payload: bytes, what: str) -> float:
    """One bare number (also as a JSON number)."""
    return _number(_text(payload), what)


def parse_switch(payload: bytes) -> bool:
    text = _text(payload).lower()
    if text in _TRUE:
        return True
    if text in _FALSE:
        return False
    raise PayloadError(f"expected ON or OFF, got {text[:20]!r}")


def describe(kind: str, payload: bytes) -> str:
    """How a refused command is echoed back on the error topic (short, printable)."""
    shown = payload[:40].decode("utf-8", "replace")
    more = "…" if len(payload) > 40 else ""
    return f"{kind} {shown!r}{more}" if payload else kind


def number(value: float) -> str:
    if value == int(value):
        return str(int(value))
    return f"{value:.2f}".rstrip("0").rstrip(".")


def switch(value: bool) -> str:
    return "ON" if value else "OFF"


def status_json(status: RotatorStatus, time_unix: float, has_elevation: bool) -> str:
    doc: dict[str, object] = {
        "bearing": status.bearing_deg,
        "target": status.target_az_deg,
    }
    if has_elevation:
        doc["elevation"] = status.elevation_deg
        doc["target_elevation"] = status.target_el_deg
    if status.controller_time is not None:
        doc["controller_time"] = status.controller_time
    if status.expected_end_unix is not None:
        doc["expected_end"] = _iso(status.expected_end_unix)
    doc.update(
        state=status.state.value,
        moving=status.moving,
        connected=status.connected,
        available=status.available,
        locked=status.locked,
        version=status.version,
        options={k: v for k, v in sorted(status.options.items())},
        last_error=status.last_error,
        last_command_source=status.last_command_source,
        estimated=status.estimated,
        time=_iso(time_unix),
    )
    return json.dumps(doc, separators=(",", ":"))


def _iso(time_unix: float) -> str:
    return datetime.fromtimestamp(time_unix, UTC).isoformat(timespec="milliseconds")
