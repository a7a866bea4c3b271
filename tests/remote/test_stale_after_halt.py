"""interfaces/mqtt/heartbeat.py rules 8 and 10: a move stamped before the rotator's last STOP or
lock ON is refused however fresh, a move is stamped with when it was seen at the remote (so one
read late across a STOP the station took another way is refused too), and a move the remote's
operator sends right after their own STOP is not. Real mosquitto, the station's bridge on an
emulated Rotor-EZ, the remote in this process (through a link this test stalls:
tests/support/remote.py's StallingLink)."""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from bridge.emulators.rotorez_models import BEARING_OUTCOMES
from bridge.interfaces import tcplines
from bridge.remote.run import Remote
from bridge.remote.settings import RemoteSettings
from tests.integration.test_attack_fence_pause import read_gate
from tests.integration.test_rotctld_integration import _replies, connect
from tests.support import Probe, wait_until
from tests.support.mosquitto import free_port
from tests.support.remote import StallingLink, ask
from tests.support.rig import Rig
from tests.support.waiting import slow


def _remote(port: int, broker_port: int, patient: bool = False, **endpoint: object) -> Remote:
    """The remote, started: rotator ``tower`` on a rotctld port, and ``endpoint``'s ports;
    ``patient``: it waits for the broker's acknowledgement as long as this machine needs (a
    test whose link never stalls: on a loaded machine a local broker's PUBACK took over the
    default second, and the remote reset its link as a stalled one)."""
    wait_s = max(1.0, slow(1.0)) if patient else 1.0
    settings = RemoteSettings(
        operator="DL1ABC",
        ack_wait_s=wait_s,
        command_expiry_s=max(5, math.ceil(wait_s)),
        mqtt={"host": "127.0.0.1", "port": broker_port, "base_topic": "rotor"},
        endpoints=[{"rotator": "tower", "rotctld_port": port, **endpoint}],
    )
    remote = Remote(settings)
    remote.start()
    return remote


def test_a_target_a_link_held_up_across_a_stop_from_home_assistant_is_refused(
    station: Rig, link: StallingLink, probe: Probe
) -> None:
    """An attack pass: the remote's target held up by its link for a second and a half (inside
    its 5 s expiry), a STOP from Home Assistant at the station meanwhile; the link delivered the
    target after the STOP and the rotor turned to it. It is refused on R/error instead, and the
    rotor stays where the STOP left it."""
    port = free_port()
    remote = _remote(port, link.port)
    try:
        emu = station.emus["tower"]
        wait_until(lambda: ask(port, b"P 30 0\n") == b"RPRT 0\n", 20, "the remote taking a move")
        station.arrived("tower", 30)
        moves = len(emu.frames(*BEARING_OUTCOMES))
        link.stall()
        assert ask(port, b"P 200 0\n") == b"RPRT -6\n"  # (never acknowledged: the link reset)
        t = time.monotonic()
        probe.publish("rotor/stop", "stop", qos=1)  # Home Assistant's STOP, at the station
        probe.wait_for("rotor/audit", lambda m: b"stop" in m.payload, after=t)  # carried out
        errors = probe.mark()
        link.recover()
        refused = probe.wait(
            lambda m: m.topic == "rotor/error" and b"before the last STOP" in m.payload,
            20,
            "the station refusing the target sent before the STOP",
            errors,
        )
        assert b"200" in refused.payload
        wait_until(lambda: remote.link is not None and remote.link.up, 30, "the link back")
        # a move asked now goes: the next command is judged as ever
        wait_until(lambda: ask(port, b"P 60 0\n") == b"RPRT 0\n", 10, "a move taken again")
        station.arrived("tower", 60)
        assert not [f for f in emu.frames(*BEARING_OUTCOMES)[moves:] if b"200" in f.data]
    finally:
        remote.stop()


def test_a_move_sent_right_after_the_remotes_own_stop_is_carried_out(station: Rig) -> None:
    """heartbeat.py rule 8: the remote stamps its STOP; the station times it by that stamp, not
    by when it came, so the target its operator sends right after it (a logger's ``S`` then
    ``P``) is not taken for older than the STOP, however short or long the link's trip."""
    port = free_port()
    remote = _remote(port, station.broker.port, patient=True)
    try:
        wait_until(lambda: ask(port, b"P 10 0\n") == b"RPRT 0\n", 20, "the remote taking a move")
        station.arrived("tower", 10)
        for target in (40, 20, 50):
            assert ask(port, b"S\n") == b"RPRT 0\n"
            assert ask(port, f"P {target} 0\n".encode()) == b"RPRT 0\n"
            station.arrived("tower", target)
        assert "before the last STOP" not in str(station.status("tower").last_error)
    finally:
        remote.stop()


def test_a_move_read_late_across_a_stop_the_station_took_another_way_is_not_carried_out(
    station: Rig, probe: Probe, monkeypatch: pytest.MonkeyPatch
) -> None:
    """tcplines.py rule 9 on the remote (a review): the remote's fence counts the halts sent
    through the remote; a STOP the station took another way (Home Assistant, its console) is
    not among them. A rotctld ``P`` sent to the remote before that STOP, read by the remote
    after it (its client paused over its budget, rule 5), went out stamped with its send
    time, after the STOP, and the station's own last word (heartbeat.py rule 8, service.py
    rule 9) took it for sent after the STOP and turned the rotor. It is stamped with when the
    remote's look found it now (heartbeat.py rule 10), before the STOP: refused. The budget
    is gated at the end of a read (``read_gate``: no clock, no sleep)."""
    gate, spent = read_gate(monkeypatch, tcplines)
    port = free_port()
    remote = _remote(port, station.broker.port)
    try:
        emu = station.emus["tower"]
        wait_until(lambda: ask(port, b"P 30 0\n") == b"RPRT 0\n", 20, "the remote taking a move")
        station.arrived("tower", 30)
        moves = len(emu.frames(*BEARING_OUTCOMES))
        with connect(port) as sock:
            spent.clear()
            sock.sendall(b"p\n")
            _replies(sock, 2)  # its thread is reading
            assert spent.wait(slow(10)), "the client's thread past its first read"
            gate.clear()  # over its budget from the end of its next read on
            sock.sendall(b"p\n")
            _replies(sock, 2)  # read and answered: its thread now sleeps, nothing unread
            sock.sendall(b"P 200 0\n")  # sent now, before the STOP: in the kernel, unread
            t = time.monotonic()
            probe.publish("rotor/stop", "stop", qos=1)  # Home Assistant's STOP, at the station
            probe.wait_for("rotor/audit", lambda m: b"stop" in m.payload, after=t)  # carried out
            errors = probe.mark()
            gate.set()
            reply = _replies(sock, 1)

        def turned() -> bool:
            return any(b"200" in f.data for f in emu.frames(*BEARING_OUTCOMES)[moves:])

        def refused() -> bool:
            return any(
                m.topic == "rotor/error" and b"200" in m.payload for m in probe.messages[errors:]
            )

        # what the operator notices: the rotor turning after the STOP, or not (refused by the
        # remote: nothing sent; sent: the station turns to it or refuses it on R/error)
        wait_until(lambda: reply != b"RPRT 0\n" or turned() or refused(), 20, "the P decided")
        assert not turned(), f"a move sent before the STOP turned the rotor after it: {reply!r}"
    finally:
        remote.stop()


def _late_across_a_home_assistant_stop(
    station: Rig,
    probe: Probe,
    port: int,
    send: bytes,
    replies: int,
    gate: threading.Event,
    spent: threading.Event,
) -> bytes:
    """A rotctld client of the remote on ``port``: its thread read and answered a ``p``, now
    asleep over its budget (``gate`` cleared at the end of that read); ``send`` goes to the
    kernel, unread; Home Assistant's STOP is carried out at the station; the gate opens and
    the remote reads what was sent. The last of ``replies`` replies."""
    with connect(port) as sock:
        spent.clear()
        sock.sendall(b"p\n")
        _replies(sock, 2)  # its thread is reading
        assert spent.wait(slow(10)), "the client's thread past its first read"
        gate.clear()  # over its budget from the end of its next read on
        sock.sendall(b"p\n")
        _replies(sock, 2)  # read and answered: its thread now sleeps, nothing unread
        sock.sendall(send)  # sent now, before the STOP: in the kernel, unread
        t = time.monotonic()
        probe.publish("rotor/stop", "stop", qos=1)  # Home Assistant's STOP, at the station
        probe.wait_for("rotor/audit", lambda m: b"stop" in m.payload, after=t)  # carried out
        gate.set()
        return _replies(sock, replies).splitlines()[-1]


def _decided(
    station: Rig,
    probe: Probe,
    moves: int,
    errors: int,
    reply: bytes,
    refused_here: Callable[[], bool] = lambda: False,
) -> Callable[[], bool]:
    """Waits until the ``200`` move is decided (refused by the remote: its reply, or
    ``refused_here`` for a front end that has none; turned or refused at the station);
    returns whether it turned the rotor."""
    emu = station.emus["tower"]

    def turned() -> bool:
        return any(b"200" in f.data for f in emu.frames(*BEARING_OUTCOMES)[moves:])

    def refused() -> bool:
        return any(
            m.topic == "rotor/error" and b"200" in m.payload for m in probe.messages[errors:]
        )

    wait_until(
        lambda: reply != b"RPRT 0" or refused_here() or turned() or refused(), 20, "the P decided"
    )
    return turned


def test_a_move_read_with_the_clients_own_stop_before_it_is_carried_out(station: Rig) -> None:
    """heartbeat.py rule 10: ``P 300 0``, ``S``, ``P 200 0`` in one segment, read in one go:
    all three seen at one look; the ``S`` is stamped then, and the second target no earlier
    than that ``S`` (the remote's own last halt): the station, comparing the two stamps
    directly, takes it; the rotor ends at 200."""
    port = free_port()
    remote = _remote(port, station.broker.port)
    try:
        wait_until(lambda: ask(port, b"P 10 0\n") == b"RPRT 0\n", 20, "the remote taking a move")
        station.arrived("tower", 10)
        with connect(port) as sock:
            sock.sendall(b"P 300 0\nS\nP 200 0\n")
            assert _replies(sock, 3) == b"RPRT 0\nRPRT 0\nRPRT 0\n"
        station.arrived("tower", 200)
        assert "before the last STOP" not in str(station.status("tower").last_error)
    finally:
        remote.stop()


def test_a_move_behind_the_clients_own_stop_sent_before_a_home_assistant_stop_is_not_carried_out(
    station: Rig, probe: Probe, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Review 24 (its HIGH finding): a move was never stamped before the remote's own last
    halt's *send* time. A hamlib client sends ``S`` then ``P 200 0`` back to back while its
    thread sleeps over its budget; Home Assistant's STOP is carried out at the station; then
    the remote reads both. Its ``S`` went out stamped after Home Assistant's STOP and the
    ``P``, seen before it, was lifted to that stamp: the rotor turned. A halt is stamped with
    when it was seen now, so the ``P`` is lifted at most to the ``S``'s seen time, before the
    STOP: refused (the station's last halt is Home Assistant's, later than both)."""
    gate, spent = read_gate(monkeypatch, tcplines)
    port = free_port()
    remote = _remote(port, station.broker.port)
    try:
        wait_until(lambda: ask(port, b"P 30 0\n") == b"RPRT 0\n", 20, "the remote taking a move")
        station.arrived("tower", 30)
        moves = len(station.emus["tower"].frames(*BEARING_OUTCOMES))
        errors = probe.mark()
        reply = _late_across_a_home_assistant_stop(
            station, probe, port, b"S\nP 200 0\n", 2, gate, spent
        )
        turned = _decided(station, probe, moves, errors, reply)
        assert not turned(), f"a move sent before the STOP turned the rotor after it: {reply!r}"
    finally:
        remote.stop()


@pytest.mark.parametrize("fionread", [True, False], ids=["linux", "windows"])
def test_a_move_behind_more_than_a_read_sent_before_a_home_assistant_stop_is_not_carried_out(
    station: Rig, probe: Probe, monkeypatch: pytest.MonkeyPatch, fionread: bool
) -> None:
    """Review 24: tcplines.py rule 9's since when, on the remote's own system (Windows: no
    FIONREAD, tests/remote/test_remote_portable.py). A client over its budget sends 40 ``p``
    and a ``P 200 0`` (88 bytes) before a STOP from Home Assistant; the first read after the
    STOP takes READ_BYTES (64) of them. On Windows no look counted the rest, and they were
    dated by the look that read the first 64, after the STOP: the rotor turned. A look only
    moves the time of the bytes not counted yet when the kernel counted them, or when a read
    took less than it asked for (``Looks.drained``): the ``P`` keeps the date of the look
    before the STOP, and is refused."""
    if not fionread:

        def no_fionread(fd: int) -> int:
            raise OSError("no FIONREAD here")  # (Windows: tcplines.unread)

        monkeypatch.setattr(tcplines, "unread", no_fionread)
    gate, spent = read_gate(monkeypatch, tcplines)
    port = free_port()
    remote = _remote(port, station.broker.port)
    try:
        wait_until(lambda: ask(port, b"P 30 0\n") == b"RPRT 0\n", 20, "the remote taking a move")
        station.arrived("tower", 30)
        moves = len(station.emus["tower"].frames(*BEARING_OUTCOMES))
        errors = probe.mark()
        burst = b"p\n" * 40 + b"P 200 0\n"
        assert len(burst) > tcplines.READ_BYTES
        reply = _late_across_a_home_assistant_stop(station, probe, port, burst, 81, gate, spent)
        turned = _decided(station, probe, moves, errors, reply)
        assert not turned(), f"a move sent before the STOP turned the rotor after it: {reply!r}"
    finally:
        remote.stop()


@pytest.mark.parametrize("kernel_stamps", [True, False], ids=["linux", "no-kernel-stamps"])
def test_a_logger_turn_read_late_across_a_stop_the_station_took_another_way_is_not_carried_out(
    station: Rig, probe: Probe, monkeypatch: pytest.MonkeyPatch, kernel_stamps: bool
) -> None:
    """Review 24: a move that reached the remote's logger port is stamped with when it got
    there. Linux's kernel stamps say (loggers/server.py rule 9); on the operator's Windows
    computer (N1MM, PstRotator) there are none, and the turn went out stamped when sent: a
    PstRotator turn that came before a STOP from Home Assistant, read by the remote after it
    (its loggers' thread held here right before its read: no clock, no sleep), turned the
    rotor. Without kernel stamps the thread dates a datagram itself: one that woke it came
    after its look just before the wait. ``kernel_stamps=False`` is that computer."""
    from tests.support.udp_logger import PstClient, reserve_pst_ports

    gate, waiting = gate_the_loggers(monkeypatch, kernel_stamps)
    port = free_port()
    pst_port, replies = reserve_pst_ports()
    remote = _remote(port, station.broker.port, pst_udp_port=pst_port)
    try:
        wait_until(lambda: ask(port, b"P 30 0\n") == b"RPRT 0\n", 20, "the remote taking a move")
        station.arrived("tower", 30)
        moves = len(station.emus["tower"].frames(*BEARING_OUTCOMES))
        with PstClient(pst_port, replies=replies) as client:
            gate.clear()  # the loggers' thread busy from its next wake-up on
            client.command("<AZIMUTH>200</AZIMUTH>")  # sent now, before the STOP
            assert waiting.wait(slow(10)), "the loggers' thread woke for the datagram"
            t = time.monotonic()
            probe.publish("rotor/stop", "stop", qos=1)  # Home Assistant's STOP, at the station
            probe.wait_for("rotor/audit", lambda m: b"stop" in m.payload, after=t)  # carried out
            errors = probe.mark()
            gate.set()
            turned = _decided(station, probe, moves, errors, b"RPRT 0")
            assert not turned(), "a logger's turn sent before the STOP turned the rotor after it"
    finally:
        remote.stop()
        replies.close()


def test_a_pty_move_read_late_across_a_stop_the_station_took_another_way_is_not_carried_out(
    station: Rig, probe: Probe, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """Review 24: the remote's GS-232 pty (``gs232_pty``), the pass above on a pty: a
    program's ``M200`` written while the pty's thread sleeps over its budget, a STOP from
    Home Assistant at the station, then the thread wakes. Its move went out stamped when
    sent, after the STOP, and turned the rotor; the pty's looks date it now (ptylines.py
    rule 10): refused."""
    import os

    from bridge.interfaces import ptylines
    from tests.test_ptylines import Client

    gate, spent = read_gate(monkeypatch, ptylines)
    port = free_port()
    path = str(tmp_path / "rotor-gs232")
    remote = _remote(port, station.broker.port, gs232_pty=path)
    try:
        wait_until(lambda: ask(port, b"P 30 0\n") == b"RPRT 0\n", 20, "the remote taking a move")
        station.arrived("tower", 30)
        moves = len(station.emus["tower"].frames(*BEARING_OUTCOMES))
        client = Client(path)
        try:
            spent.clear()
            assert client.ask(b"C\r").startswith(b"AZ=")
            # (the reply is written before the read's spend: a gate cleared before that spend
            # paused the thread ahead of the next C, answered never: review 26, 3 runs in 6)
            assert spent.wait(slow(10)), "the pty's thread past its first read"
            gate.clear()
            assert client.ask(b"C\r").startswith(b"AZ=")  # read; its thread now paused
            os.write(client.fd, b"M200\r")  # before the STOP: in the pty, unread
            t = time.monotonic()
            probe.publish("rotor/stop", "stop", qos=1)  # Home Assistant's STOP, at the station
            probe.wait_for("rotor/audit", lambda m: b"stop" in m.payload, after=t)  # carried out
            errors = probe.mark()
            gate.set()
            turned = _decided(station, probe, moves, errors, b"RPRT 0")
            assert not turned(), "a move written before the STOP turned the rotor after it"
        finally:
            client.close()
    finally:
        remote.stop()


def gate_the_loggers(
    monkeypatch: pytest.MonkeyPatch, kernel_stamps: bool
) -> tuple[threading.Event, threading.Event]:
    """The loggers' thread held at its read while ``gate`` is clear (``waiting`` set once it
    is), as a busy computer holds it; ``kernel_stamps=False``: a system that gives no datagram
    stamps (Windows, macOS). Returns (gate, waiting); the gate starts open."""
    from bridge.interfaces.loggers import server

    if not kernel_stamps:
        monkeypatch.setattr(server, "_STAMPS", 0)
    gate, waiting = threading.Event(), threading.Event()
    gate.set()
    received = server._received

    def gated(sock: object) -> object:
        if not gate.is_set():
            waiting.set()
            gate.wait(slow(30))
        return received(sock)  # type: ignore[arg-type]

    monkeypatch.setattr(server, "_received", gated)
    return gate, waiting
