"""Claim rule 5 (review 77): a group publishes ``G/info`` naming its bridge, so that a bridge
started on the group's topic is refused. A remote finds the station's rotators by their
``B/<id>/info``: the group's must not read as one (the console would leave it out with a
warning, and a start that names no rotator would list the group among the rotators)."""

from __future__ import annotations

from typing import Any

import pytest

from bridge.remote.run import Remote, StartError
from bridge.remote.settings import RemoteSettings
from tests.support import Probe
from tests.support.mosquitto import free_port
from tests.support.rig import Rig
from tests.support.waiting import slow


def test_a_remote_names_the_stations_rotators_and_never_its_group(rig: Rig, probe: Probe) -> None:
    a_station_with_a_group(rig, probe)
    endpoint = {"rotctld_port": free_port()}  # no rotator named: the ids are listed
    failed = a_remote_refused_at_start(rig, endpoint)
    assert "the station has rotators lower, upper: name one" in str(failed.value), failed.value


def a_station_with_a_group(rig: Rig, probe: Probe) -> None:
    """The station's bridge running rotators ``upper`` and ``lower`` and their group
    ``stack``, its ``rotor/stack/info`` out."""
    rig.add("upper", emu={"start_az_deg": 0, "jitter_deg": 0})
    rig.add("lower", emu={"start_az_deg": 0, "jitter_deg": 0})
    rig.sections = {"groups": [{"id": "stack", "name": "Stack", "rotators": ["upper", "lower"]}]}
    rig.start()
    rig.ready("upper")
    rig.ready("lower")
    probe.wait_for("rotor/stack/info", lambda m: b'"group":"stack"' in m.payload)


def a_remote_refused_at_start(
    rig: Rig, endpoint: dict[str, Any]
) -> pytest.ExceptionInfo[StartError]:
    """A remote on ``rig``'s broker with the one ``endpoint``; its start must fail."""
    s = RemoteSettings(
        operator="DL1ABC",
        mqtt={"host": "127.0.0.1", "port": rig.broker.port, "base_topic": "rotor"},
        endpoints=[endpoint],
        info_wait_s=slow(1.0),
    )  # type: ignore[arg-type]
    with pytest.raises(StartError) as failed:
        Remote(s).start()
    return failed
