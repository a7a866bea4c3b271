"""Independent judges for bridge/sky/, written here from published formulas and never from
skyfield: the sun and the moon by the Astronomical Almanac's low-precision formulas, a satellite
by the sgp4 package alone with our own frame rotations. Plus synthetic TLEs for the tests.

Sources:
- Sun: The Astronomical Almanac, section C, "Low-precision formulas for the Sun's coordinates"
  (mean longitude, mean anomaly, ecliptic longitude, obliquity; 0.01 deg from 1950 to 2050).
- Moon: The Astronomical Almanac, section D, "Low-precision formulae for geocentric coordinates
  of the Moon" (longitude 0.3 deg, latitude 0.2 deg, parallax 0.003 deg) and its topocentric
  correction (geocentric rectangular coordinates minus the observer's, in Earth radii).
- Sidereal time: the IAU 1982 GMST (Aoki et al. 1982), as in Vallado's gstime; UT1 taken as UTC
  (|UT1 - UTC| < 0.9 s, 0.004 deg) and the equation of the equinoxes (< 0.005 deg) left out.
- SGP4 positions are in TEME (Vallado et al., "Revisiting Spacetrack Report #3", AIAA 2006-6753):
  TEME -> Earth-fixed is a rotation by GMST about z (polar motion, metres, ignored); the station
  is on the WGS84 ellipsoid (a = 6378.137 km, 1/f = 298.257223563).
- TLE format: Celestrak's "NORAD Two-Line Element Set Format" (columns, checksum modulo 10).
"""

from __future__ import annotations

import math
from datetime import UTC, datetime

import numpy as np
from numpy.typing import NDArray
from sgp4.api import Satrec, SatrecArray

Floats = NDArray[np.float64]
_J2000 = 2451545.0
_UNIX_JD = 2440587.5
_WGS84_A_KM = 6378.137
_WGS84_F = 1 / 298.257223563


def _jd(t_unix: float | Floats) -> float | Floats:
    return _UNIX_JD + np.asarray(t_unix) / 86400.0


def gmst_deg(t_unix: float | Floats) -> Floats:
    """Greenwich mean sidereal time (IAU 1982), degrees in [0, 360)."""
    t = (_jd(t_unix) - _J2000) / 36525.0
    seconds = 67310.54841 + (876600.0 * 3600.0 + 8640184.812866) * t
    seconds += 0.093104 * t**2 - 6.2e-6 * t**3
    out: Floats = np.mod(seconds / 240.0, 360.0)
    return out


def _horizon(lat: float, lon: float, ra_deg: Floats, dec_deg: Floats, t_unix: Floats) -> tuple:
    """Equatorial (of date) -> (azimuth from north through east, elevation), degrees."""
    h = np.radians(gmst_deg(t_unix) + lon - ra_deg)  # local hour angle
    phi, dec = math.radians(lat), np.radians(dec_deg)
    el = np.arcsin(math.sin(phi) * np.sin(dec) + math.cos(phi) * np.cos(dec) * np.cos(h))
    az = np.arctan2(
        -np.cos(dec) * np.sin(h),
        np.sin(dec) * math.cos(phi) - np.cos(dec) * math.sin(phi) * np.cos(h),
    )
    return np.mod(np.degrees(az), 360.0), np.degrees(el)


def sun_altaz(lat: float, lon: float, t_unix: float) -> tuple[float, float]:
    """The sun's (azimuth, elevation), no refraction; the Almanac's low-precision formulas."""
    az, el = sun_altaz_array(lat, lon, np.array([t_unix], dtype=np.float64))
    return float(az[0]), float(el[0])


def sun_altaz_array(lat: float, lon: float, t_unix: Floats) -> tuple[Floats, Floats]:
    n = _jd(t_unix) - _J2000  # days; TT - UT (70 s) moves the sun by 0.001 deg: left out
    mean_lon = 280.460 + 0.9856474 * n
    g = np.radians(357.528 + 0.9856003 * n)
    ecl_lon = np.radians(mean_lon + 1.915 * np.sin(g) + 0.020 * np.sin(2 * g))
    eps = np.radians(23.439 - 0.0000004 * n)
    ra = np.degrees(np.arctan2(np.cos(eps) * np.sin(ecl_lon), np.cos(ecl_lon)))
    dec = np.degrees(np.arcsin(np.sin(eps) * np.sin(ecl_lon)))
    return _horizon(lat, lon, ra, dec, t_unix)  # the sun's parallax (0.0024 deg) left out


def moon_altaz(lat: float, lon: float, t_unix: float) -> tuple[float, float]:
    """The moon's topocentric (azimuth, elevation), no refraction; the Almanac's low-precision
    formulas, good to about 0.3 deg."""
    t = (float(_jd(t_unix)) - _J2000) / 36525.0

    def s(a: float, b: float) -> float:
        return math.sin(math.radians(a + b * t))

    def c(a: float, b: float) -> float:
        return math.cos(math.radians(a + b * t))

    lam = (
        218.32
        + 481267.881 * t
        + 6.29 * s(135.0, 477198.87)
        - 1.27 * s(259.3, -413335.36)
        + 0.66 * s(235.7, 890534.22)
        + 0.21 * s(269.9, 954397.74)
        - 0.19 * s(357.5, 35999.05)
        - 0.11 * s(186.5, 966404.03)
    )
    beta = (
        5.13 * s(93.3, 483202.02)
        + 0.28 * s(228.2, 960400.89)
        - 0.28 * s(318.3, 6003.15)
        - 0.17 * s(217.6, -407332.21)
    )
    parallax = (
        0.9508
        + 0.0518 * c(135.0, 477198.87)
        + 0.0095 * c(259.3, -413335.36)
        + 0.0078 * c(235.7, 890534.22)
        + 0.0028 * c(269.9, 954397.74)
    )
    r = 1.0 / math.sin(math.radians(parallax))  # Earth radii
    lam_r, beta_r = math.radians(lam), math.radians(beta)
    eps = math.radians(23.439 - 0.013 * t)
    # geocentric equatorial direction cosines, then the observer taken away (topocentric)
    x = math.cos(beta_r) * math.cos(lam_r)
    y = math.cos(eps) * math.cos(beta_r) * math.sin(lam_r) - math.sin(eps) * math.sin(beta_r)
    z = math.sin(eps) * math.cos(beta_r) * math.sin(lam_r) + math.cos(eps) * math.sin(beta_r)
    sx, sy, sz = _station_ecef_km(lat, 0.0, 0.0)  # meridian plane: only its rho, z matter
    rho_xy, rho_z = sx / _WGS84_A_KM, sz / _WGS84_A_KM
    lst = math.radians(float(gmst_deg(t_unix)) + lon)
    x, y, z = r * x - rho_xy * math.cos(lst), r * y - rho_xy * math.sin(lst), r * z - rho_z
    ra = math.degrees(math.atan2(y, x))
    dec = math.degrees(math.atan2(z, math.hypot(x, y)))
    one = np.array([t_unix], dtype=np.float64)
    az, el = _horizon(lat, lon, np.array([ra]), np.array([dec]), one)
    return float(az[0]), float(el[0])


def _station_ecef_km(lat: float, lon: float, height_m: float) -> tuple[float, float, float]:
    phi, lam = math.radians(lat), math.radians(lon)
    e2 = _WGS84_F * (2 - _WGS84_F)
    n = _WGS84_A_KM / math.sqrt(1 - e2 * math.sin(phi) ** 2)
    h = height_m / 1000.0
    return (
        (n + h) * math.cos(phi) * math.cos(lam),
        (n + h) * math.cos(phi) * math.sin(lam),
        (n * (1 - e2) + h) * math.sin(phi),
    )


def _teme_altaz(
    r_teme: Floats, t_unix: Floats, lat: float, lon: float, height_m: float
) -> tuple[Floats, Floats]:
    """TEME positions (..., 3) km at t_unix (...) -> (azimuth, elevation) from the station."""
    g = np.radians(gmst_deg(t_unix))
    x = np.cos(g) * r_teme[..., 0] + np.sin(g) * r_teme[..., 1]
    y = -np.sin(g) * r_teme[..., 0] + np.cos(g) * r_teme[..., 1]
    sx, sy, sz = _station_ecef_km(lat, lon, height_m)
    dx, dy, dz = x - sx, y - sy, r_teme[..., 2] - sz
    phi, lam = math.radians(lat), math.radians(lon)
    east = -math.sin(lam) * dx + math.cos(lam) * dy
    north = (
        -math.sin(phi) * math.cos(lam) * dx
        - math.sin(phi) * math.sin(lam) * dy
        + math.cos(phi) * dz
    )
    up = (
        math.cos(phi) * math.cos(lam) * dx + math.cos(phi) * math.sin(lam) * dy + math.sin(phi) * dz
    )
    az = np.mod(np.degrees(np.arctan2(east, north)), 360.0)
    return az, np.degrees(np.arctan2(up, np.hypot(east, north)))


def _jd_split(t_unix: Floats) -> tuple[Floats, Floats]:
    days = np.floor(np.asarray(t_unix) / 86400.0)
    return _UNIX_JD + days, np.asarray(t_unix) / 86400.0 - days


def sgp4_altaz_array(
    line1: str, line2: str, lat: float, lon: float, t_unix: Floats, height_m: float = 0.0
) -> tuple[Floats, Floats]:
    sat = Satrec.twoline2rv(line1, line2)
    jd, fr = _jd_split(t_unix)
    error, r, _ = sat.sgp4_array(jd, fr)
    assert not error.any(), f"sgp4 error codes {set(error.tolist())}"
    return _teme_altaz(r, np.asarray(t_unix, dtype=np.float64), lat, lon, height_m)


def sgp4_altaz(
    line1: str, line2: str, lat: float, lon: float, t_unix: float, height_m: float = 0.0
) -> tuple[float, float]:
    """A satellite's (azimuth, elevation) by the sgp4 package and our own frame rotations."""
    az, el = sgp4_altaz_array(line1, line2, lat, lon, np.array([t_unix]), height_m)
    return float(az[0]), float(el[0])


def tle_checksum(line: str) -> int:
    return sum(int(ch) if ch.isdigit() else ch == "-" for ch in line[:68]) % 10


def synthetic_tle(
    name: str,
    epoch_unix: float,
    *,
    inclination_deg: float,
    raan_deg: float,
    mean_anomaly_deg: float,
    mean_motion_rev_day: float = 15.5,
    eccentricity: float = 0.0005,
    arg_perigee_deg: float = 0.0,
    catalog: int = 99999,
    bstar: float = 0.0,
) -> tuple[str, str]:
    """Lines 1 and 2 of a TLE with these elements at epoch_unix, checksums right. ``name`` is
    the caller's line 0; it goes in no column. ``bstar`` (drag, per Earth radius) decays the
    orbit."""
    del name
    epoch = datetime.fromtimestamp(epoch_unix, UTC)
    new_year = datetime(epoch.year, 1, 1, tzinfo=UTC).timestamp()
    day = 1.0 + (epoch_unix - new_year) / 86400.0
    body1 = (
        f"1 {catalog:05d}U 26001A   {epoch.year % 100:02d}{day:012.8f}"
        f"  .00000000  00000-0 {_implied_exponent(bstar)} 0  999"
    )
    body2 = (
        f"2 {catalog:05d} {inclination_deg:8.4f} {raan_deg % 360:8.4f} "
        f"{round(eccentricity * 1e7):07d} {arg_perigee_deg % 360:8.4f} "
        f"{mean_anomaly_deg % 360:8.4f} {mean_motion_rev_day:11.8f}{1:5d}"
    )
    assert len(body1) == len(body2) == 68, (body1, body2)
    return body1 + str(tle_checksum(body1)), body2 + str(tle_checksum(body2))


def _implied_exponent(x: float) -> str:
    """A TLE's 8-column "decimal point assumed" number: " 12345-3" is 0.12345e-3."""
    if x == 0:
        return " 00000-0"
    exponent = math.floor(math.log10(abs(x))) + 1
    digits = round(abs(x) / 10.0**exponent * 1e5)
    if digits == 100000:
        digits, exponent = 10000, exponent + 1
    assert -9 <= exponent <= 9, x
    return f"{'-' if x < 0 else ' '}{digits:05d}{'-' if exponent < 0 else '+'}{abs(exponent)}"


def _crossing(line1: str, line2: str, lat: float, lon: float, lo: float, hi: float) -> float:
    """Bisection on elevation 0 between lo and hi (one sign change), to 1 ms."""
    up_at_lo = sgp4_altaz(line1, line2, lat, lon, lo)[1] > 0
    while hi - lo > 1e-3:
        mid = (lo + hi) / 2
        if (sgp4_altaz(line1, line2, lat, lon, mid)[1] > 0) == up_at_lo:
            lo = mid
        else:
            hi = mid
    return (lo + hi) / 2


def tle_with_pass(
    lat: float,
    lon: float,
    after_unix: float,
    *,
    within_s: float = 3600,
    min_max_el_deg: float = 25,
    max_max_el_deg: float = 70,
) -> tuple[str, str, float, float]:
    """A synthetic TLE (epoch after_unix, inclination 97.5 deg so every latitude is overflown)
    whose first pass over the station rises after after_unix, sets within within_s and peaks
    between the two elevations; with that pass's AOS and LOS (elevation 0, to 1 ms). The search
    is deterministic: RAAN then mean anomaly in fixed steps, the first that fits wins."""
    step_s = 20.0
    t = after_unix + np.arange(0.0, within_s + step_s, step_s)
    anomalies = np.arange(0.0, 360.0, 10.0)
    for raan in np.arange(0.0, 360.0, 5.0):
        tles = [
            synthetic_tle(
                "SEARCH", after_unix, inclination_deg=97.5, raan_deg=raan, mean_anomaly_deg=m
            )
            for m in anomalies
        ]
        sats = SatrecArray([Satrec.twoline2rv(a, b) for a, b in tles])
        jd, fr = _jd_split(t)
        error, r, _ = sats.sgp4(jd, fr)
        _, el = _teme_altaz(r, np.broadcast_to(t, error.shape), lat, lon, 0.0)
        for (line1, line2), row in zip(tles, el, strict=True):
            up = row > 0
            if up[0] or not up.any() or up[-1]:
                continue
            rise = int(np.argmax(up))
            sets = rise + int(np.argmax(~up[rise:]))
            if up[sets:].any() or not min_max_el_deg <= row.max() <= max_max_el_deg:
                continue
            aos = _crossing(line1, line2, lat, lon, t[rise - 1], t[rise])
            los = _crossing(line1, line2, lat, lon, t[sets - 1], t[sets])
            return line1, line2, aos, los
    raise AssertionError(f"no synthetic pass over {lat}, {lon} within {within_s} s")
