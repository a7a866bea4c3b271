"""GS-232B and Easycomm II input, sans-IO: bytes in, complete lines out, each line read into a
typed request. See the package docstring for the protocol facts and rules 1-3."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from enum import Enum

MAX_LINE = 80  # no command of either protocol is near this long: a longer line is junk


_ENDS = re.compile(rb"[\r\n]")


class LineSplitter:
    """Lines end at CR or LF (Hamlib's GS-232B sends CR, its Easycomm LF); empty lines are
    dropped. An overlong line comes out as ``None`` once it ends: junk, never a command.
    A chunk is cut at its line ends in one pass (no step per character): the work is linear
    in the bytes, and what is kept of a line never exceeds MAX_LINE."""

    def __init__(self) -> None:
        self._buf = b""
        self._overlong = False

    @property
    def idle(self) -> bool:
        """True when no line is half received."""
        return not self._buf and not self._overlong

    def feed(self, data: bytes) -> list[str | None]:
        out: list[str | None] = []
        pieces = _ENDS.split(data)
        for i, piece in enumerate(pieces):
            if not self._overlong:
                if len(self._buf) + len(piece) > MAX_LINE:
                    self._buf, self._overlong = b"", True
                else:
                    self._buf += piece
            if i == len(pieces) - 1:
                break  # the last piece has no end yet
            if self._overlong:
                out.append(None)
            elif line := self._buf.strip().decode("latin-1"):  # (ASCII blanks alone: latin-1's
                # others, \x1c-\x1f, \x85, \xa0, are no blanks of these protocols)
                out.append(line)
            self._buf, self._overlong = b"", False
        return out


# -- GS-232B ---------------------------------------------------------------------------------


class Gs232Kind(Enum):
    READ_AZ = "C"
    READ_EL = "B"
    READ_AZEL = "C2"
    GOTO_AZ = "M"
    GOTO_AZEL = "W"
    STOP = "S"
    STOP_AZ = "A"
    STOP_EL = "E"
    UNKNOWN = "?"  # anything else: answered with the error prompt


@dataclass(frozen=True)
class Gs232Request:
    kind: Gs232Kind
    az_deg: int | None = None
    el_deg: int | None = None


_FIXED = {
    "C": Gs232Kind.READ_AZ,
    "B": Gs232Kind.READ_EL,
    "C2": Gs232Kind.READ_AZEL,
    "S": Gs232Kind.STOP,
    "A": Gs232Kind.STOP_AZ,
    "E": Gs232Kind.STOP_EL,
}
_GOTO_AZ = re.compile(r"M(\d{1,3})")
_GOTO_AZEL = re.compile(r"W(\d{1,3}) +(\d{1,3})")


def parse_gs232(line: str | None) -> Gs232Request:
    """One line (from LineSplitter) as a GS-232B request; whatever is not one is UNKNOWN."""
    if line is None:
        return Gs232Request(Gs232Kind.UNKNOWN)
    if line in _FIXED:
        return Gs232Request(_FIXED[line])
    if m := _GOTO_AZ.fullmatch(line):
        return Gs232Request(Gs232Kind.GOTO_AZ, int(m[1]))
    if m := _GOTO_AZEL.fullmatch(line):
        return Gs232Request(Gs232Kind.GOTO_AZEL, int(m[1]), int(m[2]))
    return Gs232Request(Gs232Kind.UNKNOWN)


# -- Easycomm II -----------------------------------------------------------------------------

UNSUPPORTED_WORDS = frozenset({"ML", "MR", "MU", "MD", "RESET"})
# Easycomm III's jog at a speed (Hamlib's -m 204 ``M``: ``VL0050``): as unsupported as ``ML``
VELOCITY_WORDS = frozenset({"VL", "VR", "VU", "VD"})
_NUMBER = re.compile(r"[+-]?(?:\d{1,4}(?:\.\d*)?|\.\d+)")
# what a word the bridge does not know may be and still be ignored: a radio's (``UP000``,
# ``XXX``), an Easycomm III word it does not serve (``GS``); anything else is malformed
_FOREIGN_WORD = re.compile(r"[A-Za-z0-9.]+")
# Hamlib's -m 204 ends a configuration command with ``\n;``: the next line starts with it
HAMLIB_CONF_TAIL = ";"
_BLANKS = re.compile(r"[ \t]+")  # ASCII's alone: a control character is no blank (rule 12)


@dataclass(frozen=True)
class EasycommRequest:
    """What one line asks. ``queries`` keeps the order of ``AZ``/``EL``/``VE`` as asked (the
    reply echoes them in that order); ``invalid`` names a malformed word (nothing runs then
    but ``stop``: a stop word beside it still stops, package rule 6)."""

    queries: tuple[str, ...] = ()
    az_deg: float | None = None
    el_deg: float | None = None
    stop: bool = False
    park: bool = False
    unsupported: tuple[str, ...] = ()
    invalid: str | None = None
    ignored: tuple[str, ...] = field(default=())


def parse_easycomm(line: str | None) -> EasycommRequest:
    """One line (from LineSplitter): its words, separated by spaces."""
    if line is None:
        return EasycommRequest(invalid="an overlong line")
    if line.startswith(HAMLIB_CONF_TAIL):  # package rule 3: the tail of Hamlib's -m 204
        line = line[1:]  # configuration command before it (``GS\n;``), no word of this line
    queries: list[str] = []
    unsupported: list[str] = []
    ignored: list[str] = []
    az: float | None = None
    el: float | None = None
    stop = park = False
    invalid: str | None = None
    for word in _BLANKS.split(line):
        if not word:
            continue
        head, value = word[:2].upper(), word[2:]
        if word.upper() in ("PARK", "RESET"):
            if word.upper() == "PARK":
                park = True
            else:
                unsupported.append("RESET")
        elif head in ("AZ", "EL") and value == "":
            queries.append(head)
        elif head in ("AZ", "EL"):
            twice = az is not None if head == "AZ" else el is not None  # which one is meant?
            if twice or not _NUMBER.fullmatch(value):  # (``AZ190 AZ200``: neither, not the last)
                invalid = invalid or word[:16]  # (the line's stop words are still looked for)
                continue
            if head == "AZ":
                az = float(value)
            else:
                el = float(value)
        elif head in ("SA", "SE") and value == "":
            stop = True
        elif head == "VE" and value == "":
            queries.append("VE")
        elif head in UNSUPPORTED_WORDS or head in VELOCITY_WORDS:
            unsupported.append(head)
        elif _FOREIGN_WORD.fullmatch(word):
            # a radio's words (UP, DN, DM, ...) and the mode words that follow them
            ignored.append(word[:16])
        else:  # ``;AZ200.0``: no azimuth, and the line's other words are not half of it
            invalid = invalid or word[:16]
    if invalid is not None:  # package rule 3: nothing runs, but a stop (rule 6)
        return EasycommRequest(tuple(queries), stop=stop, invalid=invalid)
    return EasycommRequest(
        tuple(queries), az, el, stop, park, tuple(unsupported), None, tuple(ignored)
    )


# -- DCU-1 / Rotor-EZ ------------------------------------------------------------------------

DCU1_FRAME_MAX = 6  # "AP1ddd", the longest body: a seventh byte without an end is junk
_SEMICOLON, _CR, _LF, _A = 0x3B, 0x0D, 0x0A, 0x41


class Dcu1Kind(Enum):
    STORE = "AP1ddd;"  # keep a bearing for AM1
    GOTO = "AP1ddd<CR>"  # keep it and turn at once
    EXECUTE = "AM1;"
    READ = "AI1;"
    STOP = ";"  # and AS1;
    OPTION = "option"  # E e J j O o S s
    VERSION = "V"
    INVALID = "?"


# a byte outside a frame that is a command of its own; the option letters are the Rotor-EZ's
# (S is "unstick on", never a stop)
_DCU1_SINGLES = {
    _SEMICOLON: Dcu1Kind.STOP,
    ord("V"): Dcu1Kind.VERSION,
    **{letter: Dcu1Kind.OPTION for letter in b"EeJjOoSs"},
}
# those of them that move nothing: the TCP port lets them through at once (tcplines rule 2)
DCU1_HARMLESS = bytes(k for k, v in _DCU1_SINGLES.items() if v is not Dcu1Kind.STOP)


@dataclass(frozen=True)
class Dcu1Request:
    """One command as read: ``text`` as sent (for logs and ``R/error``), ``az_deg`` for AP1;
    ``stops`` on an INVALID frame ended by ``;`` (package rule 9)."""

    kind: Dcu1Kind
    text: str
    az_deg: int | None = None
    stops: bool = False


def _dcu1_frame(body: bytes, end: int) -> Dcu1Request:
    """A frame from ``A`` to its end (``;`` or CR), the end not in ``body``."""
    text = (body + bytes([end])).decode("latin-1")
    semicolon = end == _SEMICOLON
    if body == b"AI1":
        return Dcu1Request(Dcu1Kind.READ, text)
    if body == b"AM1" and semicolon:
        return Dcu1Request(Dcu1Kind.EXECUTE, text)
    if body == b"AS1" and semicolon:
        return Dcu1Request(Dcu1Kind.STOP, text)
    digits = body[3:]
    if body[:3] == b"AP1" and len(digits) == 3 and digits.isdigit() and int(digits) <= 360:
        kind = Dcu1Kind.STORE if semicolon else Dcu1Kind.GOTO
        return Dcu1Request(kind, text, int(digits))
    return Dcu1Request(Dcu1Kind.INVALID, text, stops=semicolon)


# one token of the stream: a frame ended, a frame too long, a frame not yet ended (at the end
# of what came), a byte that is a command of its own, line ends, a run of anything else
_DCU1_TOKEN = re.compile(
    rb"A[^;\r]{0,5}[;\r]|A[^;\r]{6}|A[^;\r]{0,5}\Z|[;VEeJjOoSs]|[\r\n]+|[^A;VEeJjOoSs\r\n]+"
)


class Dcu1Reader:
    """The DCU-1 / Rotor-EZ command stream (package rule 9): a frame opens at ``A`` and ends at
    ``;`` or CR; outside a frame each byte is a command of its own (``;`` stop, an option
    letter, ``V``), CR and LF are nothing, and a run of other bytes is one INVALID request.
    One pass over the bytes (a regular expression's), no more than DCU1_FRAME_MAX kept."""

    def __init__(self) -> None:
        self._held = b""  # a frame not yet ended

    @property
    def idle(self) -> bool:
        """True when no frame is half received."""
        return not self._held

    def feed(self, data: bytes) -> list[Dcu1Request]:
        out: list[Dcu1Request] = []
        buf, self._held = self._held + data, b""
        for match in _DCU1_TOKEN.finditer(buf):
            token = match[0]
            first, last = token[0], token[-1]
            if first == _A and last in (_SEMICOLON, _CR):
                out.append(_dcu1_frame(token[:-1], last))
            elif first == _A and len(token) > DCU1_FRAME_MAX:
                out.append(Dcu1Request(Dcu1Kind.INVALID, token.decode("latin-1")))
            elif first == _A:
                self._held = token  # the last token: what came ends inside a frame
            elif (single := _DCU1_SINGLES.get(first)) is not None:
                out.append(Dcu1Request(single, chr(first)))
            elif first not in (_CR, _LF):
                out.append(Dcu1Request(Dcu1Kind.INVALID, token.decode("latin-1")))
        return out


# -- stops, for the TCP port's accept loop (interfaces/tcplines.py rule 5) ---------------------


def gs232_holds_stop(data: bytes) -> bool:
    """Whether the complete lines in ``data`` hold a GS-232B stop (``S``, ``A``, ``E``)."""
    stops = (Gs232Kind.STOP, Gs232Kind.STOP_AZ, Gs232Kind.STOP_EL)
    return any(parse_gs232(line).kind in stops for line in LineSplitter().feed(data))


def easycomm_holds_stop(data: bytes) -> bool:
    """Whether the complete lines in ``data`` hold an Easycomm stop word (``SA``, ``SE``)."""
    return any(parse_easycomm(line).stop for line in LineSplitter().feed(data))


def dcu1_holds_stop(data: bytes) -> bool:
    """Whether ``data`` holds a DCU-1 stop (``;``, ``AS1;``, a frame ended by ``;`` that is
    none: package rule 9)."""
    return any(r.kind is Dcu1Kind.STOP or r.stops for r in Dcu1Reader().feed(data))
