"""Attack 21, a hostile neighbour on the LAN, at the console's port: a POST whose body says
``Content-Encoding: gzip`` (or ``deflate``) and is not. Real parts: the bridge in this process
on an emulated Rotor-EZ (pty), a real mosquitto, the console with a password (as one on the
LAN has).

The finding: aiohttp inflates a request's body by its ``Content-Encoding``; one that does not
inflate raises ``RequestPayloadError`` ("Can not decode content-encoding"), which is neither
the HttpProcessingError that server.py's ``Quieter`` turns into one line (rule 7) nor one of
the errors ``_login`` catches. ``api/login`` answers 500 and the log gets "Error handling
request" and "Unhandled exception" at ERROR, each with its traceback; ``api/session``, which
reads no body, answers 403 as it should, and the log still gets "Unhandled exception" with a
traceback. No token is needed for either: anyone who reaches the port writes tracebacks into
the log, where every other body a client can get wrong is a 4xx in one line at most.
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


def _post(port: int, path: str, encoding: str, more: str = "") -> bytes:
    body = b"this is not a compressed body at all"
    with socket.create_connection(("127.0.0.1", port), timeout=slow(10)) as s:
        s.sendall(
            f"POST {path} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n{more}"
            f"Content-Type: application/json\r\nContent-Encoding: {encoding}\r\n"
            f"Content-Length: {len(body)}\r\nConnection: close\r\n\r\n".encode()
            + body
        )
        answer = b""
        while chunk := s.recv(4096):  # (to its end: the console has done with it)
            answer += chunk
    return answer


@pytest.mark.parametrize("encoding", ["gzip", "deflate"])
@pytest.mark.parametrize("path", ["/api/login", "/api/session"])
def test_a_body_that_is_not_the_compression_it_names_is_a_4xx_without_a_traceback(
    guarded: tuple[Rig, ConsoleClient],
    caplog: pytest.LogCaptureFixture,
    path: str,
    encoding: str,
) -> None:
    """A bad body: a 4xx answer (400, or 403 where no body is read), nothing at ERROR, no
    traceback; the console still answers."""
    _rig, client = guarded
    caplog.set_level(logging.DEBUG, logger=server.http_log.name)  # (past the noise limit too)
    answer = _post(client.port, path, encoding)
    assert client.get("/api/hello").status == 200  # (a round of the console's loop after it)
    loud = [r for r in caplog.records if r.exc_info or r.levelno >= logging.ERROR]
    assert answer[9:10] == b"4", answer[:60]
    assert not loud, [f"{r.levelname} {r.getMessage()}" for r in loud]


def test_a_login_body_that_is_not_the_compression_it_names_counts_against_the_tries(
    guarded: tuple[Rig, ConsoleClient], caplog: pytest.LogCaptureFixture
) -> None:
    """Each such login is a 400 and a try counted against the address, as a wrong password
    is: after the burst, the right password is refused too (429); no traceback."""
    _rig, client = guarded
    caplog.set_level(logging.DEBUG, logger=server.http_log.name)
    answers = [
        _post(client.port, "/api/login", "gzip")[9:12] for _ in range(auth.LOGIN_BURST_PER_CLIENT)
    ]
    assert answers == [b"400"] * auth.LOGIN_BURST_PER_CLIENT, answers
    right = client.post("/api/login", {"password": PASSWORD}, token=False)
    assert right.status == 429, right
    loud = [r for r in caplog.records if r.exc_info or r.levelno >= logging.ERROR]
    assert not loud, [f"{r.levelname} {r.getMessage()}" for r in loud]


@pytest.mark.parametrize("encoding", ["gzip", "deflate"])
def test_a_command_body_that_is_not_the_compression_it_names_is_refused_as_invalid(
    guarded: tuple[Rig, ConsoleClient], caplog: pytest.LogCaptureFixture, encoding: str
) -> None:
    """A page's command (its token given) whose body does not inflate: 400 with code
    ``invalid``, as any bad body is, the connection closed after it, nothing at ERROR, no
    traceback; the console still takes the next command."""
    _rig, client = guarded
    caplog.set_level(logging.DEBUG, logger=server.http_log.name)
    client.token = client.post("/api/login", {"password": PASSWORD}, token=False).doc["token"]
    answer = _post(
        client.port, "/api/rotators/hf/command", encoding, f"X-Rotor-Token: {client.token}\r\n"
    )
    head, _, doc = answer.partition(b"\r\n\r\n")
    assert head.startswith(b"HTTP/1.1 400"), answer[:60]
    assert b'"code": "invalid"' in doc, doc
    assert client.command("hf", command="stop").status == 200
    loud = [r for r in caplog.records if r.exc_info or r.levelno >= logging.ERROR]
    assert not loud, [f"{r.levelname} {r.getMessage()}" for r in loud]
