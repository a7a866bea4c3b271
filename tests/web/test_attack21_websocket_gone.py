"""Attack 21, a hostile neighbour on the LAN, at the console's port: a WebSocket opening whose
client is gone before the console answers it. Real parts: the bridge in this process on an
emulated Rotor-EZ (pty), a real mosquitto, the console with a password (as one on the LAN has).

The finding: a client with no token and no password sends ``GET /api/live`` with the WebSocket
headers and closes; the console's answer (101, or the 4401 of a token that is not one) cannot
be written, and aiohttp logs "Error handling request" at ERROR with a 30-line traceback
(live.py, ``ws.prepare``), the bridge's own fault by its look. server.py rule 7 says a request
whose client went is the client's doing and logs nothing (a login's or a command's: attack 4);
this one was missed. The noise limit holds it to ten at once, then one every 10 s, at ERROR
with its traceback, and those ten take the place of the bridge's own errors of the moment.
"""

from __future__ import annotations

import logging
import socket

import pytest

from bridge.interfaces.web import server
from tests.support.console import ConsoleClient
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until

TRIES = 20  # each is caught about half the time (the 101 written before the close is read)


def _opening(port: int, protocols: str | None) -> bytes:
    offer = "" if protocols is None else f"Sec-WebSocket-Protocol: {protocols}\r\n"
    return (
        f"GET /api/live HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n"
        "Upgrade: websocket\r\nConnection: Upgrade\r\n"
        "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n"
        f"{offer}\r\n"
    ).encode()


@pytest.mark.parametrize(
    "protocols",
    ["rotor-bridge", "rotor-bridge, token.1.2.3", None],
    ids=["no-token", "bad-token", "no-subprotocol"],
)
def test_a_websocket_opening_whose_client_went_logs_no_traceback(
    guarded: tuple[Rig, ConsoleClient], caplog: pytest.LogCaptureFixture, protocols: str | None
) -> None:
    """A neighbour opens the live feed (its token as a first message later, a token that is
    not one, or no subprotocol at all: a plain WebSocket client) and closes at once, TRIES
    times: nothing of the bridge's is at fault, so no traceback and nothing at ERROR; the
    console still answers."""
    rig, client = guarded
    caplog.set_level(logging.DEBUG, logger=server.http_log.name)  # (past the noise limit too)
    for _ in range(TRIES):
        with socket.create_connection(("127.0.0.1", client.port), timeout=slow(10)) as s:
            s.sendall(_opening(client.port, protocols))
    assert rig.app is not None
    web = rig.app.web
    assert web is not None
    wait_until(lambda: len(web._conns) == 0, slow(10), "the neighbour's connections gone")
    assert client.get("/api/hello").status == 200  # (a round of the console's loop after them)
    loud = [r for r in caplog.records if r.exc_info or r.levelno >= logging.ERROR]
    assert not loud, [f"{r.levelname} {r.getMessage()}" for r in loud]
