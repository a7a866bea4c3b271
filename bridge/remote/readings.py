"""The station's retained payloads read back (``R/info``, ``R/status``): the other side of
interfaces/mqtt/payloads.py, for the remote (docs/mqtt.md says what each field means).

Rules:
1. Anyone the broker's ACL lets publish there can put anything there: a payload that is not
   what the station writes (not an object, a number that is not finite or too large, a model
   this version does not know, JSON nested past the parser's depth: ``load``) raises
   ValueError (InfoError for R/info), never more, and a field that is absent or of the wrong
   kind reads as unknown; so does a time no UTC date can show (an attack pass: ``R/control``
   naming another holder until ``9999-12-31T23:59:59-14:00``, year 10000 in UTC, raised
   ValueError where the lease's words were made, and every rotctld move got ``RPRT -7``
   with an internal error logged).
2. So does a name or an id (R/info's ``name``, ``id``) that is not one a station writes: one
   holding a control character, or blank at either end (an attack pass: a forged R/info's
   id ``"tower\nDL1ABC -> ..."`` with a terminal's escape sequence put a forged line in the
   remote's start lines on the operator's terminal); the station's model stands for it.
3. ``R/status`` is read back whole, as the station's console shows it (docs/remote.md): its
   core fields into the status's own (``control`` and ``last_operator`` too: an attack pass
   found them dropped, and the remote's page showed a free rotator while another operator
   held the lease), and every feature's block (bridge/feature.py ``StatusBlock``: rotor
   health, following, the wind, tracking...) carried as the station wrote it
   (``RotatorStatus.relayed``), by the registry's keys, so a block added there reaches the
   remote's page with no word here. A block is checked first (``checked_block``): JSON of the
   block's kind, nested no deeper than BLOCK_DEPTH, no longer than BLOCK_CHARS once written,
   every number finite, every text free of control characters (bad_char) and no longer than
   TEXT_CHARS; one that is not is left out, and the log says which and why, once while it
   stays so (each status is read again at each use). A name shown (``last_operator``, the
   lease's holder) is one ``_shown`` lets through and no longer than NAME_CHARS, or unknown
   (a lease's holder: UNSHOWN, the lease shown all the same).
4. A status read from a new payload keeps the last one's objects where it says the same, to
   the letter (``parse_status``'s ``before``: its texts, lease, order, options and blocks):
   the console's R/status text keeps what a reading leaves by its very objects
   (interfaces/mqtt/payloads.py StatusText), and a payload read all anew made that text's
   rest again at every reading (issue 39). The same payload is read once (remote/rotator.py
   ``status``).
"""

from __future__ import annotations

import json
import logging
import math
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any, NamedTuple

from bridge.core.model import (
    Control,
    MotionState,
    Order,
    RotatorStatus,
    SettingValue,
    TargetInfo,
    TrackingInfo,
    kept_if_same,
)
from bridge.core.text import bad_char
from bridge.feature import StatusBlock, status_blocks
from bridge.pointing import Pointing
from bridge.protocols import REGISTRY
from bridge.protocols.axes import Axis, can_drive, composite_spec
from bridge.protocols.base import ModelSpec

log = logging.getLogger(__name__)

BLOCK_DEPTH = 6  # rule 3: how deep a block nests (the station's nest three deep at most)
BLOCK_CHARS = 64_000  # rule 3: a block's JSON text, at most (a pass's track: a few KB)
TEXT_CHARS = 200  # rule 3: a text in a block (a reason, a call, a body's name), at most
NAME_CHARS = 64  # rule 3: an operator's name shown
UNSHOWN = "(a name not shown)"  # rule 3: a lease's holder whose name cannot be shown


class InfoError(ValueError):
    """The station's R/info cannot be used (a model this version does not know)."""


def load(payload: bytes) -> Any:
    """A station's payload as JSON; rule 1: ValueError for anything that is none, JSON
    nested past the parser's depth too (an attack pass: a forged ``R/control`` of 100 KB of
    ``{"holder":`` raised RecursionError at every move a client asked for)."""
    try:
        return json.loads(payload)
    except RecursionError:
        raise ValueError("JSON nested too deep") from None


@dataclass(frozen=True)
class Info:
    """The station's ``R/info``, parsed."""

    name: str
    spec: ModelSpec
    pointing: Pointing
    rotator_id: str | None = None  # the station's id (a station older than this: None)

    @classmethod
    def parse(cls, payload: bytes) -> Info:
        doc = load(payload)
        model = str(doc["model"])
        spec = _spec(model)
        if spec is None:
            raise InfoError(f"the station's model {model!r} is unknown to this rotor-bridge")
        az_lo, az_hi = (_finite(v) for v in doc["azimuth_range"])
        el = doc.get("elevation_range") or [spec.el_min_deg, spec.el_max_deg]
        park = doc.get("park") or None
        at = (_finite(park[0]), None if park[1] is None else _finite(park[1])) if park else None
        # the station's ranges are true bearings already: no offset here (pointing.py rule 1)
        aim = Pointing.of(
            spec,
            (az_lo, az_hi),
            (_finite(el[0]), _finite(el[1])),
            keep_out=tuple((_finite(a), _finite(b)) for a, b in doc.get("keep_out") or ()),
            park=at,
        )
        rid, name = doc.get("id"), doc.get("name")
        return cls(name if _shown(name) else model, spec, aim, rid if _shown(rid) else None)


def _shown(text: object) -> bool:
    """Rule 2: whether ``text`` is a name the remote may show (in its start line, its log)."""
    return isinstance(text, str) and text.strip() == text != "" and bad_char(text) is None


def _spec(model: str) -> ModelSpec | None:
    """The spec R/info's ``model`` names: a model's, or a rotator of two boxes' (``az+el``,
    protocols/axes.py rule 4), as the station makes it; None for one this version lacks."""
    if model in REGISTRY:
        return REGISTRY[model]
    az, _, el = model.partition("+")
    if az not in REGISTRY or el not in REGISTRY:
        return None
    if can_drive(REGISTRY[el], Axis.ELEVATION) is not None:
        return None
    return composite_spec(REGISTRY[az], REGISTRY[el])


def _setting(value: object) -> SettingValue:
    """A setting's value as the status carries it: on/off, a number or a choice's name."""
    if isinstance(value, bool | str):
        return value
    if isinstance(value, int | float):
        return float(value)
    return bool(value)


def _finite(value: object) -> float:
    """A number of R/info; ValueError for NaN and infinities: the judge would raise on them."""
    try:
        n = float(value)  # type: ignore[arg-type]  # TypeError for what is no number: caller's
    except OverflowError:  # an integer past a float's range
        n = math.inf
    if not math.isfinite(n):
        raise ValueError(f"{value!r:.20} is not a finite number")
    return n


def _num(doc: dict[str, Any], key: str) -> float | None:
    """A number, or None (Python's json reads NaN, Infinity, 1e400: never shown, rule 1)."""
    v = doc.get(key)
    if not isinstance(v, int | float) or isinstance(v, bool):
        return None
    try:
        return _finite(v)
    except ValueError:
        return None


def _unix(text: object) -> float | None:
    """Rule 1: an ISO time as unix seconds; unknown (None) for one no UTC date can show
    (``9999-12-31T23:59:59-14:00`` is in year 10000 once in UTC)."""
    try:
        if text is None:
            return None
        unix = datetime.fromisoformat(str(text)).timestamp()
        datetime.fromtimestamp(unix, UTC)  # (what shows it again: the lease's words, the page)
    except (ValueError, OverflowError, OSError):
        return None
    return unix


def _target_info(doc: object) -> TargetInfo | None:
    if not isinstance(doc, dict):
        return None
    lat, lon = _num(doc, "latitude"), _num(doc, "longitude")
    short, long = _num(doc, "short_path_deg"), _num(doc, "long_path_deg")
    if lat is None or lon is None or short is None or long is None:
        return None
    locator = doc.get("locator")
    return TargetInfo(
        lat,
        lon,
        _num(doc, "distance_km") or 0.0,
        short,
        long,
        "long" if doc.get("path") == "long" else "short",
        locator if isinstance(locator, str) else None,
    )


def _tracking(doc: object) -> TrackingInfo | None:
    if not isinstance(doc, dict) or not isinstance(doc.get("body"), str):
        return None
    nxt_or = doc.get("next")
    nxt: dict[str, Any] = nxt_or if isinstance(nxt_or, dict) else {}
    track = doc.get("pass_track") or []
    return TrackingInfo(
        doc["body"],
        str(doc.get("phase", "")),
        _num(doc, "azimuth"),
        _num(doc, "elevation"),
        _num(nxt, "azimuth"),
        _num(nxt, "elevation"),
        _unix(doc.get("aos")),
        _unix(doc.get("los")),
        _num(doc, "max_elevation"),
        _num(doc, "aos_azimuth"),
        bool(doc.get("flip")),
        tuple((float(a), float(e)) for a, e in track if isinstance(track, list)),
        _unix(doc.get("elements_epoch")),
        doc.get("elements_stale") is True,
        doc.get("elements_ahead") is True,
    )


def parse_status(
    rotator_id: str, payload: bytes, before: RotatorStatus | None = None
) -> RotatorStatus:
    """``R/status`` (docs/mqtt.md) back into a RotatorStatus: what a reading needs, and what
    the console draws (the place targeted, the body tracked). Rule 1: ValueError, never more
    (an integer past a float's range in a pass track raised OverflowError). Rule 4: what
    R/status's text is made of after its head is ``before``'s very objects (the status read
    from the last payload) where it says the same, to the letter."""
    try:
        status = _status(rotator_id, payload)
    except OverflowError as exc:
        raise ValueError(f"a number in the status is out of range: {exc}") from None
    return status if before is None else _kept(status, before)


def _kept(status: RotatorStatus, before: RotatorStatus) -> RotatorStatus:
    """Rule 4: ``status`` with ``before``'s objects where they say the same (the interface's
    StatusText keeps the rest of R/status by its very objects: every payload read anew made
    it again at every reading of the remote's console)."""
    kept = status.__dict__
    for name in ("version", "last_error", "last_command_source", "last_operator"):
        old = getattr(before, name)
        if old is not None and old == kept[name]:  # (text: equal is the same text)
            kept[name] = old
    kept["control"] = kept_if_same(status.control, before.control)
    kept["order"] = kept_if_same(status.order, before.order)
    if _same(status.options, before.options):
        kept["options"] = before.options
    relayed, was = status.relayed, before.relayed
    if relayed is not None and was is not None:
        for key, value in relayed.items():
            old = was.get(key)
            if old is not None and _same(value, old):
                relayed[key] = old
    return status


def _same(a: object, b: object) -> bool:
    """Rule 4: two JSON values that write the same text: of the same types throughout, a
    float of the same sign (``1 == 1.0 == True``, ``0.0 == -0.0``: each its own text), an
    object's keys in the same order."""
    if a is b:
        return True
    kind = type(a)
    if kind is not type(b):
        return False
    if kind is dict:
        x, y = a, b
        assert isinstance(x, dict) and isinstance(y, dict)
        return len(x) == len(y) and all(
            k == j and _same(v, w) for (k, v), (j, w) in zip(x.items(), y.items(), strict=True)
        )
    if kind is list or kind is tuple:
        x, y = a, b
        assert isinstance(x, list | tuple) and isinstance(y, list | tuple)
        return len(x) == len(y) and all(map(_same, x, y))
    if kind is float:
        return a == b and math.copysign(1.0, a) == math.copysign(1.0, b)  # type: ignore[arg-type]
    return a == b


def _status(rotator_id: str, payload: bytes) -> RotatorStatus:
    doc = load(payload)
    if not isinstance(doc, dict):  # anyone allowed on the topic can put any JSON there
        raise ValueError(f"a status is a JSON object, not {type(doc).__name__}")

    def num(key: str) -> float | None:
        return _num(doc, key)

    options = doc.get("options")

    return RotatorStatus(
        rotator_id,
        state=MotionState(doc.get("state", "offline")),
        bearing_deg=num("bearing"),
        elevation_deg=num("elevation"),
        target_az_deg=num("target"),
        target_el_deg=num("target_elevation"),
        connected=bool(doc.get("connected")),
        available=bool(doc.get("available")),
        locked=bool(doc.get("locked")),
        lock_unknown=doc.get("lock_unknown") is True,  # (the station's kept.py rule 10)
        version=doc.get("version"),
        last_error=doc.get("last_error"),
        last_command_source=doc.get("last_command_source"),
        estimated=bool(doc.get("estimated")),
        parked=bool(doc.get("parked")),
        options={str(k): _setting(v) for k, v in options.items()}
        if isinstance(options, dict)
        else {},
        controller_time=doc.get("controller_time"),
        expected_end_unix=_unix(doc.get("expected_end")),
        raw_bearing_deg=num("raw_bearing"),
        overlap=doc.get("overlap"),
        target_info=_target_info(doc.get("target_info")),
        tracking=_tracking(doc.get("tracking")),
        tracking_ended=doc.get("tracking_ended"),
        last_operator=_name(doc.get("last_operator")),
        control=_shown_control(doc.get("control")),
        relayed=_relayed(rotator_id, doc),
        order=_order(doc.get("order")),  # (the station's, shown as its console shows it)
    )


def _name(text: object) -> str | None:
    """Rule 3: an operator's name the page may show, or unknown."""
    if not isinstance(text, str) or not _shown(text) or len(text) > NAME_CHARS:
        return None
    return text


def _control(doc: object) -> Control | None:
    """Who holds the lease (features/control/payload.py's words: R/control, the status's
    ``control``), or None: free, or not what the station writes (rule 1)."""
    if not isinstance(doc, dict) or not isinstance(doc.get("holder"), str):
        return None
    until = _unix(doc.get("until"))
    return None if until is None else Control(doc["holder"], until)


def _shown_control(doc: object) -> Control | None:
    """Rule 3: the status's ``control`` as the page shows it: held by a name it may show, or
    by UNSHOWN (a lease held all the same: the station refuses the others' moves)."""
    held = _control(doc)
    if held is None or _name(held.operator) is not None:
        return held
    return Control(UNSHOWN, held.until_unix)


#: rule 3: (rotator, block) -> why it was last left out, said once while it stays so
_told: dict[tuple[str, str], str] = {}


def _relayed(rotator_id: str, doc: dict[str, Any]) -> dict[str, object]:
    """Rule 3: every feature's block of the station's status, checked; one that is not what a
    station writes is left out, and said."""
    out: dict[str, object] = {}
    for block in status_blocks():
        value = doc.get(block.key)
        if value is None:
            continue
        why = checked_block(block, value)
        if why is None:
            out[block.key] = value
            _told.pop((rotator_id, block.key), None)
        elif _told.get((rotator_id, block.key)) != why:
            _told[rotator_id, block.key] = why
            log.warning(
                "%s: the station's status has a %r block the console will not show: %s",
                rotator_id,
                block.key,
                why,
            )
    return out


def checked_block(block: StatusBlock[Any], value: object) -> str | None:
    """Rule 3: why ``value`` is no ``block`` a station writes, or None when it may be shown."""
    if not isinstance(value, block.kind):
        return f"it is {type(value).__name__}, not {block.kind.__name__}"
    why = _json_why(value, BLOCK_DEPTH)
    if why is not None:
        return why
    if len(json.dumps(value)) > BLOCK_CHARS:
        return f"it is longer than {BLOCK_CHARS} characters"
    return None


def _json_why(value: object, depth: int) -> str | None:
    """Rule 3: why ``value`` (parsed JSON) may not reach a page, or None."""
    if value is None or isinstance(value, bool):
        return None
    if isinstance(value, int | float):
        try:
            _finite(value)
        except ValueError as exc:
            return str(exc)
        return None
    if isinstance(value, str):
        if len(value) > TEXT_CHARS:
            return f"a text is longer than {TEXT_CHARS} characters"
        bad = bad_char(value)
        return None if bad is None else f"a text holds {bad}"
    if depth <= 0:
        return f"it nests deeper than {BLOCK_DEPTH}"
    if isinstance(value, dict):
        items: list[object] = [*value.keys(), *value.values()]
    elif isinstance(value, list):
        items = value
    else:  # (json.loads makes nothing else)
        return f"{type(value).__name__} is no JSON"
    for item in items:
        why = _json_why(item, depth - 1)
        if why is not None:
            return why
    return None


class StatusOrder(NamedTuple):
    """``R/status``'s word on a remote's held halts (interfaces/mqtt/remote.py rule 10): its
    ``order`` (the station's run, the newest place taken, the turn's place, the lock word's
    place) and whether the rotor has somewhere to turn to (an azimuth or an elevation
    target, tracking or following: a rotor coasting to a stop with none has taken the stop);
    whether it turns all the same (``moving``: moving or braking, not at rest; a turn no
    command of this run began, the box's own across a restart of its bridge under
    ``unasked_moves = "follow"``, shows so); whether the status knows the motion
    (``motion_known``: not while the controller is not read, ``offline`` or ``unknown``, as
    in a run's first status); whether the lock is ON and whether the status knows it
    (``lock_known``: not while ``lock_unknown``, the state file silent and the broker's lock
    state not read yet)."""

    run: str
    taken: int
    turn: int
    lock: int
    turning: bool
    locked: bool
    lock_known: bool = True
    moving: bool = False
    motion_known: bool = True
    since: int = 0  # core/model.py Order: no place of an earlier run is past it (0: none kept)


#: ``StatusOrder.moving``'s states: not at rest (a restarted bridge's first reading of a box
#: turning on its own says ``braking``: it cannot tell yet)
_NOT_AT_REST = (MotionState.MOVING.value, MotionState.BRAKING.value)
_NOT_READ = (MotionState.OFFLINE.value, MotionState.UNKNOWN.value)  # (``motion_known``)


def status_order(payload: bytes) -> StatusOrder | None:
    """``R/status``'s ``order`` and the states a halt ends (interfaces/mqtt/remote.py rule 10);
    None for a status without an ``order`` (a station's bridge before it: no halt is held for
    it) or not readable (rule 1)."""
    try:
        doc = load(payload)
    except ValueError:
        return None
    if not isinstance(doc, dict):
        return None
    order = _order(doc.get("order"))
    if order is None:
        return None
    turning = (  # (a rotor coasting or braking to a stop with no target has taken it)
        doc.get("target") is not None
        or doc.get("target_elevation") is not None  # (review 83: an elevation's own target)
        or doc.get("tracking") is not None
        or doc.get("following") is not None
    )
    run, taken, turn, lock = order.run, order.taken, order.turn, order.lock
    locked, lock_known = doc.get("locked") is True, doc.get("lock_unknown") is not True
    state = doc.get("state")
    moving = state in _NOT_AT_REST or doc.get("moving") is True
    return StatusOrder(
        run,
        taken,
        turn,
        lock,
        turning,
        locked,
        lock_known,
        moving,
        state not in _NOT_READ,
        order.since,
    )


def _order(value: object) -> Order | None:
    """``R/status``'s ``order`` as the station writes it (its run's name, four places), or
    None: a status without it (a station's bridge before it), or not what a station writes
    (rule 1; rule 3: the run's name is text the page may show)."""
    if not isinstance(value, dict):
        return None
    run, places = value.get("run"), [value.get(k) for k in ("taken", "turn", "lock")]
    if not isinstance(run, str) or not _shown(run) or len(run) > NAME_CHARS:
        return None
    if any(type(p) is not int or p < 0 for p in places):
        return None
    since = value.get("since", 0)  # (none: a station that counts from 1 in each run)
    if type(since) is not int or since < 0:
        return None
    taken, turn, lock = places
    return Order(run, taken, turn, lock, since)  # type: ignore[arg-type]


def parse_control(payload: bytes | None) -> Control | None:
    """``R/control`` (features/control/payload.py): who holds the control lease, or None (free,
    or not a payload the station writes: the station judges every command again anyway)."""
    try:
        doc = load(payload or b"null")
    except ValueError:
        return None
    return _control(doc)
