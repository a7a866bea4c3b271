"""The status's block of tracking, rendered (``tracking``, ``R/tracking``: engine/tracking.py).
Pure, beside payloads.py, which puts it into ``R/status``. (The blocks of the registered
features are their packages': bridge/features/.)
"""

from __future__ import annotations

from datetime import UTC, datetime

from bridge.model import RotatorStatus, TrackingInfo


def tracking_json(info: TrackingInfo) -> dict[str, object]:
    """The status's ``tracking`` block: the body now and in a minute, and its pass."""
    doc: dict[str, object] = {
        "body": info.body,
        "phase": info.phase,
        "azimuth": info.azimuth_deg,
        "elevation": info.elevation_deg,
        "next": {"azimuth": info.next_azimuth_deg, "elevation": info.next_elevation_deg},
    }
    if info.aos_unix is not None and info.los_unix is not None:
        doc.update(
            aos=_iso(info.aos_unix),
            los=_iso(info.los_unix),
            max_elevation=info.max_elevation_deg,
            aos_azimuth=info.aos_azimuth_deg,
        )
    if info.pass_track:
        doc["pass_track"] = [list(point) for point in info.pass_track]
    doc["flip"] = info.flip
    return doc


def tracking_state(status: RotatorStatus) -> str:
    """``R/tracking``: what is followed, or ``off``."""
    return status.tracking.body if status.tracking is not None else "off"


def _iso(time_unix: float) -> str:
    return datetime.fromtimestamp(time_unix, UTC).isoformat(timespec="milliseconds")
