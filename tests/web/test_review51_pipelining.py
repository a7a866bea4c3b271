"""Review 51: HTTP/1.1 pipelining on the console beside its looks before each halt
(interfaces/web/looks.py rule 3). Real parts: the bridge in this process on an emulated
Rotor-EZ (pty), a real mosquitto, the console's HTTP API and the rotctld TCP port; the busy
loop stood in for as in test_attack11_console_behind_a_stop.py."""

from __future__ import annotations

import http.client
import json
import socket

import pytest

from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until
from tests.web.test_attack11_console_behind_a_stop import console_beside_rotctld, console_loop_held


@pytest.mark.xfail(
    strict=True,
    reason="review 51: a request pipelined behind one sent before a STOP is dated by that "
    "one's first byte whenever the loop read both in one go (looks.py rule 3), so a target "
    "sent after the STOP's RPRT 0, behind a GET sent before it, is refused as stale (409); "
    "Low: a pipelining client, errs toward refusing, sent again it goes",
)
def test_a_target_pipelined_after_the_stop_behind_an_earlier_request_goes(rig: Rig) -> None:
    """A script's keep-alive connection: GET api/hello sent, the console's loop busy; the
    operator stops the rotor with Hamlib's S and gets RPRT 0; the script then pipelines a
    target of 60 behind its unanswered GET. Sent after the STOP, it goes."""
    app, emu, console, web_port, port = console_beside_rotctld(rig)
    body = json.dumps({"command": "target", "az": 60}).encode()
    with socket.create_connection(("127.0.0.1", web_port), timeout=slow(10)) as script:
        with console_loop_held(app.web) as held:
            wait_until(held.is_set, slow(10), "the console's loop busy")
            script.sendall(b"GET /api/hello HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")
            with socket.create_connection(("127.0.0.1", port), timeout=slow(5)) as s:
                s.sendall(b"S\n")
                assert s.recv(100) == b"RPRT 0\n"
            script.sendall(console.command_head("tower", body) + body)  # after the STOP
        answers = []
        for _ in range(2):
            response = http.client.HTTPResponse(script)
            response.begin()
            answers.append((response.status, response.read()))
    assert answers[0][0] == 200, answers
    assert answers[1][0] == 200, answers
    rig.arrived("tower", 60)
    assert not emu.state().is_moving
