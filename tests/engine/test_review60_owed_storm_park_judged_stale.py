"""Review 60: the storm's park owed after an offline (session/wind.py rule 7) is judged, the
moment the controller is back, from the reading the rotor had before it went offline, not from
where it is now; refused so, it is never tried again in the storm.

A Rotor-EZ at 300 under limits 20..340 with its storm park at 30 (from 300 the turn passes
north: refused, rightly). Unplugged; the storm begins meanwhile (the park owed once it
answers); the rotor turned by hand at its front panel to 100, from where the park is allowed.
Plugged back in: the park is judged before the first reading, "from 300", refused, and wind.py
rule 5 takes that refusal as the storm's: the antenna faces the storm at 100 all storm while
the status says "parked for the storm". (Found beside 80a0d4ee, which judges a rotator of two
boxes' park from a box's reading: test_review60_composite_storm_park_judged_stale.)

In virtual time, a Rotor-EZ."""

from __future__ import annotations

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

WIND = {
    "az_min_deg": 20,
    "az_max_deg": 340,  # the north kept out: from 300, 30 is reached only through it
    "park_az_deg": 30,
    "park_el_deg": 0,
    "wind_topic": "weather/wind",
    "wind_park_above": 60,
}
ALONE = {k: v for k, v in WIND.items() if k != "park_el_deg"}  # (a Rotor-EZ turns no elevation)
STORM_KMH = 90.0
AWAY_S = 60.0  # virtual: unplugged
PARK_TIME_S = 300.0  # virtual: a Rotor-EZ turns 70 degrees well inside this


def test_a_park_owed_after_an_offline_is_judged_from_where_the_rotor_is() -> None:
    with VirtualRotator("rotorez", settings=ALONE) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.target(300.0)
        v.run_until(
            lambda h: abs(h.truth().az_deg - 300.0) < 1.0 and h.state is MotionState.IDLE,
            120,
            "at rest at 300",
        )
        v.link_down()
        v.mailbox.put_wind(STORM_KMH)  # the storm begins while it is unplugged
        v._take()
        v.manual_rotate(100.0)  # turned at its front panel meanwhile
        v.run_for(AWAY_S)
        v.link_up()
        v.run_for(PARK_TIME_S)
        assert abs(v.truth().az_deg - 30.0) < 2.0, (
            f"rotor at {v.truth().az_deg:.0f} in the storm; said: "
            f"{[e.message for e in v.errors('refused')]}"
        )
