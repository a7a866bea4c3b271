"""Inbound payloads parsed, outbound payloads rendered. Pure functions, no paho.

Inbound rules: UTF-8 text at most MAX_COMMAND_BYTES long; numbers are finite decimals; a target
is a bare azimuth (``123``, ``123.5``), ``az el`` (space or comma), a JSON object
``{"azimuth": a, "elevation": e}``, or a place: a bare Maidenhead locator of 4, 6 or 8
characters (``PM95vq``; a two-letter field only in JSON: ``JA`` is more often a preset's name),
``{"locator": "PM95vq"}`` or ``{"latitude": 35.7, "longitude": 139.7}``, each with an optional
``"path": "long"``; switches are ON/OFF, 1/0, true/false in any case. Every payload's words
are read by one rule (``_words``: a byte-order mark before them and NULs after them dropped,
any other control character refused). Anything else raises PayloadError with a message meant
for the user.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Callable
from dataclasses import dataclass
from datetime import UTC, datetime
from operator import attrgetter, is_
from typing import Any

from bridge.core import geo
from bridge.core.jsonkeys import DuplicateKey, unique_keys
from bridge.core.model import RotatorStatus, TargetInfo
from bridge.core.text import NOT_TEXT, bad_char
from bridge.feature import StatusBlock, status_blocks
from bridge.interfaces.mqtt.call_payload import Called, CallError, parse_called
from bridge.pointing import Pointing
from bridge.protocols.base import ModelSpec, Setting, SettingKind

MAX_COMMAND_BYTES = 256
#: a satellite's name on R/track: a TLE file's name line may be long (a hand-made file naming
#: its satellite in words; an attack pass: a name of 79 the track select offered was refused at
#: 64), and this is the longest state Home Assistant keeps, the select's option being the name
MAX_NAME_CHARS = 255
#: a target's two fields: apart by spaces, or by one comma or semicolon with spaces round it
#: or not; an empty field (",30", "120,,30") is no value left out but a refusal (an attack
#: pass: ",30", meant as elevation 30, turned the rotor to azimuth 30)
_SPLIT = re.compile(r"\s*[,;]\s*|\s+")
# ASCII digits only: Python's float() also takes "１３３" and "١٤٤"
_NUMBER = re.compile(r"^[+-]?([0-9]+(\.[0-9]*)?|\.[0-9]+)([eE][+-]?[0-9]+)?$")
#: json.dumps(doc, separators=(",", ":")), the encoder made once (dumps makes one each call)
_COMPACT = json.JSONEncoder(separators=(",", ":"))


def _status_encoder() -> Callable[[object], str]:
    """``_COMPACT.encode`` for R/status's document, which is made at every reading: the C
    encoder ``encode`` makes anew at every call (json.encoder's own ``c_make_encoder``, as
    ``iterencode`` makes it), made once; no check for circles (a document made of a status
    has none: a circle would be a RecursionError). Where Python has no C encoder, the
    encoder's own ``encode``."""
    make = getattr(json.encoder, "c_make_encoder", None)
    if make is None:
        return _COMPACT.encode
    c = _COMPACT
    encode = make(
        None,
        c.default,
        json.encoder.encode_basestring_ascii,
        None,
        c.key_separator,
        c.item_separator,
        c.sort_keys,
        c.skipkeys,
        c.allow_nan,
    )
    return lambda doc: "".join(encode(doc, 0))


_STATUS_ENCODE = _status_encoder()
_BOM = "\ufeff"  # (U+FEFF: what a UTF-8 byte-order mark decodes to)
_TRUE = {"on", "1", "true"}
_FALSE = {"off", "0", "false"}
# words that never press a button (parse_press): a switch's off and what else says "no"
_NOT_A_PRESS = _FALSE | {"no", "n", "f", "none", "null", "nil", "undefined", "stop", "cancel"}


class PayloadError(ValueError):
    pass


LOGGED_CHARS = 200  # service.py rule 4: of a command or a reason, in a log line
KIND_CHARS = 80  # describe: of a command's kind and argument (an option's name) echoed back


def group_info_json(
    group_id: str, name: str, members: tuple[str, ...], bridge: dict[str, str] | None
) -> str:
    """``G/info``: a group (``group``: its id), its name and members, and its bridge's stamp
    (claim.py rule 5: a bridge started on a live bridge's group topic is refused by it, review
    77); never a rotator's (``is_group_info``)."""
    doc: dict[str, object] = {"group": group_id, "name": name, "members": list(members)}
    if bridge is not None:
        doc["bridge"] = bridge
    return json.dumps(doc, separators=(",", ":"))


def is_group_info(payload: bytes | None) -> bool:
    """Whether ``payload`` is a group's ``G/info`` (``group_info_json``), not a rotator's
    ``R/info``: a remote finds no rotator there, and stale.py rule 4 no removed rotator."""
    try:
        doc = json.loads(payload or b"")
    except (ValueError, RecursionError):
        return False
    return isinstance(doc, dict) and isinstance(doc.get("group"), str)


def one_line(text: str) -> str:
    """What a sender wrote, for a log line (service.py rule 4): what is not printable escaped
    (no payload starts a log line of its own), cut short."""
    shown = "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)
    return shown if len(shown) <= LOGGED_CHARS else shown[: LOGGED_CHARS - 3] + "..."


def _text(payload: bytes) -> str:
    """Every command payload's text, read here and nowhere else (attack 20: ``R/park`` took
    ``OFF\\0`` as a press where ``R/lock`` refused ``ON\\0``): UTF-8, not too large, then
    ``_words``."""
    if len(payload) > MAX_COMMAND_BYTES:
        raise PayloadError(f"payload too large ({len(payload)} bytes, at most {MAX_COMMAND_BYTES})")
    try:
        decoded = payload.decode("utf-8")
    except UnicodeDecodeError:
        raise PayloadError("payload is not UTF-8 text") from None
    return _words(decoded)


_BLANKS = " \t\n\r"  # _words: the blanks of a payload (str.strip's own take U+001C..U+001F, NEL)


def _words(text: str) -> str:
    """The one rule for what a sender's tools put round the words, for every topic alike (a
    payload's text; a JSON string a press is read from): blanks at either end, a UTF-8
    byte-order mark at the start (a Windows script's) and NULs at the end (a C string's
    terminator: an Arduino sketch that publishes ``strlen + 1`` bytes) are no part of the
    words and are dropped (``OFF\\0`` is OFF to the lock, a park, an option, a follow).
    Any other control character, or a byte-order mark elsewhere, is refused, naming it: no
    word a command takes holds one, and what cannot be read is never taken as a yes (a press).
    Blanks inside (space, tab, line breaks: ``_BLANKS``) are the parsers' to judge: they part a
    target's two fields; no other control character is a blank here, though Python's
    ``isspace`` says so of U+001C..U+001F and NEL (review 68: ``120<US>30`` turned the rotor to
    120, 30)."""
    text = text.strip(_BLANKS).removeprefix(_BOM).strip(_BLANKS).rstrip("\0").rstrip(_BLANKS)
    if not text:
        raise PayloadError("empty payload")
    for c in text:
        if c == _BOM:
            raise PayloadError("payload holds U+FEFF, a byte-order mark, past its start")
        if c not in _BLANKS and bad_char(c) is not None:
            raise PayloadError(
                f"payload holds U+{ord(c):04X}, which no command's words hold (a control "
                "character or a non-character; a C string's NUL is taken only at the end)"
            )
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


@dataclass(frozen=True)
class Place:
    """A target named by where it is; the bearing comes from the station (pointing.py)."""

    latitude_deg: float | None  # None (with longitude): the place of the current target
    longitude_deg: float | None
    locator: str | None = None
    long_path: bool = False


def _json_object(text: str, what: str) -> dict[str, object]:
    try:  # NaN/Infinity stay strings; a key given twice is refused (core/jsonkeys.py)
        obj = json.loads(text, parse_constant=lambda c: c, object_pairs_hook=unique_keys)
    except json.JSONDecodeError as exc:
        raise PayloadError(f"bad JSON: {exc.msg}") from None
    except DuplicateKey as exc:
        raise PayloadError(f"bad JSON: {exc}") from None
    if not isinstance(obj, dict):
        raise PayloadError(f"JSON {what} must be an object")
    return obj


def parse_aim(payload: bytes) -> tuple[float, float | None] | Place | Called:
    """A target (parse_target), a place (a locator or coordinates), or a call (call_payload.py),
    short or long path."""
    text = _text(payload)
    if len(text) == 2 and text.isalpha():  # a preset's name or a word sent to the wrong topic
        raise PayloadError(
            f"{text!r} is no bearing; a bare locator has 4, 6 or 8 characters (a field alone: "
            f'{{"locator": "{text}"}}; a preset goes to the preset topic)'
        )
    if geo.is_locator(text) or _looks_like_locator(text):
        return _place(text, None, None, False)  # a bad locator gets the locator's error
    if not text.startswith("{"):
        return parse_target(payload)
    obj = _json_object(text, "target")
    if "call" in obj:
        try:
            return parse_called(obj)
        except CallError as exc:
            raise PayloadError(str(exc)) from None
    if not {"locator", "latitude", "longitude", "path"} & set(obj):
        return parse_target(payload)
    unknown = set(obj) - {"locator", "latitude", "longitude", "path"}
    if unknown:
        raise PayloadError(f"unknown key(s) in a place target: {', '.join(sorted(unknown))}")
    path = obj.get("path", "short")
    if path not in ("short", "long"):
        raise PayloadError(f'"path" must be "short" or "long", got {json.dumps(path)[:20]}')
    locator = obj.get("locator")
    if locator is not None:
        if "latitude" in obj or "longitude" in obj:
            raise PayloadError('give "locator" or "latitude"/"longitude", not both')
        if not isinstance(locator, str):
            raise PayloadError('"locator" must be text, e.g. "PM95vq"')
        return _place(locator.strip(), None, None, path == "long")
    if set(obj) == {"path"}:  # the current place, the other way round (HA's long path button)
        return Place(None, None, None, path == "long")
    if "latitude" not in obj or "longitude" not in obj:
        raise PayloadError('a place needs "locator", or "latitude" and "longitude"')
    lat, lon = _number(obj["latitude"], "latitude"), _number(obj["longitude"], "longitude")
    if not -90 <= lat <= 90 or not -180 <= lon <= 180:
        raise PayloadError("latitude must be -90..90 and longitude -180..180")
    return _place(None, lat, lon, path == "long")


def _looks_like_locator(text: str) -> bool:
    """Two letters, then a digit, and a locator's length (``JZ62``): a bad locator, no number."""
    return (
        len(text) in geo.LOCATOR_LENGTHS
        and text[:2].isalpha()
        and (len(text) == 2 or text[2].isdigit())
    )


def _place(locator: str | None, lat: float | None, lon: float | None, long: bool) -> Place:
    if locator is not None:
        try:
            lat, lon = geo.parse_locator(locator)
        except geo.LocatorError as exc:
            raise PayloadError(str(exc)) from None
        locator = locator.upper()[:4] + locator.lower()[4:6] + locator[6:]
    assert lat is not None and lon is not None
    return Place(lat, lon, locator, long)


def parse_nudge(payload: bytes) -> tuple[float, float | None]:
    """(azimuth step, elevation step or None): ``+10``, ``-10`` or ``{"azimuth": 5, ...}``."""
    text = _text(payload)
    if not text.startswith("{"):
        return _number(text, "nudge"), None
    obj = _json_object(text, "nudge")
    unknown = set(obj) - {"azimuth", "elevation", "az", "el"}
    if unknown or not obj:
        raise PayloadError('a nudge is a number, or JSON {"azimuth": 5, "elevation": -2}')
    _one_name_each(obj)
    az, el = obj.get("azimuth", obj.get("az", 0)), obj.get("elevation", obj.get("el"))
    return _number(az, "azimuth"), None if el is None else _number(el, "elevation")


def _one_name_each(obj: dict[str, object]) -> None:
    """``{"az": 30, "azimuth": 181}`` names one axis twice: which did the sender mean?"""
    for long, short in (("azimuth", "az"), ("elevation", "el")):
        if long in obj and short in obj:
            raise PayloadError(f'give "{long}" or "{short}", not both')


def parse_name(payload: bytes, what: str) -> str:
    text = _text(payload)
    bad = bad_char(text)  # (the settings' rule for a preset's name: core/text.py)
    if bad is not None:
        raise PayloadError(f"{what} holds {bad}, {NOT_TEXT}")
    return text


def parse_track(payload: bytes) -> tuple[str, tuple[str, str, str] | None]:
    """``R/track``: ``sun``, ``moon``, ``off``, a satellite's name from the TLE file, or JSON
    ``{"tle": ["NAME", "1 ...", "2 ..."]}`` (the name line may be left out). The elements are
    checked by the rotator (sky.Body.satellite). A name is printable and at most
    MAX_NAME_CHARS long (and the payload at most MAX_COMMAND_BYTES): Home Assistant's track
    select offers only names taken here (homeassistant/info.py ``track_options``)."""
    text = _text(payload)
    if not text.startswith("{"):
        if len(text) > MAX_NAME_CHARS or not text.isprintable():
            raise PayloadError(f"track: a name of at most {MAX_NAME_CHARS} printable characters")
        return text, None
    doc = _json_object(text, "track")
    lines = doc.get("tle")
    if set(doc) != {"tle"} or not isinstance(lines, list) or len(lines) not in (2, 3):
        raise PayloadError('track: JSON must be {"tle": ["NAME", "1 ...", "2 ..."]}')
    if not all(isinstance(line, str) for line in lines):
        raise PayloadError("track: the TLE lines must be strings")
    strings = [str(line).strip() for line in lines]
    if len(strings) == 2:
        # (a name and one line: "a satellite needs a name" was all a TLE sent without its
        # line 2 got back, an attack pass)
        if not strings[0].startswith("1 "):
            raise PayloadError('track: two lines are a TLE\'s "1 ..." and "2 ...", a name first')
        strings.insert(0, "")
    name, line1, line2 = strings
    # (the name is shown and logged as a bare one is: an attack pass sent a line break and
    # terminal escapes in it, a log line forged and the retained state carrying them)
    if len(name) > MAX_NAME_CHARS or not all(line.isprintable() for line in strings):
        raise PayloadError(
            f"track: the TLE's name is at most {MAX_NAME_CHARS} printable characters, and its "
            "lines printable text"
        )
    name = name or line1[2:7].strip()  # the catalog number, as a TLE file without names
    return name, (name, line1, line2)


FOLLOW_SOURCES = ("wsjtx",)  # what R/follow can follow (session/follow.py)


def parse_follow(payload: bytes) -> tuple[bool, bool]:
    """``R/follow``: ``wsjtx`` or ``off``, or JSON ``{"source": "wsjtx", "path": "long"}``;
    (on, long path)."""
    text = _text(payload)
    doc = _json_object(text, "follow") if text.startswith("{") else {"source": text}
    unknown = set(doc) - {"source", "path"}
    if unknown:
        raise PayloadError(f"unknown key(s) in follow: {', '.join(sorted(unknown))}")
    source, path = doc.get("source"), doc.get("path", "short")
    if not isinstance(source, str) or source.strip().lower() not in (*FOLLOW_SOURCES, "off"):
        shown = repr(source[:20]) if isinstance(source, str) else json.dumps(source)
        raise PayloadError(f"follow: expected wsjtx or off, got {shown}")
    if path not in ("short", "long"):
        raise PayloadError(f'follow: "path" must be "short" or "long", got {json.dumps(path)}')
    return source.strip().lower() != "off", path == "long"


def parse_target(payload: bytes) -> tuple[float, float | None]:
    """(azimuth, elevation or None). Limits are checked later, in one place (the rotator)."""
    text = _text(payload)
    if text.startswith("{"):
        obj = _json_object(text, "target")
        unknown = set(obj) - {"azimuth", "elevation", "az", "el"}
        if unknown:
            raise PayloadError(f"unknown key(s) in target: {', '.join(sorted(unknown))}")
        _one_name_each(obj)
        az_raw = obj.get("azimuth", obj.get("az"))
        el_raw = obj.get("elevation", obj.get("el"))
        if az_raw is None:
            raise PayloadError('JSON target needs "azimuth"')
        az = _bearing(az_raw)
        return az, None if el_raw is None else _number(el_raw, "elevation")
    parts = _SPLIT.split(text)
    if len(parts) > 2 or "" in parts:
        raise PayloadError(f"target must be 'azimuth' or 'azimuth elevation', got {text[:40]!r}")
    az = _bearing(parts[0])
    el = _number(parts[1], "elevation") if len(parts) == 2 else None
    return az, el


def _bearing(raw: object) -> float:
    """A target's azimuth: a number, never one written with a plus sign. ``+10`` is the nudge
    buttons' word (Home Assistant's, docs/mqtt.md ``R/nudge``), and on the target topic it
    was the bearing 10: a rotor at 120 turned 110 degrees the other way where the sender meant
    130 (attack 20), as ``,30`` once turned one to azimuth 30. No one writes a bearing with a
    plus. A minus stays a bearing: past north counter-clockwise on a rotor whose travel goes
    there (a SPID's -180, docs/pointing.md; Hamlib's convention), and refused by the judge as
    outside 0..360 where it does not."""
    if isinstance(raw, str) and raw.strip().startswith("+"):
        shown = raw.strip()[:20]
        raise PayloadError(
            f"{shown!r} is a signed step, a nudge: send it to the nudge topic; a bearing is "
            "written without '+'"
        )
    return _number(raw, "azimuth")


def json_number(raw: object, what: str) -> float:
    """A JSON value as a number, as every payload's is read (docs/mqtt.md: in JSON a number,
    or a string that holds one; ASCII digits, finite); PayloadError naming ``what`` if not."""
    return _number(raw, what)


def parse_number(payload: bytes, what: str) -> float:
    """One bare number (also as a JSON number)."""
    return _number(_text(payload), what)


def text(payload: bytes) -> str:
    """A payload as text: UTF-8, stripped, not empty, not too large (PayloadError)."""
    return _text(payload)


def parse_press(payload: bytes, what: str, word: str) -> str:
    """A button's press (``R/park``, ``R/health/reset``): any text but a word that says no
    (OFF, 0, false: a dashboard's switch turned off must not park a rotor) and none of what
    any payload may not be (not UTF-8, too large: rule 2; an attack pass parked a rotor on
    4096 bytes of 0xFF).

    A word that says no is any spelling of one a sender may mean as "not now" (an attack pass
    parked a rotor on ``no``, ``null`` and ``{"park": false}``): the words of ``_NOT_A_PRESS``,
    also as a JSON string, JSON's false and null, a zero in any spelling, and any JSON object
    or array (a press carries no document, and one that says ``false`` inside must not move a
    rotor). A finite number other than zero is a press: Node-RED's inject node sends a
    timestamp; ``NaN``, ``Infinity``, ``-Infinity`` (or ``1e999``) is no number, so no press
    (attack 28: a Node-RED ``Number()`` of ``off`` parked a rotor).
    What cannot be read is no press either (attack 20: ``OFF\\0`` and a byte-order mark before
    ``OFF`` parked a rotor): the payload's words are read as every topic's are (``_words``:
    ``OFF\\0`` is OFF, another control character is refused naming it), and a press is
    printable text (an invisible character, a JSON string not ended, says no)."""
    text = _text(payload)
    if _not_a_press(text):
        raise PayloadError(f"{text[:20]!r} does not {what}: send {word}")
    return text


def _not_a_press(text: str) -> bool:
    word = text.lower()
    if word in _NOT_A_PRESS:
        return True
    if text[0] in "{[":
        return True  # a document, whatever it holds (see parse_press)
    if not text.isprintable():
        return True  # an invisible character (U+200B, a tab): what it says is not seen
    if text[0] == "'" and text[-1] == "'" and len(text) > 1:
        text = json.dumps(text[1:-1])  # 'OFF' (a shell's quotes kept) as "OFF"
    if text[0] == '"':
        try:
            inner = json.loads(text)
        except ValueError:
            return True  # "OFF without its end: not read, so no yes
        if not isinstance(inner, str):
            return True
        try:  # the same words as a bare payload's ("\\u0000OFF", "\\ufeffOFF": no press)
            return _not_a_press(_words(inner))
        except PayloadError:
            return True  # empty, or what cannot be read: never a yes
    try:
        value = float(word)
    except ValueError:
        return False
    # a zero in any spelling (0.0, -0, 00, 0e0) says no; so does a number that is no number
    # (attack 28: NaN, a Node-RED Number() of "off"; Infinity, -Infinity, 1e999): never a yes
    return value == 0 or not math.isfinite(value)


def parse_switch(payload: bytes) -> bool:
    text = _text(payload)
    word = text.lower()
    if word in _TRUE:
        return True
    if word in _FALSE:
        return False
    raise PayloadError(f"expected ON or OFF, got {text[:20]!r}")  # as sent, not lower-cased


def describe(kind: str, payload: bytes) -> str:
    """How a command is echoed back on the error topic and in the audit trail (printable):
    whole for any payload a command can be taken from (MAX_COMMAND_BYTES), cut short only
    beyond (an attack pass: cut at 40 bytes, a claim or a target padded with spaces was
    audited without whom the lease went to or where the rotor turned). ``kind`` is cut short
    too: it may hold a topic's level (``option <name>``), and an attack pass published on
    ``R/option/<60,000 characters>``: each R/error and audit event was 120 KB."""
    shown = payload[:MAX_COMMAND_BYTES].decode("utf-8", "replace")
    more = "…" if len(payload) > MAX_COMMAND_BYTES else ""
    kind = cut_short(kind)
    return f"{kind} {shown!r}{more}" if payload else kind


def cut_short(text: str) -> str:
    """A command's kind or a topic's level as echoed back: at most KIND_CHARS, then '…' (an
    option's name is any topic level: ``describe``'s attack pass)."""
    return text if len(text) <= KIND_CHARS else text[:KIND_CHARS] + "…"


def number(value: float) -> str:
    if value == int(value):
        return str(int(value))
    return f"{value:.2f}".rstrip("0").rstrip(".")


def switch(value: bool) -> str:
    return "ON" if value else "OFF"


def target_info(info: TargetInfo) -> dict[str, object]:
    return {
        "locator": info.locator,
        "latitude": round(info.latitude_deg, 4),
        "longitude": round(info.longitude_deg, 4),
        "distance_km": round(info.distance_km, 1),
        "short_path_deg": round(info.short_path_deg, 1),
        "long_path_deg": round(info.long_path_deg, 1),
        "path": info.path,
    }


@dataclass(frozen=True)
class ConsoleFacts:
    """What a console far from the station draws beyond the judge's terms (``R/info``'s
    ``station``, ``beamwidth``, ``nudge_step``, ``satellites``)."""

    station: tuple[float, float] | None = None  # latitude, longitude (degrees)
    locator: str | None = None
    beamwidth_deg: float = 60.0
    nudge_step_deg: float = 5.0
    satellites: tuple[str, ...] = ()  # the TLE file's names when the bridge started


def setting_info(setting: Setting) -> dict[str, object]:
    """What ``R/option/<name>`` takes, for R/info (protocols/base.py ``Setting``): its name,
    label and kind, a number's range, step and unit, a choice's names."""
    doc: dict[str, object] = {"name": setting.name, "label": setting.label, "kind": setting.kind}
    if setting.kind is SettingKind.NUMBER:
        doc.update(min=setting.minimum, max=setting.maximum, step=setting.step, unit=setting.unit)
    elif setting.kind is SettingKind.CHOICE:
        doc["choices"] = list(setting.choices)
    return doc


def info_json(
    name: str,
    spec: ModelSpec,
    pointing: Pointing,
    can_track: bool,
    console: ConsoleFacts | None = None,
    rotator_id: str | None = None,
    bridge: dict[str, str] | None = None,
) -> str:
    """``R/info``: what a rotator is and may do, for a client far from the station (limits,
    sectors, presets, capabilities as the station's configuration has them; true bearings);
    with ``console``, what a console there draws too; with ``bridge``, the bridge's stamp
    (claim.py rule 5: ``Instance.stamp``, another bridge's first look reads it)."""
    lo, hi = pointing.target_range()
    doc: dict[str, object] = {
        "id": rotator_id,
        "name": name,
        "model": spec.name,
        "model_name": spec.display_name,
        "has_elevation": spec.has_elevation,
        "can_report_position": spec.can_report_position,
        "can_track": can_track,
        "azimuth_range": [lo, hi],
        "elevation_range": [pointing.el_min_deg, pointing.el_max_deg]
        if spec.has_elevation
        else None,
        "keep_out": [list(sector) for sector in pointing.keep_out],
        "park": list(pointing.park) if pointing.park is not None else None,
        "options": sorted(spec.options),
        "settings": [setting_info(s) for s in spec.settings],
    }
    if console is not None:
        where = console.station
        doc["station"] = (
            {"latitude": where[0], "longitude": where[1], "locator": console.locator}
            if where is not None
            else None
        )
        doc["beamwidth"] = console.beamwidth_deg
        doc["nudge_step"] = console.nudge_step_deg
        doc["satellites"] = list(console.satellites)
    if bridge is not None:
        doc["bridge"] = bridge
    return json.dumps(doc, separators=(",", ":"))


def presets_json(presets: dict[str, tuple[float, float | None]]) -> str:
    """``R/presets``: name -> azimuth, or [azimuth, elevation]; whole degrees without ".0", as
    the user wrote them in the configuration."""

    def num(x: float) -> float | int:
        return int(x) if x.is_integer() else x

    doc = {n: num(az) if el is None else [num(az), num(el)] for n, (az, el) in presets.items()}
    return json.dumps(doc, separators=(",", ":"))


def status_json(
    status: RotatorStatus, time_unix: float, has_elevation: bool, shows_raw: bool = False
) -> str:
    """``R/status``, made whole: a rotator's every reading goes through its own
    ``StatusText``, which keeps what a reading leaves as it was."""
    return StatusText(has_elevation).render(status, time_unix, shows_raw)


class StatusText:
    """One rotator's ``R/status``, made at every reading: status_json's text, all but its
    head (``bearing`` to ``target_info``) and its time kept from the last status and made
    again only when a value it is made of is not the very object it was made of last time (a
    status is made of the last one's values; a turning rotor's readings change its head:
    session/status.py). The same object gives the same text (every one is immutable: frozen
    dataclasses, text, numbers, an enum; ``options``, a new dict each time, by its keys and
    values); equal values are not enough (``1 == 1.0 == True``, ``0.0 == -0.0``: four
    texts). The values are held while kept, so no other object takes their ``id``; one
    attribute holds them and the text, so another thread never reads one without the other."""

    __slots__ = ("_has_elevation", "_kept")

    def __init__(self, has_elevation: bool) -> None:
        self._has_elevation = has_elevation
        self._kept: tuple[tuple[object, ...], str, str] = ((), "", "")

    def render(self, status: RotatorStatus, time_unix: float, shows_raw: bool) -> str:
        blocks = status_blocks()
        relayed = status.relayed  # (a remote's: the station's blocks, as it wrote them)
        if relayed is None:
            values = [block.value(status) for block in blocks]
        else:
            values = [relayed.get(block.key) for block in blocks]
        options = status.options
        key = (blocks, *_REST_FIELDS(status), *values, *options, *options.values())
        kept, middle, tail = self._kept
        if len(key) != len(kept) or not all(map(is_, key, kept)):
            middle, tail = _status_rest(status, blocks, values, relayed is not None)
            self._kept = key, middle, tail
        head = _STATUS_ENCODE(_status_head(status, self._has_elevation, shows_raw))
        return f'{head[:-1]},{middle}"{_iso(time_unix)}"{tail}'  # (a time needs no escape)


#: what R/status is made of after its head, besides the feature blocks and the options
_REST_FIELDS = attrgetter(
    "parked",
    "state",
    "connected",
    "available",
    "locked",
    "lock_unknown",
    "version",
    "last_error",
    "last_command_source",
    "last_operator",
    "control",
    "estimated",
    "order",
)


def _status_head(status: RotatorStatus, has_elevation: bool, shows_raw: bool) -> dict[str, object]:
    """R/status up to ``parked``: what a reading changes."""
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
    if shows_raw:
        doc["raw_bearing"] = status.raw_bearing_deg
        doc["overlap"] = status.overlap
    if status.target_info is not None:
        doc["target_info"] = target_info(status.target_info)
    return doc


def _status_rest(
    status: RotatorStatus,
    blocks: tuple[StatusBlock[Any], ...],
    values: list[object],
    relayed: bool = False,
) -> tuple[str, str]:
    """R/status after its head, around its time: its members from ``parked`` to ``estimated``
    then ``"time":``; and after the time, the blocks rendered once (rotor health's, once per
    move) and the closing brace. The blocks are each feature's (bridge/feature.py), in the
    registry's order; ``values`` holds each one's value: with ``relayed``, each its block
    already (a remote's reading of the station's R/status: remote/readings.py rule 3)."""
    doc: dict[str, object] = {"parked": status.parked}
    tail = []
    for block, value in zip(blocks, values, strict=True):
        if value is None:
            continue
        if block.rendered:
            text = _STATUS_ENCODE(value) if relayed else block.render(value)
            tail.append(f',"{block.key}":{text}')
        else:
            doc[block.key] = value if relayed else block.render(value)
    control = status.control
    doc["state"] = status.state.value
    doc["moving"] = status.moving
    doc["connected"] = status.connected
    doc["available"] = status.available
    doc["locked"] = status.locked
    if status.lock_unknown:  # (runtime/kept.py rule 10: only while it is not known)
        doc["lock_unknown"] = True
    doc["version"] = status.version
    doc["options"] = dict(sorted(status.options.items()))
    doc["last_error"] = status.last_error
    doc["last_command_source"] = status.last_command_source
    doc["last_operator"] = status.last_operator
    doc["control"] = (
        None if control is None else {"holder": control.operator, "until": _iso(control.until_unix)}
    )
    doc["estimated"] = status.estimated
    order = status.order
    if order is not None:  # (interfaces/mqtt/remote.py rule 10 orders a remote's halts by it)
        doc["order"] = {
            "run": order.run,
            "taken": order.taken,
            "turn": order.turn,
            "lock": order.lock,
            "since": order.since,
        }
    return f'{_STATUS_ENCODE(doc)[1:-1]},"time":', f"{''.join(tail)}}}"


#: the whole seconds ``_iso`` wrote lately, and their text up to the seconds: a status with a
#: lease's end (or a move's) writes two seconds each time, and both stay known
_seconds: dict[int, str] = {}
_SECONDS_KEPT = 8


def _iso(time_unix: float) -> str:
    """``datetime.fromtimestamp(time_unix, UTC).isoformat(timespec="milliseconds")``, the same
    text: microseconds rounded half to even, as datetime rounds a timestamp, then cut to
    milliseconds. The date and the time of day are made once per second (every status says
    the time: most statuses of a second share them)."""
    if not 0 <= time_unix < math.inf:  # (before 1970, or no number: datetime's own answer)
        return datetime.fromtimestamp(time_unix, UTC).isoformat(timespec="milliseconds")
    fraction, whole = math.modf(time_unix)
    us, second = round(fraction * 1e6), int(whole)
    if us >= 1_000_000:
        us -= 1_000_000
        second += 1
    text = _seconds.get(second)
    if text is None:  # (threads that miss at once each write the same text: no harm)
        if len(_seconds) >= _SECONDS_KEPT:
            _seconds.clear()
        text = _seconds[second] = datetime.fromtimestamp(second, UTC).isoformat()[:-6]
    return f"{text}.{us // 1000:03d}+00:00"
