"""What a SatEL says and understands, as data and pure functions (see satel.py for behaviour).

What the device is: see satel.py (the SatEL Az-El controller, VE5FP-compatible, Hamlib 2101).

Frame: ASCII text. satel.py splits the host's lines off the byte stream (ended by CR or LF, the
ending removed before parsing); the forms are `p<az> <el>` point, e.g. `p100 45`; `t` read the
clock; `tYYYY/MM/DD HH:MM:SS` set it; `YYYY/MM/DD HH:MM:SS <az> <el>` store a point (it starts
with the `2` of the year). Letters in upper or lower case. The controller's status report, every
line ended in its `line_ending` (CR LF, or LF only):
    Motion ENABLED                      (or Motion DISABLED)
    Mode 0 - azimuth break at NORTH
    Time: 2001/00/00 00:00:07
    Azimuth = 000     Absolute = 000
    Elevation = 000
    <empty>
    Number of stored positions: 00
    <empty>                             (`trailing_blank_lines` of them, 2 by default)

Source documents (written from these, never from bridge/protocols): Hamlib 4.5.4's satel
backend (satel.c and its author's notes, its traffic seen with rotctl), the SatEL Az-EL
instruction manual, Appendix A and page 12 (50 stored points).

Rules:
1. Pure: a line's bytes in, a typed line out; values in, report bytes out. The controller clock
   is the one piece of state, and it is told `now` (which never goes back).
2. A line that matches none of the forms, or names a date that does not exist, parses to None:
   the controller logs it "invalid" and answers nothing. Degrees are taken as typed (one to
   three digits); clamping to the stops is the controller's business.
3. Positions in reports are rounded half up to whole degrees, three digits; Absolute equals
   Azimuth (mode 0).
4. The clock counts whole seconds from a reset or from the last `t` that set it. Unset, it reads
   `2001/00/DD HH:MM:SS` counted from power on (Hamlib's example reads `2001/00/00 00:00:07`);
   compared with stored points it stands for POWER_ON_EPOCH.
5. Outcome strings are part of the emulator's public ground truth: tests of the bridge match on
   them, so they change only together with those tests.
6. Framer splits the byte stream: a line starts with one of LINE_LETTERS and ends at CR or LF
   (an LF right after the CR that ended a line is swallowed, also while slewing); any other
   byte is a command alone; while a slew runs only `s` and `*` are commands, every other byte
   is misuse; `x` right after a lower-case `c` is the setup calibration `cx`; a line longer
   than MAX_LINE_BYTES keeps only its start.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable
from dataclasses import dataclass
from datetime import datetime, timedelta
from enum import StrEnum

from bridge.emulators.base import RotatorState

MEMORY_LIMIT = 50  # manual p. 12: "the controller only has the capacity to remember 50 data points"
MAX_LINE_BYTES = 48  # longest valid line is a stored point, 27 bytes; beyond this it is junk
LINE_LETTERS = ("p", "t", "2")  # a byte that starts a line (lower-cased), not a command alone
CR, LF = 0x0D, 0x0A
#: The unset clock reads 2001/00/00 00:00:00; for comparisons it stands for this instant.
POWER_ON_EPOCH = datetime(2000, 12, 31)
_TIME = rb"(\d{4})/(\d{2})/(\d{2}) (\d{2}):(\d{2}):(\d{2})"
_POINT_RE = re.compile(rb"[pP](\d{1,3}) (\d{1,3})")
_SET_TIME_RE = re.compile(rb"[tT]" + _TIME)
_STORE_RE = re.compile(_TIME + rb" (\d{1,3}) (\d{1,3})")


class Token(StrEnum):
    """What one byte from the host amounts to (rule 6)."""

    NOTHING = "nothing"  # part of a line, or a line ending with no line
    SINGLE = "single"  # a command alone
    LINE = "line"  # a whole line, its ending included
    MISUSE = "misuse"  # input while slewing
    CX = "cx"  # the setup calibration


class Framer:
    """The host's bytes into commands and lines (rule 6). Reset with the controller."""

    def __init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        self._line: bytearray | None = None
        self._swallow_lf = False
        self._after_c = False

    def take(self, value: int, slewing: bool) -> tuple[Token, bytes]:
        swallow, self._swallow_lf = self._swallow_lf, False
        after_c, self._after_c = self._after_c, False
        if swallow and value == LF:
            return Token.NOTHING, b""
        letter = chr(value).lower() if value < 0x80 else ""
        if slewing:
            return (Token.SINGLE if letter in ("s", "*") else Token.MISUSE), bytes([value])
        if self._line is not None:
            if value in (CR, LF):
                line, self._line = bytes(self._line) + bytes([value]), None
                self._swallow_lf = value == CR
                return Token.LINE, line
            if len(self._line) <= MAX_LINE_BYTES:
                self._line.append(value)
            return Token.NOTHING, b""
        if value in (CR, LF):
            return Token.NOTHING, b""
        if after_c and value == ord("x"):
            return Token.CX, b"cx"
        if letter in LINE_LETTERS:
            self._line = bytearray([value])
            return Token.NOTHING, b""
        self._after_c = value == ord("c")  # only a lower-case c starts the setup calibration
        return Token.SINGLE, bytes([value])


@dataclass(frozen=True)
class SatelState(RotatorState):
    """RotatorState plus what only a SatEL has (`options` repeats the three flags)."""

    motion_enabled: bool = False
    slewing: bool = False
    corrupted: bool = False
    target_el_deg: float | None = None
    controller_time: str = ""
    stored_points: tuple[StoredPoint, ...] = ()
    misuse_count: int = 0


class Outcome(StrEnum):
    """What the controller did with a command (the `outcome` of a LoggedFrame)."""

    IDENTIFY = "identify"
    STATUS = "status"
    MOTION_ENABLED = "motion enabled"
    STOP = "stop"
    RESET = "reset"
    SLEW = "slew"
    JOG = "jog"
    TIME_READ = "time read"
    TIME_SET = "time set"
    MEMORY_CLEARED = "memory cleared"
    POINT_STORED = "point stored"
    CALIBRATE = "calibrate: no-op on SatEL"
    IGNORED_CX = "ignored: cx not emulated"
    IGNORED_MOTION_DISABLED = "ignored: motion disabled"
    IGNORED_MEMORY_FULL = "ignored: memory full"
    IGNORED_CORRUPTED = "ignored: corrupted state"
    INVALID = "invalid"
    MISUSE = "misuse: input while slewing"


@dataclass(frozen=True)
class StoredPoint:
    """One ephemeris point: at controller time `when`, point at az/el (as typed)."""

    when: datetime
    az_deg: int
    el_deg: int


@dataclass(frozen=True)
class PointLine:
    """`p<az> <el>`: slew there (as typed)."""

    az_deg: int
    el_deg: int


@dataclass(frozen=True)
class ClockRead:
    """`t`: print the controller clock."""


@dataclass(frozen=True)
class ClockSet:
    """`tYYYY/MM/DD HH:MM:SS`: set the controller clock."""

    when: datetime


Line = PointLine | ClockRead | ClockSet | StoredPoint


def parse_line(body: bytes) -> Line | None:
    """One host line without its ending, or None if it is none of the forms (rule 2)."""
    if (point := _POINT_RE.fullmatch(body)) is not None:
        return PointLine(int(point[1]), int(point[2]))
    if body in (b"t", b"T"):
        return ClockRead()
    if (m := _SET_TIME_RE.fullmatch(body)) and (when := _parse_time(m.groups())):
        return ClockSet(when)
    if (m := _STORE_RE.fullmatch(body)) and (when := _parse_time(m.groups()[:6])):
        return StoredPoint(when, int(m[7]), int(m[8]))
    return None


def _parse_time(groups: Iterable[bytes]) -> datetime | None:
    """The six groups of _TIME: year, month, day, hour, minute, second."""
    try:
        year, month, day, hour, minute, second = (int(g) for g in groups)
        return datetime(year, month, day, hour, minute, second)
    except ValueError:
        return None


class ControllerClock:
    """The controller's own clock: whole seconds counted from a reset or from the last `t`."""

    def __init__(self, now: float) -> None:
        self._base: datetime | None = None
        self._origin_s = now

    def reset(self, now: float) -> None:
        self._base, self._origin_s = None, now

    def set(self, when: datetime, now: float) -> None:
        self._base, self._origin_s = when, now

    def _elapsed_s(self, now: float) -> int:
        return max(0, math.floor(now - self._origin_s))

    def read(self, now: float) -> datetime:
        return (self._base or POWER_ON_EPOCH) + timedelta(seconds=self._elapsed_s(now))

    def text(self, now: float) -> str:
        if self._base is None:
            days, rest = divmod(self._elapsed_s(now), 86400)
            hours, rest = divmod(rest, 3600)
            return f"2001/00/{days:02d} {hours:02d}:{rest // 60:02d}:{rest % 60:02d}"
        return self.read(now).strftime("%Y/%m/%d %H:%M:%S")

    def instant_s(self, when: datetime) -> float:
        """The `now` at which this clock reads `when`."""
        return self._origin_s + (when - (self._base or POWER_ON_EPOCH)).total_seconds()


def status_report(
    *,
    motion_enabled: bool,
    clock_text: str,
    az_deg: float,
    el_deg: float,
    stored_points: int,
    trailing_blank_lines: int,
    line_ending: bytes,
) -> bytes:
    """The `z` report (and the one a `p` slew prints when it ends), rule 3."""
    az, el = _whole_deg(az_deg), _whole_deg(el_deg)
    lines = [
        "Motion ENABLED" if motion_enabled else "Motion DISABLED",
        "Mode 0 - azimuth break at NORTH",
        f"Time: {clock_text}",
        f"Azimuth = {az:03d}     Absolute = {az:03d}",
        f"Elevation = {el:03d}",
        "",
        f"Number of stored positions: {stored_points:02d}",
        *[""] * trailing_blank_lines,
    ]
    return b"".join(line.encode("ascii") + line_ending for line in lines)


def _whole_deg(value_deg: float) -> int:
    return math.floor(value_deg + 0.5)
