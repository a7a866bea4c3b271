"""The remote's rotator as the GS-232, Easycomm and PstRotator endpoints use it (remote/rotator.py
rules 4 and 5), on a stand-in link and a fake clock: what it publishes, what it refuses and how
often it says so."""

from __future__ import annotations

import logging
from collections.abc import Callable

import pytest

from bridge.core.errors import RefusalCode, Refused
from bridge.core.model import (
    Lock,
    MotionState,
    Park,
    RotatorStatus,
    Source,
    Stop,
    Target,
    Toward,
)
from bridge.interfaces.gs232 import Dcu1Session, EasycommSession, Gs232Session
from bridge.interfaces.gs232.commands import DCU1_ERROR
from bridge.interfaces.mqtt.payloads import info_json, status_json
from bridge.interfaces.mqtt.topics import StationTopics
from bridge.interfaces.rotctld.server import RotctldSession
from bridge.pointing import Pointing
from bridge.protocols import REGISTRY
from bridge.remote.console import Drawn, RemoteConsoleRotator
from bridge.remote.rotator import REFUSAL_LOG_S, Info, RemoteRotator, StationView
from bridge.settings import settings_from
from tests.support.clock import FakeClock
from tests.support.remote import Link


def info(park: str = "null") -> Info:
    return Info.parse(
        b'{"name":"tower","model":"rotorez","azimuth_range":[0,360],"elevation_range":null,'
        b'"keep_out":[],"park":' + park.encode() + b',"options":[]}'
    )


def rotator(link: Link, clock: FakeClock, park: str = "null") -> RemoteRotator:
    station = StationTopics("rotor")
    view = StationView(clock)  # the station there: its bridge and the rotator online, heard
    view.put(station.bridge_state, b"online")
    view.put(station.bridge_heartbeat, b"1700000000.000")
    view.put(station.rotator("tower").availability, b"online")
    return RemoteRotator(
        "tower",
        station.rotator("tower"),
        station,
        info(park),
        view,
        link,
        "DL1ABC",
        5,
        clock=clock,
    )


def test_park_and_a_place_go_to_the_station_which_knows_where_it_is() -> None:
    link = Link()
    rot = rotator(link, FakeClock(), park="[180, null]")
    rot.submit(Park(source=Source.EASYCOMM), "easycomm PARK")
    rot.submit(Toward(35.7, 139.7, "PM95vq", source=Source.PST), "pst")
    rot.submit(Toward(35.7, 139.7, long_path=True, source=Source.PST), "pst")
    assert link.sent == [
        ("rotor/tower/park", "park"),
        ("rotor/tower/target", '{"locator":"PM95vq"}'),
        ("rotor/tower/target", '{"latitude":35.7,"longitude":139.7,"path":"long"}'),
    ]


def test_park_without_a_park_position_is_refused_and_sends_nothing() -> None:
    link = Link()
    with pytest.raises(Refused) as caught:
        rotator(link, FakeClock()).submit(Park(source=Source.PST), "pst <PARK>")
    assert caught.value.code is RefusalCode.UNSUPPORTED and link.sent == []


def test_refusals_are_logged_rarely_per_front_end_with_a_count(
    caplog: pytest.LogCaptureFixture,
) -> None:
    clock, link = FakeClock(), Link(up=False)
    rot = rotator(link, clock)
    with caplog.at_level(logging.WARNING, logger="bridge.remote.rotator"):
        for described, command in (
            ("gs232 W120 000", Target(120, None)),
            ("gs232 W121 000", Target(121, None)),
            ("pst <STOP>", Stop(Source.PST)),
            ("gs232 S", Stop(Source.GS232)),
        ):
            with pytest.raises(Refused):
                rot.submit(command, described)
        clock.t += REFUSAL_LOG_S
        with pytest.raises(Refused):
            rot.submit(Target(122, None), "gs232 W122 000")
    said = [r.getMessage() for r in caplog.records]
    assert said == [
        "tower: gs232 W120 000 refused: not connected to the station's broker",
        "tower: pst <STOP> refused: not connected to the station's broker",
        "tower: gs232 W122 000 refused: not connected to the station's broker (2 more since)",
    ]


def test_a_stop_the_broker_cannot_take_is_answered_as_a_refusal_on_gs232_and_easycomm(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """The GS-232 and Easycomm sessions (gs232/ rule 6) on the remote with its link down: the
    client hears the refusal in its protocol, and the log says it once, without a traceback."""
    clock, link = FakeClock(), Link(up=False)
    rot = rotator(link, clock)
    with caplog.at_level(logging.WARNING):
        assert Gs232Session(rot).feed(b"S\r") == [b"?>\r\n"]
        assert EasycommSession(rot).feed(b"SA SE \n") == [b""]  # Hamlib reads no reply: the log
    assert link.sent == []
    assert [(r.name, r.getMessage()) for r in caplog.records] == [
        ("bridge.remote.rotator", "tower: gs232 S refused: not connected to the station's broker"),
        (
            "bridge.remote.rotator",
            "tower: easycomm SA SE refused: not connected to the station's broker",
        ),
    ]


def test_a_stop_the_broker_cannot_take_is_answered_with_the_banner_on_dcu1(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """The DCU-1 session (gs232/ rules 6 and 10) on the remote with its link down: ``;`` and
    ``AS1;`` are answered with the Rotor-EZ's banner, the client's only error."""
    clock, link = FakeClock(), Link(up=False)
    rot = rotator(link, clock)
    with caplog.at_level(logging.WARNING):
        assert Dcu1Session(rot).feed(b";AS1;") == [DCU1_ERROR, DCU1_ERROR]
    assert link.sent == []
    assert "tower: dcu1 ; refused: not connected to the station's broker" in caplog.messages


def test_a_stop_and_a_lock_on_are_the_last_halt() -> None:
    """interfaces/web/port.py rule 2, for the console on the remote: what the console's order of
    commands (interfaces/web/commands.py rule 5) measures a command against, on the remote's
    monotonic clock."""
    mono = FakeClock(100.0)
    remote = rotator(Link(), mono)
    console = RemoteConsoleRotator(remote, Drawn(), StationView(FakeClock()))
    console.submit(Stop(Source.WEB))
    assert console.last_halt_s == 100.0
    mono.t = 200.0
    remote._view.put(StationTopics("rotor").bridge_heartbeat, b"1700000100.000")  # still heard
    console.submit(Lock(False, source=Source.WEB))  # lock OFF halts nothing
    assert console.last_halt_s == 100.0
    console.submit(Lock(True, source=Source.WEB))
    assert console.last_halt_s == 200.0


def test_a_move_asked_before_a_stop_that_went_out_is_not_sent() -> None:
    """interfaces/web/port.py rules 2a and 2b on the remote: the halt count read when a move was
    asked refuses it once a stop or lock ON of another front end went out since; a stop itself
    is never refused so, and the console's own do not count (its queue orders them)."""
    link = Link()
    remote = rotator(link, FakeClock(100.0), park="[180, null]")
    console = RemoteConsoleRotator(remote, Drawn(), StationView(FakeClock()))
    asked = console.halts
    console.submit(Stop(Source.WEB))  # the console's own
    assert console.halts == asked
    remote.submit(Stop(Source.ROTCTLD), "rotctld S")  # the logger's STOP goes out first
    assert console.halts == asked + 1
    with pytest.raises(Refused) as caught:
        console.submit(Target(200.0, None, Source.WEB), "console target 200", since=asked)
    assert caught.value.code is RefusalCode.STALE
    with pytest.raises(Refused):
        remote.submit(Park(source=Source.WEB), "console park", since=asked)
    console.submit(Stop(Source.WEB), since=asked)  # never refused
    console.submit(Target(200.0, None, Source.WEB), "console target 200", since=console.halts)
    assert link.sent == [
        ("rotor/tower/stop", "stop"),
        ("rotor/tower/stop", "stop"),
        ("rotor/tower/stop", "stop"),
        ("rotor/tower/target", '{"azimuth":200.0}'),
    ]


def stop_on_the_way(link: Link, stop: Callable[[], None]) -> None:
    """``stop`` runs when the link is handed a target: a STOP sent on another thread between
    the judge and the link."""
    hand_on = link.send

    def send(
        topic: str,
        payload: str,
        operator: str,
        expiry_s: int,
        check: Callable[[], None] | None = None,
        *,
        until_heard: bool = False,
        seen_s: float | None = None,
        after: tuple[str, ...] = (),
        reader: object = None,
        read_s: float | None = None,
    ) -> None:
        if topic.endswith("/target"):
            stop()
        hand_on(topic, payload, operator, expiry_s, check, until_heard=until_heard)

    link.send = send  # type: ignore[method-assign]


def test_a_stop_counted_while_a_move_is_on_its_way_to_the_link_is_never_overtaken() -> None:
    """interfaces/web/port.py rule 2b up to the hand-off (interfaces/mqtt/remote.py rule 9):
    the logger's STOP counted after the console's move was judged, before the link took it,
    still refuses the move, which would reach the broker after the STOP."""
    link = Link()
    remote = rotator(link, FakeClock(100.0))
    console = RemoteConsoleRotator(remote, Drawn(), StationView(FakeClock()))
    stop_on_the_way(link, lambda: remote.submit(Stop(Source.ROTCTLD), "rotctld S"))  # logger's
    with pytest.raises(Refused) as caught:
        console.submit(Target(200.0, None, Source.WEB), "console target 200", since=console.halts)
    assert caught.value.code is RefusalCode.STALE
    assert link.sent == [("rotor/tower/stop", "stop")]


def test_an_elevation_alone_goes_to_the_stations_elevation_topic(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """docs/remote.md: Easycomm's ``EL30`` alone goes to the station's ``R/target/elevation``
    (attack 17: it was refused, and a client that sends the two axes apart never lifted the
    antenna); both together go on ``R/target`` as one document."""
    station, link = StationTopics("rotor"), Link()
    azel = Info.parse(
        b'{"name":"dish","model":"rot2prog","azimuth_range":[0,360],"elevation_range":[0,90]}'
    )
    view = StationView(FakeClock())  # the station there (online, heard), as a move needs
    view.put(station.bridge_state, b"online")
    view.put(station.bridge_heartbeat, b"1700000000.000")
    view.put(station.rotator("dish").availability, b"online")
    rot = RemoteRotator("dish", station.rotator("dish"), station, azel, view, link, "X", 5)
    with caplog.at_level(logging.WARNING, logger="bridge.remote.rotator"):
        assert EasycommSession(rot).feed(b"EL30.0\n") == [b""]
    assert not caplog.records
    assert link.sent == [("rotor/dish/target/elevation", "30")]
    assert EasycommSession(rot).feed(b"AZ30.0 EL10.0\n") == [b""]
    assert link.sent[1:] == [("rotor/dish/target", '{"azimuth":30.0,"elevation":10.0}')]


def test_another_operators_lease_refuses_a_move_at_once_in_the_stations_words() -> None:
    """Rule 6: the station's retained R/control says who holds it; the remote spares its client
    the silent refusal (rotctld would answer RPRT 0 and nothing would turn)."""
    link = Link()
    rot = rotator(link, FakeClock())
    wall = 1_800_000_000.0
    rot._wall = lambda: wall  # the operator's clock
    control = rot.topics.feature("control")  # R/control (bridge/features/control/)
    rot._view.put(control, b'{"holder":"G4XYZ","until":"2027-01-15T08:30:00.000+00:00"}')
    with pytest.raises(Refused) as caught:
        rot.submit(Target(120.0, None, Source.ROTCTLD), "rotctld P 120")
    assert caught.value.code is RefusalCode.LEASED
    assert str(caught.value).startswith("G4XYZ holds the rotator until 08:30 UTC")
    rot.submit(Stop(Source.ROTCTLD), "rotctld S")  # a stop is never refused
    assert link.sent == [("rotor/tower/stop", "stop")]
    rot._view.put(control, b'{"holder":"dl1abc","until":"2027-01-15T08:30:00.000+00:00"}')
    rot.submit(Target(120.0, None, Source.ROTCTLD), "rotctld P 120")  # our own, any case
    rot._view.put(control, b'{"holder":"G4XYZ","until":"2020-01-01T00:00:00.000+00:00"}')
    rot.submit(Target(130.0, None, Source.ROTCTLD), "rotctld P 130")  # ended: the station judges
    rot._view.put(control, b'{"holder":null,"until":null}')
    rot.submit(Target(140.0, None, Source.ROTCTLD), "rotctld P 140")
    assert [p for t, p in link.sent if t == "rotor/tower/target"] == [
        '{"azimuth":120.0}',
        '{"azimuth":130.0}',
        '{"azimuth":140.0}',
    ]


def test_a_station_rotator_of_two_boxes_is_served_by_the_remote() -> None:
    """A composite rotator's R/info (its model ``rt21+gs232b``, protocols/axes.py rule 4) is
    one the remote knows: an az/el rotator whose GS-232 ``W`` goes to the station."""
    r = settings_from(
        {
            "rotators": [
                {
                    "id": "dish",
                    "azimuth": {"model": "rt21", "port": "/dev/ttyAZ"},
                    "elevation": {"model": "gs232b", "port": "/dev/ttyEL"},
                }
            ]
        },
        environ={},
    ).rotators[0]
    payload = info_json("dish", r.spec, r.pointing, True, rotator_id="dish").encode()
    azel = Info.parse(payload)  # refused as an unknown model before
    assert azel.spec.has_elevation and azel.spec.name == "rt21+gs232b"
    station, link = StationTopics("rotor"), Link()
    view = StationView(FakeClock())
    view.put(station.bridge_state, b"online")
    view.put(station.bridge_heartbeat, b"1700000000.000")
    view.put(station.rotator("dish").availability, b"online")
    rot = RemoteRotator("dish", station.rotator("dish"), station, azel, view, link, "X", 5)
    assert Gs232Session(rot).feed(b"W120 030\r") == [b""]
    assert link.sent == [("rotor/dish/target", '{"azimuth":120,"elevation":30}')]


def test_a_loggers_move_judged_before_the_consoles_stop_is_never_sent_after_it() -> None:
    """docs/architecture.md rule 11 on the remote: a move judged before a STOP another front end
    sent on another thread never runs after it. The remote's rotctld P (no ``since``: it asks
    and submits at once) was judged, then the console's STOP went out before the link took the
    P: the P reached the broker after the STOP, and the station turned the rotor after it. The
    station's own judge drops such a P (mailbox.py rule 10); the remote must not send it."""
    link = Link()
    remote = rotator(link, FakeClock(100.0))
    console = RemoteConsoleRotator(remote, Drawn(), StationView(FakeClock()))
    stop_on_the_way(link, lambda: console.submit(Stop(Source.WEB)))  # the console's
    with pytest.raises(Refused) as caught:
        remote.submit(Target(200.0, None, Source.ROTCTLD), "rotctld P 200")
    assert caught.value.code is RefusalCode.STALE
    assert link.sent == [("rotor/tower/stop", "stop")]


def test_another_dcu1_clients_stop_before_an_am1_is_handed_on_refuses_it() -> None:
    """Two DCU-1 clients on the remote's endpoint (gs232/ rule 10): A's AM1 is submitted with
    the count kept with its AP1 (``halts_for``: halts_besides DCU1), then B's ``;`` is counted
    and goes to the broker before A's bearing is handed on. The bearing, asked before that
    stop, must not follow it (a review of 1d6026b: B's stop is a DCU-1 one, left out of
    halts_besides, and the rotor turned after it; before, the submit's own count caught it)."""
    link = Link()
    rot = rotator(link, FakeClock())
    a, b = Dcu1Session(rot), Dcu1Session(rot)
    assert a.feed(b"AP1120;") == [b""]
    stop_on_the_way(link, lambda: b.feed(b";") and None)
    assert a.feed(b"AM1;") == [DCU1_ERROR]
    assert link.sent == [("rotor/tower/stop", "stop")]


def test_an_ap1_and_its_am1_turn_the_rotor_and_the_clients_own_stop_between_refuses_it() -> None:
    """gs232/ rule 10 on the remote: AP1 then AM1 goes; with the client's own ``;`` between
    them the AM1 is refused (halts, every front end's, at the check)."""
    link = Link()
    rot = rotator(link, FakeClock())
    assert Dcu1Session(rot).feed(b"AP1120;AM1;") == [b"", b""]
    assert Dcu1Session(rot).feed(b"AP1130;;AM1;")[-1] == DCU1_ERROR
    assert link.sent == [("rotor/tower/target", '{"azimuth":120}'), ("rotor/tower/stop", "stop")]


def _far_450(offset_deg: float, raw_deg: float) -> RemoteRotator:
    """The remote's view of a station's 450-degree GS-232B turned ``offset_deg`` off north
    (its R/info: true bearings, no offset), at rest at raw ``raw_deg`` (its R/status)."""
    spec = REGISTRY["gs232b-az-450"]
    aim = Pointing.of(spec, offset_deg=offset_deg)
    clock, station = FakeClock(), StationTopics("rotor")
    view = StationView(clock)
    view.put(station.bridge_state, b"online")
    view.put(station.bridge_heartbeat, b"1700000000.000")
    view.put(station.rotator("tower").availability, b"online")
    info = Info.parse(info_json("tower", spec, aim, can_track=False).encode())
    rot = RemoteRotator(
        "tower", station.rotator("tower"), station, info, view, Link(), "DL1ABC", 5, clock=clock
    )
    at = RotatorStatus(
        "tower",
        state=MotionState.IDLE,
        bearing_deg=aim.true_of(raw_deg),
        raw_bearing_deg=raw_deg,
        connected=True,
        available=True,
    )
    view.put(station.rotator("tower").status, status_json(at, 1.7e9, False, aim.shows_raw).encode())
    return rot


@pytest.mark.parametrize(("offset_deg", "raw_deg"), [(10.0, 390.0), (-20.0, 420.0), (180.0, 220.0)])
def test_a_far_client_that_named_the_side_reads_its_bearing_past_360_off_north_too(
    offset_deg: float, raw_deg: float
) -> None:
    """On the remote, a GS-232 client that sent W400 and a rotctld client that sent P 400 read
    400 once the station's rotor, mounted ``offset_deg`` off north, is there (raw 400 less the
    offset), as they do at the station. Before: the station's raw value with the remote's
    offset, which is none (its ranges are true bearings): AZ=390 for 400, 360 off and more."""
    rot = _far_450(offset_deg, raw_deg)
    gs232 = Gs232Session(rot)
    assert gs232.feed(b"W400 000\r") == [b""]
    assert gs232.feed(b"C\r") == [b"AZ=400\r\n"]
    rotctld = RotctldSession(rot)
    assert rotctld.feed(b"P 400 0\n") == [b"RPRT 0\n"]
    assert rotctld.feed(b"p\n") == [b"400.00\n0.00\n"]
    assert Gs232Session(rot).feed(b"C\r") == [b"AZ=040\r\n"]  # (one that named no side)


@pytest.mark.parametrize("stopper", ["rotctld", "gs232"])
def test_a_stop_from_another_client_fences_a_move_sent_before_it_on_the_remote(
    stopper: str,
) -> None:
    """tcplines.py rule 9 (a cold review): on the remote, a client's count of halts left out
    its own front end's (``halts_for``), so one rotctld client's STOP did not fence another
    rotctld client's move that had come before it and was read after it. The server's look at
    the second client, taken before the STOP, is set here as the server sets it."""
    link = Link()
    rot = rotator(link, FakeClock())
    late = RotctldSession(rot)
    late.fence.arrived = rot.halts  # its "P 100 0" is in the kernel
    if stopper == "rotctld":
        RotctldSession(rot).feed(b"S\n")
    else:
        Gs232Session(rot).feed(b"S\r")
    assert late.feed(b"P 100 0\n") == [b"RPRT -9\n"]
    assert [topic.rsplit("/", 1)[-1] for topic, _ in link.sent] == ["stop"]
