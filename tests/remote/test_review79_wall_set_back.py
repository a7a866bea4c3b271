"""Review 79 (interfaces/mqtt/remote.py rule 10; the author's doubt on clocks): a halt's stamp
is reckoned from the station's heartbeats, whose clock is the station's wall clock never set
back (heartbeat.py rule 6: its steady clock plus the largest offset seen), but the station
stamps ``R/status`` with its wall clock as it is (service.py's ``wall``). Once the station's
wall clock is set back (a time server found after boot), every status is stamped before every
halt sent since by the step: none ever shows a halt carried out, so a STOP the station took
and showed it took (the rotor still, no target) is held for ever and sent again whenever the
station's bridge connects again, stopping a later turn Home Assistant started at the station.
(The difference between the two machines' clocks is not the matter: the stamp is reckoned on
the station's heartbeat clock, whatever the remote's clock says.) Real parts: mosquitto, the
station's bridge on an emulated Rotor-EZ, its wall clock this test sets back, behind a route
this test cuts and heals (attack 26's), the remote's rotctld, Home Assistant's target."""

from __future__ import annotations

import time

import pytest

from tests.remote.test_attack26_stop_into_a_partition import (
    START_AZ,
    TARGET_AZ,
    CuttableLink,
    cut_then_healed_later,
    home_assistant_turn,
    remote_heard,
    route,  # noqa: F401  (the fixture)
    station_showed_stop,
)
from tests.support import wait_until
from tests.support.mosquitto import free_port
from tests.support.remote import ask
from tests.support.rig import Rig
from tests.support.waiting import slow

STEP_S = 60.0  # the station's wall clock set back by a minute


class SteppedWall:
    """The station's wall clock: the host's, less what ``back`` set it back by."""

    def __init__(self) -> None:
        self.step_s = 0.0

    def back(self, step_s: float) -> None:
        self.step_s += step_s

    def __call__(self) -> float:
        return time.time() - self.step_s


@pytest.fixture
def wall() -> SteppedWall:
    return SteppedWall()


@pytest.fixture
def station(rig: Rig, route: CuttableLink, wall: SteppedWall) -> Rig:  # noqa: F811
    rig.wall = wall
    rig.mqtt_extra["port"] = route.port  # the station's bridge reaches its broker over the route
    rig.add("tower", emu={"start_az_deg": START_AZ, "jitter_deg": 0, "speed_deg_s": 20.0})
    rig.start()
    rig.ready("tower")
    return rig


def test_a_stop_the_station_took_after_its_clock_was_set_back_is_not_sent_again(
    station: Rig,
    route: CuttableLink,  # noqa: F811
    wall: SteppedWall,
) -> None:
    port = free_port()
    remote = remote_heard(station, port)
    try:
        emu = station.emus["tower"]
        wall.back(STEP_S)  # the station's time server sets its clock back
        assert ask(port, f"P {TARGET_AZ:g} 0\n".encode()) == b"RPRT 0\n"
        wait_until(lambda: emu.state().az_deg > START_AZ + 20, slow(10), "the rotor turning")
        mark = station.probe.mark()
        assert ask(port, b"S\n") == b"RPRT 0\n"  # taken at once: the route is fine
        stopped_az = station_showed_stop(station, mark)
        home_assistant_turn(station, stopped_az + 10)
        cut_then_healed_later(station, route, remote)
    finally:
        remote.stop()
    az = emu.state().az_deg
    assert abs(az - TARGET_AZ) < 2, (
        f"Home Assistant's turn to {TARGET_AZ:g}, asked after the remote's STOP the station "
        f"took, ended at {az:.0f}"
    )
