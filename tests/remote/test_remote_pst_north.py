"""A logger's north through the remote (interfaces/loggers/commands.py rule 3, ``heading``): the
loggers pick 0 or 360 for north by the rotator's raw bearing, but the remote's rotator reads its
status from the station's ``R/status``, which leaves the raw bearing out where it equals the
bearing (pointing.py ``raw_reading``: no offset, a scale that wraps). With no raw bearing
``heading`` took 0, and the station's ``R/target`` takes 0 named as the counter-clockwise end of
the travel (pointing.py rule 2): a PstRotator (or N1MM) north sent to the remote's logger port
for a Yaesu behind a GS-232 at 355 turned it 355 degrees back through south, the turn the
station's own logger ports and the remote's DCU-1 port (review 64) no longer make."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from tests.remote.test_remote import OPERATOR
from tests.support.remote import running_remote
from tests.support.rig import Rig
from tests.support.udp_logger import PstClient, reserve_pst_ports, tag


@pytest.fixture(params=["gs232b-az", "gs232b-az-450"])  # (0..450: R/status has the raw bearing)
def yaesu_at_355(rig: Rig, request: pytest.FixtureRequest) -> Rig:
    """A Yaesu rotor (its stop at north) behind a GS-232, travel 0..360 or 0..450, at 355."""
    rig.add("tower", model=request.param, emu={"start_az_deg": 355})
    rig.start()
    rig.ready("tower")
    return rig


@pytest.fixture
def remote_pst(yaesu_at_355: Rig) -> Iterator[PstClient]:
    """The remote's PstRotator port onto the station's ``tower``, the remote's view current."""
    port, replies = reserve_pst_ports()
    endpoint = {"rotator": "tower", "pst_udp_port": port}
    try:
        with (
            running_remote(yaesu_at_355.broker.port, OPERATOR, endpoint),
            PstClient(port, replies=replies) as client,
        ):
            yield client
    finally:
        replies.close()


def test_a_pstrotator_north_through_the_remote_turns_a_yaesu_at_355_the_short_way(
    yaesu_at_355: Rig, remote_pst: PstClient
) -> None:
    emu = yaesu_at_355.emus["tower"]
    remote_pst.command(tag("AZIMUTH", 0))
    yaesu_at_355.arrived("tower", 0)  # north, on either end of the scale
    assert [f.data for f in emu.frames("move")] == [b"M360"], (
        "the rotor at 355 was sent the far end of its travel for a logger's north through the "
        "remote: a turn of 355 degrees through south for a bearing 5 degrees away"
    )
