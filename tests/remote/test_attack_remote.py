"""Attacks on ``rotor-bridge remote``: what a hostile client on the station's broker, an unlucky
network or an unlucky user can do to it, and what the operator's programs then see.

The pure parts run in virtual time on a stand-in link; the wiring on a real mosquitto with the
station's bridge on an emulator (tests/support/rig.py)."""

from __future__ import annotations

import logging
import os
import re
import signal
import socket
import subprocess
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import pytest
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.reasoncodes import ReasonCode

from bridge.core.errors import RefusalCode, Refused
from bridge.core.model import Lock, RotatorStatus, Source, Stop, TrackBody
from bridge.interfaces.gs232.commands import EasycommSession, Gs232Session
from bridge.interfaces.loggers import LoggerEndpoints
from bridge.interfaces.mqtt.heartbeat import SILENT_S
from bridge.interfaces.mqtt.remote import RemoteLink
from bridge.interfaces.mqtt.topics import StationTopics
from bridge.interfaces.rotctld.server import RotctldSession
from bridge.remote.console import (
    ConsoleFeed,
    Drawn,
    RemoteConsoleRotator,
    drawn_of,
    parse_event,
    parse_presets,
)
from bridge.remote.rotator import Info, RemoteRotator, StationView
from bridge.remote.run import Remote, StartError
from bridge.remote.settings import RemoteSettings
from tests.support import wait_until
from tests.support.clock import FakeClock
from tests.support.mosquitto import free_port
from tests.support.remote import Link, ask, remote_published
from tests.support.rig import Rig
from tests.support.waiting import slow

STATION = StationTopics("rotor")
INFO = (
    b'{"name":"tower","model":"rotorez","azimuth_range":[0,360],"elevation_range":null,'
    b'"keep_out":[],"park":null,"options":[]}'
)


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
    view.put(STATION.bridge_heartbeat, b"1700000000.000")  # heard just now
    view.put(topics.availability, b"online")
    return RemoteRotator(rid, topics, STATION, Info.parse(INFO), view, link or Link(), "DL1ABC", 5)


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
    # an attack pass: JSON nested past the parser's depth raised RecursionError, not ValueError
    pytest.param(b"[" * 100_000, id="JSON nested past the parser's depth"),
]


@pytest.mark.parametrize("payload", HOSTILE_STATUSES)
def test_a_forged_status_is_no_reading_and_no_crash(payload: bytes) -> None:
    """Anyone who may publish on the station's status topic can put any bytes there, retained.
    The remote's clients get "no position" (rotctld's error code, GS-232's ``?>``, Easycomm's
    error), never a number that is not one, and nothing raises: Gpredict polls ``p`` every
    second, each failure would be a traceback in the log."""
    view = StationView(FakeClock())
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
    view, pages = StationView(FakeClock()), Pages()
    junk, good = station_rotator(view, "a"), station_rotator(view, "b")
    shown = [RemoteConsoleRotator(r, Drawn(), view) for r in (junk, good)]
    feed = ConsoleFeed(shown, pages)
    view.put(junk.topics.status, payload)
    view.put(good.topics.status, idle_status("123.0"))
    feed.on_message(good.topics.status, idle_status("123.0"))
    assert [s.bearing_deg for s in pages.statuses["b"]] == [123.0]
    assert not pages.statuses["a"][-1].available


def test_forged_control_presets_and_errors_nested_past_the_parsers_depth_are_no_crash() -> None:
    """An attack pass: ``R/control``, ``R/presets`` and ``R/error`` nested past the JSON
    parser's depth raised RecursionError where a forged payload must read as none: every
    move a client asked for raised with it (the lease's look at ``R/control``), and the
    console's presets and error events with them."""
    deep = b'{"holder":' * 100_000
    view, link = StationView(FakeClock()), Link()
    rot = station_rotator(view, "tower", link)
    view.put(rot.topics.status, idle_status("10.0"))
    view.put(rot.topics.feature("control"), deep)
    assert RotctldSession(rot).feed(b"P 120 0\n") == [b"RPRT 0\n"]  # type: ignore[arg-type]
    assert [topic for topic, _ in link.sent] == ["rotor/tower/target"]
    assert parse_presets(deep) == {}
    assert parse_event(deep) is None


@pytest.mark.parametrize("until", ["9999-12-31T23:59:59-14:00", "0001-01-01T00:00:00+14:00"])
def test_a_forged_controls_end_no_clock_can_show_is_no_crash(until: str) -> None:
    """An attack pass: ``R/control`` naming another holder until a time past year 9999 once
    in UTC (a valid ISO time with its offset) raised ValueError where the lease's words were
    made, at every move a client asked for: rotctld answered ``RPRT -7`` and logged an
    internal error. Such a time is no station's: it reads as unknown, and the move goes."""
    view, link = StationView(FakeClock()), Link()
    rot = station_rotator(view, "tower", link)
    view.put(rot.topics.status, idle_status("10.0"))
    forged = f'{{"holder": "G4XYZ", "until": "{until}"}}'.encode()
    view.put(rot.topics.feature("control"), forged)
    assert RotctldSession(rot).feed(b"P 120 0\n") == [b"RPRT 0\n"]  # type: ignore[arg-type]
    assert [topic for topic, _ in link.sent] == ["rotor/tower/target"]


# -- the broker dropping at the worst moment ---------------------------------------------------
OPERATOR = "DL1ABC"


def remote_settings(broker_port: int, port: int, **extra: Any) -> RemoteSettings:
    return RemoteSettings(
        operator=OPERATOR,
        mqtt={"host": "127.0.0.1", "port": broker_port, "base_topic": "rotor"},
        endpoints=[{"rotator": "tower", "rotctld_port": port}],
        **extra,
    )


@contextmanager
def remote_of(rig: Rig) -> Iterator[tuple[Remote, int]]:
    """A remote on ``rig``'s broker, its rotctld port beside it, stopped at the end."""
    port = free_port()
    r = Remote(remote_settings(rig.broker.port, port))
    r.start()
    try:
        yield r, port
    finally:
        r.stop()


@pytest.fixture
def remote(station: Rig) -> Iterator[tuple[Remote, int]]:
    with remote_of(station) as remote:
        yield remote


def test_a_stop_the_broker_never_acknowledged_is_not_lost_when_it_comes_back(
    station: Rig, remote: tuple[Remote, int]
) -> None:
    """The broker stalls, then dies, between a stop's publish and its acknowledgement: the stop
    sat unacknowledged in paho's queue. The remote dropped it with the targets (never late), so
    the operator's STOP never reached the station (docs/architecture.md rule 11: a stop is never
    lost; a stop moves nothing, rule 7). No PUBACK within a second resets the connection
    (interfaces/mqtt/remote.py rule 7): the client hears the stop is not confirmed, and it goes
    again on the next connection; a target asked then is refused at once and never sent."""
    r, port = remote
    link = r.link
    assert link is not None
    station.broker.pause()
    assert ask(port, b"S\n") == b"RPRT -6\n"  # not acknowledged: held for the next connection
    assert link.resets == 1
    assert ask(port, b"P 250 0\n") == b"RPRT -6\n"  # refused at once while reconnecting
    tower = r.rotators[0]
    with pytest.raises(Refused):  # the console's lock ON (remote/console.py): not confirmed,
        # and kept like the stop (interfaces/mqtt/remote.py rule 6)
        tower.publish(tower.topics.lock, "ON")
    station.broker.kill()
    wait_until(lambda: not link.up, 30, "the remote sees the broker gone")
    log_from = station.broker.log.stat().st_size
    station.broker.restart()
    wait_until(lambda: link.up, 30, "the remote back on the broker")

    def published() -> list[bytes]:
        return remote_published(station.broker, log_from)

    wait_until(lambda: len(published()) >= 1, 10, "the unacknowledged stop sent again")
    wait_until(lambda: tower.current, 10, "the station's bridge heard again")  # (else RPRT -5)
    assert ask(port, b"S\n") == b"RPRT 0\n"  # a marker behind anything resent
    wait_until(lambda: len(published()) >= 5, 10, "the marker stop")
    # the halts kept, sent on connecting and again once the station's bridge is heard there
    # (rule 6: it may come back after the remote), then the marker; the target never
    assert published() == [b"stop", b"lock", b"stop", b"lock", b"stop"]


def test_a_kept_stop_reaches_a_station_bridge_that_comes_back_after_the_remote(rig: Rig) -> None:
    """The station's broker restarts during a move, and the station's bridge gets back on it
    after the remote does (its back-off later, or it restarts too): the operator's STOP, kept
    while the broker was away (RPRT -6: "kept and sent first on reconnect"), was sent first on
    the remote's new connection, to a broker the station's bridge had not subscribed to yet,
    and so to nobody; the rotor turned on to its last target. The kept stop goes again once
    the station's bridge is heard on the new connection (interfaces/mqtt/remote.py rule 6)."""
    emu = rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0, "speed_deg_s": 10.0})
    bridge = rig.start_process()
    rig.ready("tower")
    with remote_of(rig) as (r, port):
        link, tower = r.link, r.rotators[0]
        assert link is not None
        wait_until(lambda: tower.current, 10, "the station heard")
        assert ask(port, b"P 350 0\n") == b"RPRT 0\n"
        emu.wait_for(lambda s: s.is_moving and s.az_deg > 20, 10)
        os.kill(bridge.pid, signal.SIGSTOP)  # the station's bridge: back on the broker last
        try:
            rig.broker.kill()
            wait_until(lambda: not link.up, 30, "the remote sees the broker gone")
            assert ask(port, b"S\n") == b"RPRT -6\n"  # kept, sent first on reconnect
            log_from = rig.broker.log.stat().st_size
            rig.broker.restart()
            wait_until(lambda: link.up, 30, "the remote back on the broker")
            wait_until(
                lambda: remote_published(rig.broker, log_from) == [b"stop"], 10, "the kept stop"
            )
        finally:
            os.kill(bridge.pid, signal.SIGCONT)
        wait_until(lambda: tower.current, 30, "the station's bridge heard again")
        stopped = emu.wait_for(lambda s: not s.is_moving, 10)
        assert stopped.az_deg < 300, stopped  # stopped, not turned on to 350


@pytest.mark.parametrize("then", ["nothing", "tracking off"])
def test_a_stop_while_the_stations_bridge_restarts_reaches_it_when_it_is_back(
    rig: Rig, then: str
) -> None:
    """The station's bridge restarts during a move (a crash, an upgrade) while the controller
    turns on: the operator's STOP went to the broker while no bridge listened (answered
    RPRT -5, "may never reach the rotator"), and the bridge that started again never heard of
    it: the rotor turned on to its last target. The stop goes again once the station's bridge
    is heard (remote/rotator.py rule 3); the answer still says it had not been delivered.
    ``tracking off``: the operator then turns tracking off from the console, which goes
    whenever the link is up; it sent the STOP once more to nobody and ended its wait (a
    review): only a move asked later ends it (interfaces/mqtt/remote.py rule 6)."""
    emu = rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0, "speed_deg_s": 10.0})
    bridge = rig.start_process()
    rig.ready("tower")
    with remote_of(rig) as (r, port):
        tower = r.rotators[0]
        wait_until(lambda: tower.current, 10, "the station heard")
        assert ask(port, b"P 350 0\n") == b"RPRT 0\n"
        emu.wait_for(lambda s: s.is_moving and s.az_deg > 20, 10)
        bridge.kill()  # the station's bridge gone; the controller turns on
        wait_until(lambda: not tower.current, 30, "the station's bridge gone")
        assert ask(port, b"S\n") == b"RPRT -5\n"  # sent, not delivered
        if then == "tracking off":
            tower.submit(TrackBody("off", source=Source.WEB))  # never moves: it goes
        rig.start_process()
        wait_until(lambda: tower.current, 30, "the station's bridge heard again")
        stopped = emu.wait_for(lambda s: not s.is_moving, 10)
        assert stopped.az_deg < 300, stopped  # stopped, not turned on to 350


def test_a_lock_off_after_a_lock_on_the_station_did_not_hear_is_the_last_word(rig: Rig) -> None:
    """The operator locks the rotator while the station's bridge restarts (answered offline:
    sent again once the bridge is heard), then unlocks it: the OFF is the later word, and the
    ON kept for the bridge's return must not go after it and lock the rotator again."""
    rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
    bridge = rig.start_process()
    rig.ready("tower")
    with remote_of(rig) as (r, port):
        tower = r.rotators[0]
        wait_until(lambda: tower.current, 10, "the station heard")
        bridge.kill()
        wait_until(lambda: not tower.current, 30, "the station's bridge gone")
        log_from = rig.broker.log.stat().st_size
        with pytest.raises(Refused):
            tower.submit(Lock(True, source=Source.WEB))  # sent, not delivered
        tower.submit(Lock(False, source=Source.WEB))  # the later word
        rig.start_process()
        wait_until(lambda: tower.current, 30, "the station's bridge heard again")
        assert ask(port, b"S\n") == b"RPRT 0\n"  # a marker behind anything sent again
        wait_until(
            lambda: remote_published(rig.broker, log_from)[-1:] == [b"stop"], 10, "the marker"
        )
        assert remote_published(rig.broker, log_from) == [b"lock", b"lock", b"stop"]
        rig.probe.wait_value("rotor/lock/state", "OFF")


# -- clock skew between the operator and the station -------------------------------------------
def moving_status(station_time: str) -> bytes:
    return (
        b'{"bearing":77.0,"state":"moving","connected":true,"available":true,"locked":false,'
        b'"time":"' + station_time.encode() + b'"}'
    )


def skewed(offset_s: float, clock: FakeClock) -> str:
    """The station's clock, ``offset_s`` off the operator's (whose wall time is ``clock``)."""
    return datetime.fromtimestamp(clock() + offset_s, UTC).isoformat(timespec="milliseconds")


@pytest.mark.parametrize("station_behind_s", [30.0, 600.0])
def test_a_station_clock_behind_the_operators_does_not_blank_every_move(
    station_behind_s: float,
) -> None:
    """A station without a real-time clock (a Raspberry Pi) can be a minute off. Its moving
    statuses, arriving as it publishes them, are current: the remote read them as "gone quiet"
    because their ``time`` was older than moving_max_age_s on the operator's clock, so every
    rotctld ``p`` during every move was an error."""
    clock = FakeClock(1_700_000_000.0)
    view = StationView(clock)
    rot = station_rotator(view, "tower")
    view.put(rot.topics.status, moving_status(skewed(-station_behind_s, clock)))
    assert rot.status.bearing_deg == 77.0
    assert RotctldSession(rot).feed(b"p\n") == [b"77.00\n0.00\n"]  # type: ignore[arg-type]


def test_a_station_clock_ahead_does_not_keep_a_dead_move_current() -> None:
    """The station went quiet mid-move (a crash; its last will comes 1.5 keepalives later): its
    last moving status must turn unknown after moving_max_age_s, however far ahead the station's
    clock is. It stayed current for the whole skew (an hour here)."""
    clock = FakeClock(1_700_000_000.0)
    view = StationView(clock)
    rot = station_rotator(view, "tower")
    view.put(rot.topics.status, moving_status(skewed(3600, clock)))
    assert rot.status.bearing_deg == 77.0
    clock.t += 11  # nothing since: the station quiet for more than moving_max_age_s (10)
    assert rot.status.bearing_deg is None
    assert RotctldSession(rot).feed(b"p\n") == [b"RPRT -5\n"]  # type: ignore[arg-type]


def test_a_moving_status_replayed_from_the_brokers_store_is_unknown_until_a_live_one() -> None:
    """On (re)connecting, the broker replays the station's retained status, however old; its own
    ``time`` (the station's clock) cannot say how old on ours. Unknown until the station's next
    status, which a moving station sends within a poll."""
    clock = FakeClock(1_700_000_000.0)
    view = StationView(clock)
    rot = station_rotator(view, "tower")
    view.put(rot.topics.status, moving_status(skewed(0, clock)), replayed=True)
    assert rot.status.bearing_deg is None
    view.put(rot.topics.status, moving_status(skewed(0, clock)))
    assert rot.status.bearing_deg == 77.0


# -- the station away while the broker is there ------------------------------------------------
@pytest.mark.parametrize(
    ("gone", "word"),
    [("bridge", b"offline"), ("rotator", b"offline"), ("rotator", b"")],
    ids=["the station's bridge offline", "its rotator offline", "its rotator never described"],
)
def test_a_move_while_the_station_is_away_is_refused_at_once_and_a_stop_still_goes(
    gone: str, word: bytes
) -> None:
    """The broker is there, the station's bridge (or its controller) is not. The remote's
    console refused a move then; rotctld, GS-232, Easycomm and PstRotator said RPRT 0 / nothing
    and published a target nobody would take, as the station's own rotctld does not (it answers
    RPRT -5 for a rotator offline). A stop still goes: the station's bridge takes it, and with
    the bridge's main connection gone its stop lane may still (interfaces/mqtt/lane.py); with
    the bridge not heard, it is answered as not delivered (remote/rotator.py rule 3)."""
    view, link = StationView(FakeClock()), Link()
    rot = station_rotator(view, "tower", link)
    view.put(STATION.bridge_state if gone == "bridge" else rot.topics.availability, word)
    assert RotctldSession(rot).feed(b"P 120 0\n") == [b"RPRT -5\n"]  # type: ignore[arg-type]
    assert Gs232Session(rot).feed(b"M120\r") == [b"?>\r\n"]  # type: ignore[arg-type]
    assert EasycommSession(rot).feed(b"AZ120.0\n") == [b""]  # type: ignore[arg-type]
    assert link.sent == []
    said = b"RPRT -5\n" if gone == "bridge" else b"RPRT 0\n"
    assert RotctldSession(rot).feed(b"S\n") == [said]  # type: ignore[arg-type]
    assert link.sent == [(rot.topics.stop, "stop")]


# -- two remotes on one host -------------------------------------------------------------------
def test_two_remotes_of_one_operator_on_one_host_get_their_own_client_ids() -> None:
    """One remote per rotator, each with its own file (or a console-only one beside a rotctld
    one): with the default client id they had one id, and a broker closes the first connection
    of an id when the second comes (MQTT 5 session takeover), so both flapped for ever, every
    command refused while down."""
    one = remote_settings(1883, 4533)
    other = RemoteSettings(
        operator=OPERATOR,
        mqtt={"host": "127.0.0.1", "port": 1883, "base_topic": "rotor"},
        endpoints=[{"rotator": "mast", "gs232_pty": "/tmp/rotor-mast"}],
    )
    assert one.client_id() != other.client_id()
    assert one.client_id() == remote_settings(1883, 4533).client_id()  # stable across restarts


def test_a_takeover_names_the_client_id_the_remote_uses(caplog: pytest.LogCaptureFixture) -> None:
    """The takeover error tells the user which client id two processes share: it named the
    bridge's default id (rotor-...), not the remote's (remote-...), sending the user to look
    for a bridge."""
    s = remote_settings(1883, 4533)
    link = RemoteLink(s.mqtt, s.client_id(), [], lambda topic, payload, retain: None)
    with caplog.at_level(logging.ERROR, logger="bridge.interfaces.mqtt.connection"):
        link._ended(ReasonCode(PacketTypes.DISCONNECT, identifier=0x8E), "taken over", True)
    (said,) = [r.getMessage() for r in caplog.records]
    assert f"client id {s.client_id()!r}" in said


# -- an absurd description of the station ------------------------------------------------------
ABSURD_INFOS = [
    pytest.param(b'"azimuth_range":[NaN,NaN]', id="NaN azimuth range"),
    pytest.param(b'"azimuth_range":[0,1e400]', id="an infinite azimuth range"),
    pytest.param(b'"azimuth_range":[0,1' + b"0" * 400 + b"]", id="an integer past a float"),
    pytest.param(b'"azimuth_range":[0,360],"elevation_range":[NaN,90]', id="NaN elevation"),
    pytest.param(b'"azimuth_range":[0,360],"keep_out":[[NaN,Infinity]]', id="NaN keep-out"),
    pytest.param(b'"azimuth_range":[0,360],"park":[NaN,null]', id="NaN park"),
]


@pytest.mark.parametrize("fields", ABSURD_INFOS)
def test_an_absurd_retained_description_is_a_start_error_not_a_traceback_per_command(
    broker: Any, probe: Any, fields: bytes
) -> None:
    """A retained R/info with numbers that are not numbers: the remote started ("tower
    (rotorez, nan..nan)") and every P then raised inside the judge (a ValueError, not a
    refusal): a traceback in the log and RPRT -7 for each of Gpredict's targets. It is not the
    station's description: a one-line start error naming the topic."""
    probe.publish("rotor/info", b'{"name":"tower","model":"rotorez",' + fields + b"}", retain=True)
    probe.publish("rotor/bridge/state", "online", retain=True)
    probe.publish("rotor/availability", "online", retain=True)
    r = Remote(remote_settings(broker.port, free_port(), info_wait_s=5))
    with pytest.raises(StartError, match=r"^rotor/info is not the station's description: "):
        r.start()


def test_a_description_with_console_fields_past_a_float_leaves_the_console_its_defaults() -> None:
    """[web] on: a beamwidth of 400 digits raised OverflowError (not a ValueError) out of the
    remote's start, a traceback instead of the console with its defaults."""
    assert drawn_of(b'{"beamwidth":1' + b"0" * 400 + b"}") == Drawn()


def stand_in_station(probe: Any) -> None:
    """The station's retained description and presence, without a bridge."""
    probe.publish("rotor/info", INFO, retain=True)
    probe.publish("rotor/bridge/state", "online", retain=True)
    probe.publish("rotor/availability", "online", retain=True)


def test_the_remote_stopping_does_not_say_it_reconnects(
    broker: Any, probe: Any, caplog: pytest.LogCaptureFixture
) -> None:
    """Ctrl-C: the remote's last log line was the warning "disconnected from MQTT broker
    (Normal disconnection); reconnecting", as if the broker had gone."""
    stand_in_station(probe)
    r = Remote(remote_settings(broker.port, free_port()))
    r.start()
    with caplog.at_level(logging.INFO, logger="bridge"):
        r.stop()
    assert not [rec.getMessage() for rec in caplog.records if "reconnecting" in rec.getMessage()]


def test_the_console_on_an_endpoints_port_is_a_configuration_error() -> None:
    """[web] on the port an endpoint takes: the file was accepted, and the start then failed with
    "Address already in use", sending the user to look for another program."""
    with pytest.raises(ValueError, match=r"web.port 4533 clashes with endpoints\[0\].gs232_port"):
        RemoteSettings(
            operator=OPERATOR,
            mqtt={"host": "127.0.0.1"},
            endpoints=[{"gs232_port": 4533}],
            web={"enabled": True, "port": 4533},
        )


def test_an_error_event_the_broker_replays_is_not_shown_as_new() -> None:
    """R/error is never retained by the station; one retained there (forged, or an old tool's)
    came to every page as a fresh error on every reconnect of the remote."""
    view, pages = StationView(FakeClock()), Pages()
    rot = station_rotator(view, "tower")
    events: list[object] = []
    pages.on_event = lambda rid, event: events.append(event)  # type: ignore[method-assign]
    feed = ConsoleFeed([RemoteConsoleRotator(rot, Drawn(), view)], pages)
    event = b'{"kind":"refused","message":"rotator is locked","command":null,"time":5.0}'
    feed.on_message(rot.topics.error, event, replayed=True)
    assert events == []
    feed.on_message(rot.topics.error, event)
    assert len(events) == 1


def test_a_gs232_or_easycomm_stop_refused_offline_is_an_answer_not_a_traceback(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """The remote's link down: a stop is refused (it cannot be delivered). GS-232 ``S`` and
    Easycomm ``SA SE`` let that refusal escape as a failure: a traceback in the log for each
    (PstRotator under Wine sends stops on a timer), where a move's refusal is an answer."""
    view, link = StationView(FakeClock()), Link()
    rot = station_rotator(view, "tower", link)
    link.up = False
    with caplog.at_level(logging.WARNING):
        assert Gs232Session(rot).feed(b"S\r") == [b"?>\r\n"]  # type: ignore[arg-type]
        assert EasycommSession(rot).feed(b"SA SE\n") == [b""]  # type: ignore[arg-type]
    assert not [r for r in caplog.records if r.exc_info]


# -- start-up with the station absent ----------------------------------------------------------
def test_sigterm_while_waiting_for_an_absent_station_ends_the_remote_at_once(
    broker: Any, tmp_path: Path
) -> None:
    """No station on the broker and info_wait_s = 120: SIGTERM (or Ctrl-C) only set a flag the
    remote looked at after the start, so it sat out the whole wait (two minutes) before
    leaving. It stops waiting, exits 2 and says why."""
    conf = tmp_path / "remote.toml"
    conf.write_text(
        f'operator = "{OPERATOR}"\ninfo_wait_s = 120\n[mqtt]\nport = {broker.port}\n'
        f"[[endpoints]]\nrotctld_port = {free_port()}\n"
    )
    argv = [sys.executable, "-m", "bridge", "remote", "-c", str(conf)]
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        wait_until(
            lambda: re.search(rb"New client connected .* as remote-", broker.log.read_bytes()),
            20,
            "the remote on the broker, waiting for the station",
        )
        proc.send_signal(signal.SIGTERM)
        # below info_wait_s however slow the machine: it did not sit the wait out
        _, err = proc.communicate(timeout=min(slow(30), 100))
        assert proc.returncode == 2
        assert "stopped before the station's rotators were found" in err
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


# Ctrl-C at a point of the start: a real SIGINT raised in the remote's own process as a module
# named is about to be loaded ("import:M") or as a function named is called ("call:M.f"), in
# `python -m bridge remote -c` ("module") or the installed `rotor-bridge remote -c` ("script":
# what the console script's wrapper runs)
INTERRUPTED_AT = r"""
import importlib, importlib.abc, runpy, signal, sys
where, conf, how = sys.argv[1], sys.argv[2], sys.argv[3]
kind, _, name = where.partition(":")

# Python's own handler, as under a terminal: a suite started as a shell's background job
# inherits SIGINT ignored, the raised signal was lost and each case waited out info_wait_s
signal.signal(signal.SIGINT, signal.default_int_handler)

def interrupt():
    signal.raise_signal(signal.SIGINT)

if kind == "import":
    class Hook(importlib.abc.MetaPathFinder):
        def find_spec(self, fullname, path, target=None):
            if fullname == name:
                sys.meta_path.remove(self)
                interrupt()
            return None
    sys.meta_path.insert(0, Hook())
else:
    where_, _, attr = name.rpartition(".")
    try:
        owner = importlib.import_module(where_)
    except ModuleNotFoundError:
        module, _, cls = where_.rpartition(".")
        owner = getattr(importlib.import_module(module), cls)
    original = getattr(owner, attr)
    def hooked(*args, **kwargs):
        interrupt()
        return original(*args, **kwargs)
    setattr(owner, attr, hooked)
sys.argv = ["bridge", *(sys.argv[4:] or ["remote", "-c", conf])]
if how == "module":
    runpy.run_module("bridge", run_name="__main__", alter_sys=True)  # python -m bridge remote -c
else:
    from importlib.metadata import entry_points  # what the installed wrapper loads and runs
    sys.exit(entry_points(group="console_scripts")["rotor-bridge"].load()())
"""


@pytest.mark.parametrize("how", ["module", "script"])
@pytest.mark.parametrize(
    ("where", "said"),
    [
        ("import:bridge.cli", "rotor-bridge: stopped before it started"),
        ("import:bridge.settings", "rotor-bridge: stopped before it started"),
        ("call:argparse.ArgumentParser.parse_args", "rotor-bridge: stopped before it started"),
        ("import:bridge.remote.run", "stopped before it connected to the station's broker"),
        ("import:paho.mqtt.client", "stopped before it connected to the station's broker"),
        (
            "call:bridge.remote.settings.load_remote_settings",
            "stopped before it connected to the station's broker",
        ),
        (
            "call:bridge.interfaces.mqtt.remote.RemoteLink.start",
            "stopped before the station's rotators were found",
        ),
    ],
)
def test_ctrl_c_at_any_point_of_the_start_is_one_line_and_exit_code_2(
    tmp_path: Path, where: str, said: str, how: str
) -> None:
    """Ctrl-C in the remote's first few tenths of a second (its modules loading, its file read,
    its connection made) printed a Python traceback and died of the signal; only the waits for
    the station ended it as a start error. Every point of the start does now."""
    conf = tmp_path / "remote.toml"
    conf.write_text(
        f'operator = "{OPERATOR}"\ninfo_wait_s = 120\n[mqtt]\nport = {free_port()}\n'
        f"[[endpoints]]\nrotctld_port = {free_port()}\n"
    )
    argv = [sys.executable, "-c", INTERRUPTED_AT, where, str(conf), how]
    done = subprocess.run(argv, capture_output=True, text=True, timeout=slow(60))
    assert "Traceback" not in done.stderr
    assert done.returncode == 2, done.stderr
    lines = done.stderr.splitlines()
    assert lines and said in lines[-1], done.stderr
    assert [line for line in lines if "stopped before" in line] == [lines[-1]]
    assert done.stdout == ""  # no endpoint announced


@pytest.mark.parametrize("how", ["module", "script"])
@pytest.mark.parametrize("where", ["import:bridge.app", "call:bridge.settings.load_settings"])
def test_ctrl_c_while_the_bridge_loads_is_one_line_and_exit_code_2(
    tmp_path: Path, where: str, how: str
) -> None:
    """`rotor-bridge run` takes a few tenths of a second to load before the bridge has the
    signals (app.py): a Ctrl-C then printed a Python traceback and died of the signal."""
    conf = tmp_path / "bridge.toml"
    conf.write_text(
        f'[mqtt]\nport = {free_port()}\n[[rotators]]\nid = "tower"\nmodel = "rotorez"\n'
        'port = "/dev/null-no-such-port"\n'
    )
    argv = [sys.executable, "-c", INTERRUPTED_AT, where, str(conf), how, "run", "-c", str(conf)]
    done = subprocess.run(argv, capture_output=True, text=True, timeout=slow(60))
    assert "Traceback" not in done.stderr
    assert done.returncode == 2, done.stderr
    assert done.stderr.splitlines()[-1] == "rotor-bridge: stopped before it started"


def test_sigterm_while_waiting_for_the_stations_heartbeat_ends_the_remote_as_a_start_error(
    broker: Any, probe: Any, tmp_path: Path
) -> None:
    """The station described its rotator but its bridge is not heard: the remote waits up to
    SILENT_S for a heartbeat. SIGTERM (or Ctrl-C) then was seen only when that wait was over,
    and the remote went on to bind and announce its endpoints before it stopped. It says the
    wait when it begins, ends it, exits 2 and says why, and announces nothing."""
    probe.publish("rotor/info", INFO, retain=True)
    conf = tmp_path / "remote.toml"
    conf.write_text(
        f'operator = "{OPERATOR}"\n[mqtt]\nport = {broker.port}\n'
        f"[[endpoints]]\nrotctld_port = {free_port()}\n"
    )
    argv = [sys.executable, "-m", "bridge", "remote", "-c", str(conf)]
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    err: list[str] = []
    assert proc.stderr is not None
    reader = threading.Thread(target=lambda: err.extend(proc.stderr or ()), daemon=True)
    reader.start()
    try:
        wait_until(
            lambda: any("waiting up to" in line and "heartbeat" in line for line in err),
            slow(20),
            "the remote waiting for the station's heartbeat",
        )
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(slow(30)) == 2
        reader.join(slow(10))
        assert proc.stdout is not None and proc.stdout.read() == ""  # no endpoint announced
        assert any("stopped before the station's heartbeat was heard" in line for line in err)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def test_an_old_one_rotator_description_beside_the_stations_rotators_is_no_choice(
    broker: Any, probe: Any
) -> None:
    """A station that had one rotator (retained under rotor/) now has two (rotor/tower/,
    rotor/mast/): nothing clears the old retained rotor/info, status and availability. An
    endpoint without ``rotator`` took the old one: a stale bearing, or RPRT -5 for ever, and
    targets published where no bridge listens, without a word of why. It is a start error that
    names the rotators."""
    probe.publish("rotor/info", INFO, retain=True)  # left from the one-rotator days
    probe.publish("rotor/availability", "online", retain=True)
    probe.publish("rotor/bridge/state", "online", retain=True)
    for rid in ("tower", "mast"):
        probe.publish(f"rotor/{rid}/info", INFO.replace(b"tower", rid.encode()), retain=True)
    s = RemoteSettings(
        operator=OPERATOR,
        mqtt={"host": "127.0.0.1", "port": broker.port, "base_topic": "rotor"},
        endpoints=[{"rotctld_port": free_port()}],
        info_wait_s=5,
    )
    with pytest.raises(StartError, match=r"rotators mast, tower.*name one in endpoints.rotator"):
        Remote(s).start()


@pytest.mark.parametrize(
    "gone",
    ["the station's bridge offline", "its heartbeat silent", "its rotator offline"],
)
def test_a_lock_on_the_stations_bridge_may_not_hear_is_sent_and_said_to_be_undelivered(
    gone: str,
) -> None:
    """Someone about to climb the tower locks the rotator on the remote's console while the
    station's bridge is down (restarting): the lock ON went to the broker and the page said
    OK, but a bridge that is down never reads it (clean session) and started again unlocked.
    Sent all the same (its lane may still read it), and answered as not delivered; a rotator
    offline under a bridge that runs takes its lock: answered OK."""
    clock = FakeClock()
    view, link = StationView(clock), Link()
    rot = station_rotator(view, "tower", link)
    if gone == "the station's bridge offline":
        view.put(STATION.bridge_state, b"offline")
    elif gone == "its heartbeat silent":
        clock.t += SILENT_S + 1
    else:
        view.put(rot.topics.availability, b"offline")
    command = Lock(True, source=Source.WEB)
    if gone == "its rotator offline":
        rot.submit(command)
    else:
        with pytest.raises(Refused) as refused:
            rot.submit(command)
        assert refused.value.code is RefusalCode.OFFLINE
        assert "may never reach the rotator" in refused.value.message
    assert link.sent == [(rot.topics.lock, "ON")]
    rot.submit(Lock(False, source=Source.WEB))  # an OFF that is lost unlocks nothing: OK


@pytest.mark.parametrize("gone", ["the station's bridge offline", "its heartbeat silent"])
def test_a_stop_the_stations_bridge_may_not_hear_is_sent_and_said_to_be_undelivered(
    gone: str,
) -> None:
    """A STOP from the remote while the station's bridge is down was answered OK (rotctld's
    ``RPRT 0``) while the rotor turned on to its last target: sent all the same (the bridge's
    stop lane may still read it), and answered as not delivered."""
    clock = FakeClock()
    view, link = StationView(clock), Link()
    rot = station_rotator(view, "tower", link)
    rot.submit(Stop(source=Source.ROTCTLD))  # heard: OK
    if gone == "the station's bridge offline":
        view.put(STATION.bridge_state, b"offline")
    else:
        clock.t += SILENT_S + 1
    with pytest.raises(Refused) as refused:
        rot.submit(Stop(source=Source.ROTCTLD))
    assert refused.value.code is RefusalCode.OFFLINE
    assert "may still be turning" in refused.value.message
    assert link.sent == [(rot.topics.stop, "stop")] * 2


def test_an_n1mm_stop_the_stations_bridge_may_not_hear_is_sent_and_logs_no_fault(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """The remote's N1MM port: a STOP while the station's bridge is not heard goes out and is
    said undelivered (remote/rotator.py rule 3, on R/error and in the log as the remote's
    refusals are); it was logged at ERROR with a traceback as a fault behind the datagram
    ('the N1MM stop of rotator ... failed'), as if a bug had kept the stop from the rotator."""
    view, link = StationView(FakeClock()), Link()
    rot = station_rotator(view, "tower", link)
    view.put(STATION.bridge_state, b"offline")
    ep = LoggerEndpoints()
    ep.add_n1mm(rot, "Tower", port=0)  # type: ignore[arg-type]
    ep.start()
    try:
        port = ep.address(next(iter(ep.n1mm.values())))[1]
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            s.sendto(
                b"<N1MMRotor><stop><rotor>Tower</rotor></stop></N1MMRotor>", ("127.0.0.1", port)
            )
        wait_until(lambda: link.sent, 5, "the stop sent")
        wait_until(lambda: ep.counts["n1mm"].commands, 5, "the datagram done")
    finally:
        ep.stop()
    assert link.sent == [(rot.topics.stop, "stop")]
    assert not [r for r in caplog.records if r.levelno >= logging.ERROR], caplog.text
    assert not [r for r in caplog.records if r.exc_info], caplog.text
