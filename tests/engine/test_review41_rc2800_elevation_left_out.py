"""Review 41: an RC2800's elevation that a target leaves out stays where it stands: an
azimuth-only target keeps it where it reads (session/targets.py ``resolve``: "as ``codec`` must
be asked for it to stay on the step it read"), and an az/el RC2800 that turns a composite's
azimuth never turns its own (axes.py rule 1). Its elevation goes out in whole degrees now
(rc2800.py rule 4) while it reads in tenths, and the codec has no ``held`` for it (base.py
HoldsOnGrid): read at 30.4 it was sent ``E30`` and turned 0.4 degrees down (30.6: ``E31``,
up), with every azimuth a logger or a composite sends. In tenths, before 49dcd2c7, it stayed.
(Found in 49dcd2c7, which was taken back: the elevation goes out in tenths again, and this
test holds it there.)"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.core.model import MotionState, Target
from bridge.protocols.axes import Axis
from tests.engine.virtual import VirtualRotator
from tests.engine.virtual_composite import VirtualComposite

Rig = Callable[..., VirtualRotator]


@pytest.mark.parametrize("el_deg", [30.4, 30.6])
def test_an_azimuth_only_target_leaves_an_rc2800s_elevation_where_it_stood(
    rig: Rig, el_deg: float
) -> None:
    box = {"az_speed_deg_s": 6.0, "el_speed_deg_s": 3.0, "start_az_deg": 10.0}
    v = rig("rc2800", emulator={**box, "start_el_deg": el_deg})
    v.run_until_state(MotionState.IDLE, 30)
    v.run_for(2.0)
    v.target(100.0)
    v.run_until(lambda h: h.truth().az_deg == 100.0 and not h.truth().is_moving, 60)
    v.run_for(5.0)
    assert v.truth().el_deg == el_deg  # observed: 30.0, 31.0


@pytest.mark.parametrize("el_deg", [30.4, 30.6])
def test_an_rc2800_azimuth_boxs_own_elevation_stays_where_it_stood(el_deg: float) -> None:
    box = {"start_az_deg": 10.0, "start_el_deg": el_deg}
    with VirtualComposite("rc2800", "gs232b", emulators={Axis.AZIMUTH: box}) as v:
        v.run_until(lambda h: h.status.available, 20)
        v.run_for(3.0)
        v.aim(Target(100.0, 20.0))
        v.run_until(lambda h: h.az.truth().az_deg == 100.0 and not h.az.truth().is_moving, 60)
        v.run_for(5.0)
        assert v.az.truth().el_deg == el_deg  # observed: 30.0, 31.0
