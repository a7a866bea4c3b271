"""The console on the remote (``[web]`` in remote.toml) with real parts: a mosquitto, the station's
bridge on an emulated Rotor-EZ, the remote in this process with its console on a free port, and
the console's plain HTTP client. What is judged is what an operator notices: what the page is
told, where the station's rotor ends up, what the live feed says, the answer to a command."""

from __future__ import annotations

import socket
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from bridge.emulators.rotorez_models import BEARING_OUTCOMES
from bridge.interfaces.web import auth
from bridge.remote.run import Remote, StartError
from bridge.remote.settings import RemoteSettings
from tests.support import wait_until
from tests.support.console import ConsoleClient, EventStream, web_section
from tests.support.mosquitto import free_port
from tests.support.rig import Rig, arrival_tol

OPERATOR = "DL1ABC"
LOCATOR = "JO62qm"
PRESETS = {"EU": 45, "W6": 320}
TOL = arrival_tol("rotorez")


def remote_settings(rig: Rig, web_port: int, **web: Any) -> RemoteSettings:
    return RemoteSettings(
        operator=OPERATOR,
        mqtt={"host": "127.0.0.1", "port": rig.broker.port, "base_topic": "rotor"},
        endpoints=[{"rotator": "tower", "rotctld_port": free_port()}],
        web=web_section(web_port, **web),
    )


@pytest.fixture
def station(rig: Rig) -> Rig:
    rig.sections["station"] = {"locator": LOCATOR}
    rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0}, presets=PRESETS, beamwidth_deg=40)
    rig.start()
    rig.ready("tower")
    return rig


@pytest.fixture
def remote(station: Rig) -> Iterator[tuple[Remote, ConsoleClient, list[str]]]:
    port = free_port()
    r = Remote(remote_settings(station, port))
    lines = r.start()
    client = ConsoleClient(port)
    client.session()
    yield r, client, lines
    r.stop()


def statuses(stream: EventStream) -> Iterator[dict[str, Any]]:
    while True:
        name, data = stream.next()
        if name == "status":
            yield data["status"]


def test_the_page_is_told_the_station_and_its_rotator(
    station: Rig, remote: tuple[Remote, ConsoleClient, list[str]]
) -> None:
    r, client, lines = remote
    assert lines[-1] == f"{OPERATOR} -> 127.0.0.1: console for tower on {client_url(client)}"
    config = client.get("/api/config")
    assert config.status == 200
    st = config.doc["station"]
    assert st["locator"] == LOCATOR
    assert abs(st["latitude_deg"] - 52.52) < 0.1 and abs(st["longitude_deg"] - 13.29) < 0.1
    (rot,) = config.doc["rotators"]
    assert rot["id"] == "tower" and rot["model"] == "Rotor-EZ"
    assert rot["beamwidth_deg"] == 40
    assert rot["presets"] == {"EU": [45, None], "W6": [320, None]}
    assert rot["az_range_deg"] == [0, 360]
    assert client.get("/api/land").status == 200  # the map, centred on the station


def client_url(client: ConsoleClient) -> str:
    return f"http://127.0.0.1:{client.port}/"


def test_a_target_from_the_page_turns_the_station_rotor_and_the_feed_shows_it(
    station: Rig, remote: tuple[Remote, ConsoleClient, list[str]]
) -> None:
    _, client, _ = remote
    stream = EventStream(client)
    try:
        first = next(statuses(stream))
        assert first["available"] and abs(first["bearing"] - 10) <= TOL
        answer = client.command("tower", command="target", az=120)
        assert answer.status == 200, answer
        station.arrived("tower", 120)
        for status in statuses(stream):
            if status["state"] == "idle" and abs(status["bearing"] - 120) <= TOL:
                break
        assert status["last_command_source"] == "mqtt"  # the station heard it over its broker
    finally:
        stream.close()


def test_a_preset_then_stop_from_the_page(
    station: Rig, remote: tuple[Remote, ConsoleClient, list[str]]
) -> None:
    _, client, _ = remote
    assert client.command("tower", command="preset", name="W6").status == 200
    wait_until(lambda: station.emus["tower"].state().is_moving, 10, "the rotor turning")
    assert client.command("tower", command="stop").status == 200
    wait_until(lambda: station.status("tower").state.value == "idle", 15, "stopped")
    az = station.emus["tower"].state().az_deg
    assert abs(az - 320) > 20  # stopped on the way, long before W6


def test_a_lock_from_the_page_holds_and_a_move_is_refused_at_once_on_the_page(
    station: Rig, remote: tuple[Remote, ConsoleClient, list[str]]
) -> None:
    _, client, _ = remote
    stream = EventStream(client)
    try:
        assert client.command("tower", command="lock", on=True).status == 200
        for status in statuses(stream):
            if status["locked"]:
                break
        refused = client.command("tower", command="target", az=200)  # refused at once
        assert (refused.status, refused.doc["code"]) == (409, "locked")
        _, data = stream.until(  # the page hears it as an error event too (its own)
            lambda name, data: name == "error" and "target az 200" in str(data.get("command")),
            what="the refusal's error",
        )
        assert data["rotator"] == "tower" and "lock" in data["message"]
    finally:
        stream.close()
        client.command("tower", command="lock", on=False)


def test_broker_away_the_page_is_told_offline_and_nothing_moves_when_it_is_back(
    station: Rig, remote: tuple[Remote, ConsoleClient, list[str]]
) -> None:
    r, client, _ = remote
    emu = station.emus["tower"]
    link = r.link
    assert link is not None
    stream = EventStream(client)
    try:
        moves = len(emu.frames(*BEARING_OUTCOMES))
        station.broker.kill()
        wait_until(lambda: not link.up, 30, "the remote sees the broker gone")
        for status in statuses(stream):  # no stale bearing: the rotator greys out
            if not status["available"]:
                break
        assert status["bearing"] is None
        answer = client.command("tower", command="target", az=250)
        assert answer.status == 409 and answer.doc["code"] == "offline", answer
        assert "not connected" in answer.doc["error"]
        assert client.command("tower", command="preset", name="EU").status == 409
        station.broker.restart()
        wait_until(lambda: link.up, 30, "the remote back on the broker")
        station.ready("tower", 30)
        for status in statuses(stream):  # the station's word again, from its retained topics
            if status["available"]:
                break
        assert abs(status["bearing"] - 10) <= TOL
        assert client.command("tower", command="stop").status == 200  # a marker behind all
        wait_until(lambda: station.status("tower").last_command_source == "mqtt", 10, "stop")
        assert len(emu.frames(*BEARING_OUTCOMES)) == moves
        assert abs(emu.state().az_deg - 10) <= TOL
    finally:
        stream.close()


def test_a_console_beyond_loopback_without_a_password_is_refused(station: Rig) -> None:
    with pytest.raises(ValueError, match=r"web.password_file"):
        remote_settings(station, free_port(), bind="0.0.0.0")


@pytest.mark.parametrize("trusted", [True, False])
def test_behind_a_trusted_proxy_one_visitors_wrong_logins_hold_back_only_theirs(
    station: Rig, tmp_path: Path, trusted: bool
) -> None:
    """An attack pass: the remote's console took ``[web] trusted_proxies`` and never used it;
    behind a reverse proxy every browser came from the proxy's address, and one visitor's
    wrong passwords held back the operator's right one (429), as on the bridge before it
    believed its proxy (web/auth.py rule 6)."""
    secret = tmp_path / "web-password"
    secret.write_text("correct horse battery\n")
    secret.chmod(0o600)
    port = free_port()
    proxies = {"trusted_proxies": ["127.0.0.1"]} if trusted else {}
    r = Remote(remote_settings(station, port, password_file=str(secret), **proxies))
    r.start()
    try:
        client = ConsoleClient(port)

        def login(password: str, browser: str) -> int:
            headers = {"X-Forwarded-For": browser}
            doc = {"password": password}
            return client.post("/api/login", doc, token=False, headers=headers).status

        for _ in range(auth.LOGIN_BURST_PER_CLIENT + 2):  # a visitor behind the proxy guesses
            login("guess", "203.0.113.5")
        assert login("guess", "203.0.113.5") == 429
        # the operator, another browser behind the same proxy
        assert login("correct horse battery", "192.0.2.10") == (200 if trusted else 429)
    finally:
        r.stop()


def test_a_console_port_already_taken_is_a_start_error_naming_it(station: Rig) -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        r = Remote(remote_settings(station, port))
        with pytest.raises(StartError, match=rf"web.port {port}: the console cannot listen"):
            r.start()
        assert r.link is None and not r.servers  # nothing left running


def test_with_the_station_bridge_gone_a_turn_is_refused_at_once(
    station: Rig, remote: tuple[Remote, ConsoleClient, list[str]]
) -> None:
    r, client, _ = remote
    station.stop()  # the bridge says offline on its way out (its rotator first, then itself)
    # (the bridge's own offline, not the rotator's: a stop is heard while the bridge is, and
    # waiting for the rotator's alone let the stop go out heard, 200, in one run of the suite)
    wait_until(r.rotators[0].bridge_unheard, 10, "the remote sees the station's bridge go")
    answer = client.command("tower", command="target", az=250)
    assert answer.status == 409 and answer.doc["code"] == "offline", answer
    assert "station's rotator is offline" in answer.doc["error"]
    stop = client.command("tower", command="stop")  # a stop still goes out, said undelivered
    assert stop.status == 409 and "may still be turning" in stop.doc["error"], stop


def test_a_pages_token_still_turns_the_rotor_after_this_computers_clock_went_back(
    station: Rig,
) -> None:
    """An attack pass (remote/run.py rule 9): the operator's computer's wall clock set back 10
    minutes (its time server found) made every token the console had handed out "issued in the
    future", and each click was refused "the token has expired: log in again"."""
    behind = [0.0]
    port = free_port()
    r = Remote(remote_settings(station, port), wall=lambda: time.time() - behind[0])
    r.start()
    try:
        client = ConsoleClient(port)
        client.session()
        behind[0] = 600.0  # the clock goes back 10 minutes
        answer = client.command("tower", command="target", az=120)
        assert answer.status == 200, answer
        station.arrived("tower", 120)
    finally:
        r.stop()
