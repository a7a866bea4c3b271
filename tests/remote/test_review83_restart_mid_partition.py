"""Review 83 (interfaces/mqtt/remote.py rule 10): a held STOP is "done" on a status from
another run of the station's bridge ("a restart ends every turn"). It does not: a controller
box keeps turning to the target it was given while its bridge is down (a Rotor-EZ, a GS-232
box, a SPID), and a bridge that starts again with ``unasked_moves = "follow"`` (the default of
most models) lets that turn go on. So a STOP the broker took into the station's dying
connection, whose bridge then crashed and started again before the route healed (a power
blip at the station: the router and the PC together), is dropped by the remote at the new
run's first status, never sent again, and the rotor turns on to the old target the operator
stopped. (The new run's status shows the rotor moving; before rule 10's redesign the STOP
was held until a status showed it still.)
Real parts: mosquitto, the station's bridge as its own process on an emulated Rotor-EZ behind
a route this test cuts and heals (attack 26's), killed and started again; the remote's
rotctld."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from tests.remote.test_attack26_stop_into_a_partition import (
    START_AZ,
    TARGET_AZ,
    CuttableLink,
    killable_station,
    remote_on,
    route,  # noqa: F401  (the fixture)
)
from tests.support import wait_until
from tests.support.mosquitto import free_port
from tests.support.remote import ask
from tests.support.rig import Rig
from tests.support.waiting import slow


@pytest.fixture
def station(rig: Rig, route: CuttableLink) -> Iterator[Rig]:  # noqa: F811
    emu = {"start_az_deg": START_AZ, "jitter_deg": 0, "speed_deg_s": 10.0}
    yield from killable_station(rig, route, emu=emu, unasked_moves="follow")


def test_a_stop_held_over_a_station_restart_mid_partition_still_stops_the_rotor(
    station: Rig,
    route: CuttableLink,  # noqa: F811
) -> None:
    port = free_port()
    remote = remote_on(station, port)
    try:
        emu = station.emus["tower"]
        rotator = remote.rotators[0]
        wait_until(lambda: rotator.away() is None, slow(30), "the station heard")
        assert ask(port, f"P {TARGET_AZ:g} 0\n".encode()) == b"RPRT 0\n"
        wait_until(lambda: emu.state().az_deg > START_AZ + 20, slow(10), "the rotor turning")
        route.cut()  # the station's route dies mid-turn; the remote still hears it a while
        assert ask(port, b"S\n") == b"RPRT 0\n"  # the broker took it: the station never gets it
        stopped_at = float(emu.state().az_deg)
        assert station.bridge is not None
        station.bridge.kill()  # the station's PC goes down with its router ...
        station.start_process()  # ... and comes back: another run, the route still dead
        route.heal()
        wait_until(lambda: rotator.away() is None, slow(30), "the station's bridge back")
        wait_until(lambda: not emu.state().is_moving, slow(60), "the rotor still")
    finally:
        remote.stop()
    az = emu.state().az_deg
    assert az < TARGET_AZ - 20, (
        f"STOP pressed at {stopped_at:.0f}; the rotor turned on to {az:.0f} (target "
        f"{TARGET_AZ:g}): the remote dropped the STOP at the restarted bridge's first status"
    )
