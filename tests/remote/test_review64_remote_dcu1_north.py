"""Review 64 of cad0e49c (dcu1: a bearing of 000 is north, the nearer end of a travel whose
ends are 0 and 360): the remote's DCU-1 endpoint (remote/settings.py ``dcu1_port``, the same
Dcu1Session) marks AP1000 as either end as the station's does, but the remote hands a Target on
to the station as ``{"azimuth": 0}`` on ``R/target`` (remote/rotator.py rule 3), where 0 named
is the counter-clockwise end (pointing.py rule 2): the mark is lost on the way. A DCU-1
program on the operator's computer (rotctl -m 403 P 360, sent as ``AP1000;`` ``AM1;``) asking
a Yaesu behind a GS-232 at 355 for north turns it 355 degrees back through south, the very
turn the fix stopped on the station's own DCU-1 port."""

from __future__ import annotations

import pytest

from tests.integration.test_dcu1_endpoint import DCU1
from tests.integration.test_gs232_integration import rotctl
from tests.remote.test_remote import OPERATOR
from tests.support.mosquitto import free_port
from tests.support.remote import running_remote
from tests.support.rig import Rig

pytestmark = pytest.mark.hamlib


def test_a_dcu1_north_through_the_remote_turns_a_yaesu_at_355_the_short_way(
    rig: Rig, rotctl_path: str
) -> None:
    emu = rig.add("tower", model="gs232b-az", emu={"start_az_deg": 355})
    rig.start()
    rig.ready("tower")
    port = free_port()
    with running_remote(rig.broker.port, OPERATOR, {"rotator": "tower", "dcu1_port": port}):
        rotctl(rotctl_path, DCU1, port, "P", "360", "0")  # Hamlib sends AP1000; then AM1;
        rig.arrived("tower", 0)  # north, on either end of the scale
    assert [f.data for f in emu.frames("move")] == [b"M360"], (
        "the rotor at 355 was sent the far end of its travel for north through the remote: "
        "a turn of 355 degrees through south for a bearing 5 degrees away"
    )
