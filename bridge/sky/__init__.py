"""The sky seen from the station: where the sun, the moon and a satellite are, and when they pass
over. Pure computation (no clock, no I/O but reading the bundled ephemeris); skyfield and sgp4
do the astronomy and the searching. Each part states its own rules:

- bodies.py: what can be asked about (``Body``), TLEs and TLE files, ``SkyError``;
- positions.py: the ephemeris, times, (azimuth, elevation), what cannot be computed;
- passes.py: rise, top and set of a pass (``Pass``), found by skyfield's searches;
- station.py: ``Sky``, one station's positions and passes, the passes kept.

Computing takes from a millisecond to a second: the engine asks its sky worker
(sky/worker.py), never the thread that serves the serial lines (docs/architecture.md
rule 12).
"""

from bridge.sky.bodies import KINDS, RESERVED, Body, SkyError, parse_tles, tle_epoch_unix
from bridge.sky.passes import Pass
from bridge.sky.positions import DAY_S, EPHEMERIS_END_S
from bridge.sky.station import NO_PASS_KEPT_S, PASSES_KEPT, Sky

__all__ = [
    "DAY_S",
    "EPHEMERIS_END_S",
    "KINDS",
    "NO_PASS_KEPT_S",
    "PASSES_KEPT",
    "RESERVED",
    "Body",
    "Pass",
    "Sky",
    "SkyError",
    "parse_tles",
    "tle_epoch_unix",
]
