"""The payloads of who is turning it (pure, tested on their own: docs/architecture.md rule 4):
a claim of the control lease, a release, ``R/control``. What a claim's operator and minutes
may be is the lease's to judge (runtime/lease.py rule 1); here only the JSON's shape.

Rules:
1. A claim is a JSON object with ``minutes`` and, unless the message carries the MQTT 5 user
   property ``operator``, an ``operator``; any other key, or anything that is not such an
   object, is a PayloadError naming what was wrong (refused on ``R/error``, nothing changes).
   Its minutes are read as every payload's numbers are (interfaces/mqtt/payloads.py
   ``json_number``; docs/mqtt.md: in JSON a number, or a string that holds one): ``"30"`` is
   30 (attack 20: it was refused "minutes must be a number", where ``R/target`` took
   ``{"azimuth": "123"}``). Anything else goes as sent, for the lease to judge.
2. A release takes any payload; a JSON object's valid ``operator`` names who released it when
   the message has no user property (Home Assistant's button sends one); one that gives it
   twice names nobody (an attack pass: its last value was the name in the audit trail). It is
   read in the words a claim is (review 68: one framed with a BOM or a C string's NUL named
   nobody, where its claim had named its operator).
   (Under MQTT 3.1.1 an empty one is refused before it comes here: interfaces/mqtt/service.py
   rule 1.)
3. ``R/control`` says who holds the lease and until when (ISO 8601, UTC), or nobody.
"""

from __future__ import annotations

import json
from datetime import UTC, datetime

from bridge.core.jsonkeys import DuplicateKey, unique_keys
from bridge.core.model import Control, operator_name
from bridge.interfaces.mqtt.payloads import PayloadError, json_number
from bridge.interfaces.mqtt.payloads import text as payload_text

EXAMPLE = '{"operator": "DL1ABC", "minutes": 30}'


def parse_claim(payload: bytes, operator: str | None) -> tuple[object, object]:
    """Rule 1: (operator, minutes) as sent, minutes that a string holds as that number; the
    message's own operator when it names none."""
    text = payload_text(payload)  # (the words every topic reads: size, UTF-8, a BOM, a NUL)
    try:  # NaN: a string; a key given twice: refused (core/jsonkeys.py)
        obj = json.loads(text, parse_constant=lambda c: c, object_pairs_hook=unique_keys)
    except json.JSONDecodeError as exc:
        raise PayloadError(f"bad JSON: {exc.msg}; a claim is {EXAMPLE}") from None
    except DuplicateKey as exc:
        raise PayloadError(f"bad JSON: {exc}; a claim is {EXAMPLE}") from None
    if not isinstance(obj, dict):
        raise PayloadError(f"a claim must be a JSON object, e.g. {EXAMPLE}")
    unknown = set(obj) - {"operator", "minutes"}
    if unknown:
        raise PayloadError(f"unknown key(s) in a claim: {', '.join(sorted(unknown))}")
    if "minutes" not in obj:
        raise PayloadError(f'a claim needs "minutes", e.g. {EXAMPLE}')
    who = obj.get("operator", operator)
    if who is None:
        raise PayloadError(f'a claim needs "operator", e.g. {EXAMPLE}')
    minutes = obj["minutes"]
    if isinstance(minutes, str):  # rule 1: a string that holds a number is that number
        try:
            minutes = json_number(minutes, "minutes")
        except PayloadError:
            pass  # as sent: the lease refuses it, "minutes must be a number"
    return who, minutes


def parse_release(payload: bytes) -> str | None:
    """Rule 2: who the payload says released it, or None (a payload no command is as long as,
    or JSON nested past the parser's depth, an attack pass: names nobody, and still releases)."""
    try:  # the words every topic reads, a claim's too (review 68: a BOM or a C string's NUL)
        text = payload_text(payload)
    except PayloadError:  # (too large, not UTF-8, a control character: names nobody)
        return None
    if not text.startswith("{"):
        return None
    try:  # a key given twice names nobody (core/jsonkeys.py: which did the sender mean?)
        obj = json.loads(text, object_pairs_hook=unique_keys)
    except (ValueError, RecursionError):  # (not JSON, DuplicateKey)
        return None
    return operator_name(obj.get("operator")) if isinstance(obj, dict) else None


_FREE = json.dumps({"holder": None, "until": None}, separators=(",", ":"))  # (every status's)


def control_json(control: Control | None) -> str:
    """Rule 3: ``R/control`` (retained)."""
    if control is None:
        return _FREE
    doc = {"holder": control.operator, "until": control_time(control)}
    return json.dumps(doc, separators=(",", ":"))


def control_time(control: Control) -> str:
    """When the lease ends, as ``R/control`` and ``R/status`` say it."""
    return datetime.fromtimestamp(control.until_unix, UTC).isoformat(timespec="milliseconds")
