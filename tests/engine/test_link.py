"""The slew arithmetic of engine/link.py: how long a silent controller's move may take."""

from __future__ import annotations

import pytest

from bridge.engine.link import Slew


@pytest.mark.parametrize(
    ("start", "to", "expected_s"),
    [
        ((10.0, 5.0), (100.0, 20.0), 15.0),  # az 90 deg at 6: 15 s; el 15 deg at 2.5: 6 s
        ((10.0, 5.0), (20.0, 80.0), 30.0),  # the elevation decides
        ((350.0, 0.0), (10.0, 0.0), 340 / 6),  # the long way: no wrap past the north stop
        ((None, None), (100.0, 20.0), 360 / 6),  # start unknown: whole spans
    ],
)
def test_travel_time_is_the_slower_axis(
    start: tuple[float | None, float | None], to: tuple[float, float], expected_s: float
) -> None:
    slew = Slew(0.0, *start, *to)
    assert slew.travel_s(6.0, 2.5, 360.0, 90.0) == pytest.approx(expected_s)
