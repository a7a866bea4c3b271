"""What the page is told once per connection: the station, each rotator's fixed facts, and the
coastlines projected for this station. Pure but for reading the packaged land file.

Rules:
1. Bearings are true bearings (pointing.py rule 1): the page draws what the user named, and the
   judge has the last word on what a click may do (the page never decides a refusal).
2. ``unreachable_deg`` is the arc no target can reach: the mechanical limits' complement in true
   bearings (none on a rotor whose range spans 360 or more).
3. The land is projected here, not in the page: the station is fixed for the process, so it is
   done once (on a worker: a few thousand great circles, rule 12 of docs/architecture.md) and
   sent as integers. A ring is split where two neighbours land more than SPLIT apart on the
   disc (a coast that wraps round the antipode, the rim): only an unbroken ring may be filled.
   A ring round the antipode comes out unbroken but inside out (its projection encloses the
   centre, which it does not): it is drawn, not filled.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from importlib import resources

from bridge.interfaces.web.port import ConsoleRotator
from bridge.interfaces.web.projection import project
from bridge.pointing import norm360

SCALE = 1000  # map units per unit of the disc's radius
SPLIT = 0.25


@dataclass(frozen=True)
class RotatorFacts:
    """What the settings say of a rotator beyond the judge's terms (app.py hands them in)."""

    beamwidth_deg: float = 60.0
    nudge_step_deg: float = 5.0


def rotator_doc(
    rot: ConsoleRotator, facts: RotatorFacts, satellites: list[str]
) -> dict[str, object]:
    p = rot.pointing
    spec = rot.spec
    unreachable: list[list[float]] = []
    if p.az_max_deg - p.az_min_deg < 360.0:  # rule 2
        unreachable.append([p.true_of(p.az_max_deg), p.true_of(p.az_min_deg)])
    lo, hi = p.target_range()
    return {
        "id": rot.id,
        "name": rot.name,
        "model": spec.display_name,
        "has_elevation": spec.has_elevation,
        "can_track": rot.can_track,
        "can_report_position": spec.can_report_position,
        "beamwidth_deg": facts.beamwidth_deg,
        "az_range_deg": [lo, hi],
        "el_range_deg": [p.el_min_deg, p.el_max_deg] if spec.has_elevation else None,
        "unreachable_deg": unreachable,
        "keep_out_deg": [[norm360(a), norm360(b)] for a, b in p.keep_out],
        "presets": {name: [az, el] for name, (az, el) in p.presets.items()},
        "park": list(p.park) if p.park is not None else None,
        "nudge_step_deg": facts.nudge_step_deg,
        "satellites": satellites if rot.can_track else [],
        "options": sorted(spec.options),
    }


def station_doc(station: tuple[float, float] | None, locator: str | None) -> object:
    if station is None:
        return None
    return {"latitude_deg": station[0], "longitude_deg": station[1], "locator": locator}


def land_rings() -> list[list[list[float]]]:
    """Natural Earth's land rings, [longitude, latitude] each
    (bridge/interfaces/web/land-110m.json)."""
    text = resources.files("bridge.interfaces.web").joinpath("land-110m.json").read_text("utf-8")
    rings: list[list[list[float]]] = json.loads(text)["rings"]
    return rings


def land_doc(station: tuple[float, float], rings: list[list[list[float]]]) -> dict[str, object]:
    """Rule 3: ``{"scale", "rings": [[x0, y0, x1, y1, ...]], "closed": [...]}``."""
    out: list[list[int]] = []
    closed: list[bool] = []
    for ring in rings:
        pieces: list[list[tuple[float, float]]] = [[]]
        for lon, lat in ring:
            x, y = project(station, lat, lon)
            piece = pieces[-1]
            if piece and math.dist(piece[-1], (x, y)) > SPLIT:
                pieces.append([])
            pieces[-1].append((x, y))
        if len(pieces) > 1 and pieces[0] and pieces[-1]:  # the ring's ends meet: one piece
            head = pieces.pop(0)
            pieces[-1].extend(head)
        whole = len(pieces) == 1 and not _inside_out(pieces[0], ring, station)
        for piece in pieces:
            if len(piece) < 2:
                continue
            out.append([round(v * SCALE) for point in piece for v in point])
            closed.append(whole)
    return {"scale": SCALE, "rings": out, "closed": closed}


def _winds_round_centre(points: list[tuple[float, float]]) -> bool:
    """Whether the closed polyline goes round (0, 0): its angles add up to a full turn."""
    turn = 0.0
    for (x0, y0), (x1, y1) in zip(points, points[1:] + points[:1], strict=True):
        step = math.atan2(y1, x1) - math.atan2(y0, x0)
        turn += (step + math.pi) % (2 * math.pi) - math.pi
    return abs(turn) > math.pi


def _holds(ring: list[list[float]], lat: float, lon: float) -> bool:
    """Whether (lat, lon) lies in the ring, counted on the longitude-latitude plane."""
    inside = False
    for (x0, y0), (x1, y1) in zip(ring, ring[1:] + ring[:1], strict=True):
        if (y0 > lat) != (y1 > lat) and lon < x0 + (lat - y0) * (x1 - x0) / (y1 - y0):
            inside = not inside
    return inside


def _inside_out(
    points: list[tuple[float, float]], ring: list[list[float]], station: tuple[float, float]
) -> bool:
    """Rule 3: a ring whose projection encloses the centre without holding the station holds
    the antipode."""
    return _winds_round_centre(points) and not _holds(ring, *station)
