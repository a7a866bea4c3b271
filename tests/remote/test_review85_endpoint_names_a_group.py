"""Review 85: claim rule 5 has a group publish a retained ``G/info`` (its id, name, members and
its bridge's stamp) on ``B/<group id>/info``, the topic where a remote looks for a rotator it is
told to serve. A remote whose ``endpoints.rotator`` names the station's group (a user who turns
the stack from the station's topics would name it so) now finds "a description" there and
fails parsing it as a rotator's: "rotor/stack/info is not the station's description: 'model'",
a Python key error that neither says the id is a group's nor names the station's rotators
(before, it said "no description ... the station has rotators lower, upper: name one")."""

from __future__ import annotations

from tests.remote.test_review77_group_info_is_no_rotator import (
    a_remote_refused_at_start,
    a_station_with_a_group,
)
from tests.support import Probe
from tests.support.mosquitto import free_port
from tests.support.rig import Rig


def test_a_remote_told_a_groups_id_names_the_stations_rotators(rig: Rig, probe: Probe) -> None:
    a_station_with_a_group(rig, probe)
    failed = a_remote_refused_at_start(rig, {"rotctld_port": free_port(), "rotator": "stack"})
    said = str(failed.value)
    assert "'model'" not in said and "lower, upper" in said, said
    assert "rotor/stack/info describes a group" in said, said
