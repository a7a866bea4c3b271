"""Review 85: claim rule 5 has a group publish a retained ``G/info`` (its id, name, members and
its bridge's stamp) on ``B/<group id>/info``, the topic where a remote looks for a rotator it is
told to serve. A remote whose ``endpoints.rotator`` names the station's group (a user who turns
the stack from the station's topics would name it so) now finds "a description" there and
fails parsing it as a rotator's: "rotor/stack/info is not the station's description: 'model'",
a Python key error that neither says the id is a group's nor names the station's rotators
(before, it said "no description ... the station has rotators lower, upper: name one")."""

from __future__ import annotations

import pytest

from bridge.remote.run import Remote, StartError
from bridge.remote.settings import RemoteSettings
from tests.support import Probe
from tests.support.mosquitto import free_port
from tests.support.rig import Rig
from tests.support.waiting import slow


def test_a_remote_told_a_groups_id_names_the_stations_rotators(rig: Rig, probe: Probe) -> None:
    rig.add("upper", emu={"start_az_deg": 0, "jitter_deg": 0})
    rig.add("lower", emu={"start_az_deg": 0, "jitter_deg": 0})
    rig.sections = {"groups": [{"id": "stack", "name": "Stack", "rotators": ["upper", "lower"]}]}
    rig.start()
    rig.ready("upper")
    rig.ready("lower")
    probe.wait_for("rotor/stack/info", lambda m: b'"group":"stack"' in m.payload)
    s = RemoteSettings(
        operator="DL1ABC",
        mqtt={"host": "127.0.0.1", "port": rig.broker.port, "base_topic": "rotor"},
        endpoints=[{"rotctld_port": free_port(), "rotator": "stack"}],
        info_wait_s=slow(1.0),
    )  # type: ignore[arg-type]
    with pytest.raises(StartError) as failed:
        Remote(s).start()
    said = str(failed.value)
    assert "'model'" not in said and "lower, upper" in said, said
    assert "rotor/stack/info describes a group" in said, said
