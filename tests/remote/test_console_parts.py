"""The remote console's pure parts (bridge/remote/console.py), in virtual time: what each console
command publishes (judged by the station's own payload parsers, interfaces/mqtt/payloads.py), what
is refused at once offline, the station's R/info, R/presets, R/status and R/error read back, and
which statuses reach the pages."""

from __future__ import annotations

import json
from dataclasses import replace

import pytest

from bridge.core.errors import RefusalCode, Refused
from bridge.core.model import (
    ErrorEvent,
    ErrorKind,
    MotionState,
    RotatorStatus,
    Source,
    Target,
    TargetInfo,
    TrackingInfo,
)
from bridge.features import tracking
from bridge.interfaces.mqtt import payloads as pl
from bridge.interfaces.mqtt.topics import StationTopics
from bridge.interfaces.web.commands import carry_out, parse
from bridge.pointing import Pointing
from bridge.protocols import REGISTRY
from bridge.remote.console import (
    ConsoleFeed,
    Drawn,
    RemoteConsoleRotator,
    parse_event,
    parse_presets,
)
from bridge.remote.rotator import Info, RemoteRotator, StationView, parse_status
from tests.support.clock import FakeClock
from tests.support.remote import Link

SPEC = REGISTRY["rotorez"]
T = StationTopics("rotor").rotator(None)


class Pages:
    def __init__(self) -> None:
        self.statuses: list[RotatorStatus] = []
        self.events: list[ErrorEvent] = []

    def on_status(self, rotator_id: str, status: RotatorStatus) -> None:
        self.statuses.append(status)

    def on_event(self, rotator_id: str, event: ErrorEvent) -> None:
        self.events.append(event)


def info_payload(**console: object) -> bytes:
    facts = pl.ConsoleFacts(**console)  # type: ignore[arg-type]
    # a park position: the console's page offers park only then (console.js)
    pointing = Pointing.of(SPEC, park=(180.0, None))
    return pl.info_json("tower", SPEC, pointing, True, facts).encode()


def rig(
    wall: FakeClock | None = None,
) -> tuple[RemoteConsoleRotator, Link, Pages, StationView]:
    clock = wall or FakeClock(1_000_000.0)
    view, link, pages = StationView(clock), Link(), Pages()
    payload = info_payload(station=(52.5, 13.3), locator="JO62qm", satellites=("ISS",))
    view.put(T.info, payload)
    view.put("rotor/bridge/state", b"online")
    view.put("rotor/bridge/heartbeat", b"1000000.000")  # heard just now
    view.put(T.availability, b"online")
    remote = RemoteRotator(
        "tower", T, StationTopics("rotor"), Info.parse(payload), view, link, "DL1ABC", 5
    )
    rot = RemoteConsoleRotator(remote, Drawn.parse(payload), view, wall=clock)
    rot.pages = pages
    return rot, link, pages, view


def run(rot: RemoteConsoleRotator, **doc: object) -> None:
    carry_out(rot, parse(json.dumps(doc).encode()))


@pytest.mark.parametrize(
    ("doc", "topic", "understood"),
    [
        ({"command": "target", "az": 120}, T.target, (120.0, None)),
        (
            {"command": "toward", "locator": "PM95vq", "long_path": True},
            T.target,
            pl.Place(35.6875, 139.7917, "PM95vq", True),
        ),
        (
            {"command": "toward", "latitude_deg": -33.9, "longitude_deg": 18.4},
            T.target,
            pl.Place(-33.9, 18.4, None, False),
        ),
        ({"command": "path", "long_path": True}, T.target, pl.Place(None, None, None, True)),
        ({"command": "nudge", "d_az": -5}, T.nudge, (-5.0, None)),
        ({"command": "preset", "name": "EU"}, T.preset, "EU"),
        ({"command": "park"}, T.park, "park"),
        ({"command": "track", "body": "ISS"}, T.feature(tracking.COMMAND), ("ISS", None)),
        ({"command": "lock", "on": True}, T.lock, True),
        ({"command": "stop"}, T.stop, "stop"),
    ],
)
def test_each_command_is_one_publish_the_station_understands(
    doc: dict[str, object], topic: str, understood: object
) -> None:
    rot, link, pages, _ = rig()
    run(rot, **doc)
    ((sent_topic, payload),) = link.sent
    assert sent_topic == topic
    raw = payload.encode()
    got: object
    if topic == T.target:
        got = pl.parse_aim(raw)
        if isinstance(got, pl.Place) and got.latitude_deg is not None:
            assert got.longitude_deg is not None
            got = replace(got, latitude_deg=round(got.latitude_deg, 4))
            got = replace(got, longitude_deg=round(got.longitude_deg, 4))
    elif topic == T.nudge:
        got = pl.parse_nudge(raw)
    elif topic == T.feature(tracking.COMMAND):
        got = pl.parse_track(raw)
    elif topic == T.lock:
        got = pl.parse_switch(raw)
    else:
        got = payload
    assert got == understood
    assert not pages.events


def test_offline_every_command_is_refused_at_once_and_the_pages_hear_it() -> None:
    rot, link, pages, _ = rig()
    link.up = False
    for doc in ({"command": "stop"}, {"command": "lock", "on": True}, {"command": "park"}):
        with pytest.raises(Refused) as refused:
            run(rot, **doc)
        assert refused.value.code is RefusalCode.OFFLINE
    assert not link.sent
    assert [e.kind for e in pages.events] == [ErrorKind.REFUSED] * 3
    assert pages.events[0].command == "console: stop"


def test_with_the_station_offline_what_moves_is_refused_and_stop_and_lock_go_out() -> None:
    rot, link, pages, view = rig()
    view.put(T.availability, b"offline")
    for doc in (
        {"command": "target", "az": 120},
        {"command": "preset", "name": "EU"},
        {"command": "nudge", "d_az": 5},
        {"command": "track", "body": "sun"},
    ):
        with pytest.raises(Refused) as refused:
            run(rot, **doc)
        assert refused.value.code is RefusalCode.OFFLINE
        assert "offline" in refused.value.message
    assert not link.sent and len(pages.events) == 4
    for doc in (
        {"command": "stop"},
        {"command": "lock", "on": True},
        {"command": "lock", "on": False},
        {"command": "track", "body": "off"},
    ):
        run(rot, **doc)
    assert [topic for topic, _ in link.sent] == [
        T.stop,
        T.lock,
        T.lock,
        T.feature(tracking.COMMAND),
    ]


def test_a_target_outside_the_station_range_is_refused_here_and_nothing_sent() -> None:
    rot, link, pages, _ = rig()
    with pytest.raises(Refused):
        run(rot, command="target", az=400)
    assert not link.sent and len(pages.events) == 1


def test_a_station_that_cannot_track_is_not_asked_but_off_goes_out() -> None:
    rot, link, _, _ = rig()
    rot.drawn = Drawn(can_track=False)
    with pytest.raises(Refused):
        run(rot, command="track", body="sun")
    run(rot, command="track", body="off")
    assert link.sent == [(T.feature(tracking.COMMAND), "off")]


def test_the_station_description_and_presets_read_back() -> None:
    rot, _, _, view = rig()
    assert rot.drawn.station == (52.5, 13.3) and rot.drawn.locator == "JO62qm"
    assert rot.drawn.satellites == ("ISS",) and rot.can_track
    assert Drawn.parse(b'{"name": "old", "model": "rotorez"}') == Drawn()  # an older bridge
    assert rot.pointing.presets == {}
    view.put(T.presets, pl.presets_json({"EU": (45.0, None), "SAT": (180.0, 5.0)}).encode())
    assert rot.pointing.presets == {"EU": (45.0, None), "SAT": (180.0, 5.0)}
    assert parse_presets(b"not json") == {}
    assert parse_presets(b'{"A": [null, 5], "B": "x", "C": 10}') == {"C": (10.0, None)}


def test_a_status_reads_back_as_the_station_rendered_it() -> None:
    status = RotatorStatus(
        "tower",
        state=MotionState.MOVING,
        bearing_deg=100.0,
        target_az_deg=120.0,
        connected=True,
        available=True,
        options={"jam": True},
        last_command_source="mqtt",
        target_info=TargetInfo(35.6875, 139.7917, 8900.0, 40.0, 220.0, "short", "PM95vq"),
        tracking=TrackingInfo("sun", "tracking", 120.0, 30.0, 120.5, 30.2, flip=False),
    )
    rendered = pl.status_json(status, 1_000_000.0, False)
    again = parse_status("tower", rendered.encode())
    assert pl.status_json(again, 1_000_000.0, False) == rendered
    # a satellite's elements, stale (session/tracking.py rule 11): the remote shows it too
    sat = TrackingInfo("AO-7", "waiting", elements_epoch_unix=990_000.0, elements_stale=True)
    rendered = pl.status_json(replace(status, tracking=sat), 1_000_000.0, False)
    assert json.loads(rendered)["tracking"]["elements_stale"] is True
    again = parse_status("tower", rendered.encode())
    assert again.tracking == sat
    # ... and elements dated after the station's clock (the same rule)
    sat = replace(sat, elements_stale=False, elements_ahead=True)
    rendered = pl.status_json(replace(status, tracking=sat), 1_000_000.0, False)
    assert json.loads(rendered)["tracking"]["elements_ahead"] is True
    assert parse_status("tower", rendered.encode()).tracking == sat


def test_an_error_event_reads_back() -> None:
    event = ErrorEvent(ErrorKind.REFUSED, "rotator is locked", "target '200'", 1_000.0)
    assert parse_event(json.dumps(event.as_dict()).encode()) == event
    assert parse_event(b'{"kind": "nonsense"}') is None


def test_the_pages_see_a_status_once_and_unavailable_when_the_station_is_not_current() -> None:
    wall = FakeClock(1_000_000.0)
    rot, link, pages, view = rig(wall)
    feed = ConsoleFeed([rot], pages)
    for topic, payload in (("rotor/bridge/state", b"online"), (T.availability, b"online")):
        view.put(topic, payload)
        feed.on_message(topic, payload)
    live = RotatorStatus(
        "tower", state=MotionState.MOVING, bearing_deg=42.0, connected=True, available=True
    )
    raw = pl.status_json(live, wall(), False).encode()
    view.put(T.status, raw)
    feed.on_message(T.status, raw)
    feed.on_message(T.status, raw)  # the same again: nothing new for the pages
    assert [s.bearing_deg for s in pages.statuses] == [None, 42.0]
    wall.t += 11  # a moving status gone quiet (the remote's clock): the ticker greys it
    feed.refresh()
    assert pages.statuses[-1].bearing_deg is None and not pages.statuses[-1].available
    wall.t -= 11
    feed.refresh()
    assert pages.statuses[-1].bearing_deg == 42.0
    link.up = False  # the link gone
    feed.refresh()
    assert pages.statuses[-1].bearing_deg is None
    error = json.dumps(ErrorEvent(ErrorKind.STALLED, "stalled", None, 5.0).as_dict()).encode()
    feed.on_message(T.error, error)
    assert pages.events[-1].kind is ErrorKind.STALLED


def test_a_target_goes_as_the_remote_rotator_sends_it() -> None:
    rot, link, _, _ = rig()
    rot.submit(Target(200.0, None, Source.WEB), "console: target az 200")
    assert link.sent == [(T.target, '{"azimuth":200.0}')]
