"""The sky seen from one station: positions of a body and its passes, with the passes kept.
One ``Sky`` serves every rotator of the station, from the sky worker's thread
(sky/worker.py) and tests alike.

Rules:
1. A station is a latitude and a longitude in degrees and a height in metres on the WGS84
   ellipsoid; anything out of range or not a number is SkyError.
2. ``positions`` is one vectorised call (positions.py); a satellite without a position at one
   of the times raises SkyError saying the orbit decayed (positions.py rule 5).
3. ``next_pass`` remembers its answers per (body, min_el, within_s), PASSES_KEPT of them:
   asked again at a later time up to that pass's LOS (eight rotators tracking the sun), the
   answer is the same pass and costs nothing; no pass found is remembered for NO_PASS_KEPT_S.
   The memory is locked: any thread may ask.
4. Computing takes from a millisecond to a second: the engine asks its sky worker, never the
   thread that serves the serial lines (docs/architecture.md rule 12).
"""

from __future__ import annotations

import math
import threading
from collections.abc import Sequence

from bridge.sky.bodies import Body, SkyError
from bridge.sky.passes import Pass, find_pass
from bridge.sky.positions import DAY_S, altaz, no_position

PASSES_KEPT = 64  # next_pass's answers remembered (a few per body tracked)
NO_PASS_KEPT_S = 60.0


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
        from skyfield.api import wgs84  # (positions.py rule 6)

        self._station = wgs84.latlon(latitude_deg, longitude_deg, elevation_m=height_m)
        self._lock = threading.Lock()  # rule 3
        self._passes: dict[tuple[Body, float, float], tuple[float, Pass | None]] = {}

    def positions(self, body: Body, times_unix: Sequence[float]) -> list[tuple[float, float]]:
        """(azimuth, elevation) at each time (rule 2), in one vectorised call."""
        import numpy as np

        if len(times_unix) == 0:
            return []
        t = np.asarray(times_unix, dtype=np.float64)
        az, el = altaz(self._station, body, t)
        if body.tle is not None and np.isnan(el).any():
            raise no_position(body, float(t[np.isnan(el)][0]))
        return list(zip(az.tolist(), el.tolist(), strict=True))

    def position(self, body: Body, t_unix: float) -> tuple[float, float]:
        return self.positions(body, [t_unix])[0]

    def next_pass(
        self, body: Body, t_unix: float, min_el_deg: float = 0.0, within_s: float = 2 * DAY_S
    ) -> Pass | None:
        """The pass in progress at t_unix, else the next one rising within within_s
        (passes.py rule 1), remembered (rule 3)."""
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
        found = find_pass(self._station, body, t_unix, min_el_deg, within_s)
        with self._lock:
            self._passes[key] = (t_unix, found)
            while len(self._passes) > PASSES_KEPT:
                self._passes.pop(next(iter(self._passes)))
        return found
