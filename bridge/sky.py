"""Where the sun, the moon and a satellite are, seen from the station, and when they pass over.
Pure computation: no clock, no I/O but reading the bundled ephemeris; skyfield does the astronomy.

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
   time (whole days since 1970, then seconds of that day), so each day gets its own leap seconds.
5. A TLE is two lines of 69 characters (trailing blanks dropped), starting "1 " and "2 ", each
   ending in its checksum (the sum of its digits, a minus sign counting 1, modulo 10), with one
   catalog number on both lines, and elements that sgp4 accepts and propagates at their epoch.
   Anything else is SkyError naming the line and what is wrong. A TLE file (parse_tles) is
   3-line sets (a name line, Space-Track's "0 " prefix dropped) or bare 2-line sets (named by
   their catalog number); blank lines and CRLF are fine; a bad set is reported and skipped.
   A satellite named "off", "sun" or "moon" (any case) is called "satellite off" and so on:
   ``R/tracking`` saying "off" or "sun" must mean that.
6. A pass is an interval with the body above min_el. next_pass gives the one in progress at t
   (its aos_s <= t: the rise found looking back at most within_s, else t itself) or else the first
   that rises within within_s. A body that does not set within within_s of t (midnight sun, a GEO
   satellite in view) gives aos_s = t and los_s = t + within_s; a pass that rises in the window is
   cut at aos_s + within_s. AOS and LOS are within 1 s (refined to < 0.1 s in practice).
7. Passes are found by sampling elevation (a satellite ~90 times per orbit, the sun and the moon
   every 20 minutes), refining each sign change, and refining each sampled extremum near min_el,
   so a pass (or a dip) shorter than a sampling step is still found.
8. What cannot be computed raises SkyError, whose ``reason`` is what a user reads when tracking
   ends for it: "satellite orbit decayed" (SGP4's own error code says which), "date beyond the
   ephemeris (2053)". Computing takes from a millisecond to a second: the engine asks its sky
   worker (engine/skywork.py), never the thread that serves the serial lines.
"""

from __future__ import annotations

import functools
import math
import os
import threading
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import skyfield_data
from numpy.typing import NDArray
from sgp4.api import SGP4_ERRORS, Satrec
from skyfield.api import EarthSatellite, load, wgs84
from skyfield.errors import EphemerisRangeError
from skyfield.jpllib import SpiceKernel
from skyfield.nutationlib import iau2000b_radians

Floats = NDArray[np.float64]

DAY_S = 86400.0
PASSES_KEPT = 64  # next_pass's answers remembered (a few per body tracked)
NO_PASS_KEPT_S = 60.0
KINDS = ("sun", "moon", "satellite")
RESERVED = ("off", "sun", "moon")  # what R/track and R/tracking mean by these (rule 5)
_SUN_MOON_STEP_S = 1200.0
_CHUNK_STEPS = 256  # samples per skyfield call when scanning for passes
_SECTIONS = 64  # points per bracket when refining a crossing or an extremum
_DONE_S = 2.0  # brackets this narrow are finished by interpolation
_UNIX_JD = 2440587.5  # the Julian date of 1970-01-01 00:00 UTC
EPHEMERIS_END_S = 2643580800.0  # 2053-10-09 00:00 UTC: DE421 ends the day before


class SkyError(ValueError):
    """Input the sky cannot answer for; ``reason`` says it in a few words (rule 8)."""

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
        """A satellite called "off", "sun" or "moon" is "satellite off" etc. (rule 5)."""
        name = name.strip()
        if name.casefold() in RESERVED:
            name = f"satellite {name}"
        return Body("satellite", name, (line1.rstrip(), line2.rstrip()))


def _checksum(line: str) -> int:
    return sum(int(c) if c.isdigit() else c == "-" for c in line[:68]) % 10


def _tle_problem(line1: str, line2: str) -> tuple[int, str] | None:
    """(which line, what is wrong) with a TLE, or None when sgp4 can use it (rule 5)."""
    for number, line in ((1, line1), (2, line2)):
        if len(line) != 69:
            return number, f"has {len(line)} characters, a TLE line has 69"
        if not line.startswith(f"{number} "):
            return number, f"must start with '{number} ', got {line[:2]!r}"
        if not line[68].isdigit() or int(line[68]) != _checksum(line):
            return number, f"checksum is {line[68]!r}, the line sums to {_checksum(line)}"
    if line1[2:7] != line2[2:7]:
        return 2, f"catalog number {line2[2:7]!r} is not line 1's {line1[2:7]!r}"
    try:
        sat = Satrec.twoline2rv(line1, line2)
    except (ValueError, IndexError) as e:
        return 1, f"sgp4 cannot read the elements: {e}"
    error, _, _ = sat.sgp4(sat.jdsatepoch, sat.jdsatepochF)
    if error:
        return 2, f"sgp4 cannot propagate the elements: {SGP4_ERRORS[error]}"
    return None


def parse_tles(text: str) -> tuple[dict[str, tuple[str, str]], list[str]]:
    """The sets in a TLE file by name, and one problem per bad set, naming its line (rule 5)."""
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
                problems.append(f"line {at}: {title}: {problem[1]}")
            else:
                if title in sets:
                    first = first_line[title]
                    problems.append(f"line {start}: {title!r} again (first at line {first}): used")
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
                problems.append(f"line {name[0]}: {name[1]!r} is not followed by a TLE")
            name = (number, line[2:].strip() if line.startswith("0 ") else line)
    if name is not None:
        problems.append(f"line {name[0]}: {name[1]!r} is not followed by a TLE")
    return sets, problems


@dataclass(frozen=True)
class Pass:
    aos_s: float  # unix time the body rises above min_el (in the past if the pass is in progress)
    los_s: float  # unix time it sets below min_el
    max_s: float
    max_el_deg: float
    aos_az_deg: float
    los_az_deg: float


@functools.cache
def _ephemeris() -> tuple[Any, Any, Any, Any]:
    """(timescale, earth, sun, moon), read once per process from the bundled files (rule 3)."""
    # not get_skyfield_data_path(): it warns about its finals2000A.all, which we never read
    path = os.path.join(os.path.dirname(skyfield_data.__file__), "data", "de421.bsp")
    kernel = SpiceKernel(path)  # a plain file open: no Loader, so no way to download
    return load.timescale(builtin=True), kernel["earth"], kernel["sun"], kernel["moon"]


def _no_position(body: Body, tle: tuple[str, str], t_unix: float) -> SkyError:
    """Rule 8: SGP4 has no position at ``t_unix``. The elements propagated at their epoch
    (rule 5), so an error later means drag has brought the orbit down in the model: SGP4's own
    code (6, or an eccentricity driven out of range) goes in the message."""
    days, second = divmod(t_unix, DAY_S)
    error, _, _ = Satrec.twoline2rv(*tle).sgp4(_UNIX_JD + days, second / DAY_S)
    what = SGP4_ERRORS.get(error, f"error {error}")
    return SkyError(
        f"{body.name}: SGP4 has no position at {t_unix:.0f} (the orbit decayed: {what})",
        "satellite orbit decayed",
    )


@functools.lru_cache(maxsize=256)
def _satellite(line1: str, line2: str) -> Any:
    return EarthSatellite(line1, line2, None, _ephemeris()[0])


class Sky:
    def __init__(self, latitude_deg: float, longitude_deg: float, height_m: float = 0.0):
        for value, what, limit in (
            (latitude_deg, "latitude_deg", 90.0),
            (longitude_deg, "longitude_deg", 180.0),
            (height_m, "height_m", 1e5),
        ):
            if not math.isfinite(value) or not -limit <= value <= limit:
                raise SkyError(f"{what} must be a number from {-limit:g} to {limit:g}: {value!r}")
        self.latitude_deg, self.longitude_deg, self.height_m = (
            latitude_deg,
            longitude_deg,
            height_m,
        )
        self._station = wgs84.latlon(latitude_deg, longitude_deg, elevation_m=height_m)
        self._lock = threading.Lock()  # one Sky serves every rotator of the station
        self._passes: dict[tuple[Body, float, float], tuple[float, Pass | None]] = {}

    def positions(self, body: Body, times_unix: Sequence[float]) -> list[tuple[float, float]]:
        """(azimuth, elevation) at each time (rule 1), in one vectorised call."""
        if len(times_unix) == 0:
            return []
        az, el = self._altaz(body, np.asarray(times_unix, dtype=np.float64))
        if body.tle is not None and np.isnan(el).any():
            at = float(np.asarray(times_unix)[np.isnan(el)][0])
            raise _no_position(body, body.tle, at)
        return list(zip(az.tolist(), el.tolist(), strict=True))

    def position(self, body: Body, t_unix: float) -> tuple[float, float]:
        return self.positions(body, [t_unix])[0]

    def next_pass(
        self, body: Body, t_unix: float, min_el_deg: float = 0.0, within_s: float = 2 * DAY_S
    ) -> Pass | None:
        """The pass in progress at t_unix, else the next one rising within within_s (rule 6).

        Remembered per body: asked again at a later time up to that pass's LOS (eight rotators
        tracking the sun, one station), the answer is the same pass and costs nothing; no pass
        found is remembered for NO_PASS_KEPT_S."""
        if not within_s > 0 or not math.isfinite(within_s):
            raise SkyError(f"within_s must be a positive number of seconds: {within_s!r}")
        key = (body, min_el_deg, within_s)
        with self._lock:
            kept = self._passes.get(key)
        if kept is not None:
            asked, found = kept
            if found is not None and asked <= t_unix <= found.los_s:
                return found
            if found is None and asked <= t_unix < asked + NO_PASS_KEPT_S:
                return None
        found = self._find_pass(body, t_unix, min_el_deg, within_s)
        with self._lock:
            self._passes[key] = (t_unix, found)
            while len(self._passes) > PASSES_KEPT:
                self._passes.pop(next(iter(self._passes)))
        return found

    def _find_pass(
        self, body: Body, t_unix: float, min_el_deg: float, within_s: float
    ) -> Pass | None:
        end = t_unix + within_s
        if self._elevations(body, np.array([t_unix]))[0] > min_el_deg:
            los = next((t for t, up in self._scan(body, t_unix, end, min_el_deg) if not up), None)
            if los is None:
                return self._pass(body, t_unix, end)
            back = self._scan(body, t_unix, t_unix - within_s, min_el_deg)
            return self._pass(body, next((t for t, up in back if up), t_unix), los)
        events = self._scan(body, t_unix, end + within_s, min_el_deg)
        aos = next((t for t, up in events if up), None)
        if aos is None or aos > end:
            return None
        los = next((t for t, up in events if not up), None)
        return self._pass(body, aos, aos + within_s if los is None else min(los, aos + within_s))

    # -- the computation -----------------------------------------------------------------

    def _altaz(self, body: Body, t_unix: Floats) -> tuple[Floats, Floats]:
        ts, earth, sun, moon = _ephemeris()
        if not np.isfinite(t_unix).all():
            raise SkyError(f"times must be finite numbers: {t_unix[~np.isfinite(t_unix)][0]!r}")
        days, second = np.divmod(t_unix, DAY_S)
        t = ts.utc(1970, 1, 1 + days.astype(np.int64), 0, 0, second)  # rule 4
        t._nutation_angles_radians = iau2000b_radians(t)
        try:
            if body.tle is not None:
                place = (_satellite(*body.tle) - self._station).at(t)
            else:
                target = sun if body.kind == "sun" else moon
                place = (earth + self._station).at(t).observe(target).apparent()
        except EphemerisRangeError as e:
            late = float(t_unix.max()) > EPHEMERIS_END_S
            reason = "date beyond the ephemeris (2053)"
            if not late:
                reason = "date before the ephemeris (1899)"
            raise SkyError(
                f"{body.name}: a time outside the ephemeris (DE421, 1899-07-29..2053-10-08)", reason
            ) from e
        alt, az, _ = place.altaz()
        el_deg: Floats = alt.degrees
        az_deg: Floats = az.degrees % 360.0
        return az_deg, el_deg

    def _elevations(self, body: Body, t_unix: Floats) -> Floats:
        el = self._altaz(body, t_unix)[1]
        return np.nan_to_num(el, nan=-180.0)  # no SGP4 position: never above the horizon

    def _step_s(self, body: Body) -> float:
        if body.tle is None:
            return _SUN_MOON_STEP_S
        model = _satellite(*body.tle).model
        period_s = 2 * math.pi / float(model.no_kozai) * 60.0  # no_kozai is radians per minute
        e = float(model.ecco)  # near perigee an eccentric orbit sweeps the sky faster
        return min(600.0, max(10.0, period_s / 90.0 / math.pow((1 + e) / (1 - e), 1.5)))

    def _scan(
        self, body: Body, start: float, stop: float, min_el: float
    ) -> Iterator[tuple[float, bool]]:
        """(time, rising) of each crossing of min_el from start towards stop (either way)."""
        step = self._step_s(body)
        sign = 1.0 if stop >= start else -1.0
        a = start
        while (stop - a) * sign > 0:
            b = a + sign * min(_CHUNK_STEPS * step, abs(stop - a))
            lo, hi = min(a, b), max(a, b)
            found = [e for e in self._crossings(body, lo, hi, step, min_el) if lo <= e[0] <= hi]
            yield from (reversed(found) if sign < 0 else found)
            a = b

    def _crossings(
        self, body: Body, lo: float, hi: float, step: float, min_el: float
    ) -> list[tuple[float, bool]]:
        n = max(2, math.ceil((hi - lo) / step))
        h = (hi - lo) / n
        t: Floats = lo + h * np.arange(
            -1.0, n + 2.0
        )  # one sample beyond each end: extrema at the ends
        f = self._elevations(body, t) - min_el
        up = f > 0
        i = np.flatnonzero(up[1:-2] != up[2:-1]) + 1  # sign changes inside [lo, hi]
        brackets = [(t[i], t[i + 1], up[i + 1])]
        # a sampled extremum of one sign near zero (rule 7): the curve may cross between samples
        j = np.arange(1, n + 1)
        same = (up[j - 1] == up[j]) & (up[j] == up[j + 1])
        peak = np.where(up[j], -1.0, 1.0)
        near = np.abs(f[j]) < np.maximum(np.abs(f[j] - f[j - 1]), np.abs(f[j + 1] - f[j]))
        j = j[same & near & (peak * (f[j] - f[j - 1]) >= 0) & (peak * (f[j] - f[j + 1]) >= 0)]
        if len(j):
            tx, fx = self._extrema(body, t[j - 1], t[j + 1], np.where(up[j], -1.0, 1.0), min_el)
            k = (fx > 0) != up[j]
            brackets.append((t[j - 1][k], tx[k], ~up[j][k]))
            brackets.append((tx[k], t[j + 1][k], up[j][k]))
        a = np.concatenate([b[0] for b in brackets])
        b = np.concatenate([b[1] for b in brackets])
        rising = np.concatenate([b[2] for b in brackets])
        if len(a) == 0:
            return []
        return sorted(zip(self._roots(body, a, b, min_el).tolist(), rising.tolist(), strict=True))

    def _grid(self, lo: Floats, hi: Floats) -> Floats:
        frac = np.linspace(0.0, 1.0, _SECTIONS + 1)
        grid: Floats = lo[:, None] + (hi - lo)[:, None] * frac[None, :]
        return grid

    def _roots(self, body: Body, lo: Floats, hi: Floats, min_el: float) -> Floats:
        """Where the elevation crosses min_el in each [lo, hi] (one sign change in each)."""
        rows = np.arange(len(lo))
        while True:
            grid = self._grid(lo, hi)
            f = self._elevations(body, grid.ravel()).reshape(grid.shape) - min_el
            up = f > 0
            k = np.argmax(up[:, 1:] != up[:, :1], axis=1) + 1  # first sample past the crossing
            lo, hi = grid[rows, k - 1], grid[rows, k]
            if (hi - lo).max() <= _DONE_S:
                f0, f1 = f[rows, k - 1], f[rows, k]
                root: Floats = lo + (hi - lo) * np.clip(f0 / np.where(f0 == f1, 1, f0 - f1), 0, 1)
                return root

    def _extrema(
        self, body: Body, lo: Floats, hi: Floats, sign: Floats, min_el: float
    ) -> tuple[Floats, Floats]:
        """(time, elevation - min_el) of the maximum of sign * elevation in each [lo, hi]."""
        rows = np.arange(len(lo))
        while True:
            grid = self._grid(lo, hi)
            f = self._elevations(body, grid.ravel()).reshape(grid.shape) - min_el
            k = np.argmax(sign[:, None] * f, axis=1)
            lo, hi = grid[rows, np.maximum(k - 1, 0)], grid[rows, np.minimum(k + 1, _SECTIONS)]
            if (hi - lo).max() <= _DONE_S:
                return grid[rows, k], f[rows, k]

    def _pass(self, body: Body, aos: float, los: float) -> Pass:
        n = max(2, math.ceil((los - aos) / self._step_s(body)))
        t = np.concatenate([[aos, los], np.linspace(aos, los, n + 1)])
        az, el = self._altaz(body, t)
        k = int(np.argmax(np.nan_to_num(el[2:], nan=-180.0)))
        lo, hi = np.array([t[2 + max(k - 1, 0)]]), np.array([t[2 + min(k + 1, n)]])
        max_t, max_el = self._extrema(body, lo, hi, np.ones(1), 0.0)
        return Pass(
            aos_s=aos,
            los_s=los,
            max_s=float(max_t[0]),
            max_el_deg=float(max_el[0]),
            aos_az_deg=float(az[0]),
            los_az_deg=float(az[1]),
        )
