"""Attack 12: an RT-21 turning a composite rotator's elevation reads its one bearing as the
elevation (protocols/axes.py rule 2: "0..180 of its range"), but nothing holds a reading to that
range: a box that says ``300.0;`` (a pot past its end, a box calibrated for an azimuth rotor)
is published as elevation 300 on R/status, with el_max_deg 90 and the axis's own top 180,
and nothing on R/error. The next target's elevation of 30 then goes out as ``AP1030.0`` and
the box turns its rotor 270 degrees down through its whole travel. A reading past the axis's
scale is no elevation: said, and never shown nor counted from (as a Prosistel's position
past its unit's range, prosistel.py rule 1). In virtual time, two emulated RT-21 boxes."""

from __future__ import annotations

import pytest

from bridge.protocols.axes import ONE_AXIS_EL_MAX_DEG, Axis
from tests.engine.virtual_composite import VirtualComposite


@pytest.mark.xfail(
    strict=True,
    reason="attack 12: an RT-21 elevation box reading 300 is shown as elevation 300 with "
    "nothing said, and the next target turns it 270 degrees from there",
)
def test_an_elevation_box_reading_past_the_axis_scale_is_said_and_never_shown() -> None:
    with VirtualComposite(
        "rt21",
        "rt21",
        settings={"el_max_deg": 90},
        emulators={Axis.ELEVATION: {"start_az_deg": 300.0}},
    ) as v:
        v.run_for(10)
        shown = {s.elevation_deg for _, s in v.statuses if s.elevation_deg is not None}
        assert all(0.0 <= el <= ONE_AXIS_EL_MAX_DEG for el in shown), shown
        assert v.el.errors(), "the elevation box's reading of 300 was taken without a word"
