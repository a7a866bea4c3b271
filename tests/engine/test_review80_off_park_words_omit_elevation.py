"""Review 80: an az/el rotor whose storm park stalled on its elevation is said to stand at the
park's own azimuth.

16eb7df1 (wind.py rule 10) says where the rotor stands off the park sent, in the words of
Controller.where (stops.py ``standing``), which names the azimuth alone for a box that turns
the azimuth. An MD-01 at 90/40 whose storm park is 90/0: the elevation jams at 29 on its way
down (ice), the stall is said "at elevation 29°, azimuth 90°", and from then on every refusal
for the storm reads "its park not reached: the rotor stands at 90°" -- the park's azimuth, the
one axis that did reach it; the elevation that did not, the reason, is never named.

In virtual time on the emulated MD-01 (test_wind's ``windy``, park_el_deg 0)."""

from __future__ import annotations

from bridge.core.model import MotionState, Target
from tests.engine.test_wind import wind, windy

TURN_S = 120.0  # virtual
AFTER_S = 30.0  # virtual


def test_an_elevation_short_of_the_storm_park_is_named_in_the_refusal() -> None:
    with windy(park_el_deg=0) as v:
        v.command(Target(90.0, 40.0))
        v.run_until(
            lambda h: abs(h.truth().el_deg - 40.0) < 1.0 and h.state is MotionState.IDLE,
            TURN_S,
            "at rest at 90/40",
        )
        wind(v, 90.0)  # the storm: its park at 90/0, the elevation alone to turn
        v.run_until(lambda h: h.truth().el_deg < 30.0, TURN_S, "the elevation on its way down")
        v.device._el.jam(v.now)  # type: ignore[attr-defined]  # ice on the elevation
        v.run_until(lambda h: h.state is MotionState.STALLED, TURN_S, "the stall")
        v.run_for(AFTER_S)
        assert abs(v.truth().el_deg - 29.0) < 2.0  # 29 degrees up, facing the storm
        v.target(200.0)  # refused for the storm
        refusal = v.errors("refused")[-1].message
        assert "its park not reached" in refusal
        assert "elevation" in refusal, (
            f"the elevation stands at {v.truth().el_deg:.0f}, the park's is 0; the refusal: "
            f"{refusal!r}"
        )
