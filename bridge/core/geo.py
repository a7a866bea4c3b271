"""Maidenhead locators and great-circle paths, for pointing an antenna. Pure functions, no I/O.

Locator rules (the Maidenhead Locator System, IARU): after stripping surrounding whitespace a
locator has 2, 4, 6 or 8 characters: field A..R (20 deg of longitude by 10 deg of latitude),
square 0..9 (2 deg by 1 deg), subsquare A..X (5' by 2.5'), extended square 0..9 (30" by 15");
each pair is longitude first, then latitude, counted east from 180 W and north from 90 S. Letters
may be in either case (ASCII only). A locator names an area: parse_locator returns its centre.
Anything else raises LocatorError with a message meant for the user.

Path rules: the Earth is a sphere of mean radius 6371.0 km (IUGG mean radius, rounded), the
sphere amateur-radio locator tools commonly use; WGS84 ellipsoid distances differ by < 0.5 %. A
bearing is the initial great-circle bearing, degrees clockwise from true north, in [0, 360) (360
never appears). The long path leaves at the short bearing + 180 and covers the rest of the
circumference. Where no direction exists (the same point, or antipodal points, where every
direction is a great circle) the bearing is 0 and ``Path.has_direction`` is False: a caller
that turns an antenna refuses such a target rather than point it at 0 (pointing.py rule 7).
``destination`` is the other way round: the point a bearing and a distance lead to (at a pole,
"north" is the starting meridian continued beyond the pole, as great_circle sees it).
Latitudes must be finite and within -90..90, longitudes within -180..180, else ValueError naming
the field.

Sources: ARRL, "About grid locators and grid squares" (field, square, subsquare sizes); Ed
Williams, "Aviation Formulary" (course and distance on the sphere); the distance is the atan2 form
(sine over cosine of the angle), accurate from millimetres to the antipodes. Tests compare with
published values from these and other sources (tests/test_geo.py).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

EARTH_RADIUS_KM = 6371.0
LOCATOR_LENGTHS = (2, 4, 6, 8)

# Each pair of characters: its alphabet and its size counted in extended squares, the finest
# cell (1/120 deg of longitude by 1/240 deg of latitude), so that cells are whole numbers.
_LEVELS = (
    ("ABCDEFGHIJKLMNOPQR", "a letter A..R", 2400),
    ("0123456789", "a digit 0..9", 240),
    ("ABCDEFGHIJKLMNOPQRSTUVWX", "a letter A..X", 10),
    ("0123456789", "a digit 0..9", 1),
)
_CELLS_PER_DEG_LON = 120
_CELLS_PER_DEG_LAT = 240
_ORDINALS = ("first", "second", "third", "fourth", "fifth", "sixth", "seventh", "eighth")
_LOCATOR = re.compile(r"[A-R]{2}([0-9]{2}([A-X]{2}([0-9]{2})?)?)?", re.ASCII | re.IGNORECASE)
# sine of the angle between the points below which no direction exists (about 6 micrometres)
_NO_DIRECTION = 1e-12


class LocatorError(ValueError):
    pass


@dataclass(frozen=True)
class Path:
    short_path_deg: float
    long_path_deg: float
    distance_km: float  # along the short path
    long_distance_km: float
    has_direction: bool = True  # False at the same point and at the antipode (bearings 0, 180)


def is_locator(text: str) -> bool:
    """Whether text (blanks around it allowed) is a locator, e.g. ``PM95vq`` but not ``95``."""
    return _LOCATOR.fullmatch(text.strip()) is not None


def parse_locator(text: str) -> tuple[float, float]:
    """(latitude_deg, longitude_deg) of the centre of the locator's area."""
    code = text.strip()
    shown = code if len(code) <= 12 else code[:12] + "…"
    if not code:
        raise LocatorError("empty locator")
    if len(code) not in LOCATOR_LENGTHS:
        raise LocatorError(f"locator {shown!r}: must be 2, 4, 6 or 8 characters, got {len(code)}")
    x = y = 0  # south-west corner, in finest cells from 180 W and from 90 S
    for position, char in enumerate(code):
        alphabet, what, size = _LEVELS[position // 2]
        # ASCII first: str.upper() turns some other letters into ASCII ones (long s into S)
        if not char.isascii() or char.upper() not in alphabet:
            ordinal = _ORDINALS[position]
            raise LocatorError(
                f"locator {shown!r}: {ordinal} character must be {what}, got {char!r}"
            )
        if position % 2 == 0:
            x += alphabet.index(char.upper()) * size
        else:
            y += alphabet.index(char.upper()) * size
    half = _LEVELS[len(code) // 2 - 1][2] / 2
    return -90.0 + (y + half) / _CELLS_PER_DEG_LAT, -180.0 + (x + half) / _CELLS_PER_DEG_LON


def great_circle(lat1: float, lon1: float, lat2: float, lon2: float) -> Path:
    """Bearings and distances from point 1 to point 2 along the great circle, both ways round."""
    check_range(lat1, "lat1", 90.0)
    check_range(lon1, "lon1", 180.0)
    check_range(lat2, "lat2", 90.0)
    check_range(lon2, "lon2", 180.0)
    phi1, phi2 = math.radians(lat1), math.radians(lat2)
    dlon = math.radians(lon2 - lon1)  # any multiple of 360 deg too much is harmless here
    # point 2 seen from point 1: east and north components of the tangent direction, whose
    # length is the sine of the angle between the points, and that angle's cosine
    east = math.cos(phi2) * math.sin(dlon)
    north = math.cos(phi1) * math.sin(phi2) - math.sin(phi1) * math.cos(phi2) * math.cos(dlon)
    cosine = math.sin(phi1) * math.sin(phi2) + math.cos(phi1) * math.cos(phi2) * math.cos(dlon)
    sine = math.hypot(east, north)
    angle = math.atan2(sine, cosine)  # accurate at every distance, unlike acos or asin alone
    has_direction = sine >= _NO_DIRECTION
    short = _bearing(math.degrees(math.atan2(east, north))) if has_direction else 0.0
    distance = EARTH_RADIUS_KM * angle
    return Path(
        short_path_deg=short,
        long_path_deg=_bearing(short + 180.0),
        distance_km=distance,
        long_distance_km=2.0 * math.pi * EARTH_RADIUS_KM - distance,
        has_direction=has_direction,
    )


def destination(
    lat: float, lon: float, bearing_deg: float, distance_km: float
) -> tuple[float, float]:
    """(lat, lon) reached from (lat, lon) along the great circle at ``bearing_deg`` after
    ``distance_km``. With 3-D unit vectors, so the poles need no special case: the point is
    cos(angle) * here + sin(angle) * (the unit tangent towards the bearing)."""
    check_range(lat, "lat", 90.0)
    check_range(lon, "lon", 180.0)
    phi, lam = math.radians(lat), math.radians(lon)
    theta, angle = math.radians(bearing_deg), distance_km / EARTH_RADIUS_KM
    here = (math.cos(phi) * math.cos(lam), math.cos(phi) * math.sin(lam), math.sin(phi))
    east = (-math.sin(lam), math.cos(lam), 0.0)
    north = (-math.sin(phi) * math.cos(lam), -math.sin(phi) * math.sin(lam), math.cos(phi))
    c, s = math.cos(angle), math.sin(angle)
    px, py, pz = (
        c * h + s * (math.cos(theta) * n + math.sin(theta) * e)
        for h, n, e in zip(here, north, east, strict=True)
    )
    return math.degrees(math.atan2(pz, math.hypot(px, py))), math.degrees(math.atan2(py, px))


def _bearing(degrees: float) -> float:
    value = degrees % 360.0
    # -1e-17 % 360.0 rounds to 360.0; -0.0 becomes 0.0
    return 0.0 if value == 0.0 or value >= 360.0 else value


def apart_deg(a_deg: float, b_deg: float, wraps: bool) -> float:
    """How far apart two bearings are, in degrees: on a circle when ``wraps`` (0 and 360 one
    direction), also for a value past 360 that line noise made (450 read on a 0..360 box is
    90); else along the line (a 450-degree rotor's 10 and 370 are a whole turn apart)."""
    d = abs(a_deg - b_deg)
    if wraps and d > 180.0:
        d %= 360.0
        d = min(d, 360.0 - d)
    return d


def on_south_travel(raw_deg: float) -> tuple[float, ...]:
    """Where a raw azimuth (0..360) is on a travel whose ends are at south, raw 180, as a
    Hy-Gain rotor's are: 180..540, north mid-travel at 360; 180 itself is either end."""
    if raw_deg == 180.0:
        return (180.0, 540.0)
    return (raw_deg + 360.0,) if raw_deg < 180.0 else (raw_deg,)


def travel_deg(a_raw: float, b_raw: float, wraps: bool, ends_at_north: bool) -> float:
    """How far apart two raw azimuths are along a rotor's travel: on the scale where its ends
    are the scale's (a SPID's overlap, a Yaesu's stop at north); where they are not known to be
    (a Hy-Gain rotor's stop at south, an RT-21 that turns its own way) the farther of that and
    the way along a travel whose ends are at south (``on_south_travel``). 179 and 181 on a
    Hy-Gain rotor are a whole turn apart (session/motion.py rule 5)."""
    straight = abs(a_raw - b_raw)
    if not wraps or ends_at_north:
        return straight
    ways = (abs(x - y) for x in on_south_travel(a_raw) for y in on_south_travel(b_raw))
    return max(straight, *ways)


def check_range(value: float, name: str, limit: float) -> None:
    """ValueError naming ``name`` unless ``value`` is finite and within -limit..limit."""
    if not math.isfinite(value) or not -limit <= value <= limit:
        raise ValueError(f"{name} must be a number from {-limit:g} to {limit:g}, got {value!r}")
