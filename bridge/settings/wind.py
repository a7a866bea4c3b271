"""The wind-aware park's part of ``[[rotators]]``: where the wind speed comes from and when the
rotator parks for a storm (session/wind.py decides).

Rules:
1. Off unless ``wind_topic`` is set. With it, ``wind_park_above`` is needed, and a place to
   park: ``wind_park_az_deg`` or the rotator's ``park_az_deg``. Either is judged as a live
   target would be, when the settings are read (settings/pointing.py ``check_position``): a
   storm park in a keep-out sector or past a limit would be refused in the storm, the antenna
   left facing the wind. (``wind_park_az_deg`` without a ``wind_topic`` is not used, nor
   judged: a configuration that loaded before still loads.)
2. ``wind_release_below`` is at most ``wind_park_above`` (the same value unless given): a
   gust around one threshold must not park and release the rotor again and again, and the
   hold time (``wind_hold_min``) stands between the two anyway.
   Both are at most MAX_LEVEL_KMH in km/h, whatever ``wind_unit``: the feed drops every
   reading over features/wind/feed.py's WIND_MAX_KMH as a sensor's fault (its rule 3), and a
   level of 300 m/s (1,080 km/h), which the bound of 500 taken in the user's unit let
   through, never parked: no reading that is kept can pass it (an attack pass).
3. The topic is one topic, no wildcard: one sensor's reading, not a whole weather station;
   and none of the bridge's own (a rotator's, a group's, the bridge's: settings/config.py
   ``_wind_topics``), where no weather station publishes. Under a rotator's topic only its
   words are its own: a lone rotator's topic is the base topic, and ``rotor/weather/wind``
   beside them is taken, as with two rotators.
4. Every key carries its meaning (``description``) for docs/configuration.md.
"""

from __future__ import annotations

import math
from typing import Literal

from pydantic import Field, model_validator

from bridge.core.text import NOT_TEXT, bad_char
from bridge.settings.base import Strict

KMH_PER_MS = 3.6
MAX_LEVEL_KMH = 500.0  # rule 2: below the feed's WIND_MAX_KMH, in km/h whatever the unit


class WindFields(Strict):
    """The wind part of ``[[rotators]]``."""

    wind_topic: str | None = Field(
        None,
        description="an MQTT topic carrying the wind speed as a number (a weather station, "
        "Home Assistant's statestream of a wind sensor): above wind_park_above the rotator "
        "parks and refuses motion until the wind has calmed",
        examples=["homeassistant/sensor/wind_speed/state"],
        json_schema_extra={"unset": "no wind-aware park"},
    )
    wind_unit: Literal["km/h", "m/s"] = Field(
        "km/h",
        description='the unit of the numbers on wind_topic, "km/h" or "m/s" (the thresholds '
        "are in the same unit)",
        examples=["m/s"],
    )
    wind_park_above: float | None = Field(
        None,
        gt=0,
        le=500,
        description="park for the storm when a reading is above this speed (needs wind_topic; "
        "at most 500 km/h, 138.8 m/s)",
        examples=[60],
        json_schema_extra={"unset": "none: needed with wind_topic"},
    )
    wind_release_below: float | None = Field(
        None,
        gt=0,
        le=500,
        description="the storm is over once the wind has stayed below this for wind_hold_min",
        examples=[40],
        json_schema_extra={"unset": "wind_park_above"},
    )
    wind_hold_min: float = Field(
        10.0,
        ge=0,
        le=1440,
        description="how long the wind must stay below wind_release_below before motion is "
        "allowed again, in minutes",
        examples=[30],
    )
    wind_park_az_deg: float | None = Field(
        None,
        ge=0,
        le=360,
        description="the true bearing this antenna faces a storm with (least wind load)",
        examples=[90],
        json_schema_extra={"unset": "park_az_deg"},
    )
    wind_silent_min: float = Field(
        15.0,
        gt=0,
        le=1440,
        description="a wind topic silent this long is reported (kind wind); the rotator keeps "
        "the state it had: a storm never ends for want of readings",
        examples=[5],
    )

    @model_validator(mode="after")
    def _wind(self) -> WindFields:
        """Rules 1-3."""
        if self.wind_topic is None:
            return self
        topic = self.wind_topic
        bad = bad_char(topic)
        if not topic.strip() or any(c in topic for c in "+#") or bad is not None:
            raise ValueError(
                "wind_topic: one topic, without wildcards (+, #)"
                + ("" if bad is None else f": it holds {bad}, {NOT_TEXT}")
            )
        if self.wind_park_above is None:
            raise ValueError("wind_topic needs wind_park_above (the speed to park above)")
        if self.wind_release_below is not None and self.wind_release_below > self.wind_park_above:
            raise ValueError("wind_release_below must be at most wind_park_above")
        kmh = self.wind_kmh(self.wind_park_above)
        if kmh is not None and kmh > MAX_LEVEL_KMH:  # rule 2 (wind_release_below is below it)
            raise ValueError(
                f"wind_park_above: {self.wind_park_above:g} {self.wind_unit} is {kmh:g} km/h; "
                f"it is at most {MAX_LEVEL_KMH:g} km/h "
                f"({math.floor(MAX_LEVEL_KMH / KMH_PER_MS * 10) / 10:g} m/s): no wind measured "
                "came near, and a reading over 1000 km/h is dropped as a sensor's fault"
            )
        if self.wind_park_az_deg is None and getattr(self, "park_az_deg", None) is None:
            raise ValueError("wind_topic needs wind_park_az_deg or park_az_deg (where to park)")
        return self

    def wind_kmh(self, value: float | None) -> float | None:
        """A threshold of this rotator's unit in km/h."""
        return None if value is None else to_kmh(value, self.wind_unit)


def to_kmh(value: float, unit: str) -> float:
    """A speed in ``unit`` (a ``wind_unit``: km/h or m/s) in km/h: a threshold here, a reading
    in the feed (features/wind/feed.py rule 1)."""
    return value * KMH_PER_MS if unit == "m/s" else value
