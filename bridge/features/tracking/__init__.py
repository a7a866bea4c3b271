"""Tracking the sun, the moon or a satellite, as one feature (bridge/feature.py).

What it is made of:
- its keys: ``track_*`` in ``[[rotators]]`` (settings/pointing.py), ``[tracking]`` (the TLE
  file) and ``[station]``;
- its session part: session/tracking.py ``Tracker`` (with session/skytrack.py; the sky worker,
  sky/worker.py, computes; started and ended as a command: session/feature_commands.py), run
  by the session's step as ``PART`` here says;
- ``R/track``'s payload: interfaces/mqtt/payloads.py ``parse_track`` (beside the other commands'
  words);
- here: ``R/track``, ``R/tracking``, its ``tracking`` and ``tracking_ended`` blocks in
  ``R/status``, its Home Assistant select and sensors, its declaration.
"""

from __future__ import annotations

import json
from datetime import UTC, datetime

from bridge.core.model import Origin, RotatorStatus, Source, TrackBody, TrackingInfo
from bridge.feature import CommandTopic, EntityRow, Feature, RotatorView, StateTopic, StatusBlock
from bridge.interfaces.mqtt.payloads import parse_track
from bridge.session.parts import Part, Wake
from bridge.session.session import RotatorSession

NAME = "tracking"
COMMAND = "track"  # R/track: sun, moon, a satellite's name or TLE, off
STATE = "tracking"  # R/tracking: what is tracked, or off
NEEDS = "can_track"  # a station and a controller that reports where it points
TRACK_OPTIONS = "track_options"  # RotatorInfo's: off, sun, moon and the TLE file's satellites
AFTER = "distance"  # its entities' place in discovery (bridge/feature.py rule 5)


def _track(payload: bytes, by: Origin) -> TrackBody:
    name, tle = parse_track(payload)
    return TrackBody(name, tle, source=Source.MQTT, origin=by)


def _iso(time_unix: float) -> str:
    return datetime.fromtimestamp(time_unix, UTC).isoformat(timespec="milliseconds")


def tracking_json(info: TrackingInfo) -> dict[str, object]:
    """The status's ``tracking`` block: the body now and in a minute, its pass, and a
    satellite's elements: their epoch, and whether they are stale."""
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
    if info.elements_epoch_unix is not None:  # session/tracking.py rule 11
        doc.update(
            elements_epoch=_iso(info.elements_epoch_unix),
            elements_stale=info.elements_stale,
            elements_ahead=info.elements_ahead,
        )
    return doc


def tracking_state(status: RotatorStatus) -> str:
    """``R/tracking``: what is followed, or ``off``."""
    return status.tracking.body if status.tracking is not None else "off"


def _status(status: RotatorStatus) -> RotatorStatus:
    return status


def _tracking(status: RotatorStatus) -> TrackingInfo | None:
    return status.tracking


def _ended(status: RotatorStatus) -> str | None:
    return status.tracking_ended


def _tracked(field: str) -> str:
    """A template for a field of the status's tracking block (unknown while not tracking)."""
    return (
        f"{{{{ value_json.tracking.{field} if value_json.tracking is defined and "
        f"value_json.tracking.{field} is defined else 'None' }}}}"
    )


def _select(r: RotatorView) -> dict[str, object]:
    options = list(getattr(r, TRACK_OPTIONS))  # RotatorInfo's (needs: it has some)
    return {
        "command_topic": r.topics.feature(COMMAND), "state_topic": r.topics.feature(STATE),
        # a body not among the options (a TLE sent whole, a satellite past the first of the
        # file's) is no option: Home Assistant kept showing "off" (a review)
        "value_template": f"{{{{ value if value in {json.dumps(options)} else 'None' }}}}",
        "options": options, "icon": "mdi:satellite-variant",
    }  # fmt: skip


def _azimuth(r: RotatorView) -> dict[str, object]:
    return {
        "state_topic": r.topics.status, "value_template": _tracked("azimuth"),
        "unit_of_measurement": "°", "state_class": "measurement_angle",
        "suggested_display_precision": 1, "icon": "mdi:compass-rose",
    }  # fmt: skip


def _elevation(r: RotatorView) -> dict[str, object]:
    return {
        "state_topic": r.topics.status, "value_template": _tracked("elevation"),
        "unit_of_measurement": "°", "state_class": "measurement",
        "suggested_display_precision": 1, "icon": "mdi:angle-acute",
    }  # fmt: skip


def _aos(r: RotatorView) -> dict[str, object]:
    return {
        "state_topic": r.topics.status, "value_template": _tracked("aos"),
        "device_class": "timestamp", "icon": "mdi:clock-start",
    }  # fmt: skip


# its session part (parts.py rule 4): the sky read by the time, so every step while it tracks
PART: Part[RotatorSession] = Part(
    "tracking",
    Wake.STEP,  # it reads the sky by the time
    True,
    lambda s: s.tracker.body is not None,  # (nothing tracked: nothing to ask)
    lambda s, scene: s.tracker.step(scene),
    lambda s, now: s.features.end("internal error", tracking=True),
    lambda s, now: s.tracker.wakeup(now),
)

FEATURE = Feature(
    name=NAME,
    docs="docs/tracking.md",
    check="bridge.features.tracking.check:check",  # check-config: the TLE file, read as run
    summary="follows the sun, the moon or a satellite across the sky",
    commands=(CommandTopic(COMMAND, "track", _track),),
    states=(StateTopic(STATE, _status, tracking_state, needs=NEEDS),),
    status=(
        StatusBlock("tracking", _tracking, tracking_json),
        StatusBlock("tracking_ended", _ended, str, kind=str),
    ),
    entities=(
        EntityRow("select", "track", "Track", _select, needs=TRACK_OPTIONS, after=AFTER),
        EntityRow(
            "sensor", "track_azimuth", "Tracked azimuth", _azimuth, needs=TRACK_OPTIONS, after=AFTER
        ),
        # asks for sensor.<id>_track_el: "_track_elevation" ends with "_elevation", which
        # rotator "sat"'s shared with rotator "sat_track"'s elevation (homeassistant/ rule 10)
        EntityRow(
            "sensor",
            "track_elevation",
            "Tracked elevation",
            _elevation,
            needs=TRACK_OPTIONS,
            after=AFTER,
            suffix="track_el",
        ),
        EntityRow("sensor", "next_aos", "Next AOS", _aos, needs=TRACK_OPTIONS, after=AFTER),
    ),  # fmt: skip
    part=PART,
    console=(
        "the tracking line and the pass on the sky plot (interfaces/web/static/console.js, sky.js)",
    ),
)
