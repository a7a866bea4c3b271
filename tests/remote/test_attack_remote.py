"""Attacks on ``rotor-bridge remote``: what a hostile client on the station's broker, an unlucky
network or an unlucky user can do to it, and what the operator's programs then see.

The pure parts run in virtual time on a stand-in link; the wiring on a real mosquitto with the
station's bridge on an emulator (tests/support/rig.py)."""

from __future__ import annotations

import pytest

from bridge.errors import RefusalCode, Refused
from bridge.gs232.commands import EasycommSession, Gs232Session
from bridge.model import RotatorStatus
from bridge.mqtt.topics import StationTopics
from bridge.remote.console import ConsoleFeed, Drawn, RemoteConsoleRotator
from bridge.remote.rotator import Info, RemoteRotator, StationView
from bridge.rotctld.server import RotctldSession

STATION = StationTopics("rotor")
INFO = (
    b'{"name":"tower","model":"rotorez","azimuth_range":[0,360],"elevation_range":null,'
    b'"keep_out":[],"park":null,"options":[]}'
)


class Link:
    def __init__(self) -> None:
        self.up = True
        self.sent: list[tuple[str, str]] = []

    def send(self, topic: str, payload: str, operator: str, expiry_s: int) -> None:
        if not self.up:
            raise Refused(RefusalCode.OFFLINE, "not connected to the station's broker")
        self.sent.append((topic, payload))


class Pages:
    def __init__(self) -> None:
        self.statuses: dict[str, list[RotatorStatus]] = {}

    def on_status(self, rotator_id: str, status: RotatorStatus) -> None:
        self.statuses.setdefault(rotator_id, []).append(status)

    def on_event(self, rotator_id: str, event: object) -> None:
        pass


def station_rotator(view: StationView, rid: str, link: Link | None = None) -> RemoteRotator:
    topics = STATION.rotator(rid)
    view.put(STATION.bridge_state, b"online")
    view.put(topics.availability, b"online")
    return RemoteRotator(
        rid, topics, STATION.bridge_state, Info.parse(INFO), view, link or Link(), "DL1ABC", 5
    )


def idle_status(bearing: str) -> bytes:
    return (
        b'{"bearing":' + bearing.encode() + b',"state":"idle","connected":true,"available":true,'
        b'"locked":false,"time":"2026-01-01T00:00:00+00:00"}'
    )


# -- forged statuses on the broker -------------------------------------------------------------
HOSTILE_STATUSES = [
    pytest.param(b"[1, 2]", id="a JSON list"),
    pytest.param(b'"online"', id="a JSON string"),
    pytest.param(b"42", id="a JSON number"),
    pytest.param(idle_status("NaN"), id="a NaN bearing"),
    pytest.param(idle_status("Infinity"), id="an infinite bearing"),
    pytest.param(idle_status("1e400"), id="a bearing past a float"),
]


@pytest.mark.parametrize("payload", HOSTILE_STATUSES)
def test_a_forged_status_is_no_reading_and_no_crash(payload: bytes) -> None:
    """Anyone who may publish on the station's status topic can put any bytes there, retained.
    The remote's clients get "no position" (rotctld's error code, GS-232's ``?>``, Easycomm's
    error), never a number that is not one, and nothing raises: Gpredict polls ``p`` every
    second, each failure would be a traceback in the log."""
    view = StationView()
    rot = station_rotator(view, "tower")
    view.put(rot.topics.status, payload)
    status = rot.status  # raised AttributeError for a list, a string, a number
    assert status.bearing_deg is None
    assert RotctldSession(rot).feed(b"p\n") == [b"RPRT -5\n"]  # type: ignore[arg-type]
    assert Gs232Session(rot).feed(b"C2\r") == [b"?>\r\n"]  # type: ignore[arg-type]
    assert EasycommSession(rot).feed(b"AZ\n") == [b"ALposition unknown\n"]  # type: ignore[arg-type]


@pytest.mark.parametrize("payload", HOSTILE_STATUSES[:3])
def test_one_rotators_forged_status_does_not_freeze_the_consoles_other_rotators(
    payload: bytes,
) -> None:
    """The console's feed shows every rotator: a junk status on one must not stop the others'
    statuses reaching the pages (it stopped at the first that raised, on every message)."""
    view, pages = StationView(), Pages()
    junk, good = station_rotator(view, "a"), station_rotator(view, "b")
    shown = [RemoteConsoleRotator(r, Drawn(), view) for r in (junk, good)]
    feed = ConsoleFeed(shown, pages)
    view.put(junk.topics.status, payload)
    view.put(good.topics.status, idle_status("123.0"))
    feed.on_message(good.topics.status, idle_status("123.0"))
    assert [s.bearing_deg for s in pages.statuses["b"]] == [123.0]
    assert not pages.statuses["a"][-1].available
