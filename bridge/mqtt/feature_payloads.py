"""The status's blocks of the features that propose targets, rendered: following WSJT-X
(``following``, ``R/follow/state``: engine/follow.py) and the wind park (``wind``:
engine/wind.py). Pure, beside payloads.py, which puts them into ``R/status``.
"""

from __future__ import annotations

from datetime import UTC, datetime

from bridge.model import FollowingInfo, RotatorStatus, WindInfo


def following_json(info: FollowingInfo) -> dict[str, object]:
    """The status's ``following`` block: whom WSJT-X names, and where the rotor was turned."""
    return {
        "source": info.source,
        "path": info.path,
        "call": info.call,
        "grid": info.grid,
        "bearing": None if info.bearing_deg is None else round(info.bearing_deg, 1),
        "distance_km": None if info.distance_km is None else round(info.distance_km, 1),
        "held": info.held,
    }


def wind_json(info: WindInfo) -> dict[str, object]:
    """The status's ``wind`` block (engine/wind.py)."""
    calm = info.calm_since_unix
    return {
        "speed_kmh": info.speed_kmh,
        "storm": info.storm,
        "calm_since": None if calm is None else _iso(calm),
        "silent": info.silent,
    }


def follow_state(status: RotatorStatus) -> str:
    """``R/follow/state``: what is followed (``wsjtx``), or ``off``."""
    return status.following.source if status.following is not None else "off"


def _iso(time_unix: float) -> str:
    return datetime.fromtimestamp(time_unix, UTC).isoformat(timespec="milliseconds")
