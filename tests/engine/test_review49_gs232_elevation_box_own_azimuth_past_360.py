"""Review 49: gs232.py rule 2 (092c55df) makes an azimuth past the configured model's scale a
MISFIT, never a reading. On a composite rotator's elevation box (an az/el GS-232B turning the
elevation alone, axes.py rule 2: its azimuth is never turned, every target carries back the
azimuth the box last said) the box's OWN azimuth channel reads what it reads: a G-5500's box at
P45 whose azimuth motor rests in its overlap at 400 (the antenna's azimuth is another box's)
now answers ``AZ=400 EL=045`` with every reply taken as no reading. The elevation box never
gives a reading, the whole rotator goes offline ("answers only garbled replies") and no
target turns the elevation, where before 092c55df the same station read elevation 45 and
turned to 30. The scale the rule guards is a channel that box never turns nor publishes. In
virtual time: the elevation box a GS-232B emulator at P45, configured as ``gs232b``."""

from __future__ import annotations

from bridge import emulators
from bridge.core.model import Target
from bridge.protocols.axes import Axis
from tests.engine.virtual_composite import VirtualComposite


def test_an_elevation_box_own_azimuth_past_360_leaves_its_elevation_read_and_turned() -> None:
    with VirtualComposite(
        "gs232b", "gs232b", emulators={Axis.AZIMUTH: {"start_az_deg": 120.0}}
    ) as v:
        v.el.device = emulators.create(
            "gs232b-450", now=v.now, start_az_deg=400.0, start_el_deg=45.0
        )
        v.run_for(20)
        assert v.status.available, f"offline: {[e.message for e in v.el.errors()]}"
        assert (v.status.bearing_deg, v.status.elevation_deg) == (120.0, 45.0)
        v.aim(Target(130.0, 30.0))
        v.run_for(60)
        assert v.el.truth().el_deg == 30.0, [e.message for e in v.el.errors()]
        assert (v.status.bearing_deg, v.status.elevation_deg) == (130.0, 30.0)
