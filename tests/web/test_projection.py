"""The console's map: where a point of the Earth lands on the station's disc and back, and the
shipped coastlines. Bearings and distances are judged by bridge/core/geo.py's great_circle, which
tests/test_geo.py judges against published values."""

from __future__ import annotations

import json
import math
from importlib import resources

import pytest

from bridge.core.geo import EARTH_RADIUS_KM, great_circle
from bridge.interfaces.web.projection import RIM_KM, project, unproject

LONDON = (51.5, -0.13)
STATIONS = [
    LONDON,
    (0.0, 0.0),
    (90.0, 0.0),  # the north pole
    (-90.0, 45.0),  # the south pole
    (10.0, 180.0),  # on the date line, from both sides
    (-33.9, -180.0),
    (64.8, -147.7),  # Fairbanks
    (-41.3, 174.8),  # Wellington, near the date line
]
GRID = [(lat, lon) for lat in range(-90, 91, 15) for lon in range(-180, 181, 30)]


def _km_between(a: tuple[float, float], b: tuple[float, float]) -> float:
    return great_circle(a[0], a[1], b[0], b[1]).distance_km


def _antipode(station: tuple[float, float]) -> tuple[float, float]:
    lon = station[1] + 180.0 if station[1] <= 0 else station[1] - 180.0
    return -station[0], lon


def _land() -> dict[str, object]:
    text = resources.files("bridge.interfaces.web").joinpath("land-110m.json").read_text()
    data: dict[str, object] = json.loads(text)
    return data


def _rings() -> list[list[list[float]]]:
    rings = _land()["rings"]
    assert isinstance(rings, list)
    return rings


@pytest.mark.parametrize("station", STATIONS)
def test_the_station_is_the_centre(station: tuple[float, float]) -> None:
    assert project(station, *station) == pytest.approx((0.0, 0.0), abs=1e-12)


@pytest.mark.parametrize("station", STATIONS)
def test_the_antipode_is_on_the_rim(station: tuple[float, float]) -> None:
    x, y = project(station, *_antipode(station))
    assert math.hypot(x, y) == pytest.approx(1.0, abs=1e-9)


@pytest.mark.parametrize("station", STATIONS)
@pytest.mark.parametrize("point", GRID[::3])
def test_a_point_lands_at_its_bearing_and_distance(
    station: tuple[float, float], point: tuple[float, float]
) -> None:
    path = great_circle(*station, *point)
    x, y = project(station, *point)
    radius = math.hypot(x, y)
    assert radius == pytest.approx(path.distance_km / (math.pi * EARTH_RADIUS_KM), abs=1e-12)
    if path.has_direction:  # the angle from north towards east, clockwise, is the bearing
        angle = math.degrees(math.atan2(x, y)) % 360.0
        assert (angle - path.short_path_deg + 180.0) % 360.0 - 180.0 == pytest.approx(0, abs=1e-6)


def test_north_is_up_and_east_is_right() -> None:
    x, y = project((0.0, 0.0), 10.0, 0.0)
    assert y > 0 and x == pytest.approx(0.0, abs=1e-12)
    x, y = project((0.0, 0.0), 0.0, 10.0)
    assert x > 0 and y == pytest.approx(0.0, abs=1e-12)
    x, y = project(LONDON, 40.7, -74.0)  # New York is west, a little north of west
    assert x < 0 and y > 0


@pytest.mark.parametrize("station", STATIONS)
def test_project_then_unproject_returns_the_point(station: tuple[float, float]) -> None:
    for point in GRID:
        if _km_between(point, _antipode(station)) < 1.0:  # the whole rim is the antipode
            continue
        x, y = project(station, *point)
        lat, lon, bearing_deg, distance_km = unproject(station, x, y)
        assert -90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0
        assert 0.0 <= bearing_deg < 360.0
        assert _km_between((lat, lon), point) < 1e-6, (station, point, lat, lon)
        path = great_circle(*station, *point)
        assert distance_km == pytest.approx(path.distance_km, abs=1e-6)
        if path.has_direction:
            assert bearing_deg == pytest.approx(path.short_path_deg, abs=1e-6)


@pytest.mark.parametrize("station", STATIONS)
def test_a_click_unprojects_to_the_point_at_its_bearing_and_distance(
    station: tuple[float, float],
) -> None:
    for bearing in range(0, 360, 30):
        for radius in (0.05, 0.3, 0.6, 0.95):
            theta = math.radians(bearing)
            lat, lon, bearing_deg, distance_km = unproject(
                station, radius * math.sin(theta), radius * math.cos(theta)
            )
            assert distance_km == pytest.approx(radius * RIM_KM)
            assert bearing_deg == pytest.approx(bearing, abs=1e-9)
            path = great_circle(*station, lat, lon)
            assert path.distance_km == pytest.approx(distance_km, abs=1e-6)
            assert (path.short_path_deg - bearing + 180.0) % 360.0 - 180.0 == pytest.approx(
                0.0, abs=1e-6
            )


def test_a_click_beyond_the_rim_is_refused() -> None:
    with pytest.raises(ValueError, match="beyond the rim"):
        unproject(LONDON, 0.8, 0.8)
    assert unproject(LONDON, 0.0, 1.0)[3] == pytest.approx(RIM_KM)


def test_a_station_off_the_earth_is_refused() -> None:
    with pytest.raises(ValueError, match="station latitude"):
        unproject((91.0, 0.0), 0.1, 0.1)
    with pytest.raises(ValueError, match="lat1"):
        project((91.0, 0.0), 0.0, 0.0)


def test_the_land_file_names_its_source() -> None:
    source = _land()["source"]
    assert isinstance(source, dict)
    assert "Natural Earth" in source["data"] and "public domain" in source["data"]
    assert "world-atlas@" in source["package"] and "ISC" in source["package"]


def test_every_ring_closes_and_stays_on_the_earth() -> None:
    rings = _rings()
    assert len(rings) > 100  # Natural Earth 110 m land: continents, islands and lakes
    for ring in rings:
        assert len(ring) >= 4 and ring[0] == ring[-1]
        assert all(-180.0 <= lon <= 180.0 and -90.0 <= lat <= 90.0 for lon, lat in ring)


def _inside(ring: list[list[float]], lat: float, lon: float) -> bool:
    """Even-odd rule on the longitude-latitude plane (for rings that do not cross 180)."""
    inside = False
    for (x1, y1), (x2, y2) in zip(ring, ring[1:], strict=False):
        if (y1 > lat) != (y2 > lat) and lon < x1 + (lat - y1) * (x2 - x1) / (y2 - y1):
            inside = not inside
    return inside


def _plain(ring: list[list[float]]) -> bool:
    return max(p[0] for p in ring) - min(p[0] for p in ring) < 180.0


def test_london_is_on_land_and_the_middle_of_the_pacific_is_not() -> None:
    rings = _rings()
    assert sum(_inside(r, *LONDON) for r in rings if _plain(r)) % 2 == 1
    nearest_km = min(_km_between(LONDON, (lat, lon)) for r in rings for lon, lat in r)
    assert nearest_km < 150.0  # the coast of Britain is near

    pacific = (0.0, -150.0)
    assert not any(_inside(r, *pacific) for r in rings if _plain(r))
    nearest_km = min(_km_between(pacific, (lat, lon)) for r in rings for lon, lat in r)
    assert nearest_km > 1000.0
