"""The pointing settings: where the station is, and each rotator's offset, presets, park and
keep-out sectors (pointing.py) and its beamwidth (drawn by the console, judged by nothing).
settings/'s models include these; every value is judged here once, with the same judge as a
live command, so a preset or park position that could never be reached is a configuration
error naming the field, not a refusal at the worst moment.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Literal

from pydantic import BeforeValidator, Field, field_validator, model_validator

from bridge.core import geo
from bridge.core.errors import Refused
from bridge.core.model import Target
from bridge.core.text import NOT_TEXT, bad_char
from bridge.pointing import Pointing, norm360
from bridge.protocols.base import ModelSpec
from bridge.settings.base import Strict

PRESET_NAME_MAX = 32
Degrees = Annotated[float, Field(allow_inf_nan=False)]


def _a_number(value: object) -> bool:
    """A finite number, or text that reads as one (the environment's and lax mode's)."""
    if isinstance(value, bool):  # (a boolean: refused as one by base.py first)
        return True
    try:
        return isinstance(value, int | float | str) and math.isfinite(float(value))
    except (ValueError, OverflowError):
        return False


def _bearing_or_two(value: object) -> object:
    """A preset is a number or a list of numbers (``_two_numbers`` judges the list's length):
    anything else is one line naming the preset, where pydantic's union gave two, each named
    after one of its branches (``rotators[0].presets.EU.float``, ``...EU.list[float]``; attack
    18's loose end: ``ROTOR_BRIDGE_ROTATORS__TOWER__PRESETS__EU=abc``, or ``EU = "abc"`` in the
    file; review 69: a list whose elevation is no number, ``SAT = [180, "high"]``, ``[180,
    nan]``, was still the two)."""
    if isinstance(value, list):
        if all(_a_number(item) for item in value):
            return value
        raise ValueError(
            "a preset is a bearing (a number) or [azimuth, elevation], two finite numbers"
        )
    if _a_number(value):
        return value
    raise ValueError("a preset is a bearing (a number) or [azimuth, elevation]")


Preset = Annotated[Degrees | list[Degrees], BeforeValidator(_bearing_or_two)]


class StationSettings(Strict):
    """``[station]``: where the antenna is; needed for targets by locator or coordinates and
    for tracking."""

    locator: str | None = Field(
        None,
        description="the station's Maidenhead locator (2, 4, 6 or 8 characters); or "
        "latitude_deg and longitude_deg, not both. check-config shows where it puts you.",
        examples=["JO62qm"],
        json_schema_extra={"unset": "no station: targets by locator or sky object are refused"},
    )
    latitude_deg: float | None = Field(
        None,
        ge=-90,
        le=90,
        description="the station's latitude, north positive (with longitude_deg)",
        examples=[52.52],
        json_schema_extra={"unset": "see locator"},
    )
    longitude_deg: float | None = Field(
        None,
        ge=-180,
        le=180,
        description="the station's longitude, east positive (with latitude_deg)",
        examples=[13.40],
        json_schema_extra={"unset": "see locator"},
    )

    @model_validator(mode="after")
    def _one_way(self) -> StationSettings:
        coords = (self.latitude_deg, self.longitude_deg)
        if self.locator is not None:
            if coords != (None, None):
                raise ValueError("give locator or latitude_deg/longitude_deg, not both")
            try:
                geo.parse_locator(self.locator)
            except geo.LocatorError as exc:
                raise ValueError(f"locator: {exc}") from None
        elif (self.latitude_deg is None) != (self.longitude_deg is None):
            raise ValueError("latitude_deg and longitude_deg go together")
        return self

    @property
    def position(self) -> tuple[float, float] | None:
        """(latitude, longitude) of the station, or None when not configured."""
        if self.locator is not None:
            return geo.parse_locator(self.locator)
        if self.latitude_deg is None or self.longitude_deg is None:
            return None
        return self.latitude_deg, self.longitude_deg


class TrackingSettings(Strict):
    """``[tracking]``: where satellites' orbital elements come from (never downloaded). Each
    rotator's tracking keys are in ``[[rotators]]``."""

    tle_file: Path | None = Field(
        None,
        description="a TLE file (Celestrak's 3-line form) naming the satellites that can be "
        "tracked; re-read when it changes, so refresh it with cron. The sun and the moon need "
        "no file. A regular file of 4 MiB at most; a secret's file (a password file, the TLS "
        "key, the console's secret) or the configuration file is refused.",
        examples=["/var/lib/rotor-bridge/amateur.tle"],
        json_schema_extra={"unset": "satellites cannot be tracked (the sun and the moon can)"},
    )


class PointingFields(Strict):
    """The pointing part of ``[[rotators]]`` (the rotator's model supplies spec and limits)."""

    az_offset_deg: Degrees = Field(
        0.0,
        ge=-360,
        le=360,
        description="true bearing = the controller's bearing + this (a south-centred scale: "
        "180; a rotor mounted off north). Presets, park, keep-out and targets are true "
        "bearings; az_min_deg/az_max_deg stay on the controller's scale.",
        examples=[180],
    )
    presets: dict[str, Preset] = Field(
        default_factory=dict,
        description="named true bearings for R/preset and Home Assistant's select; on az/el "
        "models [azimuth, elevation]",
        examples=[{"EU": 45, "JA": 330}],
        json_schema_extra={"unset": "no presets"},
    )
    park_az_deg: Degrees | None = Field(
        None,
        description="where to park, a true bearing: R/park, Home Assistant's button, rotctld's "
        "K, park_after_idle_s and track_at_los",
        examples=[0],
        json_schema_extra={"unset": "park is refused"},
    )
    park_el_deg: Degrees | None = Field(
        None,
        description="the parking elevation (az/el models only; needs park_az_deg)",
        examples=[90],
        json_schema_extra={"unset": "the elevation is left as it is"},
    )
    park_after_idle_s: float = Field(
        0.0,
        ge=0,
        le=86400,
        description="park after this long without a command: 0 never, else at least 5 "
        "(needs park_az_deg)",
        examples=[1800],
    )
    keep_out: list[tuple[Degrees, Degrees]] = Field(
        default_factory=list,
        description="sectors never to point into, each [first, second] true bearing, clockwise "
        "from the first edge to the second",
        examples=[[[200, 220]]],
        json_schema_extra={"unset": "no sectors"},
    )
    nudge_step_deg: float = Field(
        10.0,
        gt=0,
        le=180,
        description="Home Assistant's nudge buttons turn this far",
        examples=[5],
    )
    beamwidth_deg: float = Field(
        60.0,
        gt=0,
        le=360,
        description="the antenna's beamwidth (half-power, full angle), drawn as the wedge "
        "around the beam on the console's map; nothing else uses it",
        examples=[30],
    )
    track_min_el_deg: float = Field(
        0.0,
        ge=-5,
        le=80,
        description="tracking (R/track, needs [station]): below this elevation the rotator "
        "waits where the next pass rises",
        examples=[5],
    )
    track_step_deg: float | None = Field(
        None,
        gt=0,
        le=45,
        description="tracking sends a new target when the body has moved this far",
        examples=[2],
        json_schema_extra={"unset": "tolerance_deg"},
    )
    track_at_los: Literal["stay", "park"] = Field(
        "stay",
        description='at the end of a pass: "stay", or "park" (needs park_az_deg)',
        examples=["park"],
    )
    follow_hold_while_tx: bool = Field(
        True,
        description="following WSJT-X (R/follow): a new station's bearing waits until the "
        "transmission ends (a beam turning while transmitting is hard on some amplifiers and "
        "feed lines)",
        examples=[False],
    )

    @field_validator("az_offset_deg")
    @classmethod
    def _one_turn(cls, offset: float) -> float:
        """-180 and 180 (or 270 and -90) turn the same way; kept in (-180, 180] so one setup has
        one range of targets on a rotor that can pass 360 (check-config shows the value)."""
        # whole turns only, added exactly: (offset + 180) % 360 - 180 would turn 0.3 into
        # 0.30000000000001137 and refuse targets a hair inside a limit
        while offset > 180.0:
            offset -= 360.0
        while offset <= -180.0:
            offset += 360.0
        return offset + 0.0  # never -0.0

    @field_validator("presets")
    @classmethod
    def _two_numbers(
        cls, presets: dict[str, float | list[float]]
    ) -> dict[str, float | list[float]]:
        """A preset's list is [azimuth, elevation], judged before the judge's terms are made of
        it (pointing_for): an attack pass: ``presets = { EU = [] }`` ended check-config and run
        in an IndexError traceback, and ``[45]`` on an az/el model was said to need one."""
        for name, value in presets.items():
            if isinstance(value, list) and len(value) != 2:
                raise ValueError(
                    f"{name!r}: [azimuth, elevation] is two numbers, not {len(value)}; "
                    "or one number, the azimuth"
                )
        return presets

    def pointing_for(
        self, spec: ModelSpec, az_limits: tuple[float, float], el_limits: tuple[float, float]
    ) -> Pointing:
        """These fields as the judge's terms, on ``spec`` with the rotator's effective limits."""
        park = None
        if self.park_az_deg is not None:
            park = (self.park_az_deg, self.park_el_deg)
        return Pointing.of(
            spec,
            az_limits,
            el_limits if spec.has_elevation else None,
            offset_deg=self.az_offset_deg,
            keep_out=tuple(self.keep_out),
            presets={name: _preset(v) for name, v in self.presets.items()},
            park=park,
        )

    def check_pointing(self, pointing: Pointing) -> None:
        """Every preset and the park position judged by ``pointing`` (this rotator's, from
        pointing_for) as a live target would be (ValueError)."""
        for i, (start, end) in enumerate(self.keep_out):
            if not (0 <= start <= 360 and 0 <= end <= 360) or norm360(start) == norm360(end):
                raise ValueError(
                    f"keep_out[{i}]: edges are bearings 0..360, clockwise from the first to the "
                    f"second, and differ (got {start:g}, {end:g})"
                )
        for name, value in self.presets.items():
            bad = bad_char(name)  # (an attack pass: R/preset refuses it, payloads.py)
            if bad is not None:
                raise ValueError(
                    f"presets: name {name!r} holds {bad}, {NOT_TEXT}: R/preset and Home "
                    "Assistant's select could never pick it"
                )
            if not name.strip() or name != name.strip() or len(name) > PRESET_NAME_MAX:
                raise ValueError(
                    f"presets: name {name!r} must be 1..{PRESET_NAME_MAX} characters "
                    "without leading or trailing spaces"
                )
            if isinstance(value, list) and (len(value) != 2 or not pointing.has_elevation):
                raise ValueError(
                    f"presets.{name}: [azimuth, elevation] only on a rotator with elevation; "
                    "else one number"
                )
        if self.park_el_deg is not None and (
            self.park_az_deg is None or not pointing.has_elevation
        ):
            raise ValueError("park_el_deg needs park_az_deg and an elevation axis")
        if self.track_at_los == "park" and self.park_az_deg is None:
            raise ValueError('track_at_los = "park" needs park_az_deg (where to park)')
        if self.park_after_idle_s > 0 and self.park_az_deg is None:
            raise ValueError("park_after_idle_s needs park_az_deg (where to park)")
        if 0 < self.park_after_idle_s < 5:
            raise ValueError("park_after_idle_s must be 0 (never) or at least 5 s")
        named = [(f"presets.{n}", az, el) for n, (az, el) in pointing.presets.items()]
        if pointing.park is not None:  # (an elevation refused names the key that holds it)
            keys = "park_az_deg" if self.park_el_deg is None else "park_az_deg, park_el_deg"
            named.append((keys, *pointing.park))
        for field, az, el in named:
            check_position(pointing, field, az, el)


def check_position(pointing: Pointing, field: str, az: float, el: float | None) -> None:
    """A position the bridge turns to by itself (a preset, a park) judged by ``pointing`` as a
    live target would be: one it could never reach is a ValueError naming ``field``."""
    if not math.isfinite(az) or not 0 <= az <= 360 and pointing.az_wraps:
        raise ValueError(f"{field}: azimuth {az:g} must be a bearing 0..360")
    try:
        pointing.judge(Target(az, el), None)
    except Refused as exc:
        raise ValueError(f"{field}: {exc.message}") from None


def _preset(value: float | list[float]) -> tuple[float, float | None]:
    if isinstance(value, list):
        return value[0], value[1] if len(value) > 1 else None
    return value, None
