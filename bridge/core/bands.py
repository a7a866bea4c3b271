"""The amateur bands by name, and the band of a frequency as each program sends it. Pure: a
table and lookups, no settings and no I/O. A rotator's ``bands`` (settings/bands.py) name rows
of this table; the loggers (interfaces/loggers/commands.py) and following (session/follow.py) ask it
which band a message is on.

Rules:
1. A band is named as ADIF and the loggers write it, lower case: ``160m``, ``20m``, ``70cm``,
   ``1.25m``. ``canonical`` takes any case and blanks around the name (``20M``, `` 20m``) and
   refuses anything else with the nearest names it knows (a "did you mean").
2. The edges are the widest any IARU region has (40 m is 7.0-7.3 MHz, Region 2's; 2 m is
   144-148 MHz): no two bands come near each other, so a frequency inside a band anywhere in
   the world names that band, and the table needs no region setting. A frequency outside every
   band (a receiver tuned to broadcast, a transverter's IF given as the dial) names none.
3. ``band_of_hz`` reads a frequency in hertz (WSJT-X's dial frequency). ``band_of_mhz`` reads
   the band field of N1MM's rotor message, a number in MHz that is either inside the band
   (``14``, ``21.0``, ``432``) or the band's round number below its lower edge (``10`` for
   30 m, ``18`` for 17 m, ``24`` for 12 m, ``5`` for 60 m): NOMINAL_MHZ lists those.
4. Edges are inclusive; a number that is not finite names no band.
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Band:
    name: str
    low_hz: int
    high_hz: int


def _band(name: str, low_khz: float, high_khz: float) -> Band:
    return Band(name, round(low_khz * 1000), round(high_khz * 1000))


# rule 2: the widest edges of the three IARU regions (kHz)
BANDS: tuple[Band, ...] = (
    _band("2190m", 135.7, 137.8),
    _band("630m", 472, 479),
    _band("160m", 1800, 2000),
    _band("80m", 3500, 4000),
    _band("60m", 5250, 5450),
    _band("40m", 7000, 7300),
    _band("30m", 10100, 10150),
    _band("20m", 14000, 14350),
    _band("17m", 18068, 18168),
    _band("15m", 21000, 21450),
    _band("12m", 24890, 24990),
    _band("10m", 28000, 29700),
    _band("6m", 50000, 54000),
    _band("4m", 70000, 70500),
    _band("2m", 144000, 148000),
    _band("1.25m", 222000, 225000),
    _band("70cm", 420000, 450000),
    _band("33cm", 902000, 928000),
    _band("23cm", 1240000, 1300000),
    _band("13cm", 2300000, 2450000),
    _band("9cm", 3300000, 3500000),
    _band("6cm", 5650000, 5925000),
    _band("3cm", 10000000, 10500000),
    _band("1.25cm", 24000000, 24250000),
)
NAMES: tuple[str, ...] = tuple(b.name for b in BANDS)
_BY_NAME = {b.name: b for b in BANDS}

# rule 3: N1MM's round numbers for bands whose lower edge is not one
NOMINAL_MHZ: dict[float, str] = {5.0: "60m", 10.0: "30m", 18.0: "17m", 24.0: "12m"}


class UnknownBand(ValueError):
    """Not a band of the table; the message names the nearest ones."""


def canonical(name: str) -> str:
    """Rule 1: the table's name for ``name``, or UnknownBand saying what was meant."""
    key = name.strip().lower()
    if key in _BY_NAME:
        return key
    near = difflib.get_close_matches(key, NAMES, n=3, cutoff=0.5)
    hint = f"; did you mean {' or '.join(repr(n) for n in near)}?" if near else ""
    raise UnknownBand(f"{name!r} is not an amateur band (one of {', '.join(NAMES)}){hint}")


def band_of_hz(hz: float) -> str | None:
    """Rules 2 and 4: the band a frequency in hertz is in, or None."""
    if not math.isfinite(hz):
        return None
    for b in BANDS:
        if b.low_hz <= hz <= b.high_hz:
            return b.name
    return None


def band_of_mhz(mhz: float) -> str | None:
    """Rule 3: N1MM's band field (MHz), or None."""
    if not math.isfinite(mhz):
        return None
    return band_of_hz(round(mhz * 1e6)) or NOMINAL_MHZ.get(mhz)


def describe_hz(hz: float) -> str:
    """``14.074 MHz`` (for a message)."""
    return f"{hz / 1e6:.6g} MHz"
