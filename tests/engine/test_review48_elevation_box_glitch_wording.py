"""Review 48: controller.py rule 9's words for a reading at rest that was not said again now
name the axis that was off (f45bac04, attack 12). On a composite rotator's elevation box (an
az/el GS-232B turning the elevation alone) a flipped bit in the box's OWN azimuth channel
(``AZ=150`` read as ``AZ=350``), which turns nothing and is none of the antenna's (axes.py rule
5; stops.py rule 4: such a box names its elevation, never its own azimuth), is told on the
rotator's R/error as "a reading at rest of 350/45, 160° off in azimuth from where the rotor
stands": the rotator's azimuth, shown at 120 by the other box all along, was never off, and the
operator reads that the antenna's azimuth jumped 160 degrees. (Before f45bac04 it said "160°
from where the rotor stands", vaguer; now it names the wrong axis outright.) In virtual time,
two emulated GS-232B boxes."""

from __future__ import annotations

from bridge.protocols.axes import Axis
from tests.engine.virtual_composite import VirtualComposite


def test_an_elevation_box_own_azimuth_glitch_is_not_told_as_the_rotators_azimuth() -> None:
    with VirtualComposite(
        "gs232b",
        "gs232b",
        emulators={
            Axis.AZIMUTH: {"start_az_deg": 120.0},
            Axis.ELEVATION: {"start_az_deg": 150.0, "start_el_deg": 45.0},
        },
    ) as v:
        v.run_for(20)
        assert (v.status.bearing_deg, v.status.elevation_deg) == (120.0, 45.0)
        t = v.now
        glitched = v.el.read_once_as(b"A", b"AZ=350  EL=045\r\n")  # the box's next reply
        v.run_for(20)
        assert b"".join(glitched).startswith(b"AZ=150"), glitched
        shown = {(s.bearing_deg, s.elevation_deg) for at, s in v.statuses if at >= t}
        assert shown <= {(120.0, 45.0)}, shown  # (dropped as it should be: never shown)
        said = [e.message for e in v.el.errors(since=t)] + [e.message for e in v.az.errors(since=t)]
        assert not [m for m in said if "off in azimuth" in m], said
