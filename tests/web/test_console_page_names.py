"""A console page's numbers (web/commands.py rule 5, ``Order.carried`` and ``scoped``).

A cold review found that a console script restarted under the same page name with a fresh
login numbered from 1 again, and its STOP was answered ok and not carried out (taken for a
copy of its last run's halt), while its targets were refused as numbered before that halt;
and another login that guessed a page name could eat that page's STOPs. A page's numbers now
count within its login.

The next review guarded what the numbers still decide, when a change told a halt's copies by
the way they came (WebSocket or POST) instead: a page's older STOP whose request was held up
on the way, arriving after the page's newer STOP and its next click, stopped the rotor short
of the click; a STOP's request the page sent once more was two STOPs in the audit trail.

Real mosquitto, the Rotor-EZ emulator on a pty, the console over HTTP and its WebSocket (raw
frames, as the page sends them).
"""

from __future__ import annotations

import json
import socket
import time
from collections.abc import Iterator
from typing import Any

import pytest

from tests.support.console import ConsoleClient, web_section
from tests.support.rig import Rig
from tests.support.waiting import slow


@pytest.fixture
def console(rig: Rig) -> Iterator[tuple[Rig, ConsoleClient]]:
    web = rig.sections["web"] = web_section()
    rig.add("hf", emu={"start_az_deg": 10.0})
    rig.start()
    rig.ready("hf")
    client = ConsoleClient(web["port"])
    client.session()
    yield rig, client


def test_a_fresh_login_under_the_same_page_name_is_a_fresh_page(
    console: tuple[Rig, ConsoleClient],
) -> None:
    rig, client = console
    assert client.command("hf", command="stop", page="logger", seq=7).status == 200
    again = ConsoleClient(client.port)
    again.session()  # the script restarted: a fresh login
    answer = again.command("hf", command="target", az=120, page="logger", seq=1)
    assert answer.status == 200, answer
    rig.arrived("hf", 120)


def test_a_page_name_guessed_from_another_session_does_not_eat_the_pages_stop(
    console: tuple[Rig, ConsoleClient],
) -> None:
    """An attack pass: a console page name is chosen by the client, and another session that
    sent a halt under it, numbered high, made the page's later STOPs count as carried out."""
    rig, client = console
    emu = rig.emus["hf"]
    other = ConsoleClient(client.port)
    other.session()
    assert other.command("hf", command="stop", page="logger", seq=1000).status == 200
    assert client.command("hf", command="target", az=300, page="logger", seq=1).status == 200
    emu.wait_for(lambda s: s.is_moving, slow(10))
    assert client.command("hf", command="stop", page="logger", seq=2).status == 200
    emu.wait_for(lambda s: not s.is_moving, slow(10))
    assert emu.state().az_deg < 290, "the STOP was answered ok and not carried out"


class _Socket:
    """The page's WebSocket, raw: opened with ``token``, sends what the page sends."""

    def __init__(self, port: int, token: str) -> None:
        self.s = socket.create_connection(("127.0.0.1", port))
        self.s.settimeout(slow(10))
        self.s.sendall(
            (
                f"GET /api/live HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n"
                "Upgrade: websocket\r\nConnection: Upgrade\r\n"
                "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n"
                f"Sec-WebSocket-Protocol: rotor-bridge, token.{token}\r\n\r\n"
            ).encode()
        )
        head = b""
        while b"\r\n\r\n" not in head:
            head += self.s.recv(1)
        assert head.startswith(b"HTTP/1.1 101"), head

    def send(self, doc: dict[str, Any]) -> None:
        payload = json.dumps(doc).encode()
        assert len(payload) < 126
        self.s.sendall(bytes([0x81, 0x80 | len(payload)]) + b"\x00\x00\x00\x00" + payload)

    def close(self) -> None:
        self.s.close()


def _audited(rig: Rig, what: str, after: float) -> Any:
    return rig.probe.wait_for(
        rig.topic("hf", "audit"), lambda m: json.loads(m.text)["command"] == what, after=after
    )


def test_a_pages_older_stop_held_up_on_the_way_does_not_stop_its_next_click(
    console: tuple[Rig, ConsoleClient],
) -> None:
    """The operator presses STOP (its socket's copy carried out at once, its request held up
    on the way), presses STOP again while the socket reconnects (by POST alone: carried out),
    then clicks 60. The first STOP's request arrives last: a copy of a click carried out
    already, and outdone by the page's newer STOP; it stopped the rotor short of 60."""
    rig, client = console
    emu = rig.emus["hf"]
    assert client.token is not None
    page = "tab-held"
    assert client.command("hf", command="target", az=300, page=page, seq=0).status == 200
    emu.wait_for(lambda s: s.is_moving, slow(10))
    ws = _Socket(client.port, client.token)
    try:
        t = time.monotonic()
        ws.send({"rotator": "hf", "command": "stop", "page": page, "seq": 1})  # its request: late
        _audited(rig, "console: stop", t)
    finally:
        ws.close()  # (the feed drops; the page reconnects)
    emu.wait_for(lambda s: not s.is_moving and not s.in_brake_delay, slow(20))
    assert client.command("hf", command="stop", page=page, seq=2).status == 200  # POST alone
    assert client.command("hf", command="target", az=60, page=page, seq=3).status == 200
    emu.wait_for(lambda s: s.is_moving, slow(10))
    t = time.monotonic()
    late = client.command("hf", command="stop", page=page, seq=1)  # STOP 1's request, at last
    assert late.status == 200, late
    assert client.command("hf", command="lock", on=False).status == 200  # (a marker)
    _audited(rig, "lock OFF", t)
    events = [
        json.loads(m.text)["command"] for m in rig.probe.on(rig.topic("hf", "audit")) if m.t >= t
    ]
    assert "console: stop" not in events, (
        f"the first STOP's held-up request was carried out again after the next click: {events}"
    )
    rig.arrived("hf", 60)


def test_a_stop_the_page_sends_again_by_post_is_one_audit_event(
    console: tuple[Rig, ConsoleClient],
) -> None:
    """console.js sends a STOP or lock ON's request once more at once when the first failed
    (its connection may have been closing); while its socket reconnects the page has no other
    copy. A first request that the bridge carried out, its answer lost, and the page's retry:
    one click, two STOPs in the audit trail (``Order.carried``: the retry came "the same way")."""
    rig, client = console
    page = "tab-retry"
    assert client.command("hf", command="target", az=300, page=page, seq=1).status == 200
    rig.emus["hf"].wait_for(lambda s: s.is_moving, slow(10))
    t = time.monotonic()
    assert client.command("hf", command="stop", page=page, seq=2).status == 200  # (answer lost)
    assert client.command("hf", command="stop", page=page, seq=2).status == 200  # the retry
    assert client.command("hf", command="lock", on=False).status == 200  # (a marker)
    _audited(rig, "lock OFF", t)
    events = [
        json.loads(m.text)["command"] for m in rig.probe.on(rig.topic("hf", "audit")) if m.t >= t
    ]
    assert [e for e in events if e == "console: stop"] == ["console: stop"], events
