"""A fifth attack pass on the operator console (bridge/interfaces/web/): credentials that are
no text, from a neighbour with nothing but its port. Real parts: the bridge in this process on
an emulated controller (pty), a real mosquitto, the console's own HTTP API.

Each test failed on the code it was written against (a finding of the pass):
- a token holding a byte that is not UTF-8 (in ``X-Rotor-Token`` or offered as the WebSocket's
  subprotocol), or a first message's token with a lone surrogate (JSON's ``\\ud800``), raised
  where the token's MAC was made: a 500, its traceback at ERROR, for anyone who reaches the
  port with no token at all, where a token that is not one is a 401 (a 4401 on the socket).
- the console's tokens were judged on the raw wall clock: set back 10 minutes (a time server
  found after boot), every token handed out before was "issued in the future", and each click
  of every open page was refused with "the token has expired: log in again" (with a password:
  a login on every page) until the clock caught up. They are on the station's clock now, the
  one its heartbeats carry, which a step back does not set back (heartbeat.py rule 6).
"""

from __future__ import annotations

import base64
import logging
import os
import socket
import time
from collections.abc import Iterator
from pathlib import Path

import aiohttp
import pytest

from bridge.app import App
from tests.support.console import ConsoleClient, run_async, web_section
from tests.support.rig import Rig
from tests.support.waiting import slow
from tests.web.conftest import PASSWORD

NOT_UTF8 = b"1.ab.\xff\xfe"  # a token's shape, with bytes no text holds


class SteppedWall:
    """The real wall clock, set back by ``behind_s`` when the test says."""

    def __init__(self) -> None:
        self.behind_s = 0.0

    def __call__(self) -> float:
        return time.time() - self.behind_s


@pytest.fixture
def console(rig: Rig) -> Iterator[tuple[Rig, ConsoleClient]]:
    web = rig.sections["web"] = web_section()
    rig.add("hf")
    rig.start()
    rig.ready("hf")
    yield rig, ConsoleClient(web["port"])


def _head(port: int, request: bytes) -> bytes:
    """The status line of the answer to ``request`` sent as it is."""
    with socket.create_connection(("127.0.0.1", port), timeout=slow(10)) as s:
        s.sendall(request)
        answer = b""
        while b"\r\n" not in answer:
            more = s.recv(4096)
            if not more:
                break
            answer += more
    return answer.split(b"\r\n", 1)[0]


def _no_traceback(caplog: pytest.LogCaptureFixture) -> None:
    assert not [r for r in caplog.records if r.exc_info], "a traceback was logged"


def test_a_token_header_that_is_no_text_is_a_401_not_a_500(
    console: tuple[Rig, ConsoleClient], caplog: pytest.LogCaptureFixture
) -> None:
    _rig, client = console
    caplog.set_level(logging.INFO)
    host = f"127.0.0.1:{client.port}".encode()
    body = b'{"command": "target", "az": 200}'
    command = (
        b"POST /api/rotators/hf/command HTTP/1.1\r\nHost: " + host + b"\r\nOrigin: http://"
        + host + b"\r\nContent-Type: application/json\r\nContent-Length: "
        + str(len(body)).encode() + b"\r\nConnection: close\r\nX-Rotor-Token: " + NOT_UTF8
        + b"\r\n\r\n" + body
    )  # fmt: skip
    assert _head(client.port, command) == b"HTTP/1.1 401 Unauthorized"
    events = (
        b"GET /api/events HTTP/1.1\r\nHost: " + host + b"\r\nConnection: close\r\n"
        b"X-Rotor-Token: " + NOT_UTF8 + b"\r\n\r\n"
    )
    assert _head(client.port, events) == b"HTTP/1.1 401 Unauthorized"
    _no_traceback(caplog)


def test_a_token_offered_as_a_subprotocol_that_is_no_text_is_closed_4401_not_a_500(
    console: tuple[Rig, ConsoleClient], caplog: pytest.LogCaptureFixture
) -> None:
    _rig, client = console
    caplog.set_level(logging.INFO)
    key = base64.b64encode(os.urandom(16))
    opening = (
        b"GET /api/live HTTP/1.1\r\nHost: 127.0.0.1:" + str(client.port).encode()
        + b"\r\nUpgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Key: " + key
        + b"\r\nSec-WebSocket-Version: 13\r\nSec-WebSocket-Protocol: rotor-bridge, token."
        + NOT_UTF8 + b"\r\n\r\n"
    )  # fmt: skip
    with socket.create_connection(("127.0.0.1", client.port), timeout=slow(10)) as s:
        s.sendall(opening)
        answer = b""
        while len(answer.partition(b"\r\n\r\n")[2]) < 4 and (more := s.recv(4096)):
            answer += more  # (up to the close frame's code: the socket waits for ours)
    head, _, frames = answer.partition(b"\r\n\r\n")
    assert head.startswith(b"HTTP/1.1 101 "), head  # taken, then closed as any token not one
    assert frames[:1] == b"\x88" and int.from_bytes(frames[2:4]) == 4401, frames
    _no_traceback(caplog)


def test_a_first_message_whose_token_is_a_lone_surrogate_is_closed_4401(
    console: tuple[Rig, ConsoleClient], caplog: pytest.LogCaptureFixture
) -> None:
    _rig, client = console
    caplog.set_level(logging.INFO)
    url = f"http://127.0.0.1:{client.port}/api/live"
    origin = {"Origin": f"http://127.0.0.1:{client.port}"}

    async def attempt() -> tuple[int | None, aiohttp.WSMsgType]:
        async with aiohttp.ClientSession() as session:
            async with session.ws_connect(url, headers=origin) as ws:
                await ws.send_str('{"token": "1.ab.\\ud800"}')
                message = await ws.receive(timeout=slow(12))
                return ws.close_code, message.type

    assert run_async(attempt()) == (4401, aiohttp.WSMsgType.CLOSE)
    _no_traceback(caplog)
    assert client.get("/api/hello").status == 200


def test_a_pages_token_still_turns_the_rotor_after_the_wall_clock_went_back(
    rig: Rig, tmp_path: Path
) -> None:
    secret = tmp_path / "web-password"
    secret.write_text(PASSWORD + "\n")
    secret.chmod(0o600)
    web = rig.sections["web"] = web_section(password_file=str(secret))
    rig.add("hf", emu={"start_az_deg": 10, "jitter_deg": 0})
    wall = SteppedWall()
    rig.app = App(rig.settings, wall=wall)
    rig.app.start()
    rig.ready("hf")
    client = ConsoleClient(web["port"])
    login = client.post("/api/login", {"password": PASSWORD}, token=False)
    assert login.status == 200, login
    client.token = login.doc["token"]
    wall.behind_s = 600.0  # the time server found: the wall clock goes back 10 minutes
    answer = client.command("hf", command="target", az=120)
    assert answer.status == 200, answer  # not "the token has expired: log in again"
    rig.arrived("hf", 120)
