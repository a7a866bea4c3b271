"""Review 26: a move seen at the remote before a STOP, read after it, must not be lifted past
that STOP by a later halt of the remote's own (heartbeat.py rule 10's ``after`` floor: a move
is never stamped before its rotator's last halt's stamp; that floor is meant for the client's
own ``S`` then ``P``, not for a halt that came after the move was seen). Real mosquitto, the
station's bridge on an emulated Rotor-EZ, the remote in this process."""

from __future__ import annotations

import threading
import time

import pytest

from bridge.emulators.rotorez_models import BEARING_OUTCOMES
from bridge.interfaces import tcplines
from tests.integration.test_attack_fence_pause import read_gate
from tests.integration.test_rotctld_integration import _replies, connect
from tests.remote.test_stale_after_halt import _decided, _remote, gate_the_loggers
from tests.support import Probe, wait_until
from tests.support.mosquitto import free_port
from tests.support.remote import ask
from tests.support.rig import Rig
from tests.support.waiting import slow


@pytest.mark.parametrize("home_assistant", [True, False], ids=["ha-stop-too", "remote-stop"])
def test_a_logger_turn_seen_before_a_stop_is_not_lifted_past_it_by_the_remotes_next_stop(
    station: Rig,
    probe: Probe,
    monkeypatch: pytest.MonkeyPatch,
    caplog: pytest.LogCaptureFixture,
    home_assistant: bool,
) -> None:
    """The remote on the operator's Windows computer (no kernel datagram stamps): a
    PstRotator turn to 200 reaches the remote's logger port and waits unread (the loggers'
    thread busy); Home Assistant's STOP is carried out at the station; the operator then
    presses ``S`` in their hamlib client (the remote's rotctld port, another front end); then
    the loggers' thread reads the turn. It is stamped with when it was seen (before both
    STOPs), then lifted to the ``S``'s stamp (the rotator's last halt the remote sent): the
    station takes it for not older than its last halt and turns the rotor, after two STOPs
    that both came after the turn was sent. Without the ``S`` it is refused (the review-24
    test): a second STOP makes the stale move pass. (Since review 30 the remote refuses it
    itself: seen before the ``S`` it sent.)"""
    from tests.support.udp_logger import PstClient, reserve_pst_ports

    gate, waiting = gate_the_loggers(monkeypatch, kernel_stamps=False)
    port = free_port()
    pst_port, replies = reserve_pst_ports()
    remote = _remote(port, station.broker.port, pst_udp_port=pst_port)
    try:
        wait_until(lambda: ask(port, b"P 30 0\n") == b"RPRT 0\n", 20, "the remote taking a move")
        station.arrived("tower", 30)
        moves = len(station.emus["tower"].frames(*BEARING_OUTCOMES))
        with PstClient(pst_port, replies=replies) as client:
            gate.clear()  # the loggers' thread busy from its next wake-up on
            client.command("<AZIMUTH>200</AZIMUTH>")  # sent now, before both STOPs
            assert waiting.wait(slow(10)), "the loggers' thread woke for the datagram"
            if home_assistant:
                t = time.monotonic()
                probe.publish("rotor/stop", "stop", qos=1)  # Home Assistant's STOP
                probe.wait_for("rotor/audit", lambda m: b"stop" in m.payload, after=t)
            time.sleep(0.05)  # (the S seen a moment later: a later millisecond)
            t = time.monotonic()
            assert ask(port, b"S\n") == b"RPRT 0\n"  # the operator's own STOP, at the remote
            probe.wait_for("rotor/audit", lambda m: b"stop" in m.payload, after=t)
            errors = probe.mark()
            gate.set()

            def here() -> bool:
                return any("seen before a STOP" in r.getMessage() for r in caplog.records)

            turned = _decided(station, probe, moves, errors, b"RPRT 0", here)
            assert not turned(), "a logger's turn sent before two STOPs turned the rotor after them"
    finally:
        remote.stop()
        replies.close()


def test_a_rotctld_move_seen_before_a_stop_is_not_lifted_past_it_by_another_connections_stop(
    station: Rig, probe: Probe, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The same on the remote's rotctld port on Windows (no FIONREAD: a halt's look counts
    only what was read, tcplines.py rule 9): client A's ``P 200 0`` waits unread while its
    thread sleeps over its budget; Home Assistant's STOP is carried out at the station; client
    B (another program on the operator's computer) sends ``S``; then A's thread reads the
    ``P``. Its seen time is before both STOPs, but it is lifted to B's ``S`` stamp."""

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
        with connect(port) as a:
            spent.clear()
            a.sendall(b"p\n")
            _replies(a, 2)
            assert spent.wait(slow(10)), "the client's thread past its first read"
            gate.clear()
            a.sendall(b"p\n")
            _replies(a, 2)  # read and answered: A's thread now sleeps, nothing unread
            a.sendall(b"P 200 0\n")  # sent now, before both STOPs: unread
            t = time.monotonic()
            probe.publish("rotor/stop", "stop", qos=1)  # Home Assistant's STOP
            probe.wait_for("rotor/audit", lambda m: b"stop" in m.payload, after=t)
            time.sleep(0.05)
            with connect(port) as b:
                t = time.monotonic()
                b.sendall(b"S\n")
                assert _replies(b, 1) == b"RPRT 0\n"
            probe.wait_for("rotor/audit", lambda m: b"stop" in m.payload, after=t)
            errors = probe.mark()
            gate.set()
            reply = _replies(a, 1).splitlines()[-1]
        turned = _decided(station, probe, moves, errors, reply)
        assert not turned(), f"a move sent before two STOPs turned the rotor after them: {reply!r}"
    finally:
        remote.stop()


def test_a_logger_turn_sent_after_a_home_assistant_stop_is_carried_out_when_it_comes_between_waits(
    station: Rig, probe: Probe, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Everyday use on the operator's Windows computer (no kernel datagram stamps,
    loggers/server.py rule 9): Home Assistant's STOP at the station; a while later PstRotator
    sends a turn to 200, which comes while the loggers' thread is between two waits (here:
    in its reports, as it is every REPORT_MOVING_S while a rotor moves). The next wake-up
    finds it waiting already and dates it from when that socket was last found empty: a
    socket never read yet, the loggers' start (``_started_s``), an hour ago for a socket last
    read an hour ago, though every wait since found it empty. The turn goes out stamped before
    Home Assistant's STOP (or older than its expiry) and is refused at the station, the
    rotor left where it was."""
    from bridge.interfaces.loggers import server
    from tests.support.udp_logger import PstClient, reserve_pst_ports

    monkeypatch.setattr(server, "_STAMPS", 0)  # (Windows, macOS: no datagram stamps)
    gate, inside = threading.Event(), threading.Event()
    gate.set()
    report = server.LoggerEndpoints._report

    def held(self: server.LoggerEndpoints, now: float) -> None:
        if not gate.is_set():
            inside.set()
            gate.wait(slow(30))
        report(self, now)

    monkeypatch.setattr(server.LoggerEndpoints, "_report", held)
    port = free_port()
    pst_port, replies = reserve_pst_ports()
    remote = _remote(port, station.broker.port, pst_udp_port=pst_port)
    try:
        wait_until(lambda: ask(port, b"P 30 0\n") == b"RPRT 0\n", 20, "the remote taking a move")
        station.arrived("tower", 30)
        t = time.monotonic()
        probe.publish("rotor/stop", "stop", qos=1)  # Home Assistant's STOP, at the station
        probe.wait_for("rotor/audit", lambda m: b"stop" in m.payload, after=t)
        time.sleep(0.5)  # (the turn sent well after the STOP)
        moves = len(station.emus["tower"].frames(*BEARING_OUTCOMES))
        errors = probe.mark()
        with PstClient(pst_port, replies=replies) as client:
            gate.clear()
            assert inside.wait(slow(10)), "the loggers' thread between two waits"
            client.command("<AZIMUTH>200</AZIMUTH>")  # after the STOP, between two waits
            time.sleep(0.05)  # (in the socket)
            gate.set()
            turned = _decided(station, probe, moves, errors, b"RPRT 0")
            assert turned(), "a logger's turn sent after the STOP was refused: " + str(
                [m.payload for m in probe.messages[errors:] if m.topic == "rotor/error"]
            )
    finally:
        remote.stop()
        replies.close()


@pytest.mark.parametrize("home_assistant", [True, False], ids=["after-ha-stop", "idle"])
def test_a_logger_turn_on_a_computer_without_datagram_stamps_is_dated_when_it_came(
    station: Rig, probe: Probe, monkeypatch: pytest.MonkeyPatch, home_assistant: bool
) -> None:
    """Everyday use on the operator's Windows computer, nothing held, nothing loaded: the
    loggers' thread dates a datagram that came during a wait by its look just before that
    wait (loggers/server.py rule 9), and a wait lasts until the next report is due: up to
    REPORT_MOVING_S (1.5 s), REPORT_IDLE_S (15 s) with nobody to report to. ``after-ha-stop``:
    a PstRotator turn sent half a second after a STOP from Home Assistant is dated before it
    (the wait began before the STOP) and refused. ``idle``: the remote idle a few seconds
    more than its 5 s expiry, a PstRotator turn is dated when the wait began and refused as
    older than its expiry. Both should turn the rotor."""
    from bridge.interfaces.loggers import server
    from tests.support.udp_logger import PstClient, reserve_pst_ports

    monkeypatch.setattr(server, "_STAMPS", 0)  # (Windows, macOS: no datagram stamps)
    port = free_port()
    pst_port, replies = reserve_pst_ports()
    remote = _remote(port, station.broker.port, pst_udp_port=pst_port)
    try:
        wait_until(lambda: ask(port, b"P 30 0\n") == b"RPRT 0\n", 20, "the remote taking a move")
        station.arrived("tower", 30)
        if home_assistant:
            t = time.monotonic()
            probe.publish("rotor/stop", "stop", qos=1)  # Home Assistant's STOP, at the station
            probe.wait_for("rotor/audit", lambda m: b"stop" in m.payload, after=t)
            time.sleep(0.5)  # (the turn sent well after the STOP)
        else:
            time.sleep(8)  # the operator between two QSOs
        moves = len(station.emus["tower"].frames(*BEARING_OUTCOMES))
        errors = probe.mark()
        with PstClient(pst_port, replies=replies) as client:
            client.command("<AZIMUTH>200</AZIMUTH>")
            turned = _decided(station, probe, moves, errors, b"RPRT 0")
            assert turned(), "a logger's turn was refused: " + str(
                [m.payload for m in probe.messages[errors:] if m.topic == "rotor/error"]
            )
    finally:
        remote.stop()
        replies.close()
