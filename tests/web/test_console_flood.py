"""The console under a local flood of requests (interfaces/web/connections.py rule 4, looks.py
rules 4 and 6). Real parts: the bridge in this process on an emulated Rotor-EZ (pty), a real
mosquitto, the console's HTTP API and the rotctld TCP port.

A measurement before these rules: 60 local connections pipelining ``GET api/hello`` (it needs
no token) held the bridge at 60-85 % of a core, and with ~250 connections held open every
halt asked each of them what it held unread, one system call each (docs/performance.md,
"Operator console").
"""

from __future__ import annotations

import http.client
import json
import logging
import socket
import time
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager

import pytest

from bridge.interfaces.fdwait import readable, ready_held
from bridge.interfaces.web.connections import MAX_CONNECTIONS, MAX_PER_ADDRESS
from bridge.interfaces.web.looks import LOOKS_KEPT, Conn
from bridge.interfaces.web.server import WebConsole
from tests.support.console import ConsoleClient
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until
from tests.web.test_attack11_console_behind_a_stop import (
    console_beside_rotctld,
    console_loop_held,
    stale_said,
)

HELLO = b"GET /api/hello HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n"
FLOODERS = 240  # with the script's and the page's own connections, under MAX_CONNECTIONS
PER_ADDRESS = 60  # under MAX_PER_ADDRESS: the flood from 127.0.0.2 on, none closed for room


def _answer(sock: socket.socket) -> tuple[int, bytes]:
    response = http.client.HTTPResponse(sock)
    response.begin()
    return response.status, response.read()


def _answers(sock: socket.socket, count: int) -> list[tuple[int, bytes]]:
    """``count`` answers read in turn from one connection (pipelined requests' answers)."""
    got: list[tuple[int, bytes]] = []
    with sock.makefile("rb") as stream:
        for _ in range(count):
            status = int(stream.readline().split()[1])
            length = 0
            while (line := stream.readline()) not in (b"\r\n", b""):
                name, _, value = line.partition(b":")
                if name.strip().lower() == b"content-length":
                    length = int(value)
            got.append((status, stream.read(length)))
    return got


def _paused_said(caplog: pytest.LogCaptureFixture) -> bool:
    return any("paused until it refills" in r.getMessage() for r in caplog.records)


@contextmanager
def _flooders(web: WebConsole, port: int) -> Iterator[list[socket.socket]]:
    """FLOODERS connections to the console from 127.0.0.2 on, every one held by it."""
    assert FLOODERS + 2 <= MAX_CONNECTIONS and PER_ADDRESS <= MAX_PER_ADDRESS
    held_before = len(web._conns)
    with ExitStack() as stack:
        socks = []
        for i in range(FLOODERS):
            sock = stack.enter_context(socket.socket())
            sock.settimeout(slow(10))
            sock.bind((f"127.0.0.{2 + i // PER_ADDRESS}", 0))
            sock.connect(("127.0.0.1", port))
            socks.append(sock)
        wait_until(
            lambda: len(web._conns) >= held_before + FLOODERS,
            slow(20),
            "the flood's connections held by the console",
        )
        for sock in socks:
            sock.setblocking(False)
        yield socks


def _flood(socks: list[socket.socket], requests: int) -> None:
    """Each connection pipelines ``requests`` GET api/hello at once, what the kernel takes."""
    for sock in socks:
        try:
            sock.send(HELLO * requests)
        except BlockingIOError:
            pass


def test_a_connection_pipelining_requests_past_its_budget_is_paused_and_others_are_served(
    rig: Rig, caplog: pytest.LogCaptureFixture
) -> None:
    """A local program pipelines 24 GET api/hello on one connection, three times what one
    connection may ask a second: it is paused (said in the log), the page's own requests on
    its own connections are served meanwhile, and every one of the program's requests is
    answered in the end: paused, never dropped."""
    caplog.set_level(logging.WARNING, logger="bridge.interfaces.web.connections")
    app, emu, console, web_port, port = console_beside_rotctld(rig)
    assert app.web is not None
    requests = 24
    with socket.create_connection(("127.0.0.1", web_port), timeout=slow(20)) as program:
        program.sendall(HELLO * requests)
        wait_until(lambda: _paused_said(caplog), slow(10), "the flooding connection paused")
        page = ConsoleClient(web_port)
        page.session()
        assert page.command("tower", command="target", az=60).status == 200
        assert page.command("tower", command="stop").status == 200
        answers = _answers(program, requests)
    assert [status for status, _ in answers] == [200] * requests
    assert all(json.loads(body)["version"] for _, body in answers)


def test_a_stop_goes_through_and_a_target_sent_before_it_is_refused_beside_a_flood(
    rig: Rig,
) -> None:
    """240 local connections pipeline GET api/hello while the rotor turns; a script posts a
    target of 200 and, before the console's busy loop reads it, the operator stops the rotor
    with Hamlib's S. The STOP stops the rotor, the target sent before it is refused as stale
    (every one of the flood's connections looked at before the halt, most of them holding bytes
    unread), the page's own STOP and its target after it go."""
    app, emu, console, web_port, port = console_beside_rotctld(rig)
    assert app.web is not None
    body = json.dumps({"command": "target", "az": 200}).encode()
    with socket.create_connection(("127.0.0.1", port), timeout=slow(5)) as s:
        s.sendall(b"P 300 0\n")
        assert s.recv(100) == b"RPRT 0\n"
    wait_until(lambda: emu.state().is_moving, slow(10), "turning to 300")
    after = time.monotonic()
    with socket.create_connection(("127.0.0.1", web_port), timeout=slow(20)) as script:
        with _flooders(app.web, web_port) as flood:
            _flood(flood, 50)
            with console_loop_held(app.web) as held:
                wait_until(held.is_set, slow(10), "the console's loop busy")
                _flood(flood, 50)
                script.sendall(console.command_head("tower", body) + body)
                with socket.create_connection(("127.0.0.1", port), timeout=slow(5)) as s:
                    s.sendall(b"S\n")  # after the target was sent
                    assert s.recv(100) == b"RPRT 0\n"
            wait_until(lambda: not emu.state().is_moving, slow(10), "stopped")
            answer = _answer(script)
            assert answer[0] == 409 and b"stale" in answer[1], answer
            wait_until(lambda: stale_said(rig, after), slow(10), "the refusal said on R/error")
            _flood(flood, 50)
            assert console.command("tower", command="stop").status == 200
            assert console.command("tower", command="target", az=60).status == 200
            rig.arrived("tower", 60)


def test_a_connection_held_through_many_halts_keeps_few_looks_and_dates_as_before() -> None:
    """A page's WebSocket is one request for hours: a halt that found it had sent more kept
    one look each, up to 4,096 a rotator, though only the first past its request's start, the
    first past the last answer's and those at bytes not read yet date anything (looks.py rule
    6). Through 200 halts it keeps a few, and its requests are dated as they were."""
    ours, peer = socket.socketpair()
    with peer, Conn(ours.family, ours.type, ours.proto, fileno=ours.detach()) as conn:
        conn._setup(["r"])
        conn.begin()  # the WebSocket's request
        for count in range(200):
            peer.sendall(b"x")
            conn.look("r", count)  # before halt count + 1: the byte still in the kernel
            assert conn.recv(16) == b"x"
        assert len(conn.looks["r"].seen) <= 3
        assert conn.arrived("r") == 0  # dated by the look at its first byte
        conn.end()
        peer.sendall(b"y")  # the next request's first byte, looked at before halt 501
        conn.look("r", 500)
        assert conn.recv(16) == b"y"
        for count in range(600, 600 + 2 * LOOKS_KEPT):  # the loop busy with it meanwhile
            peer.sendall(b"z")
            conn.look("r", count)
            assert conn.recv(16) == b"z"
        assert len(conn.looks["r"].seen) <= 3
        conn.begin()
        assert conn.arrived("r") == 500
        for count in range(900, 900 + 4 * LOOKS_KEPT):  # paused: none of them read
            peer.sendall(b"w")
            conn.look("r", count)
        assert len(conn.looks["r"].seen) <= LOOKS_KEPT
        assert conn.arrived("r") == 500


def test_the_looks_one_poll_finds_what_waits_unread_as_fdwait_does() -> None:
    """The look's poll (looks.py rule 4, the interpreter lock kept around it) finds the
    connections with bytes unread and those whose peer left, as fdwait.py's poll does, and
    never a closed one (-1)."""
    with ExitStack() as stack:
        pairs = [socket.socketpair() for _ in range(6)]
        socks = [stack.enter_context(a) for a, _ in pairs]
        peers = [stack.enter_context(b) for _, b in pairs]
        peers[0].sendall(b"GET")
        peers[3].sendall(b"x" * 100_000)
        peers[4].close()
        fds = [s.fileno() for s in socks] + [-1]
        assert ready_held(fds) == set(readable(fds, 0)) == {fds[0], fds[3], fds[4]}
        assert ready_held([]) == set()
