"""What the sky is asked about: the sun, the moon, or a satellite given by its TLE; and the TLE
files satellites are read from. Pure: no clock, no I/O, no astronomy (positions.py, passes.py).

Rules:
1. A TLE is two lines of 69 characters (trailing blanks dropped), starting "1 " and "2 ", each
   ending in its checksum (sgp4's own: the sum of its digits, a minus sign counting 1, modulo
   10), with one catalog number on both lines, and elements that sgp4 accepts and propagates at
   their epoch, each inside the range an orbit has (an epoch's day of its year, the angles, a
   mean motion above 0 and at most MOST_REVS_PER_DAY). Anything else is SkyError naming the
   line and what is wrong. A TLE is ASCII: a line holding any other character is refused first
   (``str.isdigit`` takes ``²`` and ``٣``, which ``int`` refuses or reads: the checksum's sum,
   sgp4's too, raised ValueError).
2. A TLE file (parse_tles) is 3-line sets (a name line, Space-Track's "0 " prefix dropped) or
   bare 2-line sets (named by their catalog number); blank lines and CRLF are fine; a bad set is
   reported, naming its line, and skipped; a name seen again is reported and the later set used.
   A problem quotes a line only where the file shows it to be a satellite's name (the line
   right before a TLE's two lines), cut short (core/text.py ``quoted``); a line that names no
   set (stray text: an HTML page, a file named by mistake) is said by its number and length,
   never quoted (attack 18: the MQTT password file named as tle_file put the password in the
   journal at WARNING, and a file of one long line put megabytes in one log line). sgp4's own
   complaint, which quotes the line over several lines, is cut to its first.
3. A satellite named "off", "sun" or "moon" (any case) is called "satellite off" and so on:
   ``R/tracking`` saying "off" or "sun" must mean that.
4. What cannot be computed raises SkyError, whose ``reason`` is what a user reads when tracking
   ends for it ("satellite orbit decayed", "date beyond the ephemeris (2053)").
5. sgp4 is imported when a TLE is first checked, not with the module, as the astronomy is
   (positions.py rule 6): a start without satellites never needs it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from bridge.core.text import quoted

KINDS = ("sun", "moon", "satellite")
MINUTES_PER_DAY = 1440.0
#: an orbit's most (rule 1): one at the surface goes round some 17.1 times a day; decaying
#: objects' TLEs reach 16.5
MOST_REVS_PER_DAY = 18.0
RESERVED = ("off", "sun", "moon")  # what R/track and R/tracking mean by these (rule 3)


class SkyError(ValueError):
    """Input the sky cannot answer for; ``reason`` says it in a few words (rule 4)."""

    def __init__(self, message: str, reason: str | None = None) -> None:
        super().__init__(message)
        self.reason = reason or message


@dataclass(frozen=True)
class Body:
    kind: str  # "sun" | "moon" | "satellite"
    name: str  # "sun", "moon", or the satellite's name (TLE line 0, stripped)
    tle: tuple[str, str] | None = None  # satellites: line 1, line 2

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise SkyError(f"unknown body kind {self.kind!r}: one of {', '.join(KINDS)}")
        if (self.kind == "satellite") != (self.tle is not None):
            raise SkyError(f"{self.name!r}: a satellite has a TLE, the sun and the moon none")
        if self.tle is not None:
            if not self.name:
                raise SkyError("a satellite needs a name")
            if self.name.casefold() in RESERVED:
                raise SkyError(
                    f"a satellite cannot be called {self.name!r}: Body.satellite names it"
                )
            problem = _tle_problem(*self.tle)
            if problem is not None:
                raise SkyError(f"{self.name}: TLE line {problem[0]}: {problem[1]}")

    @staticmethod
    def sun() -> Body:
        return Body("sun", "sun")

    @staticmethod
    def moon() -> Body:
        return Body("moon", "moon")

    @staticmethod
    def satellite(name: str, line1: str, line2: str) -> Body:
        """A satellite called "off", "sun" or "moon" is "satellite off" etc. (rule 3)."""
        name = name.strip()
        if name.casefold() in RESERVED:
            name = f"satellite {name}"
        return Body("satellite", name, (line1.rstrip(), line2.rstrip()))


def tle_epoch_unix(line1: str) -> float:
    """When a TLE's elements are for (line 1's epoch: a two-digit year, 57-99 the 1900s, and
    the day of the year from 1.0), as unix seconds. The line is one Body has checked."""
    from datetime import UTC, datetime

    yy = int(line1[18:20])
    year = 1900 + yy if yy >= 57 else 2000 + yy
    return datetime(year, 1, 1, tzinfo=UTC).timestamp() + (float(line1[20:32]) - 1.0) * 86400.0


def _tle_problem(line1: str, line2: str) -> tuple[int, str] | None:
    """(which line, what is wrong) with a TLE, or None when sgp4 can use it (rule 1)."""
    from sgp4.api import SGP4_ERRORS, Satrec  # rule 5
    from sgp4.io import compute_checksum

    for number, line in ((1, line1), (2, line2)):
        if not line.isascii():  # rule 1
            odd = next(c for c in line if not c.isascii())
            return number, f"holds {odd!r} (U+{ord(odd):04X}): a TLE line is ASCII text"
        if len(line) != 69:
            return number, f"has {len(line)} characters, a TLE line has 69"
        if not line.startswith(f"{number} "):
            return number, f"must start with '{number} ', got {line[:2]!r}"
        tally = int(compute_checksum(line))
        if not line[68].isdigit() or int(line[68]) != tally:
            return number, f"checksum is {line[68]!r}, the line sums to {tally}"
    if line1[2:7] != line2[2:7]:
        return 2, f"catalog number {line2[2:7]!r} is not line 1's {line1[2:7]!r}"
    try:
        sat = Satrec.twoline2rv(line1, line2)
    except (ValueError, IndexError) as e:
        said = (str(e).splitlines() or [""])[0]  # rule 2: not the line it quotes below
        return 1, f"sgp4 cannot read the elements: {said}"
    impossible = _out_of_range(sat)
    if impossible is not None:
        return impossible
    error, _, _ = sat.sgp4(sat.jdsatepoch, sat.jdsatepochF)
    if error:
        return 2, f"sgp4 cannot propagate the elements: {SGP4_ERRORS[error]}"
    return None


def _out_of_range(sat: Any) -> tuple[int, str] | None:
    """Rule 1: (which line, what is wrong) with an element no orbit has, that sgp4 reads and
    propagates all the same (an attack pass: an epoch on day 999 of its year, 660 days on, and
    an inclination of 999.9999 degrees were taken, and the rotor turned for them)."""
    day = sat.epochdays
    if not 1.0 <= day < 367.0:
        return 1, f"epoch day {day:.8f} is no day of a year (1 to 366)"
    for name, rad, top in (
        ("inclination", sat.inclo, 180.0),
        ("right ascension of the ascending node", sat.nodeo, 360.0),
        ("argument of perigee", sat.argpo, 360.0),
        ("mean anomaly", sat.mo, 360.0),
    ):
        deg = math.degrees(rad)
        if not 0.0 <= deg <= top:
            return 2, f"{name} {deg:.4f} is outside 0..{top:g} degrees"
    revs = sat.no_kozai * MINUTES_PER_DAY / (2.0 * math.pi)
    if not 0.0 < revs <= MOST_REVS_PER_DAY:
        return 2, (
            f"mean motion {revs:.8f} revolutions a day is no orbit of the Earth (0 to "
            f"{MOST_REVS_PER_DAY:g})"
        )
    return None


def parse_tles(text: str) -> tuple[dict[str, tuple[str, str]], list[str]]:
    """The sets in a TLE file by name, and one problem per bad set, naming its line (rule 2)."""
    lines = [(n, line.strip()) for n, line in enumerate(text.splitlines(), 1) if line.strip()]
    sets: dict[str, tuple[str, str]] = {}
    first_line: dict[str, int] = {}
    problems: list[str] = []
    name: tuple[int, str] | None = None
    i = 0
    while i < len(lines):
        number, line = lines[i]
        i += 1
        if line.startswith("1 ") and i < len(lines) and lines[i][1].startswith("2 "):
            start, title = name if name is not None else (number, line[2:7].strip())
            name, line2 = None, lines[i][1]
            problem = _tle_problem(line, line2)
            if problem is not None:
                at = number if problem[0] == 1 else lines[i][0]
                problems.append(f"line {at}: {quoted(title)}: {problem[1]}")
            else:
                if title in sets:
                    first = first_line[title]
                    problems.append(
                        f"line {start}: {quoted(title)} again (first at line {first}): used"
                    )
                first_line.setdefault(title, start)
                sets[title] = (line, line2)
            i += 1
        elif line.startswith(("1 ", "2 ")):
            problems.append(
                f"line {number}: a TLE line {line[0]} without its line "
                f"{'2' if line[0] == '1' else '1'}"
            )
            name = None
        else:
            if name is not None:
                problems.append(_stray(*name))
            name = (number, line[2:].strip() if line.startswith("0 ") else line)
    if name is not None:
        problems.append(_stray(*name))
    return sets, problems


def _stray(number: int, line: str) -> str:
    """Rule 2: a line no TLE follows, said by its number and length, never quoted (it may be
    anything: a password file's one line)."""
    return f"line {number}: a line of {len(line)} characters is not followed by a TLE"
