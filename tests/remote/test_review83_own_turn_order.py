"""Review 83 (interfaces/mqtt/remote.py rule 10, session/session.py ``Order``): ``R/status``'s
``order.turn`` is the place of the last COMMAND that began a turn (a target, a track or follow
start), but the turn the status shows may be the bridge's own, begun later with no command:
an auto-park after the quiet spell (or the wind's storm park, or a target put back). Such a
status shows a target and a ``turn`` from a place before the remote's held STOP, so the remote
reads it as the turn the STOP was asked against, still standing, and sends the old STOP again
when the station's bridge connects: the auto-park the station began after that STOP (a newer
decision than the halt) is stopped short of the park. (A STOP pressed during a storm park ends
the storm park for good: wind.py rule 3.)
Real parts: mosquitto, the station's bridge on an emulated Rotor-EZ with auto-park, behind a
route this test cuts and heals (attack 26's), the remote's rotctld."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest

from bridge.emulators.pty import EmulatedPort
from bridge.remote.run import Remote
from tests.integration.test_pointing_bridge import PARKING, PARKING_EMU
from tests.remote.test_attack26_stop_into_a_partition import (
    START_AZ,
    TARGET_AZ,
    CuttableLink,
    remote_on,
)
from tests.support import wait_until
from tests.support.mosquitto import free_port
from tests.support.remote import ask
from tests.support.rig import Rig
from tests.support.waiting import slow

PARK_AZ = PARKING["park_az_deg"]


@pytest.fixture
def route(rig: Rig) -> Iterator[CuttableLink]:
    link = CuttableLink(rig.broker.port)
    yield link
    link.close()


@pytest.fixture
def parking_station(rig: Rig, route: CuttableLink) -> Rig:
    rig.mqtt_extra["port"] = route.port  # the station's bridge reaches its broker over the route
    emu = {**PARKING_EMU, "start_az_deg": START_AZ, "speed_deg_s": 20.0}
    rig.add("tower", emu=emu, **PARKING)
    rig.start()
    rig.ready("tower")
    return rig


def test_an_old_stop_never_stops_the_auto_park_the_station_began_after_it(
    parking_station: Rig, route: CuttableLink
) -> None:
    station = parking_station
    port = free_port()
    emu = station.emus["tower"]
    old_stop_over_the_auto_park(
        remote_on(station, port), port, emu, route, START_AZ, TARGET_AZ, PARK_AZ
    )


def old_stop_over_the_auto_park(
    remote: Remote,
    port: int,
    emu: EmulatedPort[Any],
    route: CuttableLink,
    START_AZ: float,
    TARGET_AZ: float,
    PARK_AZ: float,
) -> None:
    """The remote's rotctld sends the rotor from START_AZ toward TARGET_AZ, the route is cut
    mid-turn and a STOP asked into it; the station's bridge auto-parks after the turn, the
    route healed mid-park: the rotor must end at the park PARK_AZ. Stops ``remote``."""
    try:
        rotator = remote.rotators[0]
        wait_until(lambda: rotator.away() is None, slow(30), "the station heard")
        assert ask(port, f"P {TARGET_AZ:g} 0\n".encode()) == b"RPRT 0\n"
        wait_until(lambda: emu.state().az_deg > START_AZ + 20, slow(10), "the rotor turning")
        route.cut()  # the station's route dies mid-turn; the remote still hears it a while
        assert ask(port, b"S\n") == b"RPRT 0\n"  # the broker took it: the station never gets it
        wait_until(lambda: emu.state().az_deg > TARGET_AZ - 2, slow(30), "the turn finished")
        # the quiet spell: the station's bridge auto-parks, its own turn, after the STOP
        wait_until(lambda: emu.state().is_moving, slow(30), "the auto-park turning")
        wait_until(lambda: emu.state().az_deg < TARGET_AZ - 20, slow(10), "well under way")
        route.heal()  # its bridge connects again mid-park
        wait_until(lambda: rotator.away() is None, slow(30), "the station's bridge back")
        wait_until(lambda: not emu.state().is_moving, slow(30), "the rotor still")
    finally:
        remote.stop()
    az = emu.state().az_deg
    assert abs(az - PARK_AZ) < 2, (
        f"the auto-park the station began after the remote's STOP ended at {az:.0f}, not at "
        f"the park ({PARK_AZ:g}): the old STOP was sent again over it"
    )
