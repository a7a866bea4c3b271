"""The demo's satellite: orbital elements made up at start-up so that a pass over the demo's
station begins when the demo says (by default within a minute), whatever the time of day. No
network, as everywhere.

Rules:
1. A circular low orbit (15.5 revolutions a day, about 400 km up), inclined 97.5 degrees so it
   reaches every latitude the station may have (to 82.5 degrees).
2. At ``closest_unix`` (the element set's epoch) it is due west or east of the station by
   OFFSET_DEG of longitude, at the station's latitude, heading north: a pass peaking around
   50 degrees, rising some five minutes before and setting five after. The node is placed by
   mean sidereal time; what this ignores (nutation, J2 over minutes, the Earth's flattening)
   moves the pass by far less than its size.
3. The element set is a valid TLE (checksums, columns), written as a Celestrak-style 3-line
   file for ``[tracking] tle_file``.
4. It rises about ``half_pass_s`` before it is closest: on a sphere, the arc along the track
   from the horizon to the point nearest the station (its ground track OFFSET_DEG of longitude
   away), at the orbit's angular rate. What this ignores (the Earth turning under the pass,
   refraction) moves the rise by seconds, not minutes.
"""

from __future__ import annotations

import calendar
import math
import time
from pathlib import Path

from sgp4.io import compute_checksum

MEAN_MOTION_REV_DAY = 15.5
EARTH_RADIUS_KM = 6378.137
MU_KM3_S2 = 398600.4418  # the Earth's gravitational parameter
INCLINATION_DEG = 97.5
OFFSET_DEG = 4.0
CATALOG = 99990  # not a real object's number
NAME = "DEMOSAT"


def gmst_deg(t_unix: float) -> float:
    """Greenwich mean sidereal time (IAU 1982, to a few arcseconds), degrees."""
    days = t_unix / 86400.0 + 2440587.5 - 2451545.0
    return (280.46061837 + 360.98564736629 * days) % 360.0


def elements(latitude_deg: float, longitude_deg: float, closest_unix: float) -> tuple[str, str]:
    """TLE lines 1 and 2 of a satellite passing the station near ``closest_unix`` (rules 1, 2)."""
    i = math.radians(INCLINATION_DEG)
    # the argument of latitude; nearer a pole than the orbit reaches: its turning point
    u = math.asin(max(-1.0, min(1.0, math.sin(math.radians(latitude_deg)) / math.sin(i))))
    ra = gmst_deg(closest_unix) + longitude_deg + OFFSET_DEG  # the satellite's right ascension
    node = (ra - math.degrees(math.atan2(math.cos(i) * math.sin(u), math.cos(u)))) % 360.0
    anomaly = math.degrees(u) % 360.0  # circular, perigee at the node: mean = true = u
    return _line1(closest_unix), _line2(node, anomaly)


def half_pass_s(latitude_deg: float) -> float:
    """From its rise to its closest approach, seconds (rule 4)."""
    period_s = 86400.0 / MEAN_MOTION_REV_DAY
    orbit_km = (MU_KM3_S2 * (period_s / (2 * math.pi)) ** 2) ** (1 / 3)
    horizon = math.acos(EARTH_RADIUS_KM / orbit_km)  # arc from the station to its horizon
    across = math.radians(OFFSET_DEG) * math.cos(math.radians(latitude_deg))
    along = math.acos(min(1.0, math.cos(horizon) / math.cos(across)))
    return along / (2 * math.pi) * period_s


def write_tle_file(
    path: Path, latitude_deg: float, longitude_deg: float, rises_in_s: float
) -> float:
    """The demo's TLE file at ``path``, its satellite rising ``rises_in_s`` from now; returns
    the time it rises (Unix seconds)."""
    rise = time.time() + rises_in_s
    line1, line2 = elements(latitude_deg, longitude_deg, rise + half_pass_s(latitude_deg))
    path.write_text(f"{NAME}\n{line1}\n{line2}\n", encoding="ascii")
    return rise


def _line1(epoch_unix: float) -> str:
    t = time.gmtime(epoch_unix)
    start = calendar.timegm((t.tm_year, 1, 1, 0, 0, 0))
    day = 1.0 + (epoch_unix - start) / 86400.0
    yy = t.tm_year % 100
    body = (
        f"1 {CATALOG:05d}U {yy:02d}001A   {yy:02d}{day:012.8f}  .00000000  00000+0  00000+0 0  999"
    )
    return body + str(compute_checksum(body))


def _line2(node_deg: float, anomaly_deg: float) -> str:
    body = (
        f"2 {CATALOG:05d} {INCLINATION_DEG:8.4f} {node_deg:8.4f} 0001000 {0.0:8.4f} "
        f"{anomaly_deg:8.4f} {MEAN_MOTION_REV_DAY:11.8f}    1"
    )
    return body + str(compute_checksum(body))
