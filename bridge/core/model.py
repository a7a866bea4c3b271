"""Plain value types shared by every layer: commands, motion states, the status snapshot.

``Command`` is the one union of everything an operator can ask of a rotator (a target, a stop,
an option, the lock, the control lease, tracking, following, a preset, park, a nudge, a place,
a path, a health reset): every front end parses into one of these frozen values and hands it to
the rotator's one entry (front.py, runtime/rotator.py ``submit``).

Nothing here does I/O or knows about MQTT or serial ports. Angles are degrees, times are
seconds (monotonic unless the name says ``_unix``).
"""

from __future__ import annotations

import enum
import ipaddress
import math
import unicodedata
from dataclasses import dataclass, field, replace
from datetime import UTC, datetime
from typing import TypeVar, get_args

from bridge.core.text import bad_char


class MotionState(enum.StrEnum):
    """What the rotor is doing, as far as the bridge can tell."""

    IDLE = "idle"  # still, brake set (or no brake), ready for a command
    MOVING = "moving"  # turning: commanded, or by hand from the front panel
    BRAKING = "braking"  # just stopped; the controller ignores bearings until its brake delay ends
    STALLED = "stalled"  # commanded but no progress for the stall timeout while off target
    # link up, but the bridge cannot tell: a controller that cannot report a position (DCU-1),
    # or a silent one whose report after a move was lost (SatEL), until its next reading
    UNKNOWN = "unknown"
    OFFLINE = "offline"  # serial link down or controller silent


class Source(enum.StrEnum):
    """Who asked for a command (shown in the status snapshot)."""

    MQTT = "mqtt"
    ROTCTLD = "rotctld"
    AUTO_PARK = "auto-park"  # park_after_idle_s: the bridge parked it, nobody asked
    TRACKING = "tracking"  # the bridge follows the sun, the moon or a satellite (R/track)
    PST = "pst"  # a logger through the PstRotator UDP endpoint (loggers/)
    N1MM = "n1mm"  # N1MM Logger+ through its rotor UDP endpoint
    WEB = "web"  # the operator console (web/)
    GS232 = "gs232"  # a program speaking Yaesu GS-232A/B to the gs232_port (gs232/)
    EASYCOMM = "easycomm"  # a program speaking Easycomm II to the easycomm_port (gs232/)
    DCU1 = "dcu1"  # a program speaking DCU-1 / Rotor-EZ to the dcu1_port (gs232/)
    LEASE = "lease"  # the control lease itself: its end, in the audit trail (runtime/operators.py)
    WSJTX = "wsjtx"  # following the QSO partner WSJT-X or JTDX names (R/follow, wsjtx/)
    WIND = "wind"  # parked for a storm (wind_topic, session/wind.py)
    DXCLUSTER = "dxcluster"  # turned to a spotted call (R/target {"call": ...}, dxcluster/)


_INTERFACES = frozenset(source.value for source in Source)  # interface_name: no operator's
# interface_name: N1MM's UDP endpoint names every sender with its address (recvfrom's:
# loggers/server.py), never by the interface alone: ``N1MM``, a real call sign, is an operator's
_NEVER_ALONE = frozenset({Source.N1MM.value})
OPERATOR_CHARS = 32  # an operator's name, at most (a call sign, a name, "rotctld <address>")
# valid_operator: NFKC makes one character of four at most (a canonical decomposition's longest,
# U+1F82): a text longer than this many times OPERATOR_CHARS is none before it is normalized
_COMPOSED_MOST = 4
_HIDDEN = ("Cf", "Zl", "Zp")  # valid_operator: format characters, line and paragraph separators
_JOINERS = ("\u200c", "\u200d")  # valid_operator: what Persian, the Indic scripts, emoji need
_VIRAMA = 9  # valid_operator: the canonical combining class of the Indic scripts' virama
# valid_operator: letters and marks that show nothing, though no format character: the Hangul
# fillers (NFKC makes U+3164 and U+FFA0 U+1160), the blank Braille pattern, the combining
# grapheme joiner, Khmer's and Mongolian's invisible vowels and selectors
_BLANK = frozenset("\u034f\u115f\u1160\u17b4\u17b5\u180b\u180c\u180d\u180f\u2800\u3164\uffa0")


def valid_operator(text: object) -> str | None:
    """``text`` as an operator's name, or None if it is not one: short text MQTT carries
    (core/text.py: isprintable refused a no-break space and Persian's zero-width non-joiner, a
    review), in its compatibility form (NFKC: a no-break space is a space, so the name typed on
    a Mac and on a phone is one operator to the lease), spaces at the ends dropped, with no
    invisible format character (a zero-width space, a word joiner: two names that look alike
    were two operators) and no direction override or line separator (the name shown reversed
    the rest of the console's line, the lease's end among it); the joiners a script needs
    (U+200C, U+200D) stay, between two of its characters, and nothing else that shows nothing
    does (``_BLANK``; an attack pass: a Hangul filler was a name that reads as blank, and
    ``DL1ABC`` with a joiner at its end another operator that looks like DL1ABC). A text too
    long to be one once normalized is none before it is (``_COMPOSED_MOST``): a stop's user
    property of 64 KiB of U+FDFA, one ligature NFKC makes 18 characters, cost the stop lane
    and the stop express some 24 ms a stop before its frame or its put (a cold review)."""
    if not isinstance(text, str):
        return None
    text = text.strip()
    if len(text) > _COMPOSED_MOST * OPERATOR_CHARS:
        return None
    name = unicodedata.normalize("NFKC", text).strip()
    if not name or len(name) > OPERATOR_CHARS or bad_char(name) is not None:
        return None
    if any(unicodedata.category(c) in _HIDDEN and c not in _JOINERS for c in name):
        return None
    if any(c in _BLANK for c in name) or _stray_joiner(name):
        return None
    return name


def _stray_joiner(name: str) -> bool:
    """A joiner with nothing to join: at either end, or beside a character of ASCII (a call
    sign's letters and digits join nothing: ``DL1ABC`` and a joiner look like ``DL1ABC``).
    A zero-width joiner right after a virama is never stray: it changes the consonant's form
    wherever it stands (Malayalam's chillu typed the older way, consonant, virama, joiner, ends
    a word: a review found മോഹന് with it, Mohan, refused)."""
    for i, c in enumerate(name):
        if c == "\u200d" and i and unicodedata.combining(name[i - 1]) == _VIRAMA:
            continue
        if c in _JOINERS:
            around = name[i - 1 : i] + name[i + 1 : i + 2]
            if len(around) < 2 or any(a.isascii() for a in around):
                return True
    return False


def interface_name(name: str) -> bool:
    """``name`` is how the bridge names an interface or a feature of its own (``mqtt``,
    ``rotctld 127.0.0.1``, ``auto-park``): no operator's, it stands for everyone who sends
    without a name there (runtime/lease.py rule 1). The bridge names a sender only so
    (``Origin.who``): the name alone, or with its peer's address; a call sign or a name that
    merely begins with one (``N1MM``, ``Mqtt Guy``, ``Web Dev``) is an operator's (review 80:
    refused, its every command went as plain ``mqtt``, a remote with it did not start)."""
    words = name.split()
    first = words[0].casefold() if words else ""
    if first not in _INTERFACES:
        return False
    if len(words) == 1:
        return first not in _NEVER_ALONE
    return len(words) == 2 and _address(words[1])


def _address(word: str) -> bool:
    """``word`` could be a peer's address as ``Origin.who`` names it: an IP address (an IPv6
    one with its zone, in brackets or with a port as some write it), or the web console's
    ``?`` for a request with none."""
    if word == "?":
        return True
    text = word[1:].split("]", 1)[0] if word.startswith("[") else word
    for candidate in (text, text.rsplit(":", 1)[0] if text.count(":") == 1 else text):
        try:
            ipaddress.ip_address(candidate.split("%", 1)[0])
        except ValueError:
            continue
        return True
    return False


def operator_name(text: object) -> str | None:
    """``text`` as the name a sender gives itself (an MQTT 5 user property ``operator``, a
    release's ``operator``), or None: ``valid_operator``'s, and not an interface's
    (``interface_name``; an attack pass: ``rotctld 192.168.1.20`` as a user property was
    audited, and shown as ``last_operator``, as the rotctld client at that address, which sent
    nothing). The one test every front end that takes a sender's own word for its name asks."""
    name = valid_operator(text)
    return None if name is None or interface_name(name) else name


def same_operator(a: str, b: str) -> bool:
    """Two operators' names (``valid_operator``'s) are one whatever their case: a call sign is
    (an attack pass: DL1ABC held the lease and was refused as dl1abc, named as the holder)."""
    return a.casefold() == b.casefold()


@dataclass(frozen=True)
class Origin:
    """Who sent a command and how (the audit log, ``last_operator``, the control lease).

    ``operator`` is what the sender said it is (the MQTT 5 user property ``operator``); without
    it the interface and the peer stand for the operator (``rotctld 192.168.1.20``)."""

    interface: Source
    operator: str | None = None
    peer: str | None = None  # the peer's address (TCP, UDP), when the interface knows it

    @property
    def who(self) -> str:
        if self.operator:
            return self.operator
        return f"{self.interface.value} {self.peer}" if self.peer else self.interface.value


def sender(origin: Origin | None, source: Source) -> str:
    """Who sent a command, as the control lease reads it (runtime/lease.py rule 5): its
    origin's name, else the source it came from."""
    return origin.who if origin is not None else source.value


@dataclass(frozen=True)
class Control:
    """The control lease: ``operator`` holds the rotator until ``until_unix`` (runtime/lease.py)."""

    operator: str
    until_unix: float

    def held_text(self, now_unix: float) -> str:
        """``DL1ABC holds the rotator until 14:30 UTC (25 min left)``."""
        end = datetime.fromtimestamp(self.until_unix, UTC).strftime("%H:%M")
        left = max(1, math.ceil((self.until_unix - now_unix) / 60.0))
        return f"{self.operator} holds the rotator until {end} UTC ({left} min left)"


@dataclass(frozen=True)
class AuditEvent:
    """One command judged, executed or refused (the audit file and ``R/audit``)."""

    time_unix: float
    rotator: str
    origin: Origin
    command: str  # as the user sent it
    result: str  # "executed" or "refused: <why>"
    bearing_before: float | None
    halt: bool = False  # an executed stop (runtime/audit.py rule 6: a flood of them is folded)
    # runtime/audit.py rule 6: a line standing for ``count`` like events, the first of them at
    # ``first_unix``, the last at ``time_unix`` (``mixed``: from more than one sender)
    count: int = 1
    first_unix: float | None = None
    mixed: bool = False
    # a ``mixed`` line's senders (runtime/audit.py rule 8): how many different ones it counts
    # (``more_senders``: more than that, uncounted) and the first few of them, as ``who`` says
    senders: int = 0
    more_senders: bool = False
    names: tuple[str, ...] = ()
    # a command that, sent again by its sender with nothing executed in between, changes nothing
    # (an absolute target, a claim, a release, a lock OFF, a setting; a lock ON, tracking or
    # following OFF when it changed nothing): folded (runtime/audit.py rule 9); not a nudge, a
    # preset or a park, which may turn the rotor anew
    same_again: bool = False
    # a halt that changed nothing: a lock ON while the lock was ON (no storm's park owed),
    # tracking OFF while nothing was tracked, following OFF while nothing was followed
    # (runtime/audit.py rule 10): folded like a stop, and R/audit counts it with the stops
    # (interfaces/mqtt/service.py rule 8)
    unchanged: bool = False
    # the command as read (``describe_command``: stripped, case-folded words), what rules 9 and
    # 10 of runtime/audit.py fold by; empty: ``command`` (a front end's words for it)
    read_as: str = ""

    @property
    def folds_as(self) -> str:
        """The command a run of like events is kept by (runtime/audit.py rules 9, 10): as read,
        not as sent (`` off`` and ``OFF\t`` are the one ``track off``)."""
        return self.read_as or self.command

    @property
    def routine(self) -> bool:
        """A refusal, an executed stop or a halt that changed nothing: what a flood is made of,
        folded into one line per sender (runtime/audit.py rules 6, 10); a move, a lease or a
        lock change never is."""
        return self.halt or self.unchanged or self.result.startswith("refused")

    def as_dict(self) -> dict[str, object]:
        doc: dict[str, object] = {
            "time": self.time_unix,
            "rotator": self.rotator,
            "operator": self.origin.who,
            "interface": self.origin.interface.value,
            "peer": self.origin.peer,
            "command": self.command,
            "result": self.result,
            "bearing_before": self.bearing_before,
        }
        if self.count > 1 or self.first_unix is not None:
            doc.update(count=self.count, first=self.first_unix, last=self.time_unix)
        if self.mixed:
            doc["mixed"] = True
            doc["senders"] = self.senders
            if self.more_senders:
                doc["more_senders"] = True
            doc["names"] = list(self.names)
        return doc


@dataclass(frozen=True)
class TargetInfo:
    """Where a target given by locator or coordinates lies (``target_info`` in the status)."""

    latitude_deg: float
    longitude_deg: float
    distance_km: float  # the path taken
    short_path_deg: float
    long_path_deg: float
    path: str = "short"  # or "long"
    locator: str | None = None


@dataclass(frozen=True)
class TrackingInfo:
    """What the rotator follows (``tracking`` in the status). Times are unix seconds."""

    body: str  # "sun", "moon" or the satellite's name
    phase: str  # "waiting" (below the minimum elevation), "tracking", "no pass"
    azimuth_deg: float | None = None  # the body now, true bearing
    elevation_deg: float | None = None
    next_azimuth_deg: float | None = None  # the body in a minute
    next_elevation_deg: float | None = None
    aos_unix: float | None = None  # the current or next pass above the minimum elevation
    los_unix: float | None = None
    max_elevation_deg: float | None = None
    aos_azimuth_deg: float | None = None
    flip: bool = False  # this pass is flown with elevation past 90 and azimuth + 180
    # the body's predicted (azimuth, elevation) over that pass, AOS to LOS, once computed
    pass_track: tuple[tuple[float, float], ...] = ()
    elements_epoch_unix: float | None = None  # a satellite's: when its elements are for
    elements_stale: bool = False  # they are older than session/tracking.py's STALE_DAYS
    elements_ahead: bool = False  # dated after the station's clock by more than its AHEAD_DAYS


_V = TypeVar("_V")


def kept_if_same(new: _V, old: _V | None) -> _V:
    """``old`` where ``new`` says the very same, to the letter, else ``new``: for a flat
    frozen dataclass of scalars (an Order, a WindInfo) made anew at every reading though
    nothing in it changed. R/status's text keeps what a reading leaves by the very objects it
    was made of (interfaces/mqtt/payloads.py StatusText): an equal one made anew made that
    text again at every reading. Equal is not enough (``1 == 1.0 == True``, ``0.0 == -0.0``:
    each its own text): each field is also of the same type, and a float of the same sign."""
    if old is None or old is new:
        return new
    if type(old) is not type(new) or old != new:
        return new
    for name in old.__dataclass_fields__:  # type: ignore[attr-defined]
        a, b = getattr(old, name), getattr(new, name)
        if type(a) is not type(b):
            return new
        if type(a) is float and math.copysign(1.0, a) != math.copysign(1.0, b):
            return new
    return old


@dataclass(frozen=True)
class FollowingInfo:
    """Whom the rotator follows (``following`` in the status): the QSO partner a program
    (WSJT-X, JTDX) names, and where it was last turned for them."""

    source: str  # "wsjtx"
    path: str = "short"  # or "long"
    call: str | None = None  # the DX call and grid last heard with a grid
    grid: str | None = None
    bearing_deg: float | None = None  # the true bearing turned to for ``grid``
    distance_km: float | None = None  # along the path taken
    held: bool = False  # a new grid waits for the transmission to end (follow_hold_while_tx)
    instance: str | None = None  # the program listened to (WSJT-X's Id; None: the first
    # heard, follow.py rule 8); not published: the WSJT-X listener keeps room for it


@dataclass(frozen=True)
class WindInfo:
    """The wind as the rotator sees it (``wind`` in the status), speeds in km/h."""

    speed_kmh: float | None = None  # the last reading (None: none yet)
    storm: bool = False  # parked for the storm: motion is refused
    calm_since_unix: float | None = None  # in a storm: below the release level since then
    silent: bool = False  # no reading for wind_silent_min: the state is kept
    refusal: str | None = None  # in a storm: why motion is refused (the judge says it too)
    halted: bool = False  # in a storm: its park was stopped, not tried again (wind.py rule 3)
    arrived: bool = False  # in a storm: its park was seen reached, owed no more (wind.py rule 7)
    replayed: bool = False  # a storm known only from a replayed reading (wind.py rule 6)
    # in a storm: its park is owed and not sent (the lock holds it back, the controller does
    # not answer: wind.py rules 4 and 7); the rotor is not parking
    waiting: bool = False
    refused: bool = False  # in a storm: the judge refused its park (wind.py rule 5): not parked
    # in a storm: its park was sent and the rotor is not on its way there nor at it (a stall
    # cut it short, a hand turned it off: wind.py rule 10): not parked
    off_park: bool = False

    @property
    def parks(self) -> bool:
        """A storm the rotor is parked for, or parking: not one known only from a replayed
        reading (session/wind.py rule 6), which parks nothing."""
        return self.storm and not self.replayed


@dataclass(frozen=True)
class Target:
    """Go here. An axis left None keeps its current target (or position): a bare azimuth on an
    az/el rotator leaves the elevation alone, an elevation-only request the azimuth."""

    az_deg: float | None
    el_deg: float | None = None
    source: Source = Source.MQTT
    info: TargetInfo | None = None  # named by locator or coordinates
    park: bool = False  # the park position: ``parked`` once there
    # A 0..360 bearing on a rotor that can pass 360 (set by the judge, pointing.py rule 2): the
    # session picks the side from where the rotor is when it sends, not when the command came.
    true_az_deg: float | None = None
    origin: Origin | None = None  # who sent it (None: the bridge's own, tracking or auto-park)
    # true bearings, lower first, the turn must stay inside (pointing.py rule 9: a group's limits)
    within_deg: tuple[float, float] | None = None
    # a nudge's raw value where its true bearing does not say it (pointing.py rule 6): an end
    # of a scale whose 0 and 360 are the ends of the travel, 360 or 0, which one true bearing
    # names both of; on a scale that does not wrap, where the nudge ends along the travel (a
    # bearing there names a raw value each side of 360); the judge sends it and clears it
    az_end_deg: float | None = None
    # the azimuth names a direction, not an end of the travel (a group member's bearing after
    # its offset: interfaces/mqtt/groups.py rule 2): where its raw value is 0 and 360, the two
    # ends of the travel, the judge takes the one nearer the rotor (pointing.py rule 2); the
    # judge clears it
    az_either_end: bool = False
    # a nudge (pointing.py rule 6): its step goes out even where it ends within the tolerance of
    # where the rotor rests (session/targets.py rule 5), as the user asked for that step
    nudge: bool = False
    # a stamped command's expiry (interfaces/mqtt/service.py rule 9) on the steady clock the
    # sessions keep: a target that waited for a stop's order (session.py rule 13) goes no later
    not_after_s: float | None = None


def combine(newer: Target, older: Target | None) -> Target:
    """``newer`` with the axis it leaves out (None) taken from ``older`` still pending: Hamlib
    4.6's PstRotator client sends ``P 200 30`` as an azimuth and then an elevation datagram,
    and an MQTT user may send a bare azimuth and then ``R/target/elevation``: one must not
    replace the other. An axis ``newer`` names wins; so do its source and place.
    Only targets from one source and one sender (``origin``) combine, and never with a park:
    another operator's azimuth taken into the control lease holder's elevation went out as the
    holder's (session/session.py rule 23; an attack pass: G4XYZ's azimuth, put before DL1ABC's
    claim, turned the rotor with DL1ABC's elevation in the claim's own batch). A newer park
    takes nothing from what waits either (session/targets.py rule 9: it takes the place of the
    turn, an axis it leaves out held where it reads; an attack pass: R/park after the same
    sender's 300/40, still waiting, went out as a GS-232B ``W000 040``, and the elevation turned
    to 40 for a park that leaves it as it is). The two together expire with the sooner of the
    two's expiries (``not_after_s``)."""
    if older is None or older.source is not newer.source or older.park or newer.park:
        return newer  # only a sender's own two halves: never a park or a tracking step
    if older.origin != newer.origin:
        return newer
    took = False
    if newer.az_deg is None and older.az_deg is not None:
        newer = replace(
            newer,
            az_deg=older.az_deg,
            true_az_deg=older.true_az_deg,
            within_deg=older.within_deg,
            az_either_end=older.az_either_end,
        )
        took = True
    if newer.el_deg is None and older.el_deg is not None:
        newer = replace(newer, el_deg=older.el_deg)
        took = True
    ends = older.not_after_s
    if took and ends is not None:  # (an axis of the older goes no later than it would have)
        if newer.not_after_s is None or ends < newer.not_after_s:
            newer = replace(newer, not_after_s=ends)
    return newer


class SentAt(float):
    """A halt's send time on the steady clock (``Stop.sent_s``, ``Lock.sent_s``) that keeps
    the stamp it was read from: ``unix``, the station's clock as its sender reckoned it
    (interfaces/mqtt/heartbeat.py rule 10). The judge keeps ``unix`` beside ``halted_s`` when
    this halt sets it (runtime/rotator.py ``halted``), and a move's stamp is compared with it
    directly, on one clock (interfaces/mqtt/service.py rule 9): put on the steady clock, two
    equal stamps could differ by the time the thread lost between two clock readings (a
    review: a millisecond lost so refused the remote's ``P`` stamped as its ``S``)."""

    unix: float

    def __new__(cls, steady_s: float, unix: float) -> SentAt:
        made = super().__new__(cls, steady_s)
        made.unix = unix
        return made


@dataclass(frozen=True)
class Stop:
    source: Source = Source.MQTT
    origin: Origin | None = None
    # when its sender sent it, on the steady clock (a stamp it carried: interfaces/mqtt/
    # heartbeat.py); None: when it came. A move stamped before it is stale (runtime/rotator.py
    # ``halted_s``)
    sent_s: float | None = None


# A controller setting's value (protocols/base.py ``Setting``): a bool option's on or off, a
# number's value, or a choice's name. Text is a value as a user sent it, which the judge reads
# by the setting's declaration.
SettingValue = bool | float | str


def setting_text(value: SettingValue) -> str:
    """A setting's value as its state topic and an echo show it: ON or OFF, a number in its
    shortest form (``2``, ``0.5``), a choice's name."""
    if isinstance(value, bool):
        return "ON" if value else "OFF"
    if isinstance(value, float | int):
        return f"{value:g}"
    return value


@dataclass(frozen=True)
class SetOption:
    """Set a controller setting: switch an option (the Rotor-EZ jam protection) on or off, or
    give a number or a choice (a GS-232's speed) its value."""

    name: str
    value: SettingValue
    source: Source = Source.MQTT
    origin: Origin | None = None


# -- the rest of what an operator can ask of a rotator (one union with the three above) ----
# Every front end parses what it reads into one of these values and hands it to the rotator's
# one entry (``submit``); the judge (runtime/rotator.py) dispatches on the type.


@dataclass(frozen=True, kw_only=True)
class Asked:
    """Who asked, on every command below (named, never by position): ``source``, the interface
    (shown in the status), and ``origin``, who sent it (the audit trail, the control lease), as
    Target, Stop and SetOption carry them."""

    source: Source = Source.MQTT
    origin: Origin | None = None


@dataclass(frozen=True)
class Lock(Asked):
    """The safety lock: ON is never refused and never delayed (docs/architecture.md rule 11).
    ``sent_s``: as a Stop's."""

    on: bool
    sent_s: float | None = None


@dataclass(frozen=True)
class Claim(Asked):
    """Claim the control lease: ``operator`` and ``minutes`` as sent (runtime/lease.py judges
    them: a name the lease refuses is a refusal like any)."""

    operator: object
    minutes: object


@dataclass(frozen=True)
class Release(Asked):
    """End the control lease, whoever holds it (runtime/lease.py rule 4)."""


@dataclass(frozen=True, kw_only=True)
class Move(Asked):
    """A command that may turn the rotor and is no Target: one that names a target in another
    way (the judge makes the Target), a track or follow start, a feature's own command. Its
    stamped expiry on the steady clock, as ``Target.not_after_s`` (interfaces/mqtt/service.py
    rule 9): a start that waited for the order of a STOP or lock goes no later (session.py
    rule 13)."""

    not_after_s: float | None = None


@dataclass(frozen=True)
class TrackBody(Move):
    """Follow the sun, the moon or a satellite (by name, or ``tle``: name and two lines);
    ``off`` ends it and is never refused."""

    name: str
    tle: tuple[str, str, str] | None = None

    @property
    def off(self) -> bool:
        return self.tle is None and self.name.strip().casefold() == "off"


@dataclass(frozen=True)
class FollowQso(Move):
    """Follow the QSO partner WSJT-X names; off ends it and is never refused."""

    on: bool
    long_path: bool = False


@dataclass(frozen=True)
class GoToPreset(Move):
    name: str


@dataclass(frozen=True)
class Park(Move):
    """Go to the configured park position (``parked`` once there)."""


@dataclass(frozen=True)
class Nudge(Move):
    """Turn by a step from where the rotor points (or is going)."""

    d_az_deg: float
    d_el_deg: float | None = None


@dataclass(frozen=True)
class Toward(Move):
    """Turn toward a place (a locator or coordinates) by the short or the long path."""

    latitude_deg: float
    longitude_deg: float
    locator: str | None = None
    long_path: bool = False


@dataclass(frozen=True)
class TakePath(Move):
    """The place of the current locator or coordinate target, by the path asked for."""

    long_path: bool


@dataclass(frozen=True)
class ResetHealth(Asked):
    """A new rotor health baseline (after a repair); it moves nothing."""


# A feature's command's value: frozen and hashable (a tuple of these for more than one).
FeatureValue = bool | int | float | str | tuple["FeatureValue", ...] | None


def feature_value_text(value: FeatureValue) -> str:
    """A feature's command's value as the audit trail and an error event show it."""
    if value is None:
        return ""
    if isinstance(value, tuple):
        return " ".join(feature_value_text(v) for v in value)
    return setting_text(value)


@dataclass(frozen=True)
class FeatureCommand(Move):
    """A registered feature's own command (bridge/feature.py ``CommandTopic``), for its
    session part (session/parts.py ``Part.command``), named by the feature's name: the judge
    judges it like a target when it ``moves`` the rotor (the lock, the wind, the lease, the
    link), and like a controller setting when it does not (the lease); it is never a stop."""

    feature: str
    name: str
    value: FeatureValue = None
    moves: bool = True  # the safe default: judged as motion


# what the judge hands the mailbox as a command for the controller (targets in raw values)
ControllerCommand = Target | Stop | SetOption
Command = (
    Target
    | Stop
    | SetOption
    | Lock
    | Claim
    | Release
    | TrackBody
    | FollowQso
    | GoToPreset
    | Park
    | Nudge
    | Toward
    | TakePath
    | ResetHealth
    | FeatureCommand
)
COMMANDS: tuple[type, ...] = get_args(Command)  # each kind, for isinstance


class ErrorKind(enum.StrEnum):
    """The ``kind`` of an error event (``R/error``). Published API: listed here and in the
    README, and nothing else can be emitted (ErrorEvent refuses any other)."""

    REFUSED = "refused"  # a command (or payload) judged and not executed: nothing moved
    STALLED = "stalled"  # a commanded rotor made no progress: the bridge stopped it
    STOP = "stop"  # the rotor kept turning after repeated stops, or after a stall's stop
    SERIAL = "serial"  # the port, the line or the controller's answers failed
    PROTOCOL = "protocol"  # the controller sent bytes that are no valid reply
    STATE = "state"  # the lock could not be saved or read in the state file
    INTERNAL = "internal"  # a bug in the bridge (see the log): the feature (or link) is reset
    WIND = "wind"  # the wind topic fell silent or sent no number: the state it had is kept
    AUDIT = "audit"  # the audit file could not be written (the bridge goes on without it)


@dataclass(frozen=True)
class ErrorEvent:
    """Something the user should hear about: a refused command, a stall, a serial fault."""

    kind: ErrorKind  # a plain string is taken if it is one of ErrorKind's values
    message: str
    command: str | None = None  # what was refused, as the user sent it
    time_unix: float = 0.0
    # who sent the command the session dropped (runtime/rotator.py: its audit line); never
    # published, and no part of the event's identity
    origin: Origin | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "kind", ErrorKind(self.kind))  # ValueError for any other

    def as_dict(self) -> dict[str, object]:
        out: dict[str, object] = {"kind": self.kind.value, "message": self.message}
        if self.command is not None:
            out["command"] = self.command
        out["time"] = self.time_unix
        return out


@dataclass(frozen=True)
class AxisHealth:
    """One axis of ``RotatorHealth``: "up" is clockwise in azimuth, up in elevation."""

    speed_up_deg_s: float | None = None  # the median of the recent moves that way
    speed_down_deg_s: float | None = None
    baseline_up_deg_s: float | None = None  # what they are judged against
    baseline_down_deg_s: float | None = None
    coast_deg: float | None = None  # turned after the last stop
    baseline_coast_deg: float | None = None
    arrival_error_deg: float | None = None  # of the last move that arrived
    odometer_deg: float = 0.0  # every degree turned, ever


@dataclass(frozen=True)
class RotatorHealth:
    """How the rotor really turns, measured from its own readings (session/health.py); published
    on ``R/health`` after each move. ``measured`` False: the controller reports no position."""

    measured: bool = True
    az: AxisHealth = AxisHealth()
    el: AxisHealth | None = None  # az/el rotators
    start_delay_s: float | None = None  # command to the first reading that moved (recent median)
    baseline_start_delay_s: float | None = None
    baseline_from: str = "learning"  # "learned" (the first moves), "settings", "learning"
    baseline_moves_left: int = 0  # still to learn from
    moves: int = 0
    stalls: int = 0
    stall_azimuths_deg: tuple[float, ...] = ()  # the recent stalls, raw
    # the recent stalls of the elevation (jammed while the azimuth turned or had come), raw
    stall_elevations_deg: tuple[float, ...] = ()
    motor_on_s: float = 0.0
    warnings: tuple[str, ...] = ()
    # what the state file keeps (session/health_judge.py); never compared
    memory: dict[str, object] = field(default_factory=dict, compare=False, repr=False)


@dataclass(frozen=True)
class Order:
    """Where a rotator's status stands in the order of the commands its station took
    (``R/status``'s ``order``; session/mailbox.py rule 10a's places): ``run`` names the run
    of the station's bridge (a restart begins a new one), ``taken`` is the newest place the
    status shows every command up to, ``turn`` the place of the command the target or turn
    shown comes from (a target, a track or follow start; 0: none known), or the place the
    bridge's own turn took when it began (auto-park, the storm's park: a place of its own,
    after every command asked before it; ``taken`` shows it too: review 83; one storm's park
    keeps its place however often it begins in that storm, across a restart too, until a
    command, stop or lock ON is put after it: session/mailbox.py rule 10b and its limits,
    and a rotator of two boxes parks both at one place of the rotator's:
    runtime/composite.py rule 10), ``lock`` the
    place of the last lock word (0: none known). A remote orders its held halts by them
    (interfaces/mqtt/remote.py rule 10). Places go on across runs (review 86): a run counts
    on after the places the runs before it reserved in the state file (runtime/kept.py rule
    12), ``since``: no place of an earlier run is past it, and ``turn`` and ``lock`` may name
    an earlier run's place (the turn and the lock word the state file kept across the
    restart). ``since`` 0: none kept (a station that counts from 1 in each run)."""

    run: str
    taken: int
    turn: int
    lock: int
    since: int = 0


@dataclass(frozen=True)
class RotatorStatus:
    """One complete snapshot of a rotator, as published on ``R/status``."""

    rotator_id: str
    state: MotionState = MotionState.OFFLINE
    bearing_deg: float | None = None
    elevation_deg: float | None = None
    target_az_deg: float | None = None
    target_el_deg: float | None = None
    connected: bool = False  # serial port open
    available: bool = False  # port open and controller answering (or cannot answer)
    locked: bool = False
    # runtime/kept.py rule 10: the state file does not say the lock and the broker's
    # R/lock/state has not been read yet: motion is refused, and ``locked`` is not known
    lock_unknown: bool = False
    version: str | None = None
    options: dict[str, SettingValue] = field(default_factory=dict)  # the controller's settings
    last_error: str | None = None
    last_command_source: str | None = None
    estimated: bool = False  # bearing/elevation estimated during a slew the controller is silent in
    controller_time: str | None = None  # the controller's own clock (SatEL)
    expected_end_unix: float | None = None  # no feedback (DCU-1): when a commanded move should end
    # bearing_deg and target_az_deg are true bearings (pointing.py); this is the controller's own
    raw_bearing_deg: float | None = None
    raw_target_az_deg: float | None = None  # the controller's own value of target_az_deg
    overlap: str | None = None  # "cw" past 360, "ccw" below 0 (rotors that can pass 360)
    target_info: TargetInfo | None = None
    parked: bool = False  # at the park position after a park, until the next move
    tracking: TrackingInfo | None = None
    tracking_ended: str | None = None  # why the last tracking ended, until the next one starts
    following: FollowingInfo | None = None  # R/follow (session/follow.py)
    following_ended: str | None = None  # why following last ended, until it starts again
    wind: WindInfo | None = None  # with a wind_topic (session/wind.py)
    health: RotatorHealth | None = None  # how the rotor turns (session/health.py)
    last_operator: str | None = None  # who sent the command of last_command_source (Origin.who)
    control: Control | None = None  # the control lease's holder, if it is held
    # what a feature's session part shows (session/parts.py ``Part.status``), by the part's
    # name; a feature's StatusBlock reads its own (bridge/feature.py)
    features: dict[str, object] = field(default_factory=dict)
    # a stop the controller is owed (session/stops.py rule 3: taken while its port was out or it
    # was silent), its first frame when it can have one; kept across a restart (runtime/kept.py)
    stop_owed: bool = False
    # the raw azimuth of the last target written, which the controller keeps and the rotor
    # rests short of (session/controller.py rule 10); kept across a restart (runtime/kept.py)
    short_of_deg: float | None = None
    # a box with no feedback (DCU-1): a turn of the bridge's may be in flight, unseen
    # (session/motion.py rule 6, ``turn_kept``); kept across a restart (runtime/kept.py)
    turn_kept: bool = False
    # ...and when that hold runs out, on the session's clock (None: no end known yet, or
    # none kept); the state file keeps it on the kernel's boot clock (runtime/kept.py rule 13)
    turn_kept_until: float | None = None
    # a remote's reading of the station's R/status (remote/readings.py rule 3): every feature's
    # block (bridge/feature.py StatusBlock) by its key, as the station wrote it, checked; the
    # status's blocks are then these, not the typed fields above (interfaces/mqtt/payloads.py)
    relayed: dict[str, object] | None = None
    order: Order | None = None  # where it stands in the order of commands taken (Order)

    @property
    def moving(self) -> bool:
        return self.state is MotionState.MOVING


def turns_rotor(command: Command) -> bool:
    """Whether ``command`` may turn the rotor: what a stop or lock ON overtakes
    (interfaces/mqtt/service.py rule 11)."""
    match command:
        case Target() | GoToPreset() | Park() | Nudge() | Toward() | TakePath():
            return True
        case TrackBody():
            return not command.off
        case FollowQso():
            return command.on
        case FeatureCommand():
            return command.moves
    return False


def describe_command(command: Command) -> str:
    """How a command is echoed back to the user in an error event (and the audit trail) when
    its front end has no words of its own for it (what the user sent)."""
    match command:
        case Target():
            axes = (("az", command.az_deg), ("el", command.el_deg))
            return "target " + " ".join(f"{axis} {v:g}" for axis, v in axes if v is not None)
        case SetOption():
            return f"option {command.name} {setting_text(command.value)}"
        case Lock():
            return f"lock {'ON' if command.on else 'OFF'}"
        case Claim():
            return "claim"
        case Release():
            return "release"
        case TrackBody():
            return "track off" if command.off else f"track {command.name}"
        case FollowQso():
            return f"follow {'ON' if command.on else 'OFF'}"
        case GoToPreset():
            return f"preset {command.name}"
        case Park():
            return "park"
        case Nudge():
            el = "" if command.d_el_deg is None else f" el {command.d_el_deg:+g}"
            return f"nudge az {command.d_az_deg:+g}{el}"
        case Toward():
            where = command.locator or f"{command.latitude_deg:.4f},{command.longitude_deg:.4f}"
            return f"toward {where}" + (" long path" if command.long_path else "")
        case TakePath():
            return "long path" if command.long_path else "short path"
        case ResetHealth():
            return "health reset"
        case FeatureCommand():
            words = (command.feature, command.name, feature_value_text(command.value))
            return " ".join(word for word in words if word)
        case Stop():
            return "stop"
