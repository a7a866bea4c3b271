"""Attack 14: on a rotator of two boxes, auto-park turns the elevation alone to its stow while
the park is refused (runtime/composite.py rule 7, app.py ``axis_configs``).

Each box's session judges the park of its own part with its own judge: the azimuth box's
(a Rotor-EZ's Hy-Gain rotor, its stop at south) refuses 30 from 300 under limits 20..340
(the turn passes north: pointing.py rule 4), while the elevation box's (a GS-232B, whose
azimuth is never turned and whose scale ends at north) takes the same park. The elevation
goes down to the stow, alone, and R/error says "auto-park refused" at every quiet spell. The
rotator's own judge refuses that park whole (R/park from there moves nothing): a bridge's own
move turns half the antenna for a park the bridge says it refused, which composite.py rule 8
keeps from happening to a target ("no axis turns alone").

In virtual time, a Rotor-EZ on the azimuth and a GS-232B used for its elevation."""

from __future__ import annotations

import pytest

from bridge.core.errors import Refused
from bridge.core.model import MotionState, Source, Target
from bridge.protocols.axes import Axis
from tests.engine.virtual_composite import VirtualComposite

LIMITS_AND_STOW = {
    "az_min_deg": 20,
    "az_max_deg": 340,  # the north kept out: from 300, 30 is reached only through it
    "park_az_deg": 30,
    "park_el_deg": 0,
    "park_after_idle_s": 60,
}
BOXES = {
    Axis.AZIMUTH: {"start_az_deg": 300.0},
    Axis.ELEVATION: {"az_speed_deg_s": 6.0, "el_speed_deg_s": 2.5},
}
SPELLS_S = 300.0  # virtual: five quiet spells


def at_300_40(v: VirtualComposite) -> bool:
    return (
        abs(v.az.truth().az_deg - 300.0) < 1.0
        and abs(v.el.truth().el_deg - 40.0) < 1.0
        and v.status.state is MotionState.IDLE
    )


def test_a_park_the_azimuth_box_refuses_moves_no_axis() -> None:
    with VirtualComposite("rotorez", "gs232b", settings=LIMITS_AND_STOW, emulators=BOXES) as v:
        v.run_until(lambda h: h.status.available, 10, "both boxes answer")
        v.aim(Target(300.0, 40.0))
        v.run_until(at_300_40, 120, "at rest at 300/40")
        with pytest.raises(Refused):  # the rotator's judge refuses this park whole
            v.cfg.aim.judge(Target(30.0, 0.0, Source.MQTT, park=True), 300.0)
        v.run_for(SPELLS_S)
        refusals = [e.message for e in v.az.errors("refused")]
        assert refusals and refusals[0].startswith("auto-park refused")  # said, each spell
        assert abs(v.az.truth().az_deg - 300.0) < 1.0
        assert abs(v.el.truth().el_deg - 40.0) < 1.0, (
            f"the elevation turned alone to {v.el.truth().el_deg:.0f} for a park R/error says "
            "was refused"
        )


def test_a_storm_park_the_azimuth_box_refuses_moves_no_axis() -> None:
    wind = {**LIMITS_AND_STOW, "park_after_idle_s": 0, "wind_topic": "w", "wind_park_above": 60}
    with VirtualComposite("rotorez", "gs232b", settings=wind, emulators=BOXES) as v:
        v.run_until(lambda h: h.status.available, 10, "both boxes answer")
        v.aim(Target(300.0, 40.0))
        v.run_until(at_300_40, 120, "at rest at 300/40")
        v.mailbox.put_wind(90.0)
        v._take()
        v.run_for(SPELLS_S)
        refusals = [e.message for e in v.az.errors("refused")]
        assert refusals and refusals[0].startswith("wind park refused")
        assert abs(v.el.truth().el_deg - 40.0) < 1.0, (
            f"the elevation turned alone to {v.el.truth().el_deg:.0f} for a park R/error says "
            "was refused"
        )
