"""Maidenhead locators and great-circle paths, judged against published values.

The bridge's acceptance rule for a path: distance within 1 %, bearing within 1 degree of an
independent reference. Every reference below is either a published value (its source is cited
beside it) or computed here by a different method than bridge/core/geo.py uses (Vincenty's inverse
on an ellipsoid, and 3-D unit vectors on the sphere), never by the module itself.
"""

from __future__ import annotations

import math
import re

import pytest
from hypothesis import given
from hypothesis import strategies as st

from bridge.core.geo import (
    LocatorError,
    Path,
    apart_deg,
    great_circle,
    is_locator,
    parse_locator,
)
from tests.support.locator import to_locator

CIRCUMFERENCE_KM = 2 * math.pi * 6371.0
US_SURVEY_MILE_KM = 6336 / 3937  # US survey foot = 1200/3937 m; a mile is 5280 feet
WGS84 = (6378137.0, 1 / 298.257223563)
INTERNATIONAL_1924 = (6378388.0, 1 / 297.0)  # the "Hayford" ellipsoid of Vincenty's test lines


def dms(degrees: float, minutes: float = 0.0, seconds: float = 0.0) -> float:
    return degrees + minutes / 60 + seconds / 3600


def off(a: float, b: float) -> float:
    """Angle between two bearings, 0..180."""
    return abs((a - b + 180.0) % 360.0 - 180.0)


# ---- independent references, not the module's formula ---------------------------------------


def vincenty_inverse(
    ellipsoid: tuple[float, float], lat1: float, lon1: float, lat2: float, lon2: float
) -> tuple[float, float]:
    """(distance_km, initial azimuth deg) on an ellipsoid, by the iteration of T. Vincenty,
    "Direct and inverse solutions of geodesics on the ellipsoid with application of nested
    equations", Survey Review XXIII (176), 1975. Not for nearly antipodal points."""
    a, f = ellipsoid
    b = (1 - f) * a
    u1 = math.atan((1 - f) * math.tan(math.radians(lat1)))
    u2 = math.atan((1 - f) * math.tan(math.radians(lat2)))
    big_l = math.radians(lon2 - lon1)
    lam = big_l
    for _ in range(200):
        sin_sigma = math.hypot(
            math.cos(u2) * math.sin(lam),
            math.cos(u1) * math.sin(u2) - math.sin(u1) * math.cos(u2) * math.cos(lam),
        )
        cos_sigma = math.sin(u1) * math.sin(u2) + math.cos(u1) * math.cos(u2) * math.cos(lam)
        sigma = math.atan2(sin_sigma, cos_sigma)
        sin_alpha = math.cos(u1) * math.cos(u2) * math.sin(lam) / sin_sigma
        cos2_alpha = 1 - sin_alpha**2
        cos_2sm = cos_sigma - 2 * math.sin(u1) * math.sin(u2) / cos2_alpha
        c = f / 16 * cos2_alpha * (4 + f * (4 - 3 * cos2_alpha))
        previous = lam
        lam = big_l + (1 - c) * f * sin_alpha * (
            sigma + c * sin_sigma * (cos_2sm + c * cos_sigma * (-1 + 2 * cos_2sm**2))
        )
        if abs(lam - previous) < 1e-12:
            break
    else:
        raise AssertionError("Vincenty's iteration did not converge")
    u_sq = cos2_alpha * (a**2 - b**2) / b**2
    big_a = 1 + u_sq / 16384 * (4096 + u_sq * (-768 + u_sq * (320 - 175 * u_sq)))
    big_b = u_sq / 1024 * (256 + u_sq * (-128 + u_sq * (74 - 47 * u_sq)))
    delta_sigma = (
        big_b
        * sin_sigma
        * (
            cos_2sm
            + big_b
            / 4
            * (
                cos_sigma * (-1 + 2 * cos_2sm**2)
                - big_b / 6 * cos_2sm * (-3 + 4 * sin_sigma**2) * (-3 + 4 * cos_2sm**2)
            )
        )
    )
    distance_m = b * big_a * (sigma - delta_sigma)
    azimuth = math.atan2(
        math.cos(u2) * math.sin(lam),
        math.cos(u1) * math.sin(u2) - math.sin(u1) * math.cos(u2) * math.cos(lam),
    )
    return distance_m / 1000, math.degrees(azimuth) % 360


def sphere_by_vectors(lat1: float, lon1: float, lat2: float, lon2: float) -> tuple[float, float]:
    """(distance_km, bearing deg) on the 6371 km sphere from 3-D unit vectors: the angle between
    the position vectors, and point 2 projected on point 1's local east and north axes."""
    p1, l1, p2, l2 = map(math.radians, (lat1, lon1, lat2, lon2))
    v1 = (math.cos(p1) * math.cos(l1), math.cos(p1) * math.sin(l1), math.sin(p1))
    v2 = (math.cos(p2) * math.cos(l2), math.cos(p2) * math.sin(l2), math.sin(p2))
    cross = (
        v1[1] * v2[2] - v1[2] * v2[1],
        v1[2] * v2[0] - v1[0] * v2[2],
        v1[0] * v2[1] - v1[1] * v2[0],
    )
    dot = sum(x * y for x, y in zip(v1, v2, strict=True))
    east_axis = (-math.sin(l1), math.cos(l1), 0.0)
    north_axis = (-math.sin(p1) * math.cos(l1), -math.sin(p1) * math.sin(l1), math.cos(p1))
    east = sum(x * y for x, y in zip(v2, east_axis, strict=True))
    north = sum(x * y for x, y in zip(v2, north_axis, strict=True))
    angle = math.atan2(math.sqrt(sum(x * x for x in cross)), dot)
    return 6371.0 * angle, math.degrees(math.atan2(east, north)) % 360


@pytest.mark.parametrize(
    ("line", "lat1", "lat2", "dlon", "azimuth", "distance_km"),
    [
        # Vincenty (1975), table of test lines, International ellipsoid, as published:
        # (b) phi1 37°19'54.95367", phi2 26°07'42.83946", L 41°28'35.50729",
        #     alpha1 95°27'59.63089", s 4 085 966.703 m
        ("b", dms(37, 19, 54.95367), dms(26, 7, 42.83946), dms(41, 28, 35.50729),
         dms(95, 27, 59.63089), 4085.966703),
        # (c) phi1 35°16'11.24862", phi2 67°22'14.77638", L 137°47'28.31435",
        #     alpha1 15°44'23.74850", s 8 084 823.839 m
        ("c", dms(35, 16, 11.24862), dms(67, 22, 14.77638), dms(137, 47, 28.31435),
         dms(15, 44, 23.74850), 8084.823839),
    ],
)  # fmt: skip
def test_the_ellipsoid_reference_reproduces_vincentys_published_lines(
    line: str, lat1: float, lat2: float, dlon: float, azimuth: float, distance_km: float
) -> None:
    distance, bearing = vincenty_inverse(INTERNATIONAL_1924, lat1, 0.0, lat2, dlon)
    assert distance == pytest.approx(distance_km, abs=1e-5)  # 1 cm
    assert off(bearing, azimuth) < dms(0, 0, 0.001)


# ---- Maidenhead -------------------------------------------------------------------------------

# Centres worked out by hand from the definition (field 20x10 deg from 180 W / 90 S, square
# 2x1 deg, subsquare 1/12 x 1/24 deg, extended square 1/120 x 1/240 deg), then the place the
# locator is known for (rounded coordinates), which must be near the centre.
KNOWN_CENTRES = [
    # J=9 O=14 6 2 q=16 m=12: lon -180+180+12+16/12+1/24, lat -90+140+2+12/24+1/48
    ("JO62qm", 52.5 + 1 / 48, 13 + 1 / 3 + 1 / 24, (52.52, 13.40), "Berlin"),
    ("JN58td", 48.125 + 1 / 48, 11 + 7 / 12 + 1 / 24, (48.14, 11.58), "Munich"),
    ("FN31pr", 41 + 17 / 24 + 1 / 48, -74 + 1.25 + 1 / 24, (41.71, -72.73), "ARRL HQ, Newington"),
    ("PM95vq", 35 + 16 / 24 + 1 / 48, 139.75 + 1 / 24, (35.68, 139.77), "Tokyo"),
    ("JO", 55.0, 10.0, (55.0, 10.0), "the field JO itself"),
    ("JO62", 52.5, 13.0, (52.52, 13.40), "Berlin"),
    # 8 characters: JO62qm corner (52.5, 13 + 1/3), extended square 4 5: +4.5/120, +5.5/240
    ("JO62qm45", 52.5 + 5.5 / 240, 13 + 1 / 3 + 4.5 / 120, (52.52, 13.40), "Berlin"),
    ("AA00aa00", -90 + 0.5 / 240, -180 + 0.5 / 120, (-90.0, -180.0), "the south-west corner"),
    ("RR99xx99", 90 - 0.5 / 240, 180 - 0.5 / 120, (90.0, 180.0), "the north-east corner"),
]


@pytest.mark.parametrize(("locator", "lat", "lon", "place", "name"), KNOWN_CENTRES)
def test_a_locator_gives_the_centre_of_its_square(
    locator: str, lat: float, lon: float, place: tuple[float, float], name: str
) -> None:
    got_lat, got_lon = parse_locator(locator)
    assert got_lat == pytest.approx(lat, abs=1e-9)
    assert got_lon == pytest.approx(lon, abs=1e-9)
    near_deg = {2: 10.0, 4: 1.0, 6: 0.1, 8: 0.1}[len(locator)]  # 0.1 deg is about 10 km
    assert abs(got_lat - place[0]) <= near_deg and abs(got_lon - place[1]) <= near_deg, name


def test_the_brandenburg_gate_is_in_jo62qm() -> None:
    # Brandenburg Gate 52.5164 N 13.3777 E, as tabulated in Martin Kompf, "Distance
    # calculation" (https://www.kompf.de/gps/distcalc.html)
    assert to_locator(52.5164, 13.3777) == "JO62QM"
    assert to_locator(52.5164, 13.3777, chars=4) == "JO62"


@pytest.mark.parametrize("text", ["jo62qm", "JO62QM", "Jo62Qm", "  jo62QM\n", "\tJO62qm "])
def test_locators_are_read_in_any_case_and_with_surrounding_blanks(text: str) -> None:
    assert parse_locator(text) == parse_locator("JO62qm")
    assert is_locator(text)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", "empty locator"),
        ("   ", "empty locator"),
        ("J", "locator 'J': must be 2, 4, 6 or 8 characters, got 1"),
        ("JO6", "locator 'JO6': must be 2, 4, 6 or 8 characters, got 3"),
        ("JO62q", "must be 2, 4, 6 or 8 characters, got 5"),
        ("JO62qm4", "must be 2, 4, 6 or 8 characters, got 7"),
        ("JO62qm45ab", "locator 'JO62qm45ab': must be 2, 4, 6 or 8 characters, got 10"),
        ("JO 62", "must be 2, 4, 6 or 8 characters, got 5"),
        ("SO62", "locator 'SO62': first character must be a letter A..R, got 'S'"),
        ("JZ62", "locator 'JZ62': second character must be a letter A..R, got 'Z'"),
        ("jz62", "locator 'jz62': second character must be a letter A..R, got 'z'"),
        ("JOx2", "locator 'JOx2': third character must be a digit 0..9, got 'x'"),
        ("JO6-", "locator 'JO6-': fourth character must be a digit 0..9, got '-'"),
        ("JO62ym", "locator 'JO62ym': fifth character must be a letter A..X, got 'y'"),
        ("JO62q1", "locator 'JO62q1': sixth character must be a letter A..X, got '1'"),
        ("JO62qmA5", "locator 'JO62qmA5': seventh character must be a digit 0..9, got 'A'"),
        ("JO62qm4Z", "locator 'JO62qm4Z': eighth character must be a digit 0..9, got 'Z'"),
        ("12.5", "locator '12.5': first character must be a letter A..R, got '1'"),
        # look-alikes outside ASCII: long s (upper-cases to S), Kelvin sign, full-width digits
        ("JO62\u017fm", "fifth character must be a letter A..X, got '\u017f'"),
        ("JO62q\u212a", "sixth character must be a letter A..X, got '\u212a'"),
        ("JO\uff16\uff12", "third character must be a digit 0..9, got '\uff16'"),
        ("JO62qm" * 7, "locator 'JO62qmJO62qm…': must be 2, 4, 6 or 8 characters, got 42"),
    ],
)
def test_a_bad_locator_says_what_is_wrong(text: str, message: str) -> None:
    with pytest.raises(LocatorError) as caught:
        parse_locator(text)
    assert message in str(caught.value)
    assert isinstance(caught.value, ValueError)
    assert not is_locator(text)


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("PM95vq", True),
        ("JO", True),
        ("jo62", True),
        ("FN31pr12", True),
        ("95", False),
        ("123.5", False),
        ("-10", False),
        ("120 30", False),
        ('{"azimuth": 120}', False),
        ("J0", False),
        # a bare "ON" is the field ON (Benelux): whoever also accepts switches must ask first
        ("ON", True),
    ],
)
def test_is_locator_tells_a_bare_locator_from_a_number(text: str, expected: bool) -> None:
    assert is_locator(text) is expected


LOCATOR_TEXT = st.text(alphabet="ABJORSXYZajorxyz01259 -\u017f\u212a", max_size=10)


@given(LOCATOR_TEXT)
def test_is_locator_agrees_with_parse_locator(text: str) -> None:
    try:
        parse_locator(text)
    except LocatorError:
        assert not is_locator(text)
    else:
        assert is_locator(text)


def valid_locators(pairs: int) -> st.SearchStrategy[str]:
    alphabets = ["ABCDEFGHIJKLMNOPQR", "0123456789", "abcdefghijklmnopqrstuvwx", "0123456789"]
    parts = [st.sampled_from(alphabets[i // 2]) for i in range(2 * pairs)]
    return st.tuples(*parts).map("".join)


@given(valid_locators(3))
def test_six_characters_round_trip_to_the_upper_case_form(locator: str) -> None:
    assert to_locator(*parse_locator(locator)) == locator.upper()


@pytest.mark.parametrize("pairs", [1, 2, 3, 4])
@given(data=st.data())
def test_every_length_round_trips(pairs: int, data: st.DataObject) -> None:
    locator = data.draw(valid_locators(pairs))
    assert to_locator(*parse_locator(locator), chars=2 * pairs) == locator.upper()


@given(
    st.floats(min_value=-90, max_value=90),
    st.floats(min_value=-180, max_value=180),
    st.sampled_from([2, 4, 6, 8]),
)
def test_the_locator_of_a_point_is_the_square_around_it(lat: float, lon: float, chars: int) -> None:
    centre_lat, centre_lon = parse_locator(to_locator(lat, lon, chars))
    half_height = {2: 5.0, 4: 0.5, 6: 0.5 / 24, 8: 0.5 / 240}[chars]
    lon_gap = off(centre_lon, lon)  # 180 E is the same meridian as 180 W
    assert abs(centre_lat - lat) <= half_height + 1e-9
    assert lon_gap <= 2 * half_height + 1e-9


def test_the_edges_of_the_map_have_locators() -> None:
    assert to_locator(-90.0, -180.0, 8) == "AA00AA00"
    assert to_locator(90.0, 179.999, 8) == "RR99XX99"  # the pole is in the top row
    assert to_locator(0.0, 180.0) == to_locator(0.0, -180.0) == "AJ00AA"  # 180 E is 180 W
    assert to_locator(0.0, 0.0) == "JJ00AA"
    assert to_locator(-0.0001, -0.0001) == "II99XX"


@pytest.mark.parametrize(
    ("lat", "lon", "chars", "message"),
    [
        (90.5, 0.0, 6, "latitude must be a number from -90 to 90, got 90.5"),
        (0.0, -181.0, 6, "longitude must be a number from -180 to 180, got -181.0"),
        (math.nan, 0.0, 6, "latitude"),
        (0.0, math.inf, 6, "longitude"),
        (0.0, 0.0, 5, "a locator has 2, 4, 6 or 8 characters, not 5"),
        (0.0, 0.0, 10, "not 10"),
    ],
)
def test_to_locator_refuses_what_it_cannot_encode(
    lat: float, lon: float, chars: int, message: str
) -> None:
    with pytest.raises(ValueError, match=re.escape(message)):
        to_locator(lat, lon, chars)


# ---- great circle -----------------------------------------------------------------------------

PUBLISHED_PATHS = [
    # Ed Williams, "Aviation Formulary" (https://edwilliams.org/avform.htm), worked example:
    # LAX 33°57'N 118°24'W to JFK 40°38'N 73°47'W, d = 0.623585 rad (= 2144 nm),
    # initial true course 1.150035 rad = 66 degrees. Spherical: the radian distance is exact here.
    pytest.param(
        dms(33, 57), -dms(118, 24), dms(40, 38), -dms(73, 47),
        0.623585 * 6371.0, math.degrees(1.150035), id="LAX-JFK Aviation Formulary",
    ),
    # Chris Veness, "Calculate distance, bearing and more between Latitude/Longitude points"
    # (https://www.movable-type.co.uk/scripts/latlong.html), sphere of 6371 km:
    # 50°03'59"N 005°42'53"W (Land's End) to 58°38'38"N 003°04'12"W (John o' Groats):
    # distance 968.9 km, initial bearing 009°07'11".
    pytest.param(
        dms(50, 3, 59), -dms(5, 42, 53), dms(58, 38, 38), -dms(3, 4, 12),
        968.9, dms(9, 7, 11), id="Land's End-John o' Groats movable-type",
    ),
    # PROJ geod(1) manual, example (https://proj.org/apps/geod.html), Clarke 1866 ellipsoid:
    # Boston 42d15'N 71d07'W to Portland OR 45d31'N 123d41'W: azimuth -66d31'50.141",
    # distance 2587.504 US statute miles.
    pytest.param(
        dms(42, 15), -dms(71, 7), dms(45, 31), -dms(123, 41),
        2587.504 * US_SURVEY_MILE_KM, 360 - dms(66, 31, 50.141), id="Boston-Portland PROJ geod",
    ),
    # Vincenty (1975), Survey Review XXIII (176), test line (b), International ellipsoid:
    # alpha1 95°27'59.63089", s = 4 085 966.703 m.
    pytest.param(
        dms(37, 19, 54.95367), 0.0, dms(26, 7, 42.83946), dms(41, 28, 35.50729),
        4085.966703, dms(95, 27, 59.63089), id="Vincenty 1975 line (b)",
    ),
    # Vincenty (1975), test line (c): alpha1 15°44'23.74850", s = 8 084 823.839 m.
    pytest.param(
        dms(35, 16, 11.24862), 0.0, dms(67, 22, 14.77638), dms(137, 47, 28.31435),
        8084.823839, dms(15, 44, 23.74850), id="Vincenty 1975 line (c)",
    ),
    # GeographicLib's JavaScript package README, example (https://npmjs.com/package/geographiclib;
    # the same example is in its Python and Go documentation), WGS84: Wellington NZ
    # (41.32S, 174.81E) to Salamanca (40.96N, 5.50W) "The distance is 19959679.267 m."
    # Nearly antipodal, where the ellipsoid's geodesic leaves in a quite different direction
    # from the sphere's great circle, so only the distance is compared.
    pytest.param(
        -41.32, 174.81, 40.96, -5.50, 19959.679267, None, id="Wellington-Salamanca GeographicLib",
    ),
]  # fmt: skip


@pytest.mark.parametrize(
    ("lat1", "lon1", "lat2", "lon2", "distance_km", "bearing"), PUBLISHED_PATHS
)
def test_paths_match_published_values(
    lat1: float, lon1: float, lat2: float, lon2: float, distance_km: float, bearing: float | None
) -> None:
    path = great_circle(lat1, lon1, lat2, lon2)
    assert path.distance_km == pytest.approx(distance_km, rel=0.01)
    if bearing is not None:
        assert off(path.short_path_deg, bearing) < 1.0


def test_berlin_to_tokyo_from_the_locators() -> None:
    # JO62qm to PM95vq: no published value for exactly these two squares was found, so the
    # references are computed here from the locator centres by two other methods: Vincenty's
    # inverse on WGS84 (checked above against his published lines), and vectors on the sphere.
    berlin, tokyo = parse_locator("JO62qm"), parse_locator("PM95vq")
    path = great_circle(*berlin, *tokyo)
    ellipsoid_km, ellipsoid_deg = vincenty_inverse(WGS84, *berlin, *tokyo)
    sphere_km, sphere_deg = sphere_by_vectors(*berlin, *tokyo)
    assert path.distance_km == pytest.approx(ellipsoid_km, rel=0.005)
    assert off(path.short_path_deg, ellipsoid_deg) < 1.0
    assert path.distance_km == pytest.approx(sphere_km, abs=1e-6)
    assert off(path.short_path_deg, sphere_deg) < 1e-9
    # what a ham reads off the dashboard: about 8920 km, turn to NE (41.5 deg); long path SW
    assert 8900 < path.distance_km < 8950
    assert 41.0 < path.short_path_deg < 42.0
    assert path.long_path_deg == pytest.approx(path.short_path_deg + 180.0)


POINT = st.tuples(st.floats(min_value=-90, max_value=90), st.floats(min_value=-180, max_value=180))


@given(POINT, POINT)
def test_the_long_path_is_the_other_way_round(
    a: tuple[float, float], b: tuple[float, float]
) -> None:
    path = great_circle(*a, *b)
    assert 0.0 <= path.short_path_deg < 360.0 and 0.0 <= path.long_path_deg < 360.0
    assert off(path.long_path_deg, path.short_path_deg + 180.0) < 1e-9
    assert path.distance_km + path.long_distance_km == pytest.approx(CIRCUMFERENCE_KM)
    assert 0.0 <= path.distance_km <= CIRCUMFERENCE_KM / 2 + 1e-9
    assert great_circle(*b, *a).distance_km == pytest.approx(path.distance_km, abs=1e-6)


@given(POINT, POINT)
def test_the_sphere_agrees_with_3d_vectors_everywhere(
    a: tuple[float, float], b: tuple[float, float]
) -> None:
    path = great_circle(*a, *b)
    distance, bearing = sphere_by_vectors(*a, *b)
    assert path.distance_km == pytest.approx(distance, abs=1e-6)
    # the direction is only defined (and only compared) away from the same point and antipodes
    if 1.0 < distance < CIRCUMFERENCE_KM / 2 - 1.0 and abs(a[0]) < 89.999:
        assert off(path.short_path_deg, bearing) < 1e-4


def test_the_same_point_is_bearing_zero_and_no_distance() -> None:
    path = great_circle(52.52, 13.375, 52.52, 13.375)
    assert isinstance(path, Path)
    assert (path.short_path_deg, path.long_path_deg, path.distance_km) == (0.0, 180.0, 0.0)
    assert not path.has_direction  # the 0 is no bearing: pointing.py refuses such a target
    assert path.long_distance_km == pytest.approx(CIRCUMFERENCE_KM)
    # 180 E and 180 W are one meridian
    path = great_circle(10.0, 180.0, 10.0, -180.0)
    assert path.short_path_deg == 0.0 and path.distance_km == pytest.approx(0.0, abs=1e-9)


def test_antipodal_points_get_bearing_zero_and_half_the_circumference() -> None:
    for lat, lon in [(0.0, 0.0), (52.52, 13.375), (-33.9, 151.2), (90.0, 0.0)]:
        other = (-lat, lon - 180.0 if lon > 0 else lon + 180.0)
        path = great_circle(lat, lon, *other)
        assert path.short_path_deg == 0.0 and path.long_path_deg == 180.0
        assert not path.has_direction
        assert path.distance_km == pytest.approx(CIRCUMFERENCE_KM / 2)
        assert path.long_distance_km == pytest.approx(CIRCUMFERENCE_KM / 2)


def test_nearly_antipodal_points_still_have_a_direction() -> None:
    # along the equator, 179.5 deg east: short path due east, long path due west
    path = great_circle(0.0, 0.0, 0.0, 179.5)
    assert path.short_path_deg == pytest.approx(90.0)
    assert path.long_path_deg == pytest.approx(270.0)
    assert path.distance_km == pytest.approx(CIRCUMFERENCE_KM * 179.5 / 360)
    assert path.long_distance_km == pytest.approx(CIRCUMFERENCE_KM * 180.5 / 360)
    # a hundredth of a degree short of the antipode, across the pole
    path = great_circle(45.0, 0.0, -44.99, 180.0)
    assert path.short_path_deg == pytest.approx(0.0, abs=1e-9) and path.has_direction
    assert path.distance_km == pytest.approx(CIRCUMFERENCE_KM * 179.99 / 360)


@pytest.mark.parametrize("lat", [0.0, 50.0, -50.0])
def test_a_path_across_the_date_line_is_short(lat: float) -> None:
    east = great_circle(lat, 179.5, lat, -179.5)
    west = great_circle(lat, -179.5, lat, 179.5)
    one_degree = CIRCUMFERENCE_KM / 360 * math.cos(math.radians(lat))
    assert east.distance_km == pytest.approx(one_degree, rel=0.001)
    assert off(east.short_path_deg, 90.0) < 1.0
    assert off(west.short_path_deg, 270.0) < 1.0
    assert east.long_distance_km > CIRCUMFERENCE_KM - 112


def test_bearings_never_read_360() -> None:
    # due north by the tiniest west: atan2 gives -0.0 or -1e-17, which % 360 turns into 360.0
    for lon2 in (-0.0, -1e-15, -1e-300):
        path = great_circle(0.0, 0.0, 10.0, lon2)
        assert path.short_path_deg == 0.0 and math.copysign(1.0, path.short_path_deg) == 1.0
        assert path.long_path_deg == 180.0
    # due south by the tiniest east: the long path is the one that would read 360
    path = great_circle(10.0, 0.0, 0.0, 1e-15)
    assert path.short_path_deg == pytest.approx(180.0)
    assert path.long_path_deg < 360.0 and off(path.long_path_deg, 0.0) < 1e-9


def test_the_poles_point_along_the_meridian_of_the_other_point() -> None:
    assert great_circle(0.0, 0.0, 90.0, 0.0).short_path_deg == 0.0
    assert great_circle(0.0, 0.0, -90.0, 0.0).short_path_deg == 180.0
    assert great_circle(90.0, 0.0, 0.0, 0.0).distance_km == pytest.approx(CIRCUMFERENCE_KM / 4)


@pytest.mark.parametrize(
    ("args", "field"),
    [
        ((90.5, 0.0, 0.0, 0.0), "lat1 must be a number from -90 to 90, got 90.5"),
        ((0.0, 180.1, 0.0, 0.0), "lon1 must be a number from -180 to 180, got 180.1"),
        ((0.0, 0.0, -91.0, 0.0), "lat2 must be a number from -90 to 90"),
        ((0.0, 0.0, 0.0, -200.0), "lon2 must be a number from -180 to 180"),
        ((math.nan, 0.0, 0.0, 0.0), "lat1"),
        ((0.0, math.inf, 0.0, 0.0), "lon1"),
        ((0.0, 0.0, -math.inf, 0.0), "lat2"),
        ((0.0, 0.0, 0.0, math.nan), "lon2"),
    ],
)
def test_great_circle_refuses_impossible_coordinates(
    args: tuple[float, float, float, float], field: str
) -> None:
    with pytest.raises(ValueError) as caught:
        great_circle(*args)
    assert field in str(caught.value)


def test_the_limits_themselves_are_coordinates() -> None:
    path = great_circle(-90.0, -180.0, 90.0, 180.0)
    assert path.distance_km == pytest.approx(CIRCUMFERENCE_KM / 2)


def test_bearings_apart_on_the_circle_and_along_the_line() -> None:
    """core/geo.py apart_deg: 359 and 1 are 2 apart on a wrapping box, 358 on a 450-degree
    one; a value past 360 that noise made is on the circle too (450 on a 0..360 box is 90)."""
    assert apart_deg(359, 1, True) == 2 and apart_deg(359, 1, False) == 358
    assert apart_deg(450, 150, True) == 60 and apart_deg(50, 450, True) == 40
    assert apart_deg(10, 370, False) == 360
