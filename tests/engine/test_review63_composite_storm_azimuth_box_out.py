"""Review 63: on a rotator of two boxes, a storm begun while the azimuth box is unplugged, and
still unplugged, keeps the dish up for the whole storm (e767230d: ``Unjudged``).

docs/architecture.md ("A rotator of two boxes"): a box that stops answering leaves the rotator
offline, "but for a storm's park: the safe side"; docs/wind.md: "one box going offline does not
stop the other box's park (each parks its own axis)". A storm begun with the *elevation* box
out parks the azimuth alone. Before e767230d, a storm begun with the *azimuth* box out was
judged whole from the azimuth box's last reading and, allowed from there, the elevation box
lowered the dish to its stow. Since e767230d the whole park raises ``Unjudged`` for as long as
the azimuth box is out: the elevation box never lowers the dish, for the whole storm, and
nothing on R/error says the storm found the rotator unable to park.

An RT-21 azimuth at 100, a GS-232B elevation at 30, the storm's park 180/0 (a dish's stow), no
limit or keep-out in the way from anywhere. In virtual time."""

from __future__ import annotations

from bridge.core.model import MotionState, Target
from bridge.protocols.axes import Axis
from tests.engine.virtual_composite import VirtualComposite

FAST = {
    Axis.AZIMUTH: {"az_speed_deg_s": 6.0},
    Axis.ELEVATION: {"az_speed_deg_s": 6.0, "el_speed_deg_s": 2.5},
}
WIND = {"wind_topic": "weather/wind", "wind_park_above": 60, "park_az_deg": 180, "park_el_deg": 0}
STORM_KMH = 90.0
STORM_S = 600.0  # virtual: the azimuth box stays out; a GS-232B lowers 30 degrees in 12 s


def test_a_storm_with_the_azimuth_box_out_still_lowers_the_dish() -> None:
    with VirtualComposite("rt21", "gs232b", settings=WIND, emulators=FAST) as v:
        v.run_until(lambda h: h.status.available, 10, "both boxes answer")
        v.aim(Target(100.0, 30.0))
        v.run_until(
            lambda h: (
                abs(h.az.truth().az_deg - 100.0) < 1.0
                and abs(h.el.truth().el_deg - 30.0) < 1.0
                and h.status.state is MotionState.IDLE
            ),
            60,
            "at rest at 100/30",
        )
        v.az.link_down()  # the azimuth box's USB unplugged, and it stays so
        v.run_until(lambda h: h.status.state is MotionState.OFFLINE, 60, "offline")
        v.mailbox.put_wind(STORM_KMH)
        v._take()
        v.run_for(STORM_S)
        el = v.el.truth().el_deg
        assert abs(el) < 1.0, f"the dish at {el:.0f} degrees after {STORM_S:.0f} s of storm"
