"""Review 86 (interfaces/mqtt/remote.py rule 10, 6887e738 and d29b5e1b): a held STOP is judged
in a new run of the station's bridge as if nothing had happened in the old run after the
remote last heard it: the stamp counts as 0, and a rotor the new run shows turning with no
target (the box's own turn, let be under ``unasked_moves = "follow"``) stands "from place 0",
read as the turn the STOP was asked against. But that turn may be a LATER one the remote never
saw: its STOP went into the station's dying connection, the remote's own link then dropped a
while (the operator's Wi-Fi), and in that while the station came back, Home Assistant turned
the rotor (a newer command, after the STOP), and the station's bridge restarted mid-turn (an
update; the box turns on). When the remote is back, its old STOP goes again and stops Home
Assistant's turn short: an old STOP over a newer turn (review 79's case, back over a restart).
Real parts: mosquitto, the station's bridge as its own process on an emulated Rotor-EZ behind a
route this test cuts and heals (attack 26's), the remote behind a route of its own, its
rotctld, Home Assistant's target published as it would."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from tests.remote.test_attack26_stop_into_a_partition import (
    START_AZ,
    TARGET_AZ,
    CuttableLink,
    killable_station,
    route,  # noqa: F401  (the fixture)
)
from tests.remote.test_review86_lock_off_before_restart import (
    remote_over,
    remote_route,  # noqa: F401  (the fixture)
    restarted_and_the_remote_back,
    station_back,
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


def test_an_old_stop_held_over_a_restart_never_stops_a_turn_begun_after_it(
    station: Rig,
    route: CuttableLink,  # noqa: F811
    remote_route: CuttableLink,  # noqa: F811
) -> None:
    port = free_port()
    remote = remote_over(remote_route, port)
    remote.start()
    try:
        emu = station.emus["tower"]
        rotator = remote.rotators[0]
        wait_until(lambda: rotator.away() is None, slow(30), "the station heard")
        status = station.topic("tower", "status")

        first = station.probe.last(status)
        assert first is not None
        route.cut()  # the station's route dies; the remote still hears it a while
        assert ask(port, b"S\n") == b"RPRT 0\n"  # the broker took it: the station never gets it
        remote_route.cut()  # the remote's own link drops a while
        mark = station.probe.mark()
        route.heal()  # the station comes back meanwhile ...
        station_back(station, remote, mark)
        station.probe.publish(station.topic("tower", "target"), f"{TARGET_AZ:g}")  # ... and
        wait_until(  # Home Assistant turns the rotor: a newer command than the STOP
            lambda: emu.state().az_deg > START_AZ + 20, slow(10), "Home Assistant's turn"
        )
        # the station's bridge restarts mid-turn (an update) and lets the box turn on (``follow``)
        restarted_and_the_remote_back(station, remote, remote_route, first)
        wait_until(lambda: not emu.state().is_moving, slow(60), "the rotor still")
    finally:
        remote.stop()
    az = emu.state().az_deg
    assert abs(az - TARGET_AZ) < 2, (
        f"Home Assistant's turn to {TARGET_AZ:g}, begun after the remote's STOP, ended at "
        f"{az:.0f}: the old STOP went again over it after the station's restart"
    )
