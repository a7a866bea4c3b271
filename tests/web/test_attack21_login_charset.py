"""Attack 21, a hostile neighbour on the LAN, at the console's port: a login whose body names a
charset Python cannot decode text with. Real parts: the bridge in this process on an emulated
Rotor-EZ (pty), a real mosquitto, the console with a password (as one on the LAN has).

The finding: ``POST api/login`` with ``Content-Type: application/json; charset=nope`` (or
``rot13``, ``uu``: codecs that are no text encodings) is a 500 Internal Server Error, and the
log gets "Error handling request" at ERROR with its traceback (LookupError: unknown encoding):
``_login`` reads the body with ``request.json()``, which decodes it by the charset the client
named, and catches ValueError and RecursionError, not LookupError. No token is needed for a
login, so anyone who reaches the port writes tracebacks into the log; the try is not counted
against the address either. Every other body a login can get wrong is a 400 or a 401 with no
traceback (attack passes 3 and 4; server.py rule 7).
"""

from __future__ import annotations

import logging

import pytest

from bridge.interfaces.web import auth, server
from tests.support.console import ConsoleClient
from tests.support.rig import Rig
from tests.web.conftest import PASSWORD


@pytest.mark.parametrize("charset", ["nope", "rot13"])
def test_a_login_naming_a_charset_that_is_no_text_encoding_is_refused_without_a_traceback(
    guarded: tuple[Rig, ConsoleClient], caplog: pytest.LogCaptureFixture, charset: str
) -> None:
    """A login body in a charset the console cannot read is a bad body (400) or a wrong
    password (401), never a 500; nothing at ERROR, no traceback."""
    _rig, client = guarded
    caplog.set_level(logging.DEBUG, logger=server.http_log.name)  # (past the noise limit too)
    kind = {"Content-Type": f"application/json; charset={charset}"}
    answer = client.post("/api/login", {"password": "not the password"}, token=False, headers=kind)
    loud = [r for r in caplog.records if r.exc_info or r.levelno >= logging.ERROR]
    assert answer.status in (400, 401), answer
    assert not loud, [f"{r.levelname} {r.getMessage()}" for r in loud]


def test_a_login_naming_a_charset_that_is_no_text_encoding_counts_against_the_tries(
    guarded: tuple[Rig, ConsoleClient],
) -> None:
    """Each such login is a try counted against the address, as a wrong password is: after
    the burst, the right password is refused too (429)."""
    _rig, client = guarded
    kind = {"Content-Type": "application/json; charset=nope"}
    answers = [
        client.post("/api/login", {"password": PASSWORD}, token=False, headers=kind).status
        for _ in range(auth.LOGIN_BURST_PER_CLIENT)
    ]
    assert answers == [401] * auth.LOGIN_BURST_PER_CLIENT, answers
    right = client.post("/api/login", {"password": PASSWORD}, token=False)
    assert right.status == 429, right
