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

from bridge.core.model import MotionState
from bridge.features.wind import wind_json
from bridge.session.session import PARK_NOT_AGAIN
from tests.engine.test_review63_storm_park_held_said_parked import WIND, ha_parked
from tests.engine.test_wind import wind, windy
from tests.engine.virtual import VirtualRotator

PARK_AZ = 90.0  # test_wind's wind_park_az_deg


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
        said_parked = ha_parked(v) == "ON"  # Home Assistant's "Parked for the storm"
        assert not said_parked and "parked for the storm" not in refusal, (
            f"the park stalled {short:.0f} degrees short; R/status wind: {block}; "
            f"the refusal: {refusal!r}"
        )
        # the true state instead (wind.py rule 10): where it stands, and no "send it again"
        assert block["storm"] and block["off_park"]
        assert f"its park not reached: the rotor stands at {v.status.bearing_deg:g}°" in refusal
        stalled = v.errors("stalled")[0].message
        assert stalled.endswith(PARK_NOT_AGAIN) and "send the target again" not in stalled


def test_a_storm_park_that_stalled_is_not_sent_again_not_after_a_line_blip() -> None:
    """Wind.py rule 10: the park that stalled is not driven against the jam again in the
    storm, not after a line blip either (rule 7: the line took no park), and the refusal says
    where the rotor stands all along."""
    with windy() as v:
        wind(v, 90.0)
        v.run_until(
            lambda h: h.truth().is_moving and h.truth().az_deg < 170, 20, "the park under way"
        )
        v.jam()
        v.run_until(lambda h: h.state is MotionState.STALLED, 60, "the stall")
        v.unjam()  # (the ice gone: a park sent again would turn it now)
        v.run_until(
            lambda h: not h.truth().is_moving and h.state is not MotionState.MOVING, 30, "at rest"
        )
        t, stands = v.now, v.truth().az_deg
        v.set_silent(True)  # a blip on the line: offline
        v.run_until(lambda h: not h.status.available, 30, "offline")
        v.set_silent(False)
        v.run_until(lambda h: h.status.available, 30, "answering again")
        v.run_for(60.0)
        moves = [f for f in v.frames(since=t) if f.outcome not in ("status", "stop")]
        assert moves == [] and abs(v.truth().az_deg - stands) < 1.0  # no park sent again
        assert v.status.wind is not None and v.status.wind.off_park and ha_parked(v) == "OFF"
        v.target(200.0)
        assert v.errors("refused")[-1].message == (
            "wind 90 km/h above 60: motion refused for the storm (its park not reached: the "
            f"rotor stands at {v.status.bearing_deg:g}°)"
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
        said_parked = ha_parked(v) == "ON"  # Home Assistant's "Parked for the storm"
        assert not said_parked and "parked for the storm" not in refusal, (
            f"the rotor stands at {v.truth().az_deg:.0f}, {PARK_AZ:g} is the park; R/status "
            f"wind: {block}; the refusal: {refusal!r}"
        )
        assert block["off_park"] and "turned off its park after reaching it" in refusal
        assert abs(v.truth().az_deg - 200.0) < 1.0  # (rule 7: not turned back by itself)
        v.manual_rotate(PARK_AZ)  # the hand turns it back to the park: parked again
        v.run_until(lambda h: h.status.parked, 60, "back at the park")
        v.target(100.0)
        assert v.errors("refused")[-1].message == "wind 90 km/h above 60: parked for the storm"
        assert ha_parked(v) == "ON"


def test_a_storm_park_reached_is_never_said_off_it_in_the_brake_window() -> None:
    """Wind.py rule 10 judges where the rotor stands, not whether it is at rest: a Rotor-EZ
    that reached its park sits out its brake window (5 s) braking, and no status of the
    whole park says it is off it (Home Assistant's "Parked for the storm" flicking OFF)."""
    with VirtualRotator("rotorez", settings=WIND) as v:  # (its park at 180)
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.target(90.0)
        v.run_until(
            lambda h: abs(h.truth().az_deg - 90.0) < 2.0 and h.state is MotionState.IDLE,
            120,
            "at rest at 90",
        )
        t = v.now
        wind(v, 90.0)
        v.run_until(lambda h: h.state is MotionState.BRAKING, 120, "braking at the park")
        v.run_until(lambda h: h.state is MotionState.IDLE, 30, "the brake window over")
        assert v.status.parked and abs(v.truth().az_deg - 180.0) < 2.0
        storm = [s.wind for s in v.published(since=t) if s.wind is not None and s.wind.storm]
        assert storm and not any(w.off_park for w in storm)
