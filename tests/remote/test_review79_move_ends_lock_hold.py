"""Review 79 (interfaces/mqtt/remote.py rule 10): a later move of this remote ends the wait of
its rotator's lock ON too (``after``: the stop and the lock), though a move never overrides a
lock: sent again after the move, the lock ON only does what the operator asked in that order
(the station refuses the move). The console's lock ON, taken by the broker into the station's
dead connection (attack 26's partition), then Gpredict's next ``P`` through the remote's rotctld
(the remote sees no lock: the station never had it): the move ends the lock ON's hold, the
station's bridge connects again, the lock ON is never sent again, and Gpredict's next turn
turns a rotor the operator locked for tower work. Real parts: mosquitto, the station's bridge on
an emulated Rotor-EZ behind a route this test cuts and heals (attack 26's), the remote's
console rotator and rotctld."""

from __future__ import annotations

import contextlib

from bridge.core.errors import Refused
from bridge.core.model import Lock, Source
from tests.remote.test_attack26_stop_into_a_partition import (
    CuttableLink,
    bridge_back_after,
    remote_on,
    route,  # noqa: F401  (the fixture)
    station,  # noqa: F401  (the fixture)
    turning_then_cut,
)
from tests.support import wait_until
from tests.support.mosquitto import free_port
from tests.support.remote import ask
from tests.support.rig import Rig
from tests.support.waiting import slow

NEXT_AZ, LATER_AZ = 100.0, 150.0


def test_a_lock_on_lost_in_a_partition_is_not_given_up_for_a_later_move(
    station: Rig,  # noqa: F811
    route: CuttableLink,  # noqa: F811
) -> None:
    port = free_port()
    remote = remote_on(station, port)
    try:
        emu = station.emus["tower"]
        rotator = remote.rotators[0]
        turning_then_cut(station, route, port)
        with contextlib.suppress(Refused):  # (taken by the broker, or said not delivered)
            rotator.submit(Lock(on=True, source=Source.MQTT), "lock ON")  # the console's
        said_next = ask(port, f"P {NEXT_AZ:g} 0\n".encode())  # Gpredict's next, after it
        mark = station.probe.mark()
        route.heal()  # the station's bridge connects again, a clean session
        bridge_back_after(station, remote, mark)
        said_later = ask(port, f"P {LATER_AZ:g} 0\n".encode())  # Gpredict's next again
        wait_until(
            lambda: (
                station.status("tower").locked
                or (not emu.state().is_moving and abs(emu.state().az_deg - LATER_AZ) < 2)
            ),
            slow(30),
            "the station locked, or the rotor at Gpredict's later target",
        )
    finally:
        remote.stop()
    az = emu.state().az_deg
    assert station.status("tower").locked, (
        f"the console's lock ON never reached the station; P {NEXT_AZ:g}: {said_next!r}, "
        f"P {LATER_AZ:g}: {said_later!r}; the rotor turned to {az:.0f}"
    )
