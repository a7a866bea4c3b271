"""``R/health``, rendered: how the rotor turns (session/health.py), for MQTT clients, Home
Assistant's sensors and the console (``health`` in ``R/status``). Pure.

Rules:
1. Every field is always there; a value not measured yet is null (Home Assistant shows it
   unknown). Speeds, the start delay and the coast are the median of the recent moves; the
   baseline they are judged against is beside them, with where it came from.
2. A report is new only after a move: it is rendered once (``health_json`` keeps the last
   few), never at every status.
3. A controller that reports no position says so (``measured`` false) and nothing else.
"""

from __future__ import annotations

import json

from bridge.core.model import AxisHealth, RotatorHealth

_COMPACT = json.JSONEncoder(separators=(",", ":"))


def health_doc(health: RotatorHealth) -> dict[str, object]:
    """``R/health`` (and ``health`` in ``R/status``): how the rotor turns (session/health.py).
    A value not measured yet is null; speeds are the median of the recent moves."""
    if not health.measured:
        return {"measured": False, "reason": "the controller reports no position"}
    az = health.az
    doc: dict[str, object] = {
        "measured": True,
        "speed_cw_deg_s": _rounded(az.speed_up_deg_s, 2),
        "speed_ccw_deg_s": _rounded(az.speed_down_deg_s, 2),
        "start_delay_s": _rounded(health.start_delay_s, 2),
        "coast_deg": _rounded(az.coast_deg, 1),
        "arrival_error_deg": _rounded(az.arrival_error_deg, 1),
        "moves": health.moves,
        "stalls": health.stalls,
        "stall_azimuths": [round(a, 1) for a in health.stall_azimuths_deg],
        "odometer_deg": round(az.odometer_deg, 1),
        "motor_on_s": round(health.motor_on_s, 1),
    }
    if health.el is not None:
        doc.update(_el_health(health.el))
        doc["stall_elevations"] = [round(a, 1) for a in health.stall_elevations_deg]
    baseline: dict[str, object] = {
        "from": health.baseline_from,
        "moves_to_learn": health.baseline_moves_left,
        "speed_cw_deg_s": _rounded(az.baseline_up_deg_s, 2),
        "speed_ccw_deg_s": _rounded(az.baseline_down_deg_s, 2),
        "start_delay_s": _rounded(health.baseline_start_delay_s, 2),
        "coast_deg": _rounded(az.baseline_coast_deg, 1),
    }
    if health.el is not None:
        baseline["speed_up_deg_s"] = _rounded(health.el.baseline_up_deg_s, 2)
        baseline["speed_down_deg_s"] = _rounded(health.el.baseline_down_deg_s, 2)
    doc["baseline"] = baseline
    doc["warnings"] = list(health.warnings)
    return doc


def _el_health(el: AxisHealth) -> dict[str, object]:
    return {
        "speed_up_deg_s": _rounded(el.speed_up_deg_s, 2),
        "speed_down_deg_s": _rounded(el.speed_down_deg_s, 2),
        "el_coast_deg": _rounded(el.coast_deg, 1),
        "el_arrival_error_deg": _rounded(el.arrival_error_deg, 1),
        "el_odometer_deg": round(el.odometer_deg, 1),
    }


def health_json(health: RotatorHealth) -> str:
    """A report is new only after a move: rendered once, not at every status. Kept by the
    report itself (the same object in every status until the next move), so no status hashes
    the whole report to find its text."""
    kept = _rendered.get(id(health))
    if kept is not None and kept[0] is health:
        return kept[1]
    text = _COMPACT.encode(health_doc(health))
    if len(_rendered) >= _RENDERED_KEPT:
        _rendered.clear()
    _rendered[id(health)] = (health, text)  # (the report kept: its id is not another's)
    return text


_rendered: dict[int, tuple[RotatorHealth, str]] = {}
_RENDERED_KEPT = 64  # reports whose text is kept (a few per rotator)


def _rounded(value: float | None, digits: int) -> float | None:
    return None if value is None else round(value, digits)
