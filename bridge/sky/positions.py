"""Where the sun, the moon and a satellite are, seen from a station: the bundled ephemeris, the
times skyfield is asked at, and the errors it raises turned into SkyError. Pure computation: no
clock, no I/O but reading the bundled ephemeris; skyfield and sgp4 do the astronomy.

Rules:
1. A position is topocentric, from the station on the WGS84 ellipsoid: (azimuth, elevation) in
   degrees, azimuth clockwise from true north in [0, 360), elevation above the horizon plane.
   No atmospheric refraction: the antenna points where the body is (refraction near the horizon
   depends on weather the bridge does not know; it lifts the body by about 0.5 deg at el 0).
2. The sun and the moon are apparent places (light time, aberration, deflection) from JPL's
   DE421 (1899-07-29 .. 2053-10-08; a time outside raises SkyError). A satellite is SGP4 from
   its TLE, the geometric place (its light time is milliseconds). Nutation is IAU 2000B, as in
   skyfield's own almanac: 1 mas from 2000A at a fraction of the cost.
3. Nothing is downloaded: DE421 comes from the skyfield-data package, the leap seconds and delta T
   from skyfield's built-in tables. The ephemeris is opened (memory-mapped) on first use, once per
   process; a satellite's propagator is built once per TLE.
4. Times are unix seconds (UTC without its leap seconds); they become skyfield times one day at a
   time (whole days since 1970, then seconds of that day), so each day gets its own leap seconds;
   and skyfield's times come back the same way.
5. A satellite SGP4 has no position for (its orbit decayed in the model) has elevation NaN;
   ``alive`` is the part of a time span where it has one (SGP4 fails from some time on, or
   before some time going back, never in between), ``no_position`` the SkyError saying why.
6. numpy, skyfield and sgp4 are imported where they are first used, not with the module: a
   bridge that tracks nothing never loads them (a seventh of its start-up's CPU).
"""

from __future__ import annotations

import functools
import math
import os
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any

from bridge.sky.bodies import Body, SkyError

if TYPE_CHECKING:  # numpy, skyfield and sgp4 are imported on first use (rule 6)
    import numpy as np
    from numpy.typing import NDArray

    Floats = NDArray[np.float64]

DAY_S = 86400.0
EPHEMERIS_END_S = 2643580800.0  # 2053-10-09 00:00 UTC: DE421 ends the day before
_UNIX_JD = 2440587.5  # the Julian date of 1970-01-01 00:00 UTC
_ALIVE_S = 1.0  # how closely the end of a decayed orbit is found (rule 5)


@functools.cache
def ephemeris() -> tuple[Any, Any, Any, Any]:
    """(timescale, earth, sun, moon), read once per process from the bundled files (rule 3)."""
    import skyfield_data
    from skyfield.api import load
    from skyfield.jpllib import SpiceKernel

    # not get_skyfield_data_path(): it warns about its finals2000A.all, which we never read
    path = os.path.join(os.path.dirname(skyfield_data.__file__), "data", "de421.bsp")
    kernel = SpiceKernel(path)  # a plain file open: no Loader, so no way to download
    return load.timescale(builtin=True), kernel["earth"], kernel["sun"], kernel["moon"]


@functools.lru_cache(maxsize=256)
def satellite(line1: str, line2: str) -> Any:
    from skyfield.api import EarthSatellite

    return EarthSatellite(line1, line2, None, ephemeris()[0])


def to_time(t_unix: Floats) -> Any:
    """Unix seconds as a skyfield Time (rule 4), nutation set to IAU 2000B (rule 2)."""
    import numpy as np
    from skyfield.nutationlib import iau2000b_radians

    if not np.isfinite(t_unix).all():
        raise SkyError(f"times must be finite numbers: {t_unix[~np.isfinite(t_unix)][0]!r}")
    days, second = np.divmod(t_unix, DAY_S)
    t = ephemeris()[0].utc(1970, 1, 1 + days.astype(np.int64), 0, 0, second)
    t._nutation_angles_radians = iau2000b_radians(t)
    return t


def to_unix(t: Any) -> list[float]:
    """A skyfield Time array back as unix seconds (rule 4)."""
    return [d.timestamp() for d in t.utc_datetime()]


@contextmanager
def in_ephemeris(body: Body, t_unix: float) -> Iterator[None]:
    """Rule 2: a time outside DE421 is SkyError saying which end (``t_unix``: the latest asked)."""
    from skyfield.errors import EphemerisRangeError

    try:
        yield
    except EphemerisRangeError as e:
        reason = "date beyond the ephemeris (2053)"
        if t_unix <= EPHEMERIS_END_S:
            reason = "date before the ephemeris (1899)"
        raise SkyError(
            f"{body.name}: a time outside the ephemeris (DE421, 1899-07-29..2053-10-08)", reason
        ) from e


def altaz(station: Any, body: Body, t_unix: Floats) -> tuple[Floats, Floats]:
    """(azimuth, elevation) in degrees at each time (rule 1); NaN where SGP4 fails (rule 5)."""
    _, earth, sun, moon = ephemeris()
    t = to_time(t_unix)
    with in_ephemeris(body, float(t_unix.max())):
        if body.tle is not None:
            place = (satellite(*body.tle) - station).at(t)
        else:
            target = sun if body.kind == "sun" else moon
            place = (earth + station).at(t).observe(target).apparent()
    alt, az, _ = place.altaz()
    el_deg: Floats = alt.degrees
    az_deg: Floats = az.degrees % 360.0
    return az_deg, el_deg


def _sgp4_fails(tle: tuple[str, str], t_unix: float) -> int:
    from sgp4.api import Satrec

    days, second = divmod(t_unix, DAY_S)
    error, _, _ = Satrec.twoline2rv(*tle).sgp4(_UNIX_JD + days, second / DAY_S)
    return int(error)


def alive(body: Body, start: float, stop: float) -> tuple[float, float] | None:
    """Rule 5: the part of [start, stop] (either order) from ``start`` on where the satellite
    has a position, as (start, new stop); None if it has none at ``start``. Sun, moon: as is."""
    if body.tle is None:
        return start, stop
    if _sgp4_fails(body.tle, start):
        return None
    if not _sgp4_fails(body.tle, stop):
        return start, stop
    good, bad = start, stop
    while abs(bad - good) > _ALIVE_S:
        mid = (good + bad) / 2
        good, bad = (good, mid) if _sgp4_fails(body.tle, mid) else (mid, bad)
    return start, good


def no_position(body: Body, t_unix: float) -> SkyError:
    """Rule 5: SGP4 has no position at ``t_unix``. The elements propagated at their epoch
    (bodies.py rule 1), so an error later means drag has brought the orbit down in the model:
    SGP4's own code (6, or an eccentricity driven out of range) goes in the message."""
    from sgp4.api import SGP4_ERRORS

    assert body.tle is not None
    error = _sgp4_fails(body.tle, t_unix)
    what = SGP4_ERRORS.get(error, f"error {error}")
    return SkyError(
        f"{body.name}: SGP4 has no position at {t_unix:.0f} (the orbit decayed: {what})",
        "satellite orbit decayed",
    )


def period_s(body: Body) -> float:
    """A satellite's orbital period from its mean motion (the sun and the moon: a day)."""
    if body.tle is None:
        return DAY_S
    return 2 * math.pi / float(satellite(*body.tle).model.no_kozai) * 60.0  # rad per minute
