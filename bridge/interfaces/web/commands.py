"""The console's commands: a JSON body in, one command (core/model.py's union) for the rotator's
judge out.

Rules:
1. ``parse`` is pure: a JSON object in, a ``WebCommand`` out, or BadCommand naming the field.
   Numbers are finite; text is bounded; unknown keys are refused (a typo must not be dropped
   silently on a machine that turns an antenna).
2. ``carry_out`` hands the command (``WebCommand.command_for``) to the same judge every front
   end uses, through the same one entry (front.py, runtime/rotator.py ``submit``):
   limits, keep-out sectors, the lock, the offset, the link. A refusal raises Refused, and the
   judge has already reported it on R/error; a bad body is reported there by the server. On
   the remote (remote/console.py) the rotator is the station's far away (interfaces/web/port.py):
   the command is published on the station's topic and the station's judge has the last word.
3. Stop and lock ON are never refused (docs/architecture.md rule 11): they go straight into the
   mailbox, which takes a stop first. Tracking ``off`` likewise. On the remote they are refused
   only while they cannot be delivered (the broker out of reach), and the answer says so. A
   lock word is the rotator's owner's step (docs/architecture.md rule 14), the same as MQTT's:
   the console keeps no lock of its own, and a lock OFF racing another interface's lock ON
   leaves the judge, the status and the state file with one of them.
4. Every command carries ``Source.WEB``, so the status says the console sent it (from the
   remote the station's status says ``mqtt``: it came over its broker), and who sent it
   (``Origin``: ``web`` and the browser's address, as the server saw it: port.py rule 4).
5. A STOP or a lock ON is the last word over everything sent before it (docs/architecture.md
   rule 11), whichever of the browser's connections brought what first. ``Order`` refuses, as
   stale, a command that reached the bridge before a STOP or lock ON (from any interface: MQTT,
   rotctld, the console) was carried out while it was still arriving (its body held up on the
   way; one whose bytes came before it and were read after it, the loop busy: server.py rule
   11, looks.py) or that the page stamped as sent before it (``sent``, rule 6: an attack pass,
   a click held up before its request reached the console, after a STOP by MQTT, turned the
   rotor; a lock OFF sent before a lock ON by MQTT undid it), and a command a page numbered
   (``page`` and ``seq``, which the console's page sends) before a STOP or lock ON the same
   page sent after it, however late it comes; but not one the same page numbered after its own
   STOP, the latest there is, that merely overtook it. A stop, a lock ON and tracking off are
   never stale. A page's numbers count within its login (``scoped``: the token's): a script
   restarted with a fresh login under the same page name numbers from 1 again (a cold review:
   its targets were refused and its STOP taken for a copy already carried out).
5a. Among a page's other commands the newest it numbered wins: one numbered before another
   command of the same page that the console already handed to the judge is refused as stale
   (``OVERTAKEN``), however late it comes. The browser sends each click on a connection of
   its own, and a click held up on the way reached the bridge after the click that replaced
   it and turned the rotor there (a review: the operator clicked 200 and then 60, the rotor
   ended at 200). A nudge is a step from where the rotor is, which no later nudge replaces:
   it is stale only when numbered before another command the page aimed with (three quick
   clicks on +5 are +15 in whatever order they come).
6. A move may carry its send time, ``sent``: the bridge's steady clock (live.py rule 8) as the
   page reckons it when the click is made (the clock the page last heard on its live feed plus
   the page's own steady time since: the phone's wall clock is never asked). ``aged`` refuses,
   as stale, one older than MAX_AGE_S when the console takes it ("not carried out: sent 12 s
   ago"), or more than AHEAD_S ahead of the bridge's clock (a reckoning from before the
   bridge's host restarted, whose clock is another: one or the other): a click a bad mobile
   link held up for seconds, with no STOP or newer click after it, was carried out whenever
   it came (an attack pass). The reckoning
   errs on the old side only (a message arrives after it left), by the fastest trip down the
   feed. A stop, a lock ON and tracking off are never refused for their age; a body without
   ``sent`` (a script's) is judged as before. Why a clock and not a sequence the feed
   acknowledges: a sequence says the order, which rules 5 and 5a judge already, not how long a
   click was on its way; the feed's clock says that with one number and no round trip.
   The clock is ``feed_clock``: the host's steady clock moved by an offset drawn from the
   boot's own random id (the same for every process until the host reboots, so a bridge
   restarted goes on judging the reckonings made against the one before; nobody can work it
   out without that id). The steady clock alone counts from the boot: it told every page how
   long the host had been up (when it was last rebooted, so whether its kernel was patched
   since). Without the boot's id, an offset of this process's own.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import time
from collections import OrderedDict
from dataclasses import dataclass, replace

from bridge.core import geo
from bridge.core.jsonkeys import unique_keys
from bridge.core.model import (
    Command,
    GoToPreset,
    Lock,
    Nudge,
    Origin,
    Park,
    Source,
    Stop,
    TakePath,
    Target,
    Toward,
    TrackBody,
)
from bridge.core.text import NOT_TEXT, bad_char
from bridge.interfaces.web.port import ConsoleRotator

MAX_BODY_BYTES = 4096
PAGES_KEPT = 1024  # pages whose last STOP is remembered (rule 5)
STALE = "sent before a STOP or lock ON that came first: not carried out"
OVERTAKEN = "sent before a newer command of the same page that came first: not carried out"
MAX_AGE_S = 5.0  # rule 6: a move older than this when the console takes it is not carried out
AHEAD_S = 1.0  # rule 6: a send time this far ahead of the bridge's clock is no reckoning of it


class BadCommand(ValueError):
    """Not a command the console sends: the message names what is wrong."""


@dataclass(frozen=True)
class WebCommand:
    command: str
    az_deg: float | None = None
    el_deg: float | None = None
    latitude_deg: float | None = None
    longitude_deg: float | None = None
    locator: str | None = None
    long_path: bool = False
    name: str | None = None  # a preset's, or the body to track
    on: bool = False  # lock
    page: str | None = None  # rule 5: the page that sent it, and its number there
    seq: int | None = None
    sent: float | None = None  # rule 6: the bridge's steady clock as the page reckoned it

    def halts(self) -> bool:
        """Stop, lock ON, tracking off: never refused, never stale (rules 3, 5)."""
        if self.command == "track":
            return (self.name or "").strip().casefold() == "off"
        return self.command == "stop" or (self.command == "lock" and self.on)

    def from_status(self) -> bool:
        """Made from the rotator's status by its judge (a nudge, the other path): judged once
        what is on its way shows there (server.py rule 10)."""
        return self.command in ("nudge", "path")

    def command_for(self, by: Origin) -> Command:
        """The command for the judge (core/model.py's union), sent by ``by`` (rule 4)."""
        src = Source.WEB
        match self.command:
            case "stop":
                return Stop(src, by)
            case "lock":
                return Lock(self.on, source=src, origin=by)
            case "target":
                return Target(self.az_deg, self.el_deg, src, origin=by)
            case "toward":
                assert self.latitude_deg is not None and self.longitude_deg is not None
                lat, lon = self.latitude_deg, self.longitude_deg
                return Toward(lat, lon, self.locator, self.long_path, source=src, origin=by)
            case "path":
                return TakePath(self.long_path, source=src, origin=by)
            case "preset":
                assert self.name is not None
                return GoToPreset(self.name, source=src, origin=by)
            case "park":
                return Park(source=src, origin=by)
            case "nudge":
                assert self.az_deg is not None
                return Nudge(self.az_deg, self.el_deg, source=src, origin=by)
            case "track":
                assert self.name is not None
                return TrackBody(self.name, None, source=src, origin=by)
        raise BadCommand(f"unknown command {self.command[:40]!r}")  # parse() lets none through

    def described(self) -> str:
        """How an error event echoes it ("console: target az 120")."""
        parts = [self.command]
        for label, value in (("az", self.az_deg), ("el", self.el_deg)):
            if value is not None:
                parts.append(f"{label} {value:g}")
        if self.locator is not None:
            parts.append(self.locator)
        elif self.latitude_deg is not None and self.longitude_deg is not None:
            parts.append(f"{self.latitude_deg:.4f},{self.longitude_deg:.4f}")
        if self.command in ("toward", "path"):
            parts.append("long path" if self.long_path else "short path")
        if self.name is not None:
            parts.append(self.name)
        if self.command == "lock":
            parts.append("ON" if self.on else "OFF")
        return "console: " + " ".join(parts)


_KEYS: dict[str, frozenset[str]] = {
    "stop": frozenset(),
    "target": frozenset({"az", "el"}),
    "toward": frozenset({"latitude_deg", "longitude_deg", "locator", "long_path"}),
    "path": frozenset({"long_path"}),
    "preset": frozenset({"name"}),
    "park": frozenset(),
    "nudge": frozenset({"d_az", "d_el"}),
    "track": frozenset({"body"}),
    "lock": frozenset({"on"}),
}


def parse(body: bytes) -> WebCommand:
    """Rule 1."""
    if len(body) > MAX_BODY_BYTES:
        raise BadCommand(f"a command is at most {MAX_BODY_BYTES} bytes")
    try:
        text = body.decode("utf-8")  # a key given twice: refused (core/jsonkeys.py)
        doc = json.loads(text, parse_constant=_no_constant, object_pairs_hook=unique_keys)
    except RecursionError:
        raise BadCommand("not a JSON command: nested too deep") from None
    except ValueError as exc:  # not UTF-8, not JSON, a number too long to read
        raise BadCommand(f"not a JSON command: {str(exc)[:120]}") from None
    if not isinstance(doc, dict):
        raise BadCommand('a command is a JSON object such as {"command": "stop"}')
    kind = doc.pop("command", None)
    if not isinstance(kind, str) or kind not in _KEYS:
        raise BadCommand(f"unknown command {str(kind)[:40]!r}; one of: {', '.join(_KEYS)}")
    page, seq = doc.pop("page", None), doc.pop("seq", None)
    sent = _number(doc, "sent", None)  # rule 6
    doc.pop("sent", None)
    unknown = set(doc) - _KEYS[kind]
    if unknown:
        raise BadCommand(f"unknown key(s) for {kind}: {', '.join(sorted(unknown)[:5])}")
    if (page is None) != (seq is None):
        raise BadCommand('"page" and "seq" come together')
    if page is not None and (not isinstance(page, str) or not 1 <= len(page) <= 40):
        raise BadCommand('"page" must be text (1 to 40 characters)')
    if seq is not None and (isinstance(seq, bool) or not isinstance(seq, int) or seq < 0):
        raise BadCommand('"seq" must be a whole number, 0 or more')
    if sent is not None and sent < 0:
        raise BadCommand('"sent" must be 0 or more (the bridge\'s clock, in seconds)')
    return replace(_parsed(kind, doc), page=page, seq=seq, sent=sent)


def _boot_offset() -> float:
    """Rule 6: whole seconds below 2**30, the same for every process of one boot."""
    try:
        with open("/proc/sys/kernel/random/boot_id", "rb") as f:
            seed = f.read()
    except OSError:
        seed = os.urandom(16)
    digest = hashlib.sha256(b"rotor-bridge feed clock\0" + seed).digest()
    return float(int.from_bytes(digest[:4], "big") >> 2)


_OFFSET_S = _boot_offset()


def feed_clock() -> float:
    """Rule 6: the bridge's steady clock as the pages are told it and their send times are
    judged on: the host's steady clock moved by the boot's offset."""
    return time.monotonic() + _OFFSET_S


def aged(cmd: WebCommand, now: float) -> str | None:
    """Rule 6: why ``cmd`` is too old (or stamped ahead) at ``now``, the bridge's steady clock;
    None when it is not, has no send time, or halts."""
    if cmd.sent is None or cmd.halts():
        return None
    age = now - cmd.sent
    if age > MAX_AGE_S:
        limit = f"a move older than {MAX_AGE_S:g} s is refused"
        return f"not carried out: sent {age:.0f} s ago ({limit})"
    if age < -AHEAD_S:
        return "not carried out: its send time is ahead of the bridge's clock (reload the page)"
    return None


def _parsed(kind: str, doc: dict[str, object]) -> WebCommand:
    if kind == "target":
        return WebCommand(kind, az_deg=_number(doc, "az"), el_deg=_number(doc, "el", None))
    if kind == "toward":
        return _toward(doc)
    if kind == "path":
        return WebCommand(kind, long_path=_flag(doc, "long_path"))
    if kind == "preset":
        return WebCommand(kind, name=_text(doc, "name"))
    if kind == "nudge":
        d_az, d_el = _number(doc, "d_az", 0.0), _number(doc, "d_el", None)
        assert d_az is not None
        return WebCommand(kind, az_deg=d_az, el_deg=d_el)
    if kind == "track":
        return WebCommand(kind, name=_text(doc, "body"))
    if kind == "lock":
        return WebCommand(kind, on=_flag(doc, "on", required=True))
    return WebCommand(kind)  # stop, park


def _toward(doc: dict[str, object]) -> WebCommand:
    long_path = _flag(doc, "long_path")
    if "locator" in doc:
        if "latitude_deg" in doc or "longitude_deg" in doc:
            raise BadCommand('give "locator" or "latitude_deg"/"longitude_deg", not both')
        text = _text(doc, "locator").strip()
        try:
            lat, lon = geo.parse_locator(text)
        except geo.LocatorError as exc:
            raise BadCommand(str(exc)) from None
        locator = text.upper()[:4] + text.lower()[4:6] + text[6:]
        return WebCommand(
            "toward", latitude_deg=lat, longitude_deg=lon, locator=locator, long_path=long_path
        )
    lat_or_none, lon_or_none = _number(doc, "latitude_deg"), _number(doc, "longitude_deg")
    assert lat_or_none is not None and lon_or_none is not None
    lat, lon = lat_or_none, lon_or_none
    if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0):
        raise BadCommand("latitude_deg must be -90..90 and longitude_deg -180..180")
    return WebCommand("toward", latitude_deg=lat, longitude_deg=lon, long_path=long_path)


_REQUIRED = object()


def _number(doc: dict[str, object], key: str, default: object = _REQUIRED) -> float | None:
    value = doc.get(key, default)
    if value is _REQUIRED:
        raise BadCommand(f'"{key}" is missing')
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise BadCommand(f'"{key}" must be a finite number')
    try:
        number = float(value)  # an integer too big for a float raises here
    except OverflowError:
        number = math.inf
    if not math.isfinite(number):
        raise BadCommand(f'"{key}" must be a finite number')
    return number


def _flag(doc: dict[str, object], key: str, *, required: bool = False) -> bool:
    value = doc.get(key, _REQUIRED if required else False)
    if value is _REQUIRED:
        raise BadCommand(f'"{key}" is missing')
    if not isinstance(value, bool):
        raise BadCommand(f'"{key}" must be true or false')
    return value


def _text(doc: dict[str, object], key: str) -> str:
    value = doc.get(key)
    if not isinstance(value, str) or not value.strip() or len(value) > 80:
        raise BadCommand(f'"{key}" must be text (1 to 80 characters)')
    bad = bad_char(value)  # (as the settings and R/preset take names: core/text.py; a lone
    if bad is not None:  # surrogate, JSON's "\\ud800", is no text: MQTT could not send it)
        raise BadCommand(f'"{key}" holds {bad}, {NOT_TEXT}')
    return value


def scoped(cmd: WebCommand, token: str) -> WebCommand:
    """Rule 5: ``cmd`` with its page named within the session of ``token``: pages count
    within one session each, so another session's commands under the same page name (a
    script restarted with a fresh login, or someone who guessed the name) are not judged by
    its numbers. The token is not kept, a digest of it is (never shown)."""
    if cmd.page is None:
        return cmd
    digest = hashlib.sha256(token.encode()).hexdigest()[:16]
    return replace(cmd, page=f"{digest}/{cmd.page}")


class Order:
    """Rule 5, for one console (the server's event loop alone calls it)."""

    def __init__(self) -> None:
        # rotator -> the console's last halt: when it was carried out, the page and its number
        self._last: dict[str, tuple[float, str | None, int | None]] = {}
        self._last_kind: dict[str, str] = {}  # rotator -> what that halt was (``_kind``)
        self._halt_seq: OrderedDict[tuple[str, str], int] = OrderedDict()  # (page, rotator)
        self._took_seq: OrderedDict[tuple[str, str], int] = OrderedDict()  # rule 5a: the same
        self._took_aim: OrderedDict[tuple[str, str], int] = OrderedDict()  # rule 5a: no nudge

    def stale(
        self, rotator_id: str, cmd: WebCommand, started: float, halted_s: float = -math.inf
    ) -> str | None:
        """Why ``cmd`` (its request begun at ``started``) is not carried out; ``halted_s``:
        when the rotator last carried out a STOP or lock ON from any interface (all times
        monotonic)."""
        if cmd.halts():
            return None
        numbered = cmd.page is not None and cmd.seq is not None
        if numbered:
            last_seq = self._halt_seq.get((str(cmd.page), rotator_id))
            if last_seq is not None and cmd.seq is not None and cmd.seq < last_seq:
                return STALE
            newer = self._took_aim if cmd.command == "nudge" else self._took_seq
            took = newer.get((str(cmd.page), rotator_id))
            if took is not None and cmd.seq is not None and cmd.seq < took:
                return OVERTAKEN  # rule 5a
        at, page, seq = self._last.get(rotator_id, (-math.inf, None, None))
        latest = max(at, halted_s)
        # sent before the halt, by the page's reckoning (rule 6), is sent before it however
        # late its request began: a click held up on the way before it reached the console
        born = started if cmd.sent is None else min(started, cmd.sent - _OFFSET_S)
        if born < latest:
            # the page's own halt, numbered before this command and the latest there is: the
            # page sent this after it, whichever arrived first
            own = numbered and page == cmd.page and seq is not None and at >= halted_s
            if not (own and cmd.seq is not None and seq is not None and cmd.seq > seq):
                return STALE
        return None

    def took(self, rotator_id: str, cmd: WebCommand) -> None:
        """Rule 5a: a command the page numbered, not a halt, handed to the judge (whatever the
        judge says: what the page sent before it is older all the same)."""
        if cmd.halts() or cmd.page is None or cmd.seq is None:
            return
        _keep(self._took_seq, (cmd.page, rotator_id), cmd.seq)
        if cmd.command != "nudge":
            _keep(self._took_aim, (cmd.page, rotator_id), cmd.seq)

    def carried(self, rotator_id: str, cmd: WebCommand) -> bool:
        """Whether ``cmd`` is a halt the page numbered and the console carried out already, or
        one it numbered before that, as the rotator's latest: the page sends each halt both over
        its WebSocket and by POST (console.js), and one click was two events in the audit
        trail (an attack pass). The second copy is not carried out again (the first was),
        nor an older halt's copy coming after the page's newer one that does all it does
        (its socket's copies wait past its budget, live.py rule 7: carried out after the
        click the page made next, they stopped it): a STOP's after a STOP or a lock ON, a
        lock ON's after a lock ON, tracking off's after any; any other halt in between, and
        the copy goes again (stopping twice is harmless). So a page's numbers must never
        start again under the same name within one login (``scoped``): a script restarted so
        had its STOP answered ok and not carried out (a cold review; telling copies by the
        way they came instead let an older STOP's late POST stop the page's next click, the
        next review)."""
        if not cmd.halts() or cmd.page is None or cmd.seq is None:
            return False
        _at, page, seq = self._last.get(rotator_id, (-math.inf, None, None))
        if page != cmd.page or seq is None or cmd.seq > seq:
            return False
        # an older halt only where the newer one does all it does: a STOP does not lock, and
        # tracking off does not stop a turn (a review: a lock ON whose copies came after the
        # page's next click, a STOP, was never carried out, and its POST answered "ok")
        return cmd.seq == seq or self._last_kind.get(rotator_id) in _OUTDONE_BY[_kind(cmd)]

    def halted(self, rotator_id: str, cmd: WebCommand, now: float) -> None:
        self._last[rotator_id] = (now, cmd.page, cmd.seq)
        self._last_kind[rotator_id] = _kind(cmd)
        self.pressed(rotator_id, cmd)

    def pressed(self, rotator_id: str, cmd: WebCommand) -> None:
        """A halt the page numbered, carried out or not: one refused as not delivered yet (the
        remote's, its broker away) is kept and sent first on reconnect, so what the page
        numbered before it is stale all the same (not ``carried``: its other copy still goes)."""
        if cmd.page is not None and cmd.seq is not None:
            _keep(self._halt_seq, (cmd.page, rotator_id), cmd.seq)


def _kind(cmd: WebCommand) -> str:
    """A halt's kind for ``Order.carried``: ``stop``, ``lock`` (ON) or ``off`` (tracking)."""
    return "lock" if cmd.command == "lock" else "off" if cmd.command == "track" else "stop"


# a halt's kind -> the kinds of a newer halt that do all it does (``Order.carried``): a lock ON
# stops and locks, a STOP stops and ends tracking, tracking off ends tracking only
_OUTDONE_BY = {"stop": {"stop", "lock"}, "lock": {"lock"}, "off": {"stop", "lock", "off"}}


def _keep(kept: OrderedDict[tuple[str, str], int], key: tuple[str, str], seq: int) -> None:
    """The highest ``seq`` of ``key``, most recent last, PAGES_KEPT keys at most."""
    kept[key] = max(seq, kept.pop(key, seq))
    while len(kept) > PAGES_KEPT:
        kept.popitem(last=False)


def _no_constant(name: str) -> object:
    raise ValueError(f"{name} is not a number here")


def carry_out(
    rot: ConsoleRotator, cmd: WebCommand, peer: str | None = None, since: int | None = None
) -> None:
    """Rule 2: raises Refused (already reported) when the judge says no; ``peer``: the
    browser's address (rule 4); ``since``: the rotator's halt count read before rule 5's look
    (port.py rule 2a)."""
    rot.submit(cmd.command_for(Origin(Source.WEB, None, peer)), cmd.described(), since=since)
