"""Review 79 (interfaces/mqtt/remote.py rule 10): a STOP to a rotor already still, whose last
command was this operator's (Gpredict's ``S`` on disengaging after its own turn), changes
nothing the station publishes, so the remote holds it for ever (until its own next move) and
sends it again whenever the station's bridge connects again. (A STOP after another operator's
word is shown: ``last_operator`` changes, the station publishes a status, the hold ends.)
Home Assistant then turns the rotor at the station, after that STOP; the station's route to
its broker dies mid-turn and heals (a home router's reboot), its bridge connects again, and
the remote's old STOP goes again and stops the newer turn short of its target: an older
command from one front end overriding a newer one from another. The station said what could
tell the hold it is superseded: a live status stamped after the STOP showing a target and
another ``last_operator`` (a new turn the station took after it).
Real parts: mosquitto, the station's bridge on an emulated Rotor-EZ behind a route this test
cuts and heals (attack 26's), the remote's rotctld, Home Assistant's target published as it
would be."""

from __future__ import annotations

from tests.remote.test_attack26_stop_into_a_partition import (
    TARGET_AZ,
    CuttableLink,
    cut_then_healed_later,
    home_assistant_turn,
    remote_heard,
    route,  # noqa: F401  (the fixture)
    station,  # noqa: F401  (the fixture)
)
from tests.support.mosquitto import free_port
from tests.support.remote import ask
from tests.support.rig import Rig

FIRST_AZ = 60.0


def test_an_old_stop_to_a_still_rotor_never_stops_a_later_turn_from_the_station(
    station: Rig,  # noqa: F811
    route: CuttableLink,  # noqa: F811
) -> None:
    port = free_port()
    remote = remote_heard(station, port)
    try:
        emu = station.emus["tower"]
        assert ask(port, f"P {FIRST_AZ:g} 0\n".encode()) == b"RPRT 0\n"  # the operator's turn
        station.arrived("tower", FIRST_AZ)
        # Gpredict disengaging sends S: the rotor is still, this operator's word the last the
        # station took, so the STOP changes nothing the station publishes
        assert ask(port, b"S\n") == b"RPRT 0\n"
        home_assistant_turn(station, FIRST_AZ + 20)
        cut_then_healed_later(station, route, remote)
    finally:
        remote.stop()
    az = emu.state().az_deg
    assert abs(az - TARGET_AZ) < 2, (
        f"Home Assistant's turn to {TARGET_AZ:g}, asked after the remote's STOP, ended at {az:.0f}"
    )
