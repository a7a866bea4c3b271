"""Review 79 (interfaces/mqtt/remote.py rule 10): the station's route to its broker dies
mid-turn without a word (attack 26's partition). The operator sends STOP, then at once a new
target; the broker takes both (``RPRT 0``) and hands both to the station's dead connection. The
later move ends the STOP's hold (rule 10: "a later move of its rotator"), though the station
never showed it had the move either: when the station's bridge connects again with a clean
session, nothing is sent again, and the rotor turns on to the target the operator stopped,
neither stopped nor at the new one. Real parts as in attack 26's test: mosquitto, the station's
bridge on an emulated Rotor-EZ behind a route this test cuts and heals, the remote's rotctld."""

from __future__ import annotations

from tests.remote.test_attack26_stop_into_a_partition import (
    TARGET_AZ,
    CuttableLink,
    healed_later,
    remote_on,
    route,  # noqa: F401  (the fixture)
    station,  # noqa: F401  (the fixture)
    turning_then_cut,
)
from tests.support.mosquitto import free_port
from tests.support.remote import ask
from tests.support.rig import Rig

NEW_AZ = 120.0


def test_a_stop_then_a_new_target_both_lost_do_not_leave_the_rotor_on_the_old_target(
    station: Rig,  # noqa: F811
    route: CuttableLink,  # noqa: F811
) -> None:
    port = free_port()
    remote = remote_on(station, port)
    try:
        emu = station.emus["tower"]
        cut_az = turning_then_cut(station, route, port)
        said_stop = ask(port, b"S\n")  # the operator's STOP, at once
        said_move = ask(port, f"P {NEW_AZ:g} 0\n".encode())  # then a new target
        healed_later(station, route, remote, cut_az)
    finally:
        remote.stop()
    az = emu.state().az_deg
    assert said_stop == b"RPRT 0\n" and said_move == b"RPRT 0\n"  # both taken by the broker
    assert abs(az - TARGET_AZ) > 30, (
        f"STOP and P {NEW_AZ:g} answered RPRT 0; the rotor turned on to {az:.0f}, the target "
        "the operator stopped"
    )
