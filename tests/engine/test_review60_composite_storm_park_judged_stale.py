"""Review 60: on a rotator of two boxes, a storm begun while the azimuth box is unplugged has
its park judged whole (runtime/composite.py rule 7, 80a0d4ee: ``judged_whole``) by the
elevation box from the azimuth box's reading from before its offline, and that refusal is
final for the storm (session/wind.py rule 5): nothing owes the elevation box its park again.

A Rotor-EZ azimuth + GS-232B elevation rotator at 300/40, limits 20..340, storm park 30/0. The
azimuth box unplugged, its rotor turned by hand at the front panel to 100 (from where the park
is allowed); the storm begins. The elevation box judges the whole park "from 300" and refuses;
before 80a0d4ee it lowered the dish to its stow. The azimuth box, back, owes its park again
(wind.py rule 7) and judges it from its stale reading too
(test_review60_owed_storm_park_judged_stale); were that judged from where it is, the azimuth
would park and the elevation, refused for good, stay at 40: one axis parked alone, the very
thing 80a0d4ee set out to stop. The antenna faces the storm at 100/40 while the status says
"parked for the storm".

In virtual time, the rotator of test_attack14_composite_auto_park_one_axis."""

from __future__ import annotations

from bridge.core.model import MotionState, Target
from bridge.protocols.axes import Axis
from tests.engine.virtual_composite import VirtualComposite

WIND = {
    "az_min_deg": 20,
    "az_max_deg": 340,  # the north kept out: from 300, 30 is reached only through it
    "park_az_deg": 30,
    "park_el_deg": 0,
    "wind_topic": "weather/wind",
    "wind_park_above": 60,
}
BOXES = {
    Axis.AZIMUTH: {"start_az_deg": 300.0},
    Axis.ELEVATION: {"az_speed_deg_s": 6.0, "el_speed_deg_s": 2.5},
}
STORM_KMH = 90.0
AWAY_S = 60.0  # virtual: unplugged
PARK_TIME_S = 300.0  # virtual: a Rotor-EZ turns 70 degrees, a GS-232B lowers 40, well inside


def test_a_composite_storm_begun_with_the_azimuth_box_out_parks_both_axes_once_it_is_back() -> None:
    with VirtualComposite("rotorez", "gs232b", settings=WIND, emulators=BOXES) as v:
        v.run_until(lambda h: h.status.available, 10, "both boxes answer")
        v.aim(Target(300.0, 40.0))
        v.run_until(
            lambda h: (
                abs(h.az.truth().az_deg - 300.0) < 1.0
                and abs(h.el.truth().el_deg - 40.0) < 1.0
                and h.status.state is MotionState.IDLE
            ),
            120,
            "at rest at 300/40",
        )
        v.az.link_down()
        v.az.manual_rotate(100.0)  # turned at its front panel while unplugged
        v.run_for(AWAY_S)
        v.mailbox.put_wind(STORM_KMH)  # the storm begins with the azimuth box out
        v._take()
        v.run_for(AWAY_S)
        v.az.link_up()
        v.run_for(PARK_TIME_S)
        az, el = v.az.truth().az_deg, v.el.truth().el_deg
        assert abs(az - 30.0) < 2.0 and abs(el) < 1.0, (
            f"antenna at {az:.0f}/{el:.0f} in the storm; said: "
            f"{[e.message for e in [*v.az.errors('refused'), *v.el.errors('refused')]]}"
        )
