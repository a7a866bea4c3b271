"""The station the remote's tests drive: one emulated Rotor-EZ, ``tower``, bridged and
answering (a module with a station of its own defines its own ``station``)."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from tests.support.remote import StallingLink
from tests.support.rig import Rig


@pytest.fixture
def station(rig: Rig) -> Rig:
    rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
    rig.start()
    rig.ready("tower")
    return rig


@pytest.fixture
def link(station: Rig) -> Iterator[StallingLink]:
    stalling = StallingLink(station.broker.port)
    yield stalling
    stalling.close()
