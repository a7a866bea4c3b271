"""The wind-aware park, as one feature (bridge/feature.py): a rotator with a ``wind_topic``
parks for a storm and refuses motion until the wind has calmed.

What it is made of:
- its keys in ``[[rotators]]``: settings/wind.py ``WindFields`` (the rotator's table includes
  them; the settings' layer sits below the MQTT parts this package uses);
- its session part: session/wind.py ``WindPark``, run by the session's step as ``PART`` here
  says (the registry's order is the step's);
- its input: the user's wind topic, read by feed.py;
- here: its ``wind`` block in ``R/status``, its Home Assistant sensors (the speed, unknown
  while the topic is silent; the storm, on only for a storm the rotor is parked or parking
  for, not one known only from a replay, one whose park a stop cut short, one whose park
  waits for the lock OFF nor one the rotor stands off: a stall, a hand) and its declaration.
"""

from __future__ import annotations

from collections.abc import Sequence
from datetime import UTC, datetime
from typing import Any

from pydantic import BaseModel

from bridge.core.model import RotatorStatus, WindInfo
from bridge.feature import EntityRow, Feature, Input, RotatorView, StatusBlock
from bridge.features.wind.feed import wind_feed
from bridge.session.parts import Part, Wake
from bridge.session.session import RotatorSession
from bridge.session.wind import WindPark
from bridge.settings.wind import WindFields

NAME = "wind"


def wind_json(info: WindInfo) -> dict[str, object]:
    """The status's ``wind`` block (session/wind.py)."""
    calm = info.calm_since_unix
    return {
        "speed_kmh": info.speed_kmh,
        "storm": info.storm,
        "replayed": info.replayed,
        # a STOP or lock ON stopped this storm's park before the rotor was seen there (wind.py
        # rules 3 and 7): it stands where the stop left it, and the park is not tried again
        "halted": info.halted and not info.arrived,
        # its park is owed and not sent: the lock holds it back (wind.py rule 4), or the
        # controller does not answer (rule 7); the rotor stands where it was
        "waiting": info.waiting,
        # the judge refused its park (wind.py rule 5): the rotor stands where the storm found it
        "refused": info.refused,
        # its park was sent and the rotor stands off it: its turn ended short (a stall), or a
        # hand turned it off after it was reached (wind.py rule 10); the refusal says where
        "off_park": info.off_park,
        "calm_since": None
        if calm is None
        else datetime.fromtimestamp(calm, UTC).isoformat(timespec="milliseconds"),
        "silent": info.silent,
    }


def _wind(status: RotatorStatus) -> WindInfo | None:
    return status.wind


def _speed(r: RotatorView) -> dict[str, object]:
    """The last reading; unknown while the topic is silent (session/wind.py rule 4), not that
    reading as if it were the wind now (a review: a station dead for hours showed its last
    108 km/h, in the statistics too)."""
    return {
        "state_topic": r.topics.status, "unit_of_measurement": "km/h",
        "device_class": "wind_speed", "state_class": "measurement",
        "value_template": "{{ value_json.wind.speed_kmh if value_json.wind is defined and "
                          "value_json.wind.speed_kmh is not none and not value_json.wind.silent "
                          "else 'None' }}",
    }  # fmt: skip


def _storm(r: RotatorView) -> dict[str, object]:
    """On while the rotor is parked, or parking, for a storm: not for a storm known only from a
    replayed reading, which parks nothing (session/wind.py rule 6), nor for one whose park a
    STOP or lock ON stopped short (rule 3), nor for one whose park waits for the lock OFF (rule
    4), nor once the rotor stands off the park sent (rule 10: a stall cut it short, a hand
    turned it off). A review: Home Assistant said "Parked for the storm" while the rotor stood
    where it was, or where the stop or the lock left it."""
    return {
        "state_topic": r.topics.status, "icon": "mdi:weather-windy",
        "value_template": "{{ 'ON' if value_json.wind is defined and value_json.wind.storm and "
                          "not value_json.wind.replayed and not value_json.wind.halted and "
                          "not value_json.wind.waiting and not value_json.wind.refused and "
                          "not value_json.wind.off_park else 'OFF' }}",
    }  # fmt: skip


def _configured(r: BaseModel) -> bool:
    return isinstance(r, WindFields) and r.wind_topic is not None


def _replayed(r: BaseModel) -> str | None:
    """Feed.py rule 2: a reading the broker replays says so by its retain flag."""
    return r.wind_topic if isinstance(r, WindFields) else None


def _inputs(pairs: Sequence[tuple[Any, Any]]) -> Input:
    """Each rotator's wind topic, read into its ``wind`` (runtime/rotator.py)."""
    entries = [(r.wind_topic, r.wind_unit, rot.wind) for r, rot in pairs if _configured(r)]
    return Input(*wind_feed(entries))


def _reset(s: RotatorSession, now: float) -> None:
    # a storm goes on (refusing is the safe side); a park stopped stays stopped (wind.py rule 3),
    # and one seen reached is not sent again (rule 7); one known only from a replay parks
    # nothing (rule 6)
    w = s.wind
    s.wind = WindPark(
        s.cfg,
        storm=w.storm,
        halted=w.park_halted,
        arrived=w.park_arrived,
        replayed=w.park_replayed,
        storms=w.storms,  # (the same storm's park: mailbox.py rule 10b)
    )


# its session part (parts.py rule 4)
PART: Part[RotatorSession] = Part(
    "wind",
    Wake.STEP,  # the silence of its sensor is counted in time
    True,
    lambda s: s.wind.on,
    lambda s, scene: s.wind.step(scene),
    _reset,
    lambda s, now: s.wind.wakeup(now),
)

FEATURE = Feature(
    name=NAME,
    docs="docs/wind.md",
    summary="parks for a storm from a wind speed on MQTT and refuses motion until it calms",
    status=(StatusBlock("wind", _wind, wind_json),),
    entities=(
        EntityRow("sensor", "wind", "Wind", _speed, needs=NAME, after="distance"),
        EntityRow(
            "binary_sensor", "storm", "Parked for the storm", _storm, needs=NAME, after="distance"
        ),
    ),
    rotator_settings=WindFields,
    settings_section=(
        "Wind (per rotator)",
        "Parking for a storm, from a wind speed published on MQTT.",
    ),
    configured=_configured,
    inputs=_inputs,
    replayed=_replayed,
    part=PART,
)
