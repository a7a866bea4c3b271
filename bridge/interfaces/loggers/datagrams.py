"""The loggers' datagrams: PstRotator's ``<PST>`` interface and N1MM's rotor messages, parsed
and rendered. Pure. Written from ../shared/protocols/logger-udp.md.

Rules:
1. A datagram is at most MAX_DATAGRAM bytes of ASCII; anything else is Malformed (but for one
   that may be a stop, rules 6 and 7, whose bytes that are not ASCII are read as ``?``: a stop is
   never refused, and a degree sign or a Latin-1 byte beside one dropped it whole), and so is
   every datagram that is not wholly understood: a number that is not one (NaN, inf, empty,
   ``12x``), text outside the tags, a tag left open, a ``PARK`` that is neither ``1`` nor ``0``
   (an attack pass: ``0.0``, ``false`` or ``no`` parked the rotor), a ``QRA`` that is no 4, 6
   or 8 characters. Malformed datagrams move nothing.
2. PST: ``<PST>`` ... ``</PST>``, tags matched in any case, several in one datagram, parsed
   all before anything is done. A value is a decimal number, optionally followed by the
   ``.2`` Hamlib 4.6 appends (``120.000000.2``). ``STOP`` wins over everything else in the
   datagram; then ``PARK``; then the axes present. ``AZ?``/``EL?`` are queries, each kind
   once however often asked (one reply per kind: a datagram must not buy hundreds); ``TRACK``,
   ``MODE?`` and tags nobody documents are ignored (and counted). Ambiguous is Malformed: one
   of ``AZIMUTH``, ``ELEVATION``, ``QRA``, ``PARK`` given twice with different values, or an
   ``AZIMUTH`` beside a ``QRA`` (two bearings); the same value twice says one thing. Beside a
   ``STOP`` nothing is ambiguous: the stop is never refused, an ambiguous target is dropped.
3. PST replies: integer degrees and one CR (``AZ:123\\r``), the form the strictest client
   (Minos) accepts and every other does.
4. N1MM: ``<N1MMRotor>`` with ``<rotor>``, ``<goazi>`` (0..360), ``<offset>``,
   ``<bidirectional>``, ``<freqband>`` in any order and layout; any ``<stop`` element is a stop,
   the rotor's name then from ``<rotor>`` wherever it is, else the text of ``<stop>``. A turn
   gives ``<rotor>``, ``<goazi>``, ``<offset>``, ``<bidirectional>``, ``<freqband>`` once each
   (N1MM's one form): a repeated one is ambiguous, Malformed. A stop is never refused: the other
   names it gives (a second ``<rotor>``, ``<stop>``'s text beside ``<rotor>``) are in ``also``.
   ``<freqband>`` (MHz, ``14``, ``21.0``) is kept as a number; one that is none is kept as
   absent (before it chose a rotator it was never read: a sender whose band field is odd still
   turns a rotator it names), its text kept for the refusal of a turn chosen by band (a
   review: ``abc`` or ``1e308`` was refused as "the message has no <freqband>").
5. N1MM position report: ``name @ heading*10`` as plain text (``Tower @ 650`` is 65.0).
6. Whether a datagram may be a stop is told by one byte search, before any parsing: ``<STOP>``
   (PST, any case) or ``<stop`` (N1MM, any case), the forms rules 2 and 4 read as a stop, so
   every datagram the parsers call a stop is one of them (and some junk too).
7. A datagram over MAX_DATAGRAM bytes (the socket gives the first MAX_DATAGRAM + 1 of it, the
   rest is lost) is Malformed, but for a stop: one that begins as its form does (``<PST>``,
   ``<N1MMRotor>``) and holds its stop (``<STOP>``; ``<stop`` and a rotor's name, from
   ``<rotor>`` or ``<stop>``'s text) in what was read is that stop (a stop is never refused:
   one padded past 2 KiB was dropped, and the rotor turned on). Anything else in it is moot.
8. What an XML writer may put in front of the root element is passed over, as an XML parser
   would: a UTF-8 byte-order mark and one XML declaration (``<?xml version="1.0"
   encoding="utf-8"?>``, the head of N1MM's other broadcasts), with white space around them
   (an attack pass: a datagram so headed was Malformed, a stop included). A declaration is
   what XML 1.0's grammar calls one (review 70: ``<?xml`` and any junk up to ``?>``, which no
   XML reader takes, turned the rotor). Nothing else is (no comment, no DOCTYPE): the forms
   are the fact sheet's.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import dataclass

from bridge.core.text import shown_past

MAX_DATAGRAM = 2048
MAX_NAME = 64

_PST = re.compile(rb"^\s*<pst>(?P<body>.*)</pst>\s*$", re.I | re.S)
_ITEM = re.compile(
    r"\s*(?:<(?P<tag>[a-z][a-z0-9_]{0,31})>(?P<value>[^<]{0,64})</(?P=tag)>|(?P<query>[a-z]{2,8})\?)\s*",
    re.I,
)
_VALUE = re.compile(r"^\s*([+-]?(?:\d+(?:\.\d*)?|\.\d+))(?:\.\d+)?\s*$")
_N1MM = re.compile(rb"^\s*<n1mmrotor>(?P<body>.*)</n1mmrotor>\s*$", re.I | re.S)
#: rule 8: a byte-order mark and an XML declaration ahead of the root element, as XML 1.0's
#: grammar has it (``XMLDecl``): a version, then an encoding and a standalone, each optional
_DECLARATION = (
    rb"<\?xml\s+version\s*=\s*(?:\"1\.[0-9]+\"|'1\.[0-9]+')"
    rb"(?:\s+encoding\s*=\s*(?:\"[A-Za-z][A-Za-z0-9._-]*\"|'[A-Za-z][A-Za-z0-9._-]*'))?"
    rb"(?:\s+standalone\s*=\s*(?:\"(?:yes|no)\"|'(?:yes|no)'))?\s*\?>"
)
_PROLOG = re.compile(rb"^\s*(?:\xef\xbb\xbf)?\s*(?:" + _DECLARATION + rb")?")


class Malformed(ValueError):
    """The datagram is not understood; the message says why (for a debug log)."""


@dataclass(frozen=True)
class PstRequest:
    stop: bool = False
    park: bool = False
    azimuth: float | None = None
    elevation: float | None = None
    locator: str | None = None
    queries: tuple[str, ...] = ()  # "AZ", "EL", in the order asked
    ignored: tuple[str, ...] = ()  # TRACK, MODE and unknown tags


@dataclass(frozen=True)
class N1mmRequest:
    rotor: str
    stop: bool = False
    azimuth: float | None = None
    offset: float = 0.0
    bidirectional: bool = False
    also: tuple[str, ...] = ()  # a stop's other names (rule 4)
    freqband_mhz: float | None = None  # the radio's band as N1MM writes it (rule 4)
    freqband_unread: str | None = None  # rule 4: a <freqband> given that is no number, as sent


def ascii_text(datagram: bytes) -> str:
    """A datagram as text, each byte that is not ASCII read as ``?`` (rule 1)."""
    return datagram.decode("ascii", "replace").replace("\ufffd", "?")


def may_stop_pst(datagram: bytes) -> bool:
    """Rule 6."""
    return b"<stop>" in datagram.lower()


def may_stop_n1mm(datagram: bytes) -> bool:
    """Rule 6."""
    return b"<stop" in datagram.lower()


def without_prolog(datagram: bytes) -> bytes:
    """Rule 8: ``datagram`` from its root element on (a byte-order mark and an XML declaration
    in front of it passed over), else as it is."""
    m = _PROLOG.match(datagram)  # it matches the empty prolog too
    return datagram if m is None else datagram[m.end() :]


def _text(
    datagram: bytes, pattern: re.Pattern[bytes], what: str, may_stop: Callable[[bytes], bool]
) -> str:
    if len(datagram) > MAX_DATAGRAM:
        raise Malformed(f"{len(datagram)} bytes, over {MAX_DATAGRAM}")
    datagram = without_prolog(datagram)
    if not datagram.isascii():
        if not may_stop(datagram):
            raise Malformed("not ASCII")
        datagram = ascii_text(datagram).encode("ascii")  # rule 1: a stop's other bytes, '?'

    m = pattern.match(datagram)
    if m is None:
        raise Malformed(f"not a {what} datagram")
    return m.group("body").decode("ascii")


def _number(text: str, tag: str) -> float:
    m = _VALUE.match(text)
    if m is None:
        raise Malformed(f"{tag}: {text[:20]!r} is not a number")
    value = float(m.group(1))
    if not math.isfinite(value):
        raise Malformed(f"{tag}: not a finite number")
    return value


def _over_long_stop(datagram: bytes, head: bytes, may_stop: Callable[[bytes], bool]) -> str | None:
    """Rule 7: an over-long datagram of this form that may be a stop: its text as read (the
    socket gives at most MAX_DATAGRAM + 1 bytes, the rest is lost), else None."""
    if len(datagram) <= MAX_DATAGRAM or not may_stop(datagram):
        return None
    datagram = without_prolog(datagram)
    if datagram.lstrip()[: len(head)].lower() != head:
        return None
    return ascii_text(datagram)


def parse_pst(datagram: bytes) -> PstRequest:
    """Rule 2 (Malformed for anything not wholly understood, or ambiguous; a stop never)."""
    if _over_long_stop(datagram, b"<pst>", may_stop_pst) is not None:  # rule 7
        return PstRequest(stop=True)
    body = _text(datagram, _PST, "<PST>", may_stop_pst)
    try:
        return _pst(body)
    except Malformed:
        if "<STOP>" in body.upper():  # never refused: what is beside it is moot
            return PstRequest(stop=True)
        raise


def _pst(body: str) -> PstRequest:
    targets: dict[str, set[float | str | bool]] = {}  # AZIMUTH, ELEVATION, QRA, PARK
    stop = False
    queries: list[str] = []
    ignored: list[str] = []
    pos = 0
    while pos < len(body):
        m = _ITEM.match(body, pos)
        if m is None or m.end() == pos:
            raise Malformed(f"cannot read {body[pos : pos + 20]!r}")
        pos = m.end()
        if m.group("query") is not None:
            q = m.group("query").upper()
            if q not in queries and q not in ignored:  # one answer per kind
                (queries if q in ("AZ", "EL") else ignored).append(q)
            continue
        tag, value = m.group("tag").upper(), m.group("value")
        if tag in ("AZIMUTH", "ELEVATION"):
            targets.setdefault(tag, set()).add(_number(value, tag))
        elif tag == "QRA":  # 4, 6 or 8 characters (a field of 2 is a whole continent)
            if len(value.strip()) not in (4, 6, 8):
                raise Malformed(f"QRA: {value.strip()[:20]!r} is no 4, 6 or 8 character locator")
            targets.setdefault(tag, set()).add(value.strip())
        elif tag == "STOP":
            stop = True
        elif tag == "PARK":  # 1 parks, 0 does not; nothing else is either (rule 2)
            word = value.strip()
            if word not in ("0", "1"):
                raise Malformed(f"PARK: {word[:20]!r} is neither 1 nor 0")
            targets.setdefault(tag, set()).add(word == "1")
        else:
            ignored.append(tag)
    ambiguous = [tag for tag, values in targets.items() if len(values) > 1]
    if "AZIMUTH" in targets and "QRA" in targets:
        ambiguous.append("AZIMUTH and QRA")
    if ambiguous and not stop:  # a stop is never refused: what is beside it is moot
        raise Malformed(f"ambiguous: {', '.join(ambiguous)}")
    one = {tag: next(iter(values)) for tag, values in targets.items() if tag not in ambiguous}
    return PstRequest(
        stop=stop,
        park=one.get("PARK") is True,
        azimuth=_float_or_none(one.get("AZIMUTH")),
        elevation=_float_or_none(one.get("ELEVATION")),
        locator=str(one["QRA"]) if "QRA" in one else None,
        queries=tuple(queries),
        ignored=tuple(ignored),
    )


def _float_or_none(value: object) -> float | None:
    return value if isinstance(value, float) else None


def pst_reply(query: str, degrees: float) -> bytes:
    """Rule 3: ``AZ:123\\r``."""
    return f"{query}:{math.floor(degrees + 0.5):d}\r".encode("ascii")


_N1MM_TAG = re.compile(r"<(?P<tag>[a-z]+)>(?P<value>[^<]{0,64})</(?P=tag)>", re.I)
_ONCE = ("rotor", "goazi", "offset", "bidirectional", "freqband")  # a turn's, each once
_STOP_WRAP = re.compile(r"</?stop\s*/?>", re.I)  # <stop>, </stop>, <stop/>


def _stop_names(text: str) -> list[str]:
    """Rule 7: the rotors' names an over-long stop gives in what was read, ``<rotor>``'s first."""
    tags = [(m.group("tag").lower(), m.group("value").strip()) for m in _N1MM_TAG.finditer(text)]
    names = [v for t, v in tags if t == "rotor"] + [v for t, v in tags if t == "stop"]
    return [n for n in dict.fromkeys(names) if n and len(n) <= MAX_NAME and n.isprintable()]


def parse_n1mm(datagram: bytes) -> N1mmRequest:
    """Rule 4 (Malformed for anything not understood, or ambiguous)."""
    long = _over_long_stop(datagram, b"<n1mmrotor>", may_stop_n1mm)
    if long is not None and (names := _stop_names(long)):  # rule 7
        return N1mmRequest(names[0], stop=True, also=tuple(names[1:]))
    body = _text(datagram, _N1MM, "<N1MMRotor>", may_stop_n1mm)
    stop = "<stop" in body.lower()
    rest = _STOP_WRAP.sub("", _N1MM_TAG.sub("", body))
    if rest.strip() and not stop:  # (beside a stop, what cannot be read is moot)
        raise Malformed(f"cannot read {rest.strip()[:20]!r}")
    given: dict[str, list[str]] = {}
    for m in _N1MM_TAG.finditer(body):
        given.setdefault(m.group("tag").lower(), []).append(m.group("value").strip())
    names = list(dict.fromkeys(n for n in given.get("rotor", []) if n))
    if stop:  # the stop's text is a name when no <rotor> gives one, else perhaps one more
        names += [n for n in dict.fromkeys(given.get("stop", [])) if n and n not in names]
        names = [n for n in names if len(n) <= MAX_NAME and n.isprintable()]  # the others'
    if not names or any(len(n) > MAX_NAME or not n.isprintable() for n in names):
        raise Malformed("no rotor name")
    if stop:
        return N1mmRequest(names[0], stop=True, also=tuple(names[1:]))
    repeated = [t for t in _ONCE if len(given.get(t, [])) > 1]
    if repeated:
        raise Malformed(f"ambiguous: <{'>, <'.join(repeated)}> given twice")
    values = {tag: texts[0] for tag, texts in given.items()}
    if "goazi" not in values:
        raise Malformed("neither <goazi> nor <stop>")
    az = _number(values["goazi"], "goazi")
    if not 0.0 <= az <= 360.0:
        raise Malformed(f"goazi {shown_past(az, 0.0, 360.0)} outside 0..360")
    offset = _number(values["offset"], "offset") if values.get("offset") else 0.0
    flag = values.get("bidirectional", "0").strip()
    if flag not in ("", "0", "1"):  # (an attack pass: "abc" was a yes: the reciprocal bearing)
        raise Malformed(f"bidirectional {flag[:16]!r} is neither 0 nor 1")
    bidirectional = flag == "1"
    band: float | None = None  # rule 4: kept as absent, but for what a refusal says
    unread = None
    try:
        band = _number(values["freqband"], "freqband")
    except KeyError:
        pass
    except Malformed:
        unread = values["freqband"]
    return N1mmRequest(
        names[0],
        azimuth=az,
        offset=offset,
        bidirectional=bidirectional,
        freqband_mhz=band,
        freqband_unread=unread,
    )


def n1mm_report(name: str, heading_deg: float) -> bytes:
    """Rule 5: ``Tower @ 650``."""
    return f"{name} @ {round((heading_deg % 360.0) * 10) % 3600:d}".encode("ascii")
