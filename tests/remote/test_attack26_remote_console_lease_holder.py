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

import json
import logging
from collections.abc import Iterator
from typing import Any

import paho.mqtt.client as paho
import pytest
from paho.mqtt.enums import CallbackAPIVersion

from bridge.core.model import MotionState, RotatorStatus
from bridge.interfaces.mqtt import payloads as pl
from bridge.remote.readings import UNSHOWN, parse_status
from bridge.remote.run import Remote
from tests.remote.test_remote_console import remote, remote_settings, station, statuses
from tests.support import wait_until
from tests.support.console import ConsoleClient, EventStream, web_section
from tests.support.mosquitto import free_port
from tests.support.rig import Rig

__all__ = ["remote", "station"]  # (the fixtures, as test_remote_console.py makes them)


@pytest.fixture
def g4xyz(rig: Rig) -> Iterator[paho.Client]:
    other = paho.Client(CallbackAPIVersion.VERSION2, client_id="g4xyz", protocol=paho.MQTTv5)
    other.connect("127.0.0.1", rig.broker.port)
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


WIND = "wx/wind"  # the station's wind speed topic (a rotator's ``wind_topic``)


@pytest.fixture
def both(rig: Rig) -> Iterator[tuple[Rig, ConsoleClient, Remote, ConsoleClient]]:
    """The station with its own console, and the remote with its console, on one rotator."""
    web = rig.sections["web"] = web_section()
    rig.add(
        "tower",
        emu={"start_az_deg": 10, "jitter_deg": 0},
        wind_topic=WIND,
        wind_park_above=80,
        park_az_deg=0,
    )
    rig.start()
    rig.ready("tower")
    own = ConsoleClient(web["port"])
    own.session()
    port = free_port()
    r = Remote(remote_settings(rig, port))
    r.start()
    far = ConsoleClient(port)
    far.session()
    yield rig, own, r, far
    r.stop()


def test_the_remote_console_shows_every_status_field_the_station_s_console_shows(
    both: tuple[Rig, ConsoleClient, Remote, ConsoleClient], g4xyz: paho.Client
) -> None:
    """Every field of the station's console's status, the feature blocks among them (the
    rotor's health after a turn, the wind, the lease, the last command's sender), is on the
    remote's console with the same value: one comparison over the whole field set, so a field
    the station's console shows and the remote leaves out fails it, whichever."""
    station, own, r, far = both
    assert far.command("tower", command="target", az=60).status == 200  # DL1ABC's turn
    station.arrived("tower", 60)
    g4xyz.publish(WIND, "20", qos=1)
    g4xyz.publish("rotor/control/claim", '{"operator": "G4XYZ", "minutes": 5}', qos=1)

    def settled() -> bool:
        st = station.status("tower")
        return None not in (st.control, st.wind, st.health) and st.state.value == "idle"

    wait_until(settled, 10, "the station's status: the lease, the wind, the rotor's health")
    heard = b'"G4XYZ"', b'"wind":', b'"health":'
    wait_until(  # (the remote's page is told what its view of the station holds)
        lambda: all(part in (r.view.get("rotor/status") or b"") for part in heard),
        10,
        "the remote's view of the station's status",
    )

    def at_rest(page: ConsoleClient) -> bool:
        doc = newest_status(page)
        return doc.get("state") == "idle" and "G4XYZ" in json.dumps(doc.get("control"))

    wait_until(  # (each page is told each status in turn: both at the settled one)
        lambda: at_rest(own) and at_rest(far), 10, "both pages told the settled status"
    )
    shown, relayed = newest_status(own), newest_status(far)
    del shown["time"], relayed["time"]  # (each made when it was rendered)
    assert sorted(relayed) == sorted(shown), set(shown) ^ set(relayed)
    assert relayed == shown


def forged_status(**fields: object) -> bytes:
    """A station's R/status as its bridge renders it, with ``fields`` put in by whoever else
    may publish there (readings.py rule 1)."""
    status = RotatorStatus(
        "tower", state=MotionState.IDLE, bearing_deg=100.0, connected=True, available=True
    )
    doc = json.loads(pl.status_json(status, 1_000_000.0, False))
    doc.update(tracking_ended="the pass is over", **fields)
    return json.dumps(doc).encode()


def page_doc(payload: bytes) -> dict[str, Any]:
    """What the remote's page is told of that status: strict JSON, as a browser reads it."""
    text = pl.status_json(parse_status("tower", payload), 1_000_000.0, False)

    def no_constant(name: str) -> None:
        raise AssertionError(f"{name} is no JSON a browser reads: {text[:200]}")

    return json.loads(text, parse_constant=no_constant)  # type: ignore[no-any-return]


WIND_OK = {"speed_kmh": 20.0, "storm": False, "replayed": False, "halted": False}


@pytest.mark.parametrize(
    ("block", "says"),
    [
        ({"speed_kmh": float("nan"), "storm": False}, "not a finite number"),
        ({"speed_kmh": 1e400}, "not a finite number"),
        ({"speed_kmh": 20.0, "note": "\x1b]0;owned\x07"}, "a text holds U+001B"),
        ({"speed_kmh": 20.0, "note": "<script>" + "x" * 100_000}, "longer than"),
        ({"speed_kmh": 20.0, "more": [[[[[[[[1]]]]]]]]}, "nests deeper"),
        ({"speed_kmh": 20.0, "more": list(range(30_000))}, "longer than"),
        ("strong", "it is str, not dict"),
    ],
)
def test_a_block_of_the_station_s_status_that_no_station_writes_is_left_out_and_said(
    block: object, says: str, caplog: pytest.LogCaptureFixture
) -> None:
    """Readings.py rule 3: a forged block does not reach the page (a browser's JSON, a page
    drawn by console.js), the rest of the status does, and the log says which block and why,
    once while it stays."""
    payload = forged_status(wind=block)
    with caplog.at_level(logging.WARNING, logger="bridge.remote.readings"):
        shown = page_doc(payload)
        page_doc(payload)  # (read again at the next use: said once)
    assert "wind" not in shown
    assert shown["tracking_ended"] == "the pass is over" and shown["bearing"] == 100.0
    said = [rec.getMessage() for rec in caplog.records]
    assert len(said) == 1 and "'wind' block" in said[0] and says in said[0], said
    assert page_doc(forged_status(wind=WIND_OK))["wind"] == WIND_OK  # once right: shown


@pytest.mark.parametrize(
    ("who", "shown"),
    [
        ("G4XYZ", "G4XYZ"),
        ("G4XYZ\n[ok] lease free", UNSHOWN),
        ("x" * 5_000, UNSHOWN),
        (17, None),
    ],
)
def test_a_name_in_the_station_s_status_is_shown_only_as_a_station_writes_one(
    who: object, shown: str | None
) -> None:
    """Readings.py rule 3: the lease's holder and the last command's sender as the page shows
    them; a lease held by a name the page may not show is still a lease held."""
    doc = page_doc(
        forged_status(
            control={"holder": who, "until": "1970-01-12T13:46:40+00:00"}, last_operator=who
        )
    )
    if shown is None:
        assert doc["control"] is None and doc["last_operator"] is None
        return
    assert doc["control"]["holder"] == shown
    assert doc["last_operator"] == (shown if shown != UNSHOWN else None)
