"""Review 86 (interfaces/mqtt/remote.py rule 10, e95fa575): on a rotator of two boxes the
bridge's own auto-park takes its place in the order of commands from each box's OWN mailbox
(runtime/composite.py builds each box's Worker on it), a counter no command advances, so
R/status shows the park's ``order.turn`` as 1, before the commands asked before it. A remote's
STOP the broker took into the station's dying connection reads the park, begun after that
STOP, as the turn it was asked against, still standing, and goes again when the station's
bridge connects: the auto-park is stopped short of the park (review 83's own-turn case,
test_review83_own_turn_order, on one box only).
Real parts: mosquitto, the station's bridge on an RT-21 (azimuth) and a GS-232B (elevation)
emulator on ptys with auto-park, behind a route this test cuts and heals (attack 26's), the
remote's rotctld."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest

from bridge.remote.run import Remote
from bridge.remote.settings import RemoteSettings
from tests.remote.test_attack26_stop_into_a_partition import CuttableLink
from tests.remote.test_review83_own_turn_order import old_stop_over_the_auto_park
from tests.support.mosquitto import free_port
from tests.support.rig import FAST_GS232, FAST_POLLING, FAST_RT21, Rig

PARK_AZ, START_AZ, TARGET_AZ = 10.0, 10.0, 200.0
PARK = {"park_az_deg": PARK_AZ, "park_el_deg": 0, "park_after_idle_s": 5}


@pytest.fixture
def route(rig: Rig) -> Iterator[CuttableLink]:
    link = CuttableLink(rig.broker.port)
    yield link
    link.close()


@pytest.fixture
def sky(rig: Rig, route: CuttableLink) -> tuple[Rig, Any]:
    """The station: the sky rotator (two boxes) reaching its broker over ``route``; the
    azimuth box's emulator."""
    rig.mqtt_extra["port"] = route.port
    az = rig.open_line(rig, "sky-az", "rt21", {**FAST_RT21, "start_az_deg": START_AZ})
    el = rig.open_line(rig, "sky-el", "gs232b", dict(FAST_GS232))
    rig.rotators.append(
        {
            "id": "sky",
            "azimuth": {"model": "rt21", "port": str(az.path)},
            "elevation": {"model": "gs232b", "port": str(el.path)},
            **FAST_POLLING,
            **PARK,
        }
    )
    rig.start()
    rig.probe.wait_value("rotor/availability", "online", timeout_s=15)
    rig.probe.wait_value("rotor/state", "idle", timeout_s=15)
    return rig, az.emu


def test_an_old_stop_never_stops_a_two_box_rotators_auto_park_begun_after_it(
    sky: tuple[Rig, Any], route: CuttableLink
) -> None:
    station, emu = sky
    port = free_port()
    remote = Remote(
        RemoteSettings(
            operator="DL1ABC",
            mqtt={"host": "127.0.0.1", "port": station.broker.port, "base_topic": "rotor"},
            endpoints=[{"rotator": "sky", "rotctld_port": port}],
        )
    )
    remote.start()
    old_stop_over_the_auto_park(remote, port, emu, route, START_AZ, TARGET_AZ, PARK_AZ)
