"""The console's map: the azimuthal equidistant projection centred on the station. Pure, no I/O.

Rules:
1. A station is (latitude_deg, longitude_deg); latitudes within -90..90 and longitudes within
   -180..180, finite, else ValueError naming the field (as bridge/core/geo.py).
2. The map is the unit disc: the station at (0, 0), north up (+y), east right (+x). A point at
   great-circle bearing b (degrees clockwise from true north) and distance d km along the short
   path lies at angle b from +y towards +x and radius d / (pi * EARTH_RADIUS_KM): the antipode
   is the rim, radius 1. Bearing and distance are bridge/core/geo.py's ``great_circle``.
3. At the station itself the point is (0, 0); the antipode, where no direction exists, is drawn
   at (0, 1), the top of the rim (core/geo.py gives it bearing 0).
4. ``unproject`` is the inverse for a click: the bearing is the click's angle, in [0, 360), the
   distance its radius times pi * EARTH_RADIUS_KM, and the point the one reached from the
   station along that bearing and distance. A click beyond the rim (radius over 1, with 1e-9 of
   slack for rounding) raises ValueError: it is off the Earth. At a pole, "north" is the
   direction of the station's own meridian continued beyond the pole, as in core/geo.py.
5. A returned longitude is in -180..180; at a pole the longitude carries no meaning.
"""

from __future__ import annotations

import math

from bridge.core.geo import EARTH_RADIUS_KM, check_range, destination, great_circle

Point = tuple[float, float]  # (latitude_deg, longitude_deg)
Station = Point

RIM_KM = math.pi * EARTH_RADIUS_KM  # the distance to the antipode, drawn at radius 1
_RIM_SLACK = 1e-9


def project(station: Station, lat: float, lon: float) -> tuple[float, float]:
    """(x, y) on the unit disc of the point (lat, lon) seen from the station (rules 2, 3)."""
    path = great_circle(station[0], station[1], lat, lon)
    radius = path.distance_km / RIM_KM
    bearing = math.radians(path.short_path_deg)
    return radius * math.sin(bearing), radius * math.cos(bearing)


def unproject(station: Station, x: float, y: float) -> tuple[float, float, float, float]:
    """(lat_deg, lon_deg, bearing_deg, distance_km) of the map point (x, y) (rule 4)."""
    lat0, lon0 = station
    check_range(lat0, "station latitude", 90.0)
    check_range(lon0, "station longitude", 180.0)
    if not (math.isfinite(x) and math.isfinite(y)):
        raise ValueError(f"map point ({x}, {y}) is not a finite point")
    radius = math.hypot(x, y)
    if radius > 1.0 + _RIM_SLACK:
        raise ValueError(f"map point ({x:.3f}, {y:.3f}) is beyond the rim (radius {radius:.3f})")
    radius = min(radius, 1.0)
    bearing_deg = math.degrees(math.atan2(x, y)) % 360.0 if radius > 0.0 else 0.0
    if bearing_deg >= 360.0:  # a tiny negative angle rounds up to 360
        bearing_deg = 0.0
    lat, lon = destination(lat0, lon0, bearing_deg, radius * RIM_KM)
    return lat, lon, bearing_deg, radius * RIM_KM
