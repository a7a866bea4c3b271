"""Review 49: review 48's fix (df0a614f, controller.py rule 9 ``_how_far``) names a composite
elevation box's own azimuth channel as none of the antenna's in one message, a glitch at rest.
The same channel turned (a G-5500's box turning the elevation alone, its azimuth motor run
from the panel, 150 to 250; the antenna's azimuth is the other box's, 120, and never moves) is
still the rotator's in the words and status beside it: with ``unasked_moves = "stop"`` the
rotator's R/error says "the rotor turned with no command from the bridge, from 150°/45° to
156°/45°", and with "follow" the rotator's status shows MOVING for as long as that channel
turns, its azimuth and elevation standing still (tests/engine/test_session_easycomm.py tells
an elevation box's turn by its elevation alone; this is the other channel). In virtual time,
two emulated GS-232B boxes."""

from __future__ import annotations

from bridge.core.model import MotionState
from bridge.protocols.axes import Axis
from tests.engine.virtual_composite import VirtualComposite

BOXES = {
    Axis.AZIMUTH: {"start_az_deg": 120.0},
    Axis.ELEVATION: {"start_az_deg": 150.0, "start_el_deg": 45.0},
}


def test_an_elevation_box_own_azimuth_turned_is_not_told_as_the_rotor_turning() -> None:
    with VirtualComposite(
        "gs232b", "gs232b", settings={"unasked_moves": "stop"}, emulators=BOXES
    ) as v:
        v.run_for(20)
        assert (v.status.bearing_deg, v.status.elevation_deg) == (120.0, 45.0)
        t = v.now
        v.el.manual_rotate(250.0)
        v.run_for(40)
        assert (v.status.bearing_deg, v.status.elevation_deg) == (120.0, 45.0)
        told = [e.message for e in v.el.errors(since=t) + v.az.errors(since=t)]
        assert not any("rotor turned" in m and "150°" in m for m in told), told


def test_an_elevation_box_own_azimuth_turned_never_shows_the_rotator_moving() -> None:
    with VirtualComposite(
        "gs232b", "gs232b", settings={"unasked_moves": "follow"}, emulators=BOXES
    ) as v:
        v.run_for(20)
        t = v.now
        v.el.manual_rotate(250.0)
        v.run_for(40)
        shown = [(s.state, s.bearing_deg, s.elevation_deg) for at, s in v.statuses if at >= t]
        now = (v.status.state, v.status.bearing_deg, v.status.elevation_deg)
        assert all(s == (MotionState.IDLE, 120.0, 45.0) for s in [*shown, now]), shown
