"""The wind topics (bridge/features/wind/feed.py) and the wind keys (bridge/settings/wind.py):
readings to km/h for the rotators whose topic it is, junk dropped and logged rarely, settings
refused with the key named."""

from __future__ import annotations

import logging
import math
from typing import Any

import pytest
from pydantic import ValidationError

from bridge.features.wind.feed import BAD_LOG_S, wind_feed
from bridge.interfaces.mqtt.connection import command_filters
from bridge.settings import RotatorSettings
from tests.support.clock import FakeClock


def test_readings_reach_the_rotators_of_their_topic_in_km_h(
    caplog: pytest.LogCaptureFixture,
) -> None:
    got: list[tuple[str, float, bool]] = []
    clock = FakeClock()
    subs, handle = wind_feed(
        [
            ("w/kmh", "km/h", lambda v, r: got.append(("a", v, r))),
            ("w/ms", "m/s", lambda v, r: got.append(("b", v, r))),
            ("w/kmh", "km/h", lambda v, r: got.append(("c", v, r))),
        ],
        clock,
    )
    assert subs == ["w/kmh", "w/ms"]
    assert handle("w/kmh", b"12.5", False) and handle("w/ms", b" 10 ", True)  # replayed: taken
    assert got == [("a", 12.5, False), ("c", 12.5, False), ("b", 36.0, True)]  # ... as replayed
    assert not handle("other/topic", b"99", False)  # not the feed's
    caplog.set_level(logging.WARNING, "bridge.features.wind.feed")
    for junk in (b"calm", b"-3", b"nan", b'{"speed": 3}', b""):
        assert handle("w/kmh", junk, False)  # the feed's, dropped
    assert len(got) == 3 and len(caplog.records) == 1  # logged once per BAD_LOG_S
    clock.t += BAD_LOG_S
    handle("w/kmh", b"inf", False)
    assert len(caplog.records) == 2


def test_a_reading_no_wind_can_have_is_dropped_in_either_unit(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """An attack pass: ``1e308`` in m/s was finite, became infinite km/h, started a storm
    and put ``Infinity`` (no JSON) in R/status. Over WIND_MAX_KMH is a sensor's fault."""
    got: list[float] = []
    subs, handle = wind_feed([("w/ms", "m/s", lambda v, r: got.append(v))], FakeClock())
    caplog.set_level(logging.WARNING, "bridge.features.wind.feed")
    for junk in (b"1e308", b"300"):  # 300 m/s: 1,080 km/h
        assert handle("w/ms", junk, False)
    assert got == [] and "over 1000 km/h" in caplog.text
    assert handle("w/ms", b"250", False) and got == [900.0]  # 900 km/h: a reading


@pytest.mark.parametrize("unit", ["km/h", "m/s"])
def test_a_reading_of_minus_zero_reaches_the_rotator_as_zero(unit: str) -> None:
    """Attack 28: ``-0`` is not below 0 and was taken with its sign: R/status said -0.0."""
    got: list[float] = []
    subs, handle = wind_feed([("w", unit, lambda v, r: got.append(v))], FakeClock())
    assert handle("w", b"-0", False) and handle("w", b"-0.0e5", False)
    assert [math.copysign(1.0, v) for v in got] == [1.0, 1.0], got


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


def test_a_wind_topic_is_subscribed_so_that_the_retain_flag_says_replayed() -> None:
    """connection.py rule 1: commands keep retain-as-published (a retained command is known
    as such); the wind topic goes without it, so the broker sets the retain flag only on what
    it replays on subscribing (as MQTT 3.1.1 does for every topic)."""
    filters = dict(
        command_filters(["r/target", "r/stop", "w"], frozenset({"r/stop"}), True, frozenset({"w"}))
    )
    assert filters["r/target"].retainAsPublished and filters["r/stop"].retainAsPublished
    assert filters["r/stop"].retainHandling == 2
    assert not filters["w"].retainAsPublished and filters["w"].retainHandling == 0
    assert command_filters(["w"], frozenset(), False, frozenset({"w"})) == [("w", 0)]


def test_a_park_level_in_m_s_that_no_reading_can_pass_is_refused() -> None:
    """An attack pass: ``wind_park_above`` was bounded at 500 in the rotator's own unit, so
    ``wind_unit = "m/s"`` and ``wind_park_above = 300`` (1,080 km/h) loaded, and check-config
    said nothing; but every reading above it is over WIND_MAX_KMH and dropped as a sensor's
    fault (feed.py rule 3): that rotator never parked for any storm. The bound is 500 km/h
    in either unit (``wind_release_below`` is at most the park level, so it holds too)."""
    _, handle = wind_feed([("w", "m/s", lambda v, r: None)], FakeClock())
    assert handle("w", b"301", False)  # (dropped: no reading above 300 m/s reaches a rotator)
    with pytest.raises(ValidationError, match=r"wind_park_above: 300 m/s is 1080 km/h"):
        rotator(wind_topic="w", wind_unit="m/s", wind_park_above=300, park_az_deg=0)
    ok = rotator(wind_topic="w", wind_unit="m/s", wind_park_above=25, park_az_deg=0)
    assert ok.wind_kmh(ok.wind_park_above) == 90.0
    assert rotator(wind_topic="w", wind_park_above=500, park_az_deg=0).wind_park_above == 500


def test_a_reading_too_high_in_one_rotators_unit_still_reaches_the_others(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """An attack pass: two rotators on one wind topic, one in km/h, one in m/s (one of the two
    set wrong). 300 is a storm in km/h, and 1,080 km/h in m/s, over WIND_MAX_KMH: the reading
    was dropped for both, and the rotator whose unit was right never parked for a 300 km/h
    wind. Feed.py rule 3 holds per rotator: each one's unit decides whether it is a reading."""
    got: list[tuple[str, float]] = []
    _, handle = wind_feed(
        [
            ("w", "km/h", lambda v, r: got.append(("a", v))),
            ("w", "m/s", lambda v, r: got.append(("b", v))),
        ],
        FakeClock(),
    )
    caplog.set_level(logging.WARNING, "bridge.features.wind.feed")
    assert handle("w", b"300", False)
    assert got == [("a", 300.0)]  # (b's 1,080 km/h is a sensor's fault: dropped, logged)
    assert "over 1000 km/h" in caplog.text
    assert handle("w", b"20", False) and got[1:] == [("a", 20.0), ("b", 72.0)]
