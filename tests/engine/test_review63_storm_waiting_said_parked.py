"""Review 63: a storm's park that waits (owed, not sent) is said "parked for the storm".

52f0f8e0 made a refused park say so, but ``WindPark.refusal`` still ends in "parked for the
storm" for a park that waits: e767230d's ``Unjudged`` (a two-box rotator's azimuth box
unplugged) keeps the park owed, R/status says ``waiting: true``, Home Assistant's "Parked for
the storm" is off, and in the same status the wind's refusal, the words every operator's move
is refused with on R/error (runtime/rotator.py: the wind's refusal verbatim), says "wind 90 km/h
above 60: parked for the storm" while the dish stands at 30 degrees facing the storm.

Since review 63's fix of test_review63_composite_storm_azimuth_box_out the elevation box lowers
the dish alone meanwhile (runtime/composite.py rule 7); the azimuth box's park still waits for
that box, and the words must say so.

An RT-21 azimuth + GS-232B elevation at 100/30, the storm's park 180/0. In virtual time."""

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
STORM_S = 60.0  # virtual: the azimuth box stays out


def test_a_storm_park_that_waits_is_not_said_parked() -> None:
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
        v.az.link_down()
        v.run_until(lambda h: h.status.state is MotionState.OFFLINE, 60, "offline")
        v.mailbox.put_wind(STORM_KMH)
        v._take()
        v.run_for(STORM_S)
        wind = v.status.wind
        assert wind is not None and wind.storm and wind.waiting
        assert abs(v.az.truth().az_deg - 100.0) < 1.0  # the azimuth's park waits for its box
        assert wind.refusal is not None and "parked for the storm" not in wind.refusal, wind.refusal
