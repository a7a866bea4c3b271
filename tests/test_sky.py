"""The sun, the moon and satellites seen from the station, judged by independent computations
(tests/support/sky.py: the Astronomical Almanac's low-precision formulas, the sgp4 package with our
own frame rotations), never by skyfield, which bridge/sky/ uses.

What a user would notice: the antenna pointing off the body (a sun noise measurement wants
0.1 deg, a satellite beam a few degrees), a rotor pre-positioned at the wrong AOS time or
azimuth, a pass that is missed, a TLE file that stops loading because one set in it is bad.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
from datetime import UTC, datetime
from pathlib import Path

import numpy as np
import pytest
from sgp4.api import Satrec

from bridge.sky import Body, Sky, SkyError, parse_tles
from tests.support.sky import (
    gmst_deg,
    moon_altaz,
    sgp4_altaz,
    sgp4_altaz_array,
    sun_altaz,
    sun_altaz_array,
    synthetic_tle,
    tle_with_pass,
)

BERLIN = (52.52, 13.29)  # JO62qm, the demo's station
T0 = datetime(2026, 11, 25, 0, 0, tzinfo=UTC).timestamp()
DAY = 86400.0


def unix(*args: int) -> float:
    return datetime(*args, tzinfo=UTC).timestamp()


def separation_deg(a: tuple[float, float], b: tuple[float, float]) -> float:
    """The angle on the sky between two (azimuth, elevation) directions."""
    az1, el1, az2, el2 = map(math.radians, (*a, *b))
    cos = math.sin(el1) * math.sin(el2) + math.cos(el1) * math.cos(el2) * math.cos(az1 - az2)
    return math.degrees(math.acos(max(-1.0, min(1.0, cos))))


# ---- the sun and the moon against the Almanac's formulas --------------------------------------

PLACES = [
    BERLIN,
    (-33.92, 18.42),  # Cape Town
    (-45.87, 170.50),  # Dunedin, near the date line from the west
    (64.84, -179.99),  # Chukotka side of the date line
    (0.0, -78.5),  # the equator
    (78.22, 15.65),  # Longyearbyen
    (-77.85, 166.67),  # McMurdo
]
DATES = [unix(1999, 3, 20), unix(2012, 6, 21), unix(2026, 11, 25), unix(2041, 12, 21)]


@pytest.mark.parametrize("place", PLACES, ids=lambda p: f"{p[0]},{p[1]}")
def test_sun_agrees_with_the_almanac_everywhere(place: tuple[float, float]) -> None:
    times = np.array([d + h * 3600 + 417 for d in DATES for h in range(0, 24, 3)])
    got = Sky(*place).positions(Body.sun(), times.tolist())
    ref_az, ref_el = sun_altaz_array(*place, times)
    assert len(got) == len(times)
    for (az, el), raz, rel in zip(got, ref_az, ref_el, strict=True):
        assert 0.0 <= az < 360.0
        assert abs(el - rel) < 0.05
        assert separation_deg((az, el), (raz, rel)) < 0.05
        if abs(rel) > 0.05:
            assert (el > 0) == (rel > 0)


def test_sun_position_is_one_of_positions_and_height_changes_little() -> None:
    sky = Sky(*BERLIN)
    t = unix(2026, 6, 21, 11)
    assert sky.position(Body.sun(), t) == sky.positions(Body.sun(), [t])[0]
    up_high = Sky(*BERLIN, height_m=3000.0).position(Body.sun(), t)
    assert separation_deg(up_high, sky.position(Body.sun(), t)) < 0.01  # parallax 8.8"
    assert sky.positions(Body.sun(), []) == []


@pytest.mark.parametrize("place", [BERLIN, (-33.92, 18.42), (64.84, -179.99)])
def test_moon_agrees_with_the_almanac(place: tuple[float, float]) -> None:
    times = [T0 + k * 7919.0 for k in range(40)]  # over a lunar month, every 2.2 hours
    got = Sky(*place).positions(Body.moon(), times)
    for t, pos in zip(times, got, strict=True):
        assert separation_deg(pos, moon_altaz(*place, t)) < 0.5  # the formula's own 0.3 deg


def sun_crossing(lat: float, lon: float, lo: float, hi: float, min_el: float = 0.0) -> float:
    up = sun_altaz(lat, lon, lo)[1] > min_el
    while hi - lo > 0.01:
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if (sun_altaz(lat, lon, mid)[1] > min_el) == up else (lo, mid)
    return lo


def test_sun_rises_and_sets_over_berlin_when_the_almanac_says() -> None:
    sky = Sky(*BERLIN)
    p = sky.next_pass(Body.sun(), T0)  # midnight
    assert p is not None
    rise = sun_crossing(*BERLIN, p.aos_s - 1800, p.aos_s + 1800)
    sets = sun_crossing(*BERLIN, p.los_s - 1800, p.los_s + 1800)
    # 0.01 deg of the formula is about 6 s of a November sunrise at 52 N
    assert abs(p.aos_s - rise) < 20 and abs(p.los_s - sets) < 20
    assert unix(2026, 11, 25, 6, 30) < p.aos_s < unix(2026, 11, 25, 7, 15)  # centre, no refraction
    assert unix(2026, 11, 25, 14, 45) < p.los_s < unix(2026, 11, 25, 15, 30)
    noon = np.arange(p.aos_s, p.los_s, 10.0)
    ref_el = sun_altaz_array(*BERLIN, noon)[1]
    assert abs(p.max_el_deg - ref_el.max()) < 0.05
    assert abs(p.max_s - noon[np.argmax(ref_el)]) < 300  # the top is flat: minutes are fine
    assert abs(p.aos_az_deg - sun_altaz(*BERLIN, p.aos_s)[0]) < 0.1
    assert abs(p.los_az_deg - sun_altaz(*BERLIN, p.los_s)[0]) < 0.1
    # asked at noon: the same day, in progress
    now = sky.next_pass(Body.sun(), unix(2026, 11, 25, 11))
    assert now is not None and now.aos_s < unix(2026, 11, 25, 11) < now.los_s
    assert abs(now.aos_s - p.aos_s) < 1 and abs(now.los_s - p.los_s) < 1
    # asked after sunset: tomorrow
    later = sky.next_pass(Body.sun(), p.los_s + 60)
    assert later is not None and later.aos_s - p.aos_s == pytest.approx(DAY, abs=300)


def test_sun_above_a_minimum_elevation() -> None:
    p = Sky(*BERLIN).next_pass(Body.sun(), T0, min_el_deg=10.0)
    assert p is not None
    rise = sun_crossing(*BERLIN, p.aos_s - 1800, p.aos_s + 1800, 10.0)
    assert abs(p.aos_s - rise) < 30
    assert Sky(*BERLIN).next_pass(Body.sun(), T0, min_el_deg=20.0) is None  # 16.4 in November


def test_polar_night_has_no_pass_and_midnight_sun_one_whole_window() -> None:
    svalbard = Sky(78.22, 15.65)
    assert svalbard.next_pass(Body.sun(), unix(2026, 12, 15)) is None
    t = unix(2026, 6, 15, 3)
    p = svalbard.next_pass(Body.sun(), t, within_s=DAY)
    assert p is not None and p.aos_s == t and p.los_s == t + DAY
    assert 30.0 < p.max_el_deg < 36.0  # 90 - 78.2 + 23.3 at noon
    assert p.aos_az_deg == pytest.approx(sun_altaz(78.22, 15.65, t)[0], abs=0.1)


def test_at_the_poles_the_sun_and_the_moon_rise_and_set_by_their_declination() -> None:
    """Near a pole a body rises once its declination lifts it over the horizon, not as the sky
    turns: the almanac's hour-angle search found neither the sun's rise nor its set at the
    equinoxes, nor the moon's at the South Pole (Amundsen-Scott), and said no pass or a body
    up for days instead."""
    north, south = Sky(90.0, 0.0), Sky(-90.0, 0.0)
    t = unix(2026, 3, 20)
    p = north.next_pass(Body.sun(), t)
    assert p is not None, "the sun rises at the North Pole on 20 March 2026"
    rise = sun_crossing(90.0, 0.0, t, t + 2 * DAY)
    assert abs(p.aos_s - rise) < 3600  # the formula's 0.01 deg is 40 minutes of it here
    t = unix(2026, 9, 22)
    p = north.next_pass(Body.sun(), t)
    assert p is not None and p.aos_s <= t
    sets = sun_crossing(90.0, 0.0, t, t + 2 * DAY)
    assert abs(p.los_s - sets) < 3600, "the sun sets at the North Pole on 22 September 2026"
    t = unix(2026, 1, 7, 4, 48)
    p = south.next_pass(Body.moon(), t)
    assert p is not None, "the moon rises at the South Pole on 8 January 2026"
    times = np.arange(t, t + 2 * DAY, 60.0)
    up = next(u for u in times if moon_altaz(-90.0, 0.0, u)[1] > 0)
    assert abs(p.aos_s - up) < 3600


def test_moon_rises_and_sets_where_the_almanac_has_it_on_the_horizon() -> None:
    sky = Sky(*BERLIN)
    t = T0
    for _ in range(3):
        p = sky.next_pass(Body.moon(), t)
        assert p is not None and p.aos_s > t - DAY and p.los_s - p.aos_s < DAY
        assert abs(moon_altaz(*BERLIN, p.aos_s)[1]) < 0.5
        assert abs(moon_altaz(*BERLIN, p.los_s)[1]) < 0.5
        assert p.aos_s <= p.max_s <= p.los_s and p.max_el_deg > 0
        t = p.los_s + 60


# ---- satellites against the sgp4 package and our own frames ----------------------------------

STATIONS = [BERLIN, (-33.92, 18.42), (64.84, -179.99)]


@pytest.fixture(scope="module", params=STATIONS, ids=lambda p: f"{p[0]},{p[1]}")
def leo(request: pytest.FixtureRequest) -> tuple[tuple[float, float], str, str, float, float]:
    station = request.param
    line1, line2, aos, los = tle_with_pass(*station, T0 + 3600)
    return station, line1, line2, aos, los


def brute_force(
    station: tuple[float, float], line1: str, line2: str, lo: float, hi: float
) -> tuple[np.ndarray, np.ndarray, float, float]:
    """Elevations every second from lo to hi, and the first and last second above 0."""
    times = np.arange(math.floor(lo), math.ceil(hi) + 1.0)
    el = sgp4_altaz_array(line1, line2, *station, times)[1]
    up = np.flatnonzero(el > 0)
    return times, el, float(times[up[0]]), float(times[up[-1]])


def test_satellite_positions_agree_with_sgp4_over_a_pass(leo) -> None:
    station, line1, line2, aos, los = leo
    sat = Body.satellite(" TESTSAT \n", line1, line2)
    assert sat.name == "TESTSAT"
    times = np.linspace(aos - 120, los + 120, 120)
    got = Sky(*station).positions(sat, times.tolist())
    for t, pos in zip(times, got, strict=True):
        ref = sgp4_altaz(line1, line2, *station, t)
        assert abs(pos[1] - ref[1]) < 0.1
        assert separation_deg(pos, ref) < 0.1


def test_next_pass_of_a_satellite_matches_a_brute_force_scan(leo) -> None:
    station, line1, line2, aos, los = leo
    sat = Body.satellite("TESTSAT", line1, line2)
    p = Sky(*station).next_pass(sat, T0 + 3600)
    assert p is not None
    times, el, first_up, last_up = brute_force(station, line1, line2, aos - 60, los + 60)
    assert first_up - 1 <= p.aos_s <= first_up + 1 and last_up - 1 <= p.los_s <= last_up + 1
    assert abs(p.aos_s - aos) < 1 and abs(p.los_s - los) < 1  # the bisected crossings
    assert abs(p.max_el_deg - el.max()) < 0.05
    assert p.aos_s < p.max_s < p.los_s
    assert (
        separation_deg((p.aos_az_deg, 0.0), (sgp4_altaz(line1, line2, *station, aos)[0], 0.0)) < 0.2
    )
    assert (
        separation_deg((p.los_az_deg, 0.0), (sgp4_altaz(line1, line2, *station, los)[0], 0.0)) < 0.2
    )


def test_a_pass_in_progress_has_its_aos_in_the_past(leo) -> None:
    station, line1, line2, aos, los = leo
    sat = Body.satellite("TESTSAT", line1, line2)
    sky = Sky(*station)
    now = (aos + los) / 2
    p = sky.next_pass(sat, now)
    assert p is not None and abs(p.aos_s - aos) < 1 and abs(p.los_s - los) < 1 and p.aos_s < now
    after = sky.next_pass(sat, los + 1)
    assert after is not None and after.aos_s > los + 1  # the next one, not this one again


def test_a_pass_asked_for_just_after_its_rise_is_that_pass(leo) -> None:
    """skyfield's search gives a rise up to half a second after the moment the elevation
    crosses 0: asked in between, the satellite is already up, and the rise found looking back
    was the previous orbit's, a pass spanning the time below the horizon."""
    station, line1, line2, _, _ = leo
    sat = Body.satellite("TESTSAT", line1, line2)
    sky = Sky(*station)
    for p0 in (sky.next_pass(sat, T0 + 3600), sky.next_pass(sat, T0 + 3 * 3600)):
        assert p0 is not None
        lo, hi = p0.aos_s - 5, p0.aos_s + 5  # the elevation's own crossing, to 1 ms
        while hi - lo > 0.001:
            mid = (lo + hi) / 2
            lo, hi = (lo, mid) if sky.position(sat, mid)[1] > 0 else (mid, hi)
        now = hi
        p = Sky(*station).next_pass(sat, now)
        assert p is not None and p.aos_s <= now
        assert now - p.aos_s < 1, f"the rise {now - p.aos_s:.0f} s before, an orbit ago"
        assert abs(p.los_s - p0.los_s) < 1


def test_min_elevation_and_a_pass_shorter_than_the_sampling_step(leo) -> None:
    station, line1, line2, aos, los = leo
    sat = Body.satellite("TESTSAT", line1, line2)
    sky = Sky(*station)
    p = sky.next_pass(sat, T0 + 3600, min_el_deg=10.0)
    assert p is not None and aos < p.aos_s < p.los_s < los
    assert sgp4_altaz(line1, line2, *station, p.aos_s)[1] == pytest.approx(10.0, abs=0.05)
    assert sgp4_altaz(line1, line2, *station, p.los_s)[1] == pytest.approx(10.0, abs=0.05)
    top = sky.next_pass(sat, T0 + 3600)
    assert top is not None
    # just under the top: a pass of seconds, between two samples of the search; still found
    graze = sky.next_pass(sat, T0 + 3600, min_el_deg=top.max_el_deg - 0.02)
    assert graze is not None and graze.los_s - graze.aos_s < 30
    assert abs(graze.max_s - top.max_s) < 15
    # just over it: not this pass (a later one, higher, or none in the window)
    over = sky.next_pass(sat, T0 + 3600, min_el_deg=top.max_el_deg + 0.02)
    assert over is None or over.aos_s > los


def test_an_eccentric_orbit_whose_passes_last_most_of_a_revolution() -> None:
    """A Molniya-like orbit (12 h, e 0.7): passes of 8 to 11 hours with gaps of two or three.
    From every start the pass is the one a scan every 5 s finds, never one missed."""
    line1, line2 = synthetic_tle(
        "HEO",
        T0,
        inclination_deg=97.5,
        raan_deg=37.1398,
        mean_anomaly_deg=142.581,
        mean_motion_rev_day=2.006,
        eccentricity=0.7,
        arg_perigee_deg=270.0,
    )
    sat = Body.satellite("HEO", line1, line2)
    times = np.arange(T0, T0 + 4 * DAY, 5.0)
    up = sgp4_altaz_array(line1, line2, *BERLIN, times)[1] > 0
    change = np.flatnonzero(up[1:] != up[:-1])  # a crossing between times[i] and times[i + 1]
    rises, sets = change[up[change + 1]], change[~up[change + 1]]
    for k in range(12):
        start = T0 + DAY + k * 7200.0 + 17.0
        i = int(np.searchsorted(times, start)) - 1
        rise = rises[rises < i][-1] if up[i] else rises[rises >= i][0]
        sets_after = sets[sets > rise][0]
        p = Sky(*BERLIN).next_pass(sat, start)
        assert p is not None
        assert times[rise] - 1 <= p.aos_s <= times[rise + 1] + 1, k
        assert times[sets_after] - 1 <= p.los_s <= times[sets_after + 1] + 1, k


def test_geostationary_satellite_always_up_or_never() -> None:
    epoch = T0
    line1, line2 = synthetic_tle(
        "GEO",
        epoch,
        inclination_deg=0.0,
        raan_deg=0.0,
        mean_anomaly_deg=0.0,
        mean_motion_rev_day=1.00273791,
        eccentricity=0.0001,
    )
    geo = Body.satellite("GEO", line1, line2)
    under = ((-float(gmst_deg(epoch)) + 180.0) % 360.0) - 180.0  # the sub-satellite longitude
    facing = Sky(45.0, under)
    p = facing.next_pass(geo, epoch + 600, within_s=DAY)
    assert p is not None and (p.aos_s, p.los_s) == (epoch + 600, epoch + 600 + DAY)
    assert 35 < p.max_el_deg < 40  # seen from 45 deg north under it
    assert abs(p.aos_az_deg - 180.0) < 2
    behind = Sky(45.0, under + 180.0 if under < 0 else under - 180.0)
    assert behind.next_pass(geo, epoch + 600, within_s=DAY) is None


def test_a_decayed_orbit_has_no_position_and_no_pass() -> None:
    line1, line2 = synthetic_tle(
        "LOW", T0, inclination_deg=51.6, raan_deg=0.0, mean_anomaly_deg=0.0, bstar=0.05
    )
    sat = Body.satellite("LOW", line1, line2)  # fine at its epoch
    sky = Sky(*BERLIN)
    with pytest.raises(SkyError, match="LOW: SGP4 has no position"):
        sky.positions(sat, [T0 + 400 * DAY])
    assert sky.next_pass(sat, T0 + 400 * DAY) is None


def test_a_pass_the_orbit_decays_in_ends_there() -> None:
    """SGP4 stops having a position in the middle of a pass (drag, or a TLE left to age): the
    pass ends then, its rise and top are found though the decay cuts the search short, and
    every time of it has a position (tracking samples the whole pass)."""
    line1, line2 = synthetic_tle(
        "DECAY", T0, inclination_deg=51.6, raan_deg=10.0, mean_anomaly_deg=0.0,
        mean_motion_rev_day=16.2, bstar=0.5,
    )  # fmt: skip
    sat = Body.satellite("DECAY", line1, line2)
    orbit = Satrec.twoline2rv(line1, line2)
    good, bad = T0, T0 + 60 * DAY  # the last moment SGP4 has a position
    while bad - good > 0.01:
        mid = (good + bad) / 2
        days, second = divmod(mid, DAY)
        failed = orbit.sgp4(2440587.5 + days, second / DAY)[0] != 0
        good, bad = (good, mid) if failed else (mid, bad)
    decay = good
    grid = [(lat, lon) for lat in range(-60, 61, 2) for lon in range(-180, 180, 2)]
    station = max(grid, key=lambda p: sgp4_altaz(line1, line2, *p, decay - 1)[1])
    now = decay - 60  # over that station: in a pass the decay ends
    times = np.arange(now - 900, decay, 0.5)
    el = sgp4_altaz_array(line1, line2, *station, times)[1]
    rise = times[np.flatnonzero(el <= 0)[-1] + 1]
    assert el[-1] > 0 and rise < now  # up from before now until the decay
    p = Sky(*station).next_pass(sat, now)
    assert p is not None
    assert abs(p.los_s - decay) < 2, "the pass ends when the orbit does"
    assert abs(p.aos_s - rise) < 2
    grid_s = np.linspace(p.aos_s, p.los_s, 200)  # every time of it has a position
    tops = [e for _, e in Sky(*station).positions(sat, list(grid_s))]
    assert p.max_el_deg >= max(tops) - 0.1 and p.max_el_deg > 20


# ---- bad input ---------------------------------------------------------------------------------


def test_times_and_places_out_of_range_are_refused() -> None:
    with pytest.raises(SkyError, match="latitude_deg"):
        Sky(91.0, 0.0)
    with pytest.raises(SkyError, match="longitude_deg"):
        Sky(0.0, math.nan)
    sky = Sky(*BERLIN)
    with pytest.raises(SkyError, match="outside the ephemeris"):
        sky.position(Body.moon(), unix(2100, 1, 1))
    with pytest.raises(SkyError, match="finite"):
        sky.position(Body.sun(), math.inf)
    with pytest.raises(SkyError, match="within_s"):
        sky.next_pass(Body.sun(), T0, within_s=0)


# ---- TLEs --------------------------------------------------------------------------------------


def tle(catalog: int, raan: float = 10.0) -> tuple[str, str]:
    return synthetic_tle(
        "X", T0, inclination_deg=51.6, raan_deg=raan, mean_anomaly_deg=20.0, catalog=catalog
    )


def with_checksum(line: str, digit: int) -> str:
    return line[:68] + str(digit)


def test_body_satellite_refuses_each_fault_by_name() -> None:
    l1, l2 = tle(25544)
    bad_sum = (int(l2[68]) + 1) % 10
    other1, other2 = tle(25545)
    cases = [
        ((l1[:60], l2), "line 1: has 60 characters"),
        (("3" + l1[1:], l2), "line 1: must start with '1 '"),
        ((l1, with_checksum(l2, bad_sum)), f"line 2: checksum is '{bad_sum}'"),
        ((l1, other2), "line 2: catalog number '25545' is not line 1's '25544'"),
        ((l2, l1), "line 1: must start with '1 '"),
    ]
    for (a, b), message in cases:
        with pytest.raises(SkyError, match=f"^SAT: TLE {message}"):
            Body.satellite("SAT", a, b)
    decayed = synthetic_tle("X", T0, inclination_deg=50, raan_deg=0, mean_anomaly_deg=0,
                            eccentricity=0.99)  # fmt: skip
    with pytest.raises(SkyError, match="sgp4 cannot propagate"):
        Body.satellite("SAT", *decayed)
    with pytest.raises(SkyError, match="needs a name"):
        Body.satellite("  ", l1, l2)
    with pytest.raises(SkyError, match="unknown body kind 'planet'"):
        Body("planet", "mars")
    with pytest.raises(SkyError, match="a satellite has a TLE"):
        Body("satellite", "ISS")
    with pytest.raises(SkyError, match="a satellite has a TLE"):
        Body("sun", "sun", (l1, l2))
    assert Body.sun() == Body("sun", "sun") and Body.moon().name == "moon"
    assert Body.satellite("SAT", l1 + "  ", l2 + "\r").tle == (l1, l2)


def forged(line: str, start: int, text: str) -> str:
    """``line`` with ``text`` from column ``start`` (0-based), its checksum made good."""
    from sgp4.io import compute_checksum

    body = line[:start] + text + line[start + len(text) : 68]
    return body + str(compute_checksum(body))


@pytest.mark.parametrize(
    ("line", "start", "text", "message"),
    [
        (1, 20, "999.00000000", "line 1: epoch day 999.00000000 is no day of a year"),
        (1, 20, "000.50000000", "line 1: epoch day 0.50000000 is no day of a year"),
        (2, 8, "999.9999", "line 2: inclination 999.9999 is outside 0..180 degrees"),
        (2, 8, "180.5000", "line 2: inclination 180.5000 is outside 0..180 degrees"),
        (2, 17, "400.0000", "line 2: right ascension of the ascending node 400.0000 is outside"),
        (2, 34, "361.0000", "line 2: argument of perigee 361.0000 is outside"),
        (2, 43, "999.0000", "line 2: mean anomaly 999.0000 is outside"),
        (2, 52, "99.00000000", "line 2: mean motion 99.00000000 revolutions a day is no orbit"),
        (2, 52, " 0.00000000", "line 2: mean motion 0.00000000 revolutions a day is no orbit"),
    ],
)
def test_a_tle_with_an_element_no_orbit_has_is_refused_naming_it(
    line: int, start: int, text: str, message: str
) -> None:
    """An attack pass: sgp4 reads and propagates these, and the rotor turned for a TLE dated day
    999 of its year and for an inclination of 999.9999 degrees; check-config passed a file of
    them. Each is refused naming its line and the element, in a command and in a file."""
    l1, l2 = tle(25544)
    if line == 1:
        l1 = forged(l1, start, text)
    else:
        l2 = forged(l2, start, text)
    with pytest.raises(SkyError, match=f"^SAT: TLE {message}"):
        Body.satellite("SAT", l1, l2)
    sets, problems = parse_tles(f"SAT\n{l1}\n{l2}\n")
    at = 2 if line == 1 else 3  # (the file's lines: the name first)
    assert sets == {} and len(problems) == 1, problems
    assert problems[0].startswith(f"line {at}: 'SAT': {message.split(': ', 1)[1]}"), problems
    fine = forged(tle(25544)[1], 52, "16.90000000")  # a decaying object's mean motion
    assert Body.satellite("SAT", tle(25544)[0], fine).tle[1] == fine


def test_parse_tles_reads_a_celestrak_file() -> None:
    (a1, a2), (b1, b2) = tle(1), tle(2)
    text = f"ISS (ZARYA)\n{a1}\n{a2}\nNOAA 19   \n{b1}\n{b2}\n"
    assert parse_tles(text) == ({"ISS (ZARYA)": (a1, a2), "NOAA 19": (b1, b2)}, [])
    messy = "\r\n\r\n" + text.replace("\n", "  \r\n").replace("NOAA 19", "\r\nNOAA 19")
    assert parse_tles(messy) == parse_tles(text)
    space_track = f"0 ISS (ZARYA)\n{a1}\n{a2}\n"
    assert parse_tles(space_track) == ({"ISS (ZARYA)": (a1, a2)}, [])
    assert parse_tles("") == ({}, [])


def test_parse_tles_names_a_bare_set_by_its_catalog_number() -> None:
    (a1, a2), (b1, b2) = tle(1), tle(43017)
    sets, problems = parse_tles(f"{b1}\n{b2}\nAO-7\n{a1}\n{a2}\n")
    assert sets == {"43017": (b1, b2), "AO-7": (a1, a2)} and problems == []


def test_parse_tles_skips_bad_sets_and_says_where() -> None:
    (a1, a2), (b1, b2), (c1, c2), (d1, d2) = tle(1), tle(2), tle(3), tle(4)
    bad_sum = (int(b2[68]) + 3) % 10
    text = "\n".join(
        [
            "GOOD",  # 1
            a1,
            a2,
            "BAD SUM",  # 4
            b1,
            with_checksum(b2, bad_sum),  # 6
            "MIXED",  # 7
            c1,
            d2,  # 9: another satellite's line 2
            "<html>garbage</html>",  # 10
            "ALSO GOOD",  # 11
            d1,
            d2,
            c1,  # 14: a line 1 alone
            "GOOD",  # 15: again
            c1,
            c2,
            "TRAILING",  # 18
        ]
    )
    sets, problems = parse_tles(text)
    assert sets == {"GOOD": (c1, c2), "ALSO GOOD": (d1, d2)}
    assert problems == [
        f"line 6: 'BAD SUM': checksum is '{bad_sum}', the line sums to {b2[68]}",
        "line 9: 'MIXED': catalog number '00004' is not line 1's '00003'",
        "line 10: a line of 20 characters is not followed by a TLE",  # (never quoted)
        "line 14: a TLE line 1 without its line 2",
        "line 15: 'GOOD' again (first at line 1): used",
        "line 18: a line of 8 characters is not followed by a TLE",
    ]


def test_parse_tles_quotes_no_stray_line_and_cuts_a_long_name_short() -> None:
    """Attack 18 (bodies.py rule 2): a line no TLE follows may be anything (the one line of a
    password file named as tle_file): said by its number and length, never quoted; a
    satellite's name is quoted, escaped and cut short, so a file of one long line is no
    megabyte log line."""
    (a1, a2), (b1, b2) = tle(1), tle(2)
    secret = "Wr1tten-0nly-1n-the-password-file"
    bad = with_checksum(a2, (int(a2[68]) + 1) % 10)
    text = "\n".join([secret, "N" * 100_000, a1, bad, "\x1b[2J" * 2, b1, b2, "\x1b[2J"])
    _sets, problems = parse_tles(text)
    assert problems == [
        "line 1: a line of 33 characters is not followed by a TLE",
        f"line 4: {'N' * 40!r}… (100000 characters): checksum is '{bad[68]}', the line sums "
        f"to {a2[68]}",
        "line 8: a line of 4 characters is not followed by a TLE",  # (an escape: never in)
    ]


# ---- nothing from the network ------------------------------------------------------------------

NO_NETWORK = """
import socket, urllib.request
import skyfield.iokit

def refuse(*args, **kwargs):
    raise AssertionError(f"a download was tried: {args!r}")

socket.socket.connect = refuse
socket.create_connection = refuse
urllib.request.urlopen = refuse
skyfield.iokit.download = refuse

from bridge.sky import Body, Sky
sky = Sky(52.52, 13.29)
t = 1795996800.0
print(sky.position(Body.sun(), t), sky.position(Body.moon(), t))
line1, line2 = TLE_LINES
print(sky.next_pass(Body.satellite("SAT", line1, line2), t))
"""


def test_ephemeris_and_timescale_load_without_any_download(tmp_path: Path) -> None:
    """A fresh process, every way out to the network closed, in an empty directory and home
    (skyfield's loader would write what it downloads there): the sun, the moon and a pass."""
    env = {**os.environ, "HOME": str(tmp_path), "PYTHONPATH": str(Path(__file__).parents[1])}
    code = NO_NETWORK.replace("TLE_LINES", repr(tle(5)))
    run = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True
    )
    assert run.returncode == 0, run.stderr
    assert "Pass(" in run.stdout and "RuntimeWarning" not in run.stderr
    assert list(tmp_path.iterdir()) == []
