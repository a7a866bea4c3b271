"""When a body passes over the station: its rise above a minimum elevation, its top and its set.
The searching is skyfield's: ``EarthSatellite.find_events`` for a satellite, the almanac's
``find_risings`` / ``find_settings`` / ``find_transits`` for the sun and the moon; this module
only asks them over the right spans and turns their answers into one ``Pass``.

Rules:
1. A pass is an interval with the body above min_el (its centre, no refraction: positions.py
   rule 1). ``find_pass`` gives the one in progress at t (its aos_s <= t: the rise found looking
   back at most within_s, else t itself) or else the first that rises within within_s. A body
   that does not set within within_s of t (midnight sun, a GEO satellite in view) gives
   aos_s = t and los_s = t + within_s; a pass that rises in the window is cut at
   aos_s + within_s. AOS and LOS are within 1 s (skyfield refines to half a second or better).
2. A satellite is searched a few orbits at a time (CHUNK_ORBITS, at least CHUNK_MIN_S), each
   span widened by one orbit on both sides so that the top of a pass cut by the span's edge is
   inside it: find_events finds a rise or a set by the top it brackets. It samples 20 times an
   orbit and refines every maximum, so a pass shorter than a sample step is still found. But it
   looks for a rise or a set only between a top and the midpoint to the next, which misses both
   when passes last a good part of an orbit: for a deep-space orbit (SGP4's own class, a period
   over 225 minutes) or an eccentric one (e > ECCENTRIC), the rises and sets of skyfield's
   ``find_discrete`` over whether the satellite is up are added, sampled about 90 times an
   orbit and more densely the faster perigee sweeps the sky (dense_step_s), one orbit at a
   time. The sun and the moon are found in one call over the whole span (the almanac's search
   is geometric: it turns the sky at the body's declination of the moment). Beyond
   POLAR_LAT_DEG of latitude that fails, as a body there rises and sets by its declination,
   not by the sky turning (the moon at 88.5 deg, the sun at the pole's equinoxes were not
   found at all): there their rises and sets are find_discrete's crossings, sampled every
   POLAR_STEP_S (the elevation changes slowly there). A search that finds a rise goes on with
   what it found around it: the set and the top of that pass most often come with it.
3. A satellite whose orbit decays in the span is searched only where SGP4 has a position
   (positions.py rule 5); with none at t there is no pass. A pass still up when the orbit
   decays ends there, and a span cut by the decay (which may cut off the top find_events
   brackets a rise or a set by) has find_discrete's crossings added, as in rule 2.
4. The top of a pass (max_s, max_el_deg) is its highest culmination (satellite) or meridian
   transit (sun, moon) inside it, or one of its ends when the pass is cut before its top
   (or a sample across it, where the search missed the top: rule 3). The
   moon's declination moves while it crosses the meridian: its true top can be minutes from
   the transit (20 at 78 deg latitude), its elevation a few hundredths of a degree higher.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from bridge.sky.bodies import Body
from bridge.sky.positions import (
    DAY_S,
    alive,
    altaz,
    ephemeris,
    in_ephemeris,
    period_s,
    satellite,
    to_time,
    to_unix,
)

CHUNK_ORBITS = 4  # rule 2
CHUNK_MIN_S = 6 * 3600.0
RISE, TOP, SET = 0, 1, 2  # find_events' own numbering
ECCENTRIC = 0.1  # rule 2
POLAR_LAT_DEG = 85.0  # rule 2: nearer a pole, the almanac's rises and sets are not searched
POLAR_STEP_S = 300.0
_SAME_S = 5.0  # a rise (a set) found by both searches this close together is one
_REFINED_S = 1.0  # rule 1: how far a rise found may lie from the crossing
_TOP_SAMPLES = 65  # rule 4: besides the culminations found


@dataclass(frozen=True)
class Pass:
    aos_s: float  # unix time the body rises above min_el (in the past if the pass is in progress)
    los_s: float  # unix time it sets below min_el
    max_s: float
    max_el_deg: float
    aos_az_deg: float
    los_az_deg: float


def find_pass(
    station: Any, body: Body, t_unix: float, min_el_deg: float, within_s: float
) -> Pass | None:
    """The pass in progress at t_unix, else the next one rising within within_s (rule 1)."""
    import numpy as np

    end = t_unix + within_s
    if alive(body, t_unix, t_unix) is None:
        return None  # rule 3
    if altaz(station, body, np.array([t_unix]))[1][0] > min_el_deg:
        los, _ = _first(station, body, t_unix, end, min_el_deg, SET)
        los = _decays(body, t_unix, end) if los is None else los
        if los is None:
            return _pass(station, body, t_unix, end)
        # the search's rise can come up to half a second after the elevation crossed (rule 1):
        # looking back from t, one of those is this pass's, not the previous orbit's
        back = min(t_unix + _REFINED_S, los)
        aos, _ = _first(station, body, back, t_unix - within_s, min_el_deg, RISE)
        return _pass(station, body, t_unix if aos is None else min(aos, t_unix), los)
    aos, seen = _first(station, body, t_unix, end, min_el_deg, RISE)
    if aos is None:
        return None
    cut = aos + within_s
    # a satellite's search found the whole pass already, most often (rule 2)
    los = next((t for t, k in seen if k == SET and aos < t <= cut), None)
    if los is None:
        los, _ = _first(station, body, aos, cut, min_el_deg, SET)
        los = _decays(body, aos, cut) if los is None else los
    elif body.tle is not None:
        tops = [t for t, k in seen if k == TOP and aos < t < los]
        return _pass(station, body, aos, los, tops)
    return _pass(station, body, aos, cut if los is None else los)


def _decays(body: Body, start: float, stop: float) -> float | None:
    """Rule 3: when a satellite up from ``start`` stops having a position before ``stop``
    (the pass ends there), if it does."""
    span = alive(body, start, stop)
    return span[1] if span is not None and span[1] < stop else None


Events = list[tuple[float, int]]  # (unix time, RISE | TOP | SET), in time order


def _first(
    station: Any, body: Body, start: float, stop: float, min_el: float, kind: int
) -> tuple[float | None, Events]:
    """The first ``kind`` event (RISE or SET) from start towards stop (either way), if any; and
    every event found in the span it was found in (only those of ``kind`` for the sun and the
    moon)."""
    span = alive(body, start, stop)  # rule 3
    if span is None:
        return None, []
    start, stop = span
    sign = 1.0 if stop >= start else -1.0
    chunk, pad = abs(stop - start), 0.0
    if body.tle is not None:  # rule 2
        pad = period_s(body)
        chunk = max(CHUNK_MIN_S, (1 if _dense(body) else CHUNK_ORBITS) * pad)
    a = start
    while (stop - a) * sign > 0:
        b = a + sign * min(chunk, abs(stop - a))
        lo, hi = min(a, b), max(a, b)
        wide = alive(body, lo, lo - pad) or (lo, lo), alive(body, hi, hi + pad) or (hi, hi)
        seen = _events(station, body, (wide[0][1], wide[1][1]), (lo, hi), min_el, kind)
        found = [t for t, k in seen if k == kind and t != start]
        if found:
            return (min(found) if sign > 0 else max(found)), seen
        a = b
    return None, []


def _events(
    station: Any,
    body: Body,
    wide: tuple[float, float],
    span: tuple[float, float],
    min_el: float,
    want: int,
) -> Events:
    """(unix time, RISE | TOP | SET) of the events in ``span``, in time order (rule 2): those of
    kind ``want`` at least (a satellite's search finds all three at once, over ``wide``)."""
    import numpy as np
    from skyfield import almanac

    lo, hi = span
    if hi <= lo:
        return []
    t0, t1 = to_time(np.array([lo, hi]))
    with in_ephemeris(body, wide[1]):
        if body.tle is not None:
            found = _satellite_events(station, body, wide, span, min_el, want)
            return [e for e in found if lo <= e[0] <= hi]
        _, earth, sun, moon = ephemeris()
        observer, target = earth + station, sun if body.kind == "sun" else moon
        if want == TOP:
            found = [(u, TOP) for u in to_unix(almanac.find_transits(observer, target, t0, t1))]
        elif abs(station.latitude.degrees) > POLAR_LAT_DEG:
            found = _polar_crossings(observer, target, (t0, t1), min_el, want)
        else:
            search = almanac.find_risings if want == RISE else almanac.find_settings
            t, real = search(observer, target, t0, t1, horizon_degrees=min_el)
            found = [(u, want) for u, ok in zip(to_unix(t), real, strict=True) if ok]
    return sorted(e for e in found if lo <= e[0] <= hi)


def _polar_crossings(
    observer: Any, target: Any, span: tuple[Any, Any], min_el: float, want: int
) -> Events:
    """Rule 2: the sun's or the moon's rises (or sets) near a pole, as find_discrete's
    crossings of min_el."""
    from skyfield.nutationlib import iau2000b_radians
    from skyfield.searchlib import find_discrete

    def up(t: Any) -> Any:
        t._nutation_angles_radians = iau2000b_radians(t)  # positions.py rule 2
        return observer.at(t).observe(target).apparent().altaz()[0].degrees > min_el

    up.step_days = POLAR_STEP_S / DAY_S  # type: ignore[attr-defined]
    crossings, now_up = find_discrete(*span, up)
    rising = want == RISE
    return [(u, want) for u, r in zip(to_unix(crossings), now_up, strict=True) if r == rising]


def _satellite_events(
    station: Any,
    body: Body,
    wide: tuple[float, float],
    span: tuple[float, float],
    min_el: float,
    want: int,
) -> Events:
    """Rule 2: find_events over ``wide``, and for a long or eccentric orbit find_discrete's
    crossings over ``span`` (sampled regularly: nothing to miss at its ends)."""
    import numpy as np
    from skyfield.nutationlib import iau2000b_radians
    from skyfield.searchlib import find_discrete

    assert body.tle is not None
    sat = satellite(*body.tle)
    t0, t1 = to_time(np.array(wide))
    t, kinds = sat.find_events(station, t0, t1, altitude_degrees=min_el)
    found = list(zip(to_unix(t), (int(k) for k in kinds), strict=True))
    orbit = period_s(body)  # an end cut by a decay (rule 3) may cut off the top find_events needs
    cut = span[0] - wide[0] < orbit - 1.0 or wide[1] - span[1] < orbit - 1.0
    if want == TOP or not (_dense(body) or cut):
        return found
    at = (sat - station).at

    def up(t: Any) -> Any:
        t._nutation_angles_radians = iau2000b_radians(t)  # positions.py rule 2
        return np.nan_to_num(at(t).altaz()[0].degrees, nan=-180.0) > min_el

    up.step_days = dense_step_s(body) / 86400.0  # type: ignore[attr-defined]
    crossings, now_up = find_discrete(*to_time(np.array(span)), up)
    for u, rising in zip(to_unix(crossings), now_up, strict=True):
        kind = RISE if rising else SET
        if not any(k == kind and abs(v - u) < _SAME_S for v, k in found):
            found.append((u, kind))
    return sorted(found)


def _dense(body: Body) -> bool:
    """Rule 2: a deep-space or an eccentric orbit, whose passes find_events alone may miss."""
    model = satellite(*body.tle).model if body.tle is not None else None
    return model is not None and (model.method == "d" or float(model.ecco) > ECCENTRIC)


def dense_step_s(body: Body) -> float:
    """Rule 2: 90 samples an orbit, denser by how much faster than average perigee is swept."""
    e = float(satellite(*body.tle).model.ecco) if body.tle is not None else 0.0
    return float(min(600.0, max(10.0, period_s(body) / 90.0 / ((1 + e) / (1 - e)) ** 1.5)))


def _pass(
    station: Any, body: Body, aos: float, los: float, tops: list[float] | None = None
) -> Pass:
    """Rule 4: the pass from aos to los, its top the highest culmination in it (``tops``, when
    a search found them already) or an end."""
    import numpy as np

    if tops is None:
        events = _events(station, body, (aos, los), (aos, los), -90.0, TOP)
        tops = [t for t, k in events if k == TOP and aos < t < los]
    # and samples across it: a search cut short (rule 3) can miss the top it ends near
    times = np.array([aos, los, *tops, *np.linspace(aos, los, _TOP_SAMPLES)])
    az, el = altaz(station, body, times)
    k = int(np.argmax(np.nan_to_num(el, nan=-180.0)))
    return Pass(
        aos_s=aos,
        los_s=los,
        max_s=float(times[k]),
        max_el_deg=float(el[k]),
        aos_az_deg=float(az[0]),
        los_az_deg=float(az[1]),
    )
