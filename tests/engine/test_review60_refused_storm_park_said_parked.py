"""Review 60: a storm's park the judge refuses leaves the status saying "parked for the storm"
(session/wind.py rules 1 and 5).

80a0d4ee judges a rotator of two boxes' storm park whole (runtime/composite.py rule 7): on a
Rotor-EZ azimuth + GS-232B elevation rotator at 300/40, limits 20..340, park 30/0, both boxes
now refuse it (the turn passes north) and neither axis moves: R/error says "wind park refused".
But the wind part then counts its park as done: ``refusal`` says "wind 90 km/h above 60: parked
for the storm", which R/status, Home Assistant's "Parked for the storm" and every motion
command refused in the storm repeat, while the antenna faces the storm where it stood. wind.py
rule 1 already says the refusal must not claim a park a STOP cut short (a review: "motion
refused for the storm (a stop or lock ON stopped its park)"); a park never sent is the same
lie. (The settings' guard, settings/wind.py rule 1, judges the park without a reading, so it
lets this one through; one controller alone says the same.)

In virtual time, the rotator of test_attack14_composite_auto_park_one_axis."""

from __future__ import annotations

from bridge.core.model import Target
from tests.engine.test_attack14_composite_auto_park_one_axis import (
    BOXES,
    LIMITS_AND_STOW,
    SPELLS_S,
    at_300_40,
)
from tests.engine.virtual_composite import VirtualComposite

WIND = {**LIMITS_AND_STOW, "park_after_idle_s": 0, "wind_topic": "w", "wind_park_above": 60}
STORM_KMH = 90.0


def test_a_refused_storm_park_is_not_said_parked() -> None:
    with VirtualComposite("rotorez", "gs232b", settings=WIND, emulators=BOXES) as v:
        v.run_until(lambda h: h.status.available, 10, "both boxes answer")
        v.aim(Target(300.0, 40.0))
        v.run_until(at_300_40, 120, "at rest at 300/40")
        v.mailbox.put_wind(STORM_KMH)
        v._take()
        v.run_for(SPELLS_S)
        assert at_300_40(v)  # (the park refused whole: nothing moved)
        refused = [e.message for e in v.az.errors("refused")]
        assert refused and refused[0].startswith("wind park refused")
        wind = v.status.wind
        assert wind is not None and wind.storm and wind.refusal is not None
        assert "parked for the storm" not in wind.refusal, (
            f"R/status says {wind.refusal!r} while the antenna stands at 300/40"
        )
