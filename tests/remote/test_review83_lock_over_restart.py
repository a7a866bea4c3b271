"""Review 83 (interfaces/mqtt/remote.py rule 10): a held lock ON is "done" on a status from
another run of the station's bridge. A restart ends no lock OFF: the station's lock is kept
across restarts (its state file), so the bridge that starts again shows the same lock OFF the
remote's lock ON was asked against. A lock ON the broker took into the station's dying
connection, its bridge then killed and started again before the route healed (a power blip at
the station: the router and the PC together), is dropped by the remote at the new run's first
status and never sent again: the station stays unlocked while the operator who locked it
from the console sends someone up the tower.
Real parts: mosquitto, the station's bridge as its own process on an emulated Rotor-EZ behind
a route this test cuts and heals (attack 26's), killed and started again; the remote's
console lock."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

import pytest

from bridge.core.errors import Refused
from bridge.core.model import Lock, Source
from tests.remote.test_attack26_stop_into_a_partition import (
    START_AZ,
    CuttableLink,
    killable_station,
    remote_on,
    route,  # noqa: F401  (the fixture)
)
from tests.support import wait_until
from tests.support.mosquitto import free_port
from tests.support.rig import Rig
from tests.support.waiting import slow


@pytest.fixture
def station(rig: Rig, route: CuttableLink) -> Iterator[Rig]:  # noqa: F811
    yield from killable_station(rig, route, emu={"start_az_deg": START_AZ, "jitter_deg": 0})


def test_a_lock_on_held_over_a_station_restart_mid_partition_still_locks_it(
    station: Rig,
    route: CuttableLink,  # noqa: F811
) -> None:
    port = free_port()
    remote = remote_on(station, port)
    try:
        rotator = remote.rotators[0]
        wait_until(lambda: rotator.away() is None, slow(30), "the station heard")
        lock_state = station.topic("tower", "lock/state")

        def said() -> bytes | None:  # the station's retained lock/state
            last = station.probe.last(lock_state)
            return None if last is None else bytes(last.payload)

        wait_until(lambda: said() == b"OFF", slow(10), "the station's lock/state OFF")
        route.cut()  # the station's route dies; the remote still hears it a while
        with contextlib.suppress(Refused):  # (taken by the broker, or said not delivered)
            rotator.submit(Lock(on=True, source=Source.MQTT), "lock ON")
        assert station.bridge is not None
        station.bridge.kill()  # the station's PC goes down with its router ...
        station.start_process()  # ... and comes back: another run, the route still dead
        route.heal()
        wait_until(lambda: rotator.away() is None, slow(30), "the station's bridge back")
        wait_until(
            lambda: said() == b"ON",
            slow(10),
            "the station locked (the console's lock ON, held, sent again)",
        )
    finally:
        remote.stop()
