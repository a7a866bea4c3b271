"""Review 49: axes.py rule 2 (43b6e7b5) reads a one-axis elevation box's bearing up to
EL_READ_SLACK_DEG (then half a degree) past an end as that end; further is a MISFIT, the last
elevation forgotten, and no target goes to that box until it reads in scale again. An RT-21
turning a 0..180 (flip) elevation that rests at its end and reads a degree past it (181: a pot
that drifted a degree with the weather, a coast past the end; gs232.py rule 2 reads 3 degrees
past a GS-232's top as the top for that reason) is then offline for good: every reply a
MISFIT, "answers only garbled replies", and a target of 90 never turns it: nothing the bridge
can do brings it back, the operator has to go to the box. Before 43b6e7b5 it read 181 and a
target of 90 turned it there. In virtual time, two emulated RT-21s."""

from __future__ import annotations

from bridge.core.model import Target
from bridge.protocols.axes import Axis
from tests.engine.virtual_composite import VirtualComposite


def test_an_elevation_box_a_degree_past_its_end_is_still_turned_back() -> None:
    with VirtualComposite("rt21", "rt21", emulators={Axis.ELEVATION: {"start_az_deg": 170.0}}) as v:
        v.run_for(10)
        v.aim(Target(0.0, 180.0))
        v.run_for(60)
        assert v.status.elevation_deg == 180.0 and v.status.available
        v.el.device.manual_rotate(181.0, v.now)  # a degree past the end
        v.run_for(20)
        v.aim(Target(0.0, 90.0))
        v.run_for(120)
        told = [e.message for e in v.el.errors()]
        assert v.el.truth().az_deg == 90.0, told
        assert v.status.available and v.status.elevation_deg == 90.0, told
