"""Attack 25: a storm's park that stalls on its way (ice, a caught cable: what a storm brings) is
still said "parked for the storm".

The rotor stops 78 degrees short of the storm's park; the stall is said once on R/error ("target
dropped: send the target again", though every target is refused for the storm). From then on
R/status's ``wind`` block reads as a park that was sent and not stopped (``storm`` true,
``halted``, ``waiting``, ``refused`` and ``replayed`` false: Home Assistant's "Parked for the
storm" is ON, features/wind ``_storm``), and every refusal for the storm says "parked for the
storm", while the antenna faces the wind where the stall left it. Reviews 60 and 63 made the
same words false for a refused park, a park stopped short and a park waiting (session/wind.py
rules 3, 5, 9): a park the rotor never finished is none either.

In virtual time on the emulated MD-01 (its azimuth jammed mid-park).
"""

from __future__ import annotations

import pytest

from bridge.core.model import MotionState
from bridge.features.wind import wind_json
from tests.engine.test_wind import wind, windy

PARK_AZ = 90.0  # test_wind's wind_park_az_deg


@pytest.mark.xfail(
    strict=True,
    reason="attack 25: a storm's park that stalled 78 degrees short is still 'parked for the "
    "storm' in R/status (Home Assistant's sensor ON) and in every refusal",
)
def test_a_storm_park_that_stalls_short_is_not_said_parked() -> None:
    with windy() as v:
        wind(v, 90.0)
        v.run_until(
            lambda h: h.truth().is_moving and h.truth().az_deg < 170, 20, "the park under way"
        )
        v.device._az.jam(v.now)  # type: ignore[attr-defined]  # ice: the motor runs, no progress
        v.run_until(lambda h: h.state is MotionState.STALLED, 60, "the stall")
        short = abs(v.truth().az_deg - PARK_AZ)
        assert short > 45.0  # the antenna faces the storm far from its park
        assert [e.kind.value for e in v.errors()] == ["stalled"]
        v.target(200.0)  # an operator would send the rotor there: refused for the storm
        refusal = v.errors("refused")[-1].message
        assert v.status.wind is not None
        block = wind_json(v.status.wind)
        said_parked = block["storm"] and not any(
            block[k] for k in ("replayed", "halted", "waiting", "refused")
        )  # Home Assistant's "Parked for the storm" (features/wind ``_storm``)
        assert not said_parked and "parked for the storm" not in refusal, (
            f"the park stalled {short:.0f} degrees short; R/status wind: {block}; "
            f"the refusal: {refusal!r}"
        )


@pytest.mark.xfail(
    strict=True,
    reason="attack 25: a rotor turned 110 degrees off the storm's park at its front panel is "
    "still 'parked for the storm' in R/status (Home Assistant's sensor ON) and every refusal",
)
def test_a_storm_park_left_by_hand_is_not_said_parked() -> None:
    """The same words from the other side: the park reached, then a hand at the front panel
    turns the rotor 110 degrees off it (session/wind.py rule 7: the bridge rightly does not
    turn it back). R/status's own ``parked`` goes false; its ``wind`` block and every refusal
    still say the rotor is parked for the storm."""
    with windy() as v:
        wind(v, 90.0)
        v.run_until(lambda h: h.status.parked, 60, "parked for the storm")
        v.manual_rotate(200.0)
        v.run_until(
            lambda h: not h.truth().is_moving and abs(h.truth().az_deg - 200.0) < 1.0,
            60,
            "the hand's turn",
        )
        v.run_until(lambda h: h.state is MotionState.IDLE, 30, "at rest")
        assert not v.status.parked  # R/status: the rotor left its park
        v.target(100.0)  # refused for the storm
        refusal = v.errors("refused")[-1].message
        assert v.status.wind is not None
        block = wind_json(v.status.wind)
        said_parked = block["storm"] and not any(
            block[k] for k in ("replayed", "halted", "waiting", "refused")
        )  # Home Assistant's "Parked for the storm" (features/wind ``_storm``)
        assert not said_parked and "parked for the storm" not in refusal, (
            f"the rotor stands at {v.truth().az_deg:.0f}, {PARK_AZ:g} is the park; R/status "
            f"wind: {block}; the refusal: {refusal!r}"
        )
