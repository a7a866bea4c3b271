"""Review 65: on a rotator of two boxes, a storm that lowered the dish while the azimuth box was
out, its azimuth park refused once that box is back, is said to have parked nothing.

a294fa69: with the azimuth box offline the storm's park is the elevation box's alone, and it
lowers the dish (the safe side); the azimuth box parks its own axis once it answers and has
read its bearing (docs/wind.md). Back at 300 under limits 20..340, the azimuth's park to 30 is
refused (its turn would pass north): "wind park refused". From then on the rotator is said as
if the storm had moved nothing: R/status ``refused`` (docs/mqtt.md: "the rotor stands where the
storm found it"), and when the wind sensor falls silent the azimuth box says on R/error "a
storm whose park was refused: motion refused, nothing parked" while the elevation box says
"parked for the storm" (different words: rule 9 says both). The dish stands at its stow: an
operator told "nothing parked" goes out to lower a dish that is down, or believes the stow
failed.

The rotator of test_attack14_composite_auto_park_one_axis (a Rotor-EZ azimuth and a GS-232B
elevation at 300/40, limits 20..340, park 30/0). In virtual time."""

from __future__ import annotations

from bridge.core.model import MotionState, Target
from tests.engine.test_attack14_composite_auto_park_one_axis import (
    BOXES,
    LIMITS_AND_STOW,
    at_300_40,
)
from tests.engine.virtual_composite import VirtualComposite

WIND = {**LIMITS_AND_STOW, "wind_topic": "w", "wind_park_above": 60}
STORM_KMH = 90.0
LOWERED_S = 120.0  # virtual: a GS-232B lowers 40 degrees in 16 s
SILENT_S = 2000.0  # virtual: past the 15 min a silent wind sensor is said after


def test_a_dish_lowered_for_the_storm_is_not_said_nothing_parked() -> None:
    with VirtualComposite("rotorez", "gs232b", settings=WIND, emulators=BOXES) as v:
        v.run_until(lambda h: h.status.available, 10, "both boxes answer")
        v.aim(Target(300.0, 40.0))
        v.run_until(at_300_40, 120, "at rest at 300/40")
        v.az.link_down()  # the azimuth box's USB unplugged
        v.run_until(lambda h: h.status.state is MotionState.OFFLINE, 60, "offline")
        v.mailbox.put_wind(STORM_KMH)
        v._take()
        v.run_for(LOWERED_S)
        assert abs(v.el.truth().el_deg) < 1.0  # the dish lowered alone (a294fa69)
        v.az.link_up()
        v.run_for(LOWERED_S)
        refused = [e.message for e in v.az.errors("refused")]
        assert refused and refused[0].startswith("wind park refused")  # the azimuth's, said
        wind = v.status.wind  # R/status: the refusal says which axis stands unparked
        assert wind is not None and wind.refused
        assert wind.refusal is not None and "the other axis parked" in wind.refusal, wind.refusal
        v.run_for(SILENT_S)  # the wind sensor says no more
        assert abs(v.el.truth().el_deg) < 1.0  # (the dish still down)
        said = [e.message for box in (v.az, v.el) for e in box.errors("wind")]
        assert said  # (the silence is said)
        wrong = [m for m in said if "nothing parked" in m]
        assert not wrong, f"the dish stands at its stow; R/error says {wrong} (all: {said})"
