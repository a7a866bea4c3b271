"""Review 50 (cold review of the tracking start mid-turn, d2067f87..f87b1948): f87b1948 keeps
the start's first target waiting "only [for] a brake window (a stop's, a stall's)", tracking.py
rule 3, by ``m.state in (BRAKING, STALLED)``. A stall is no window: the motion stays
``stalled`` until a target goes out (session/motion.py rule 3), so a tracking start taken after
a stall waits for itself. The rotor jammed on its way, freed, and then ``track sun``: the
status says tracking sun for good, and nothing is ever sent (ten minutes here); the same bearing
on ``R/target`` at that moment goes out after the brake delay (or at once on a GS-232B). What a
user notices: tracking shown on, the rotor standing 15 degrees off the sun, forever."""

from __future__ import annotations

import pytest

from bridge.core.model import MotionState
from bridge.sky import Body
from tests.engine.test_review46_track_start_mid_turn import turning_away_from_the_sun
from tests.engine.test_session_tracking import off_deg
from tests.support.sky import sun_altaz


@pytest.mark.parametrize("model", ["rotorez", "gs232b-az"])
def test_a_tracking_start_after_a_stall_turns_the_rotor_to_the_body(model: str) -> None:
    with turning_away_from_the_sun(model) as (v, lat, lon):
        v.jam()
        v.run_until(lambda h: h.state is MotionState.STALLED, 60, "the stall said")
        v.unjam()
        v.run_for(1.0)  # (freed: not a deadline)
        t = v.now
        v.track(Body.sun())
        v.run_for(120.0)  # (some 15 degrees back, and a brake delay: not a deadline)
        assert v.status.tracking is not None and v.status.tracking.phase == "tracking"
        assert v.frames("executed", "move", since=t)  # observed: nothing sent, for good
        sun = sun_altaz(lat, lon, v.wall())[0]
        assert off_deg(v.truth().az_deg, sun) <= 1.5 + 3.0
