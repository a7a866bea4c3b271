"""Review 79 (interfaces/mqtt/remote.py rule 10): a lock ON to a station already locked (the
console's lock pressed again) changes nothing the station publishes, so the remote holds it
for ever and sends it again whenever the station's bridge connects again. Someone at the
tower then unlocks it at the station (Home Assistant's lock OFF, after that lock ON); the
station's route to its broker drops and heals, its bridge connects again, and the remote's
old lock ON goes again and locks the station: a lock OFF undone by an older lock ON from
another front end, and the operator's next turn refused. Real parts: mosquitto, the station's
bridge on an emulated Rotor-EZ behind a route this test cuts and heals (attack 26's), the
remote's console rotator and rotctld, Home Assistant's lock OFF published as it would be."""

from __future__ import annotations

from bridge.core.model import Lock, Source
from tests.remote.test_attack26_stop_into_a_partition import (
    CuttableLink,
    bridge_back_after,
    remote_heard,
    route,  # noqa: F401  (the fixture)
    station,  # noqa: F401  (the fixture)
)
from tests.support import wait_until
from tests.support.mosquitto import free_port
from tests.support.remote import ask
from tests.support.rig import Rig
from tests.support.waiting import slow

TURN_AZ = 100.0


def test_a_lock_off_at_the_station_is_not_undone_by_an_older_lock_on_sent_again(
    station: Rig,  # noqa: F811
    route: CuttableLink,  # noqa: F811
) -> None:
    port = free_port()
    remote = remote_heard(station, port)
    try:
        emu = station.emus["tower"]
        rotator = remote.rotators[0]
        rotator.submit(Lock(on=True, source=Source.MQTT), "lock ON")  # the console's
        wait_until(lambda: station.status("tower").locked, slow(10), "the station locked")
        lock_state = station.topic("tower", "lock/state")
        wait_until(  # (the station's retained word reaches the remote a moment later)
            lambda: remote.view.get(lock_state) == b"ON", slow(10), "the remote told it"
        )
        assert ask(port, b"P 200 0\n") == b"RPRT -9\n"  # the remote sees it locked
        rotator.submit(Lock(on=True, source=Source.MQTT), "lock ON")  # pressed again
        state = station.topic("tower", "lock/state")
        mark = station.probe.mark()
        station.probe.publish(station.topic("tower", "lock"), "OFF")  # at the tower, later
        station.probe.wait(
            lambda m: m.topic == state and m.payload == b"OFF", slow(10), "unlocked", mark
        )
        mark = station.probe.mark()
        route.cut()
        route.heal()  # the station's bridge connects again, a clean session
        bridge_back_after(station, remote, mark)
        said = ask(port, f"P {TURN_AZ:g} 0\n".encode())  # the operator's next turn
        wait_until(
            lambda: (
                station.status("tower").locked
                or (not emu.state().is_moving and abs(emu.state().az_deg - TURN_AZ) < 2)
            ),
            slow(30),
            "the station locked again, or the rotor at the operator's target",
        )
    finally:
        remote.stop()
    assert not station.status("tower").locked, (
        f"the lock OFF at the tower undone by the remote's older lock ON; P {TURN_AZ:g}: {said!r}"
    )
