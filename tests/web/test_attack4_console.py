"""A fourth attack pass on the operator console (bridge/interfaces/web/), as a confused user
(what the page says of the lock) and as a neighbour with nothing but its port. Real parts: the
bridge in this process on an emulated controller (pty), a real mosquitto, the console's own
HTTP API and the page in Debian's Chromium.

Each test failed on the code it was written against (a finding of the pass):
- a rotator whose lock the state file does not say refuses motion until the broker's
  ``R/lock/state`` is read (runtime/kept.py rule 10), but its status said ``"locked": false``:
  the page showed "Lock OFF" while every click was refused for a lock that may be ON, and its
  button, labelled "Lock OFF", locked the rotator when the refusal said "a lock OFF releases
  it".
- an ``Origin`` header that is no URL (``http://[::1``, an unclosed bracket) was a 500, its
  traceback logged at ERROR, from any client that reaches the port, token or not;
- a login (or a command) whose client closed its connection before the body came was a
  traceback at ERROR in the log (``Connection lost``), a login's from any client.
"""

from __future__ import annotations

import logging
import socket
import time
from collections.abc import Callable
from typing import Any

import pytest
from playwright.sync_api import Browser, expect

from tests.support.console import ConsoleClient, EventStream, web_section
from tests.support.rig import Rig
from tests.support.waiting import slow, slow_ms
from tests.web.conftest import PASSWORD, open_console


def _status_until(
    stream: EventStream, want: Callable[[dict[str, Any]], bool], deadline_s: float
) -> dict[str, Any]:
    """The first status of ``hf`` on the stream for which ``want(status)`` is true."""
    end = time.monotonic() + deadline_s
    while time.monotonic() < end:
        name, doc = stream.next()
        if name == "status" and doc["rotator"] == "hf" and want(doc["status"]):
            return dict(doc["status"])
    raise AssertionError("no such status came")


def test_a_lock_not_known_yet_is_said_as_such_and_no_longer_once_the_broker_is_read(
    rig: Rig,
) -> None:
    """The broker down at the start, a new state file: the status the page reads says the
    lock is not known (motion refused), not OFF; once the broker is reached and holds no lock
    ON, it says OFF and a click turns the rotor."""
    web = rig.sections["web"] = web_section()
    rig.add("hf")
    rig.broker.stop()
    rig.start()
    client = ConsoleClient(web["port"])
    client.session()
    stream = EventStream(client, timeout_s=30)
    try:
        shown = _status_until(stream, lambda s: s["available"], slow(15))
        assert shown["lock_unknown"] is True and shown["locked"] is False, shown
        refused = client.command("hf", command="target", az=150)
        assert refused.status == 409 and "R/lock/state" in refused.doc["error"], refused
        rig.broker.start()
        known = _status_until(stream, lambda s: "lock_unknown" not in s, slow(30))
        assert known["locked"] is False, known
    finally:
        stream.close()
    assert client.command("hf", command="target", az=150).status == 200
    rig.arrived("hf", 150)


def test_the_page_shows_lock_not_known_yet_until_the_broker_is_read(
    rig: Rig, browser: Browser
) -> None:
    """In Chromium: while the lock is not known the button reads "Lock ?" (not "Lock OFF")
    beside a badge that says so; once the broker is read (it holds no lock ON), "Lock OFF"."""
    web = rig.sections["web"] = web_section()
    rig.add("hf")
    rig.broker.stop()
    rig.start()
    page = open_console(browser, f"http://127.0.0.1:{web['port']}/")
    try:
        expect(page.locator("#lock")).to_have_text("Lock ?")
        expect(page.locator("#badges")).to_contain_text("LOCK NOT KNOWN YET")
        rig.broker.start()
        expect(page.locator("#lock")).to_have_text("Lock OFF", timeout=slow_ms(30_000))
        expect(page.locator("#badges")).not_to_contain_text("LOCK")
    finally:
        page.context.close()


@pytest.mark.parametrize("origin", ["http://[::1", "http://[127.0.0.1:8754"])
def test_an_origin_that_is_no_url_is_another_sites_refused_not_a_500(
    rig: Rig, caplog: pytest.LogCaptureFixture, origin: str
) -> None:
    web = rig.sections["web"] = web_section()
    rig.add("hf")
    rig.start()
    caplog.set_level(logging.INFO)
    client = ConsoleClient(web["port"])
    answer = client.post("/api/session", {}, token=False, headers={"Origin": origin})
    assert answer.status == 403, answer
    assert "another site" in answer.doc["error"], answer
    assert not [r for r in caplog.records if r.exc_info], "a traceback was logged"


def test_a_login_whose_client_goes_before_its_body_logs_no_traceback(
    guarded: tuple[Rig, ConsoleClient], caplog: pytest.LogCaptureFixture
) -> None:
    """A neighbour with no token sends a login's head and half its body, then closes: nothing
    of the bridge's is at fault, so nothing is logged as an error; the right password still
    logs in."""
    _rig, client = guarded
    caplog.set_level(logging.INFO)
    for _ in range(3):
        with socket.create_connection(("127.0.0.1", client.port), timeout=slow(10)) as s:
            s.sendall(
                f"POST /api/login HTTP/1.1\r\nHost: 127.0.0.1:{client.port}\r\n"
                "Content-Type: application/json\r\nContent-Length: 40\r\n\r\n{".encode()
            )
            s.shutdown(socket.SHUT_WR)  # gone, as far as the body goes
            said = s.recv(64)  # closed: its handler is woken before the next request is read
            assert said == b"" or said.startswith(b"HTTP/1.1 400"), said
    answer = client.post("/api/login", {"password": PASSWORD}, token=False)
    assert answer.status == 200, answer

    def logged() -> list[logging.LogRecord]:
        return [r for r in caplog.records if r.exc_info or r.levelno >= logging.ERROR]

    assert not logged(), [r.getMessage() for r in logged()]
