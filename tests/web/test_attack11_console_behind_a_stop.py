"""An eleventh attack pass, on the front ends together: a console command sent before another
front end's STOP, read by the console after it. Real parts: the bridge in this process on an
emulated Rotor-EZ (pty), a real mosquitto, the console's HTTP API and the rotctld TCP port.

The console dates a command by when its request began on the console's event loop
(server.py ``_started``), not by when its bytes reached the bridge: a request that waited in
the kernel while the loop was busy (other pages' requests, or a local program's flood of
them, which needs no token: 60 connections pipelining GET api/hello kept the bridge at 60-85 %
of a core here, and 2 of 12 targets posted 2 ms before a rotctld S turned the rotor after it)
is dated after any STOP carried out meanwhile, and a script's command (no ``sent``:
commands.py rule 6) is then carried out after that STOP. The TCP ports and the loggers look at
what each connection has unread right before every halt (tcplines.py rule 9,
loggers/server.py rule 9); the console has no such look.

The busy loop is stood in for, as test_last_word_other_interfaces.py stands in for a backlog
on the main connection, by a callback on the console's loop that holds it until the test
lets it go: the request was sent, whole, before the STOP.
"""

from __future__ import annotations

import http.client
import json
import socket
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any, NamedTuple

from bridge.app import App
from bridge.emulators.pty import EmulatedPort
from bridge.emulators.rotorez_models import BEARING_OUTCOMES
from bridge.interfaces.web.server import WebConsole
from tests.support import free_port
from tests.support.console import ConsoleClient, web_section
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until


class ConsoleBesideRotctld(NamedTuple):
    app: App
    emu: EmulatedPort[Any]
    console: ConsoleClient
    web_port: int
    rotctld_port: int


def console_beside_rotctld(rig: Rig) -> ConsoleBesideRotctld:
    """The bridge in this process on an emulated Rotor-EZ at 10 with a rotctld port, its console
    up and a session open on it."""
    web = rig.sections["web"] = web_section()
    port = free_port()
    emu = rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0}, rotctld_port=port)
    app = rig.start()
    rig.ready("tower")
    console = ConsoleClient(web["port"])
    console.session()
    assert app.web is not None
    return ConsoleBesideRotctld(app, emu, console, web["port"], port)


@contextmanager
def console_loop_held(web: WebConsole) -> Iterator[threading.Event]:
    """The console's event loop busy (set once it is) until the block ends."""
    release, held = threading.Event(), threading.Event()

    def busy() -> None:
        held.set()
        release.wait(slow(30))

    loop = web._loop
    assert loop is not None
    loop.call_soon_threadsafe(busy)
    try:
        yield held
    finally:
        release.set()


def test_a_console_target_sent_before_a_rotctld_stop_and_read_after_it_never_turns_the_rotor(
    rig: Rig,
) -> None:
    """A script posts a target of 200 to the console; before the console's busy loop reads
    it, the operator stops the rotor with Hamlib's S. The target, sent first, was carried out
    after the stop: the rotor turned to 200."""
    app, emu, console, web_port, port = console_beside_rotctld(rig)
    body = json.dumps({"command": "target", "az": 200}).encode()
    after = time.monotonic()
    with socket.create_connection(("127.0.0.1", web_port), timeout=slow(10)) as script:
        with console_loop_held(app.web) as held:
            wait_until(held.is_set, slow(10), "the console's loop busy")
            script.sendall(console.command_head("tower", body) + body)  # whole, in the kernel
            with socket.create_connection(("127.0.0.1", port), timeout=slow(5)) as s:
                s.sendall(b"S\n")  # after the target was sent
                assert s.recv(100) == b"RPRT 0\n"
        response = http.client.HTTPResponse(script)
        response.begin()
        answer = response.status, response.read()
    # the rotor turns to the console's target, or the console refuses it (said on R/error)
    wait_until(
        lambda: emu.state().is_moving or stale_said(rig, after),
        slow(10),
        "the console's target carried out or refused",
    )
    assert not emu.state().is_moving, f"turning after the STOP, to the console's {answer}"
    assert answer[0] == 409 and b"stale" in answer[1], answer
    # a target sent after the stop is obeyed; the one before it never went out
    with socket.create_connection(("127.0.0.1", port), timeout=slow(5)) as s:
        s.sendall(b"P 60 0\n")
        assert s.recv(100) == b"RPRT 0\n"
    rig.arrived("tower", 60)
    assert not [f.data for f in emu.frames(*BEARING_OUTCOMES) if b"200" in f.data]


def stale_said(rig: Rig, after: float) -> bool:
    """R/error said, since ``after``, that a command sent before a STOP was not carried out."""
    m = rig.probe.last("rotor/error")
    return m is not None and m.t >= after and b"before a STOP" in m.payload


def test_a_console_lock_off_sent_before_an_mqtt_lock_on_and_read_after_it_leaves_it_locked(
    rig: Rig,
) -> None:
    """The same hole's worse face: a script unlocks the rotator on the console; before the
    console's busy loop reads it, someone about to climb the tower locks it from Home
    Assistant (R/lock ON). The OFF, sent first, was carried out after the ON: unlocked."""
    web = rig.sections["web"] = web_section()
    rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
    app = rig.start()
    rig.ready("tower")
    console = ConsoleClient(web["port"])
    console.session()
    rot = app.rotators[0]
    assert app.web is not None
    body = json.dumps({"command": "lock", "on": False}).encode()
    after = time.monotonic()
    with socket.create_connection(("127.0.0.1", web["port"]), timeout=slow(10)) as script:
        with console_loop_held(app.web) as held:
            wait_until(held.is_set, slow(10), "the console's loop busy")
            script.sendall(console.command_head("tower", body) + body)  # whole, in the kernel
            rig.probe.publish("rotor/lock", "ON")  # after the OFF was sent
            wait_until(lambda: rot.status.locked, slow(10), "locked")
        response = http.client.HTTPResponse(script)
        response.begin()
        answer = response.status, response.read()
    wait_until(
        lambda: not rot.status.locked or stale_said(rig, after),
        slow(10),
        "the console's lock OFF carried out or refused",
    )
    assert rot.status.locked, f"unlocked after the lock ON, by the console's {answer}"
    assert rig.probe.wait_value("rotor/lock/state", "ON", slow(10), after=after)
    assert answer[0] == 409 and b"stale" in answer[1], answer


def test_the_same_connection_s_next_command_sent_after_the_stop_is_carried_out(rig: Rig) -> None:
    """The look dates each request from its own first byte (looks.py rule 3), not from its
    connection's: on the script's keep-alive connection whose target the STOP overtook, the
    target it sends after the STOP (and after the refusal came back) turns the rotor."""
    app, emu, console, web_port, port = console_beside_rotctld(rig)
    first = json.dumps({"command": "target", "az": 200}).encode()
    then = json.dumps({"command": "target", "az": 60}).encode()
    with socket.create_connection(("127.0.0.1", web_port), timeout=slow(10)) as script:
        with console_loop_held(app.web) as held:
            wait_until(held.is_set, slow(10), "the console's loop busy")
            script.sendall(console.command_head("tower", first) + first)
            with socket.create_connection(("127.0.0.1", port), timeout=slow(5)) as s:
                s.sendall(b"S\n")
                assert s.recv(100) == b"RPRT 0\n"
        response = http.client.HTTPResponse(script)
        response.begin()
        assert (response.status, b"stale" in response.read()) == (409, True)
        script.sendall(console.command_head("tower", then) + then)  # after the STOP
        response = http.client.HTTPResponse(script)
        response.begin()
        answer = response.status, response.read()
    assert answer[0] == 200, answer
    rig.arrived("tower", 60)
    assert not [f.data for f in emu.frames(*BEARING_OUTCOMES) if b"200" in f.data]
