"""A third attack pass on the operator console (bridge/interfaces/web/): a neighbour on the LAN,
with nothing but the console's port. Real parts: the bridge in this process on an emulated
controller (pty) and a real mosquitto.

Each test failed on the code it was written against (a finding of the pass):
- a login whose password holds a lone surrogate (JSON's ``\\ud800``) was a 500, logged with a
  traceback and never counted against the address's tries: unlimited, each an ERROR in the log;
- every malformed HTTP request was logged by aiohttp at ERROR with its traceback, eleven
  lines each, two thousand requests a second from one client: the bridge's own warnings
  drowned, and journald's rate limit drops every line of the service;
- a login whose body never came was waited for without end, its connection never swept.
"""

from __future__ import annotations

import logging
import socket

import pytest

from bridge.interfaces.web import auth, server
from tests.support.console import ConsoleClient
from tests.support.rig import Rig
from tests.support.waiting import slow
from tests.web.conftest import PASSWORD


def _login(client: ConsoleClient, body: bytes) -> int:
    headers = {"Content-Type": "application/json", "Origin": f"http://127.0.0.1:{client.port}"}
    return client.request("POST", "/api/login", body, headers).status


def test_a_password_no_text_can_hold_is_a_wrong_one_and_counts_against_the_tries(
    guarded: tuple[Rig, ConsoleClient], caplog: pytest.LogCaptureFixture
) -> None:
    """A lone surrogate in the password (valid JSON, no UTF-8) is a wrong password: 401, then
    429 like any other guess, and no traceback in the log."""
    _rig, client = guarded
    caplog.set_level(logging.INFO)
    body = b'{"password": "\\ud800' + PASSWORD.encode() + b'"}'
    answers = [_login(client, body) for _ in range(auth.LOGIN_BURST_PER_CLIENT + 1)]
    assert answers == [401] * auth.LOGIN_BURST_PER_CLIENT + [429], answers
    assert not [r for r in caplog.records if r.exc_info], "a traceback was logged"


def test_a_flood_of_malformed_requests_does_not_flood_the_log(
    guarded: tuple[Rig, ConsoleClient], caplog: pytest.LogCaptureFixture
) -> None:
    """Each malformed request is refused (400), but what the log says of them is a few lines,
    no traceback: the log is the bridge's, not the neighbour's."""
    _rig, client = guarded
    caplog.set_level(logging.INFO)
    flood = 200
    for _ in range(flood):
        with socket.create_connection(("127.0.0.1", client.port), timeout=slow(10)) as s:
            s.sendall(
                b"GET / HTTP/1.1\r\nHost: x\r\nContent-Length: 1\r\nContent-Length: 2\r\n\r\n"
            )
            assert s.recv(64).startswith(b"HTTP/1.0 400")
    said = [r for r in caplog.records if r.levelno >= logging.INFO and "aiohttp" in r.name]
    said += [r for r in caplog.records if r.name.startswith("bridge.interfaces.web")]
    assert len(said) <= flood // 10, f"{len(said)} lines for {flood} requests"
    assert not [r for r in said if r.exc_info], "a traceback was logged"


def test_a_login_whose_body_never_comes_is_answered_and_not_held(
    guarded: tuple[Rig, ConsoleClient], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A login's body, as a command's, comes within BODY_S (shortened here) or is answered 408:
    a connection dribbling one is never busy (connections.py rule 2), so never swept."""
    _rig, client = guarded
    monkeypatch.setattr(server, "BODY_S", 0.3)
    with socket.create_connection(("127.0.0.1", client.port), timeout=slow(10)) as s:
        s.sendall(
            b"POST /api/login HTTP/1.1\r\nHost: 127.0.0.1\r\n"
            b"Content-Type: application/json\r\nContent-Length: 40\r\n\r\n{"
        )
        try:
            answer = s.recv(64)
        except TimeoutError:
            pytest.fail("the login's body was still waited for")
        s.sendall(b" " * 39)  # (the rest, late: aiohttp reads it away, nothing left pending)
    assert answer.startswith(b"HTTP/1.1 408"), answer
