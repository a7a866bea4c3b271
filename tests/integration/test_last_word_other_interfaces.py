"""The last word across interfaces (interfaces/mqtt/lastword.py rule 11): a stop or lock ON
given on the console, rotctld, a logger comes on neither MQTT connection, yet a target or a
lock OFF published on MQTT before it and read after it (a backlog) must not turn the rotor
again, nor unlock it. Real parts: mosquitto, the bridge (App) with its console and rotctld
port, an emulated Rotor-EZ on a pty.

The backlog is stood in for, as in test_stop_lane.py, by a main connection held on one message
until the test lets it go: that message was published before the other interface's halt."""

from __future__ import annotations

import json
import select
import socket
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from bridge.app import App
from bridge.emulators.rotorez_models import BEARING_OUTCOMES
from bridge.interfaces.mqtt.lastword import FENCE_MARKERS_OUT
from tests.support import free_port
from tests.support.console import ConsoleClient, web_section
from tests.support.rig import Rig
from tests.support.udp_logger import reserve_pst_ports, udp_socket
from tests.support.waiting import slow, wait_until


@contextmanager
def main_held_on(app: App, topic: str, payload: bytes) -> Iterator[threading.Event]:
    """The main connection stuck on ``topic`` = ``payload`` (set once it is) until the block
    ends; the stop lane reads on meanwhile."""
    release, held = threading.Event(), threading.Event()
    handle = app.client._handler

    def stuck(t: str, p: bytes, retain: bool, *rest: object) -> None:
        if t == topic and p == payload:
            held.set()
            release.wait(slow(30))
        handle(t, p, retain, *rest)

    app.client._handler = stuck
    try:
        yield held
    finally:
        release.set()


def test_an_older_mqtt_lock_off_read_after_the_consoles_lock_on_leaves_it_locked(
    rig: Rig,
) -> None:
    """Someone at the tower locks the rotator on the console, which says ON; a lock OFF an
    automation published just before, held up on the main connection, was read after it and
    unlocked the rotator (a lane's lock ON is kept from that by rule 8; the console's was not)."""
    web = rig.sections["web"] = web_section()
    rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
    app = rig.start()
    rig.ready("tower")
    console = ConsoleClient(web["port"])
    console.session()
    rot = app.rotators[0]
    t = time.monotonic()
    with main_held_on(app, "rotor/lock", b"OFF") as held:
        rig.probe.publish("rotor/lock", "OFF")  # published first, read last
        wait_until(held.is_set, 10, "the main connection held on the lock OFF")
        assert console.command("tower", command="lock", on=True).status == 200
        wait_until(lambda: rot.status.locked, 10, "locked")
    err = rig.probe.wait_for("rotor/error", lambda m: b"lock OFF" in m.payload, 10, after=t)
    assert "published before a lock ON" in json.loads(err.payload)["message"]
    assert rot.locked and rig.probe.wait_value("rotor/lock/state", "ON", 10, after=t)
    # a lock OFF published after it is the last word: obeyed (the fence's marker went out
    # with the lock ON, so the main connection reads it before this)
    rig.probe.publish("rotor/lock", "OFF")
    wait_until(lambda: not rot.locked, 10, "unlocked by the newer OFF")


def test_a_target_published_before_a_rotctld_stop_and_read_after_it_never_turns_the_rotor(
    rig: Rig,
) -> None:
    """The operator stops the rotor with Hamlib's S; a target published just before, behind
    on the main connection, was read after the stop and turned the rotor again."""
    port = free_port()
    emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 20.0}, rotctld_port=port)
    app = rig.start()
    rig.ready("tower")
    rig.probe.publish("rotor/target", "200")
    emu.wait_for(lambda s: s.is_moving, 10)
    t = time.monotonic()
    with main_held_on(app, "rotor/target", b"300") as held:
        rig.probe.publish("rotor/target", "300")  # published first, read last
        wait_until(held.is_set, 10, "the main connection held on the target")
        with socket.create_connection(("127.0.0.1", port), timeout=slow(5)) as s:
            s.sendall(b"S\n")
            assert s.recv(100) == b"RPRT 0\n"
        emu.wait_for(lambda s: not s.is_moving, 10)
    err = rig.probe.wait_for("rotor/error", lambda m: b"300" in m.payload, 10, after=t)
    assert "published before a STOP or lock ON" in json.loads(err.payload)["message"]
    assert not emu.state().is_moving
    assert not [f.data for f in emu.frames(*BEARING_OUTCOMES) if b"300" in f.data]
    # a target published after the stop is obeyed (after the fence's marker, as above)
    rig.probe.publish("rotor/target", "60")
    rig.arrived("tower", 60)


def test_a_flood_of_logger_stops_puts_a_few_markers_behind_a_slow_main_connection(
    rig: Rig,
) -> None:
    """A program floods the PstRotator port with stops (25 bytes a datagram) while the main
    connection is behind: each stop published a fence marker of its own (an attack pass: 20,000
    in 8 s), every one of them read back by the main connection, behind which every rotator's
    targets waited (another rotator's target after its STOP turned it 2.3 s after the flood
    ended, over 10 s once). At most FENCE_MARKERS_OUT go out; the stops after them wait for
    one to come back, and are fenced all the same: the target published before them is
    refused, the one after them obeyed."""
    port, replies = reserve_pst_ports()
    emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 20.0}, pst_udp_port=port)
    app = rig.start()
    rig.ready("tower")
    assert app.loggers is not None
    counts = app.loggers.counts["pst"]
    rig.probe.publish("rotor/target", "200")
    emu.wait_for(lambda s: s.is_moving, 10)
    t = time.monotonic()
    mark = rig.probe.mark()
    with main_held_on(app, "rotor/target", b"300") as held, udp_socket() as sender, replies:
        rig.probe.publish("rotor/target", "300")  # published first, read last
        wait_until(held.is_set, 10, "the main connection held on the target")
        for burst in range(1, 11):  # 300 stops, in bursts the system's buffer takes whole
            for _ in range(30):
                sender.sendto(b"<PST><STOP>1</STOP></PST>", ("127.0.0.1", port))
            wait_until(lambda b=burst: counts.commands >= 30 * b, 10, "the stops carried out")
        emu.wait_for(lambda s: not s.is_moving, 10)
    err = rig.probe.wait_for("rotor/error", lambda m: b"300" in m.payload, 10, after=t)
    assert "published before a STOP or lock ON" in json.loads(err.payload)["message"]
    assert not [f.data for f in emu.frames(*BEARING_OUTCOMES) if b"300" in f.data]
    # the last stops' marker was owed until one of the first came back, and a target published
    # before it went out is refused as older than them, as it should be (a CI run published
    # 60 once the 300 was refused, 50 ms before that marker, and waited for 60 in vain): the
    # fence ends (a marker, no clock), and a target after it is obeyed
    wait_until(lambda: not app.mqtt._halts.fenced("tower"), 10, "the last stops' fence ended")
    rig.probe.publish("rotor/target", "60")
    rig.arrived("tower", 60)
    # (held, the main connection wrote none: they went out once it was let go; a marker out
    # for RESEND_S is sent again, and makes room for as many again)
    fence = [m for m in rig.probe.messages[mark:] if m.topic == "rotor/bridge/fence"]
    assert 1 <= len(fence) <= 3 * FENCE_MARKERS_OUT, f"{len(fence)} markers for 300 stops"


@contextmanager
def loggers_held_on(app: App, data: bytes) -> Iterator[threading.Event]:
    """The loggers' thread stuck on the datagram ``data`` (set once it is) until the block
    ends: a stand-in for a flood it is behind with (what came meanwhile waits in the system's
    buffer, read after)."""
    assert app.loggers is not None
    release, held = threading.Event(), threading.Event()
    carry_out = app.loggers._carry_out

    def stuck(sock: socket.socket, endpoint: object, got: bytes, *rest: Any) -> None:
        if got == data:
            held.set()
            release.wait(slow(30))
        carry_out(sock, endpoint, got, *rest)  # type: ignore[arg-type]

    app.loggers._carry_out = stuck  # type: ignore[method-assign]
    try:
        yield held
    finally:
        release.set()


def _tower_on_pst_and_rotctld(rig: Rig) -> tuple[Any, Any, int, socket.socket, int]:
    """A turning-capable Rotor-EZ ``tower`` with a PstRotator port and a rotctld port, its
    bridge started and ready: the emulator, the app, the PST port, the socket its replies come
    to, and the rotctld port."""
    port, replies = reserve_pst_ports()
    rotctld = free_port()
    emu = rig.add(
        "tower",
        emu={"start_az_deg": 10, "speed_deg_s": 20.0},
        pst_udp_port=port,
        rotctld_port=rotctld,
    )
    app = rig.start()
    rig.ready("tower")
    return emu, app, port, replies, rotctld


def test_a_logger_target_sent_before_a_rotctld_stop_and_read_after_it_never_turns_the_rotor(
    rig: Rig,
) -> None:
    """A logger turns the rotor to 300 on the PstRotator port; the operator, seeing the wrong
    call, stops it with Hamlib's S on rotctld. The loggers' thread was behind (a neighbour's
    flood on the port): the datagram, in the system's buffer before the stop, was read after
    it and turned the rotor again (an attack pass)."""
    emu, app, port, replies, rotctld = _tower_on_pst_and_rotctld(rig)
    assert app.loggers is not None
    counts = app.loggers.counts["pst"]
    blocker = b"<PST>MODE?</PST>"
    t = time.monotonic()
    with udp_socket() as neighbour, udp_socket() as logger, replies:
        with loggers_held_on(app, blocker) as held:
            neighbour.sendto(blocker, ("127.0.0.1", port))
            wait_until(held.is_set, 10, "the loggers' thread behind")
            logger.sendto(b"<PST><AZIMUTH>300</AZIMUTH></PST>", ("127.0.0.1", port))
            with socket.create_connection(("127.0.0.1", rotctld), timeout=slow(5)) as s:
                s.sendall(b"S\n")
                assert s.recv(100) == b"RPRT 0\n"
        # the logger's next datagram is answered once the one before it was carried out
        logger.sendto(b"<PST>AZ?</PST>", ("127.0.0.1", port))
        assert select.select([replies], [], [], slow(10))[0], "no reply to AZ?"
        assert replies.recv(100).startswith(b"AZ:")

        def turned() -> list[bytes]:
            return [f.data for f in emu.frames(*BEARING_OUTCOMES) if b"300" in f.data]

        def refused() -> bool:
            return any(m.topic == "rotor/error" and b"300" in m.payload for m in rig.probe.messages)

        wait_until(lambda: turned() or refused(), 10, "the 300 carried out or refused")
        assert not turned() and counts.commands == 0, (turned(), counts)
        err = rig.probe.wait_for("rotor/error", lambda m: b"300" in m.payload, 10, after=t)
        assert "before a STOP or lock ON" in json.loads(err.payload)["message"]
        assert not emu.state().is_moving
        # a turn the logger sends after the stop is obeyed
        logger.sendto(b"<PST><AZIMUTH>60</AZIMUTH></PST>", ("127.0.0.1", port))
        rig.arrived("tower", 60)


def test_a_logger_target_looked_at_just_before_a_rotctld_stop_never_turns_the_rotor(
    rig: Rig,
) -> None:
    """loggers/commands.py rule 8 at its edge: the loggers' thread looked at the rotator's
    last halt for a logger's 300 (none since it came), and the operator's rotctld S was carried
    out right then, before the 300 reached the judge. The judge read the halt count only when
    the 300 came to it, after the S, and the rotor turned to 300 after the STOP (an attack
    pass: under a neighbour's flood the loggers' thread loses the interpreter anywhere in its
    loop, to the very thread that carries out the S)."""
    emu, app, port, replies, rotctld = _tower_on_pst_and_rotctld(rig)
    assert app.loggers is not None
    commands = app.loggers._commands
    looked = commands._stale
    operator = socket.create_connection(("127.0.0.1", rotctld), timeout=slow(5))

    def stop_right_after(*args: Any) -> bool:
        stale = looked(*args)
        operator.sendall(b"S\n")  # the operator's S, carried out before the look returns
        assert operator.recv(100) == b"RPRT 0\n"
        return stale

    commands._stale = stop_right_after  # type: ignore[method-assign]
    t = time.monotonic()
    with operator, udp_socket() as logger, replies:
        logger.sendto(b"<PST><AZIMUTH>300</AZIMUTH></PST>", ("127.0.0.1", port))

        def turned() -> list[bytes]:
            return [f.data for f in emu.frames(*BEARING_OUTCOMES) if b"300" in f.data]

        def refused() -> bool:
            return any(m.topic == "rotor/error" and b"300" in m.payload for m in rig.probe.messages)

        wait_until(lambda: turned() or refused(), 10, "the 300 carried out or refused")
        assert not turned(), turned()
        err = rig.probe.wait_for("rotor/error", lambda m: b"300" in m.payload, 10, after=t)
        assert json.loads(err.payload)["kind"] == "refused", err.payload
        assert not emu.state().is_moving
        commands._stale = looked  # type: ignore[method-assign]
        logger.sendto(b"<PST><AZIMUTH>60</AZIMUTH></PST>", ("127.0.0.1", port))
        rig.arrived("tower", 60)  # a turn after the stop is obeyed
