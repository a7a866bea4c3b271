"""Attack pass 26: the console on the remote shows the station's rotator "exactly as the station's
own console shows" it (docs/remote.md), and the console shows, while an operator holds the
control lease, *Control*: who and until when (docs/console.md), and beside the last command's
source the operator who sent it (``mqtt · DL1ABC``). The station's ``R/status`` carries both
(``control``, ``last_operator``), but the remote reads it back into a status without them
(remote/readings.py ``_status``): on the remote's page nobody ever holds the lease, and no
command has an operator. The remote operator sees a free rotator while G4XYZ holds it, and learns
of the lease only from the refusal of each click. Real parts: mosquitto, the station's bridge on
an emulated Rotor-EZ, the remote in this process with its console, the console's HTTP client
(tests/remote/test_remote_console.py's station and remote)."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import paho.mqtt.client as paho
import pytest
from paho.mqtt.enums import CallbackAPIVersion

from bridge.remote.run import Remote
from tests.remote.test_remote_console import remote, station, statuses
from tests.support import wait_until
from tests.support.console import ConsoleClient, EventStream
from tests.support.rig import Rig

__all__ = ["remote", "station"]  # (the fixtures, as test_remote_console.py makes them)


@pytest.fixture
def g4xyz(station: Rig) -> Iterator[paho.Client]:
    other = paho.Client(CallbackAPIVersion.VERSION2, client_id="g4xyz", protocol=paho.MQTTv5)
    other.connect("127.0.0.1", station.broker.port)
    other.loop_start()
    yield other
    other.loop_stop()
    other.disconnect()


def newest_status(client: ConsoleClient) -> dict[str, Any]:
    """What a page opened now is told of the rotator first: its newest status."""
    stream = EventStream(client)
    try:
        return next(statuses(stream))
    finally:
        stream.close()


@pytest.mark.xfail(
    strict=True,
    reason="attack 26: the remote's console never shows who holds the lease (nor who sent)",
)
def test_the_remote_console_shows_who_holds_the_lease_as_the_stations_does(
    station: Rig, remote: tuple[Remote, ConsoleClient, list[str]], g4xyz: paho.Client
) -> None:
    r, client, _ = remote
    assert client.command("tower", command="target", az=30).status == 200  # DL1ABC's turn
    station.arrived("tower", 30)
    wait_until(lambda: b'"DL1ABC"' in (r.view.get("rotor/status") or b""), 10, "its sender")
    g4xyz.publish("rotor/control/claim", '{"operator": "G4XYZ", "minutes": 5}', qos=1)
    wait_until(lambda: station.status("tower").control is not None, 10, "the station's lease")
    wait_until(lambda: b"G4XYZ" in (r.view.get("rotor/control") or b""), 10, "the remote's view")
    wait_until(lambda: b"G4XYZ" in (r.view.get("rotor/status") or b""), 10, "the status read")
    refused = client.command("tower", command="target", az=200)  # the remote knows: it refuses
    assert (refused.status, refused.doc["code"]) == (409, "leased"), refused
    shown = newest_status(client)
    assert shown["available"], shown
    assert shown["control"] is not None, shown  # the page: Control G4XYZ until hh:mm UTC
    assert shown["control"]["holder"] == "G4XYZ"
    assert shown["last_operator"] == "DL1ABC"  # the page: mqtt · DL1ABC, the last turn's sender
