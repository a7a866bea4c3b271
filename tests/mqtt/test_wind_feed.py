"""The wind topics (bridge/mqtt/wind.py) and the wind keys (bridge/settings_wind.py): readings
to km/h for the rotators whose topic it is, junk dropped and logged rarely, settings refused
with the key named."""

from __future__ import annotations

import logging
from typing import Any

import pytest
from pydantic import ValidationError

from bridge.mqtt.wind import BAD_LOG_S, wind_feed
from bridge.settings import RotatorSettings
from tests.support.clock import FakeClock


def test_readings_reach_the_rotators_of_their_topic_in_km_h(
    caplog: pytest.LogCaptureFixture,
) -> None:
    got: list[tuple[str, float]] = []
    clock = FakeClock()
    subs, handle = wind_feed(
        [
            ("w/kmh", "km/h", lambda v: got.append(("a", v))),
            ("w/ms", "m/s", lambda v: got.append(("b", v))),
            ("w/kmh", "km/h", lambda v: got.append(("c", v))),
        ],
        clock,
    )
    assert subs == ["w/kmh", "w/ms"]
    assert handle("w/kmh", b"12.5", False) and handle("w/ms", b" 10 ", True)  # retained: taken
    assert got == [("a", 12.5), ("c", 12.5), ("b", 36.0)]
    assert not handle("other/topic", b"99", False)  # not the feed's
    caplog.set_level(logging.WARNING, "bridge.mqtt.wind")
    for junk in (b"calm", b"-3", b"nan", b'{"speed": 3}', b""):
        assert handle("w/kmh", junk, False)  # the feed's, dropped
    assert len(got) == 3 and len(caplog.records) == 1  # logged once per BAD_LOG_S
    clock.t += BAD_LOG_S
    handle("w/kmh", b"inf", False)
    assert len(caplog.records) == 2


def rotator(**wind: Any) -> RotatorSettings:
    return RotatorSettings(id="t", model="rotorez", port="/x", **wind)


@pytest.mark.parametrize(
    ("wind", "says"),
    [
        ({"wind_topic": "w"}, "needs wind_park_above"),
        ({"wind_topic": "w", "wind_park_above": 60}, "wind_park_az_deg or park_az_deg"),
        ({"wind_topic": "w/#", "wind_park_above": 60, "park_az_deg": 0}, "without wildcards"),
        (
            {"wind_topic": "w", "wind_park_above": 60, "wind_release_below": 70, "park_az_deg": 0},
            "at most wind_park_above",
        ),
        ({"wind_unit": "knots"}, "wind_unit"),
    ],
)
def test_wind_settings_that_cannot_work_are_refused(wind: dict[str, Any], says: str) -> None:
    with pytest.raises(ValidationError, match=says):
        rotator(**wind)


def test_a_wind_park_of_its_own_or_the_park_position() -> None:
    assert rotator(wind_topic="w", wind_park_above=60, park_az_deg=0).wind_park_az_deg is None
    assert rotator(wind_topic="w", wind_park_above=60, wind_park_az_deg=90).wind_topic == "w"
