"""Attack 17 on the remote's PstRotator endpoint: Hamlib 4.6's PstRotator client sends a
``P 200 30`` as two datagrams, ``<AZIMUTH>`` and then ``<ELEVATION>`` each on its own
(../shared/protocols/logger-udp.md 1.1; KST4Contest sends ``<ELEVATION>`` alone too). The
station's own PstRotator port turns both axes (the mailbox keeps the azimuth it replaces,
test_mailbox.py), and the station's broker takes an elevation alone on ``R/target/elevation``
(docs/mqtt.md); the remote refuses every elevation datagram as "an elevation alone cannot go
to the station" (remote/rotator.py rule 3), so through the remote an az/el rotator driven by
such a client never lifts its antenna: a front end dead for one axis, said in the remote's
log alone."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.remote.test_remote_endpoints import Endpoints
from tests.support.rig import Rig
from tests.support.udp_logger import hamlib, tag


@pytest.fixture
def station(rig: Rig) -> Rig:
    rig.add("tower", model="gs232b", emu={"start_az_deg": 10, "start_el_deg": 0})
    rig.start()
    rig.ready("tower")
    return rig


@pytest.fixture
def endpoints(station: Rig, tmp_path: Path) -> Iterator[Endpoints]:
    e = Endpoints(station, tmp_path)
    yield e
    e.stop()


def test_hamlibs_azimuth_then_elevation_datagrams_turn_both_axes_through_the_remote(
    station: Rig, endpoints: Endpoints
) -> None:
    with endpoints.pst() as client:
        client.command(tag("AZIMUTH", hamlib(200)))  # Hamlib 4.6: one datagram per axis
        client.command(tag("ELEVATION", hamlib(30)))
        station.arrived("tower", 200, 30)
