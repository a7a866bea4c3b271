"""Review 20 of the fence (tcplines rule 9, ptylines rule 10): the holes it found, each failing
before its fix (the pty's two by 1fe0fde7, the one on Windows by the commit that adds them).

Gates model scheduling only (a thread paused over its budget); no sleeps as synchronisation."""

from __future__ import annotations

import errno
import os
import socket
import threading
from pathlib import Path

import pytest

from bridge.interfaces import ptylines, tcplines
from bridge.interfaces.ptylines import PtyLineServer
from tests.integration.test_attack_fence_pause import (
    mqtt_stop_carried,
    read_gate,
    shut_after_read,
)
from tests.integration.test_rotctld_integration import _replies, ask, connect, start
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until
from tests.test_ptylines import Client

pytestmark = pytest.mark.hamlib


def _pty(rig: Rig, tmp_path: Path) -> tuple[str, PtyLineServer]:
    path = str(tmp_path / "rotor-gs232")
    rig.add("tower", emu={"start_az_deg": 0, "jitter_deg": 0}, gs232_pty=path)
    app = rig.start()
    rig.ready("tower")
    (server,) = [e for e in app.emulations if isinstance(e, PtyLineServer) and e.path == path]
    return path, server


def test_pty_a_target_written_while_the_thread_is_paused_before_a_stop_is_refused(
    rig: Rig, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """ptylines rule 10 says a move is judged against the first look that held its bytes; but
    the pty server looks only after its own reads and has no halt watcher (tcplines.py's second
    attack pass, never carried to the pty): a program's M100 written while the thread sleeps
    over its budget, then an MQTT STOP, then the thread wakes: its first look at the M100 is
    after the STOP and the target is carried out."""
    gate, spent = read_gate(monkeypatch, ptylines)
    path, server = _pty(rig, tmp_path)
    emu = rig.emus["tower"]
    client = Client(path)
    try:
        spent.clear()
        os.write(client.fd, b"M300\r")  # (M answers nothing)
        emu.wait_for(lambda s: s.is_moving, slow(10))
        shut_after_read(gate, spent)
        assert client.ask(b"C\r").startswith(b"AZ=")  # read; its thread now paused
        os.write(client.fd, b"M100\r")  # before the STOP
        wait_until(lambda: tcplines.unread(server._master) == 5, slow(5), "the M100 in the pty")
        mqtt_stop_carried(rig, emu, server)  # the STOP carried out
        gate.set()
        wait_until(lambda: tcplines.unread(server._master) == 0, slow(5), "the M100 read")
        reply = client.ask(b"C\r")
    finally:
        client.close()
    assert reply.startswith(b"?>\r\n"), f"a target written before the STOP went: {reply!r}"


def test_pty_a_target_written_before_a_stop_and_read_with_a_poll_after_it_is_refused(
    rig: Rig, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Hole (1) of the commit, on the pty: one read holds the M100 written before the STOP
    (looked at before it: a burst's first read counted it) and the C written after it; the
    read is judged at the look that counted its last byte, after the STOP."""
    gate, spent = read_gate(monkeypatch, ptylines)
    path, server = _pty(rig, tmp_path)
    emu = rig.emus["tower"]
    client = Client(path)
    try:
        spent.clear()
        os.write(client.fd, b"M300\r")
        emu.wait_for(lambda s: s.is_moving, slow(10))
        shut_after_read(gate, spent)
        # one write: 64 bytes of polls (the first read's READ_BYTES) and the M100 behind them;
        # the look after that first read counts the M100 (before the STOP)
        polls = b"C\r" * (ptylines.READ_BYTES // 2)
        os.write(client.fd, polls + b"M100\r")
        got = client.read(b"\n", slow(5))
        while got.count(b"\n") < len(polls) // 2:
            more = client.read(b"\n", slow(5))
            assert more, f"replies stopped: {got!r}"
            got += more
        assert tcplines.unread(server._master) == 5  # the M100 unread, its thread paused
        mqtt_stop_carried(rig, emu, server)  # the STOP carried out
        os.write(client.fd, b"C\r")  # after the STOP: a poll, moves nothing
        gate.set()
        reply = client.read(b"\n", slow(5))
    finally:
        client.close()
    assert reply.startswith(b"?>\r\n"), f"a target written before the STOP went: {reply!r}"


class _NoDontwait:
    """The socket module as Windows' Python has it: no MSG_DONTWAIT (winsock has none)."""

    def __getattr__(self, name: str) -> object:
        if name == "MSG_DONTWAIT":
            raise AttributeError("module 'socket' has no attribute 'MSG_DONTWAIT'")
        return getattr(socket, name)


def test_windows_a_rotctld_client_is_answered_without_msg_dontwait_and_fionread(
    rig: Rig, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The remote runs on Windows (tests/remote/test_remote_portable.py proves it starts there,
    never that a client is served). Windows' socket module has no MSG_DONTWAIT and no FIONREAD:
    the accept loop's ``_peek`` (``_stop_in``, every accept), ``_greet`` and the fenced read in
    ``_serve`` each name socket.MSG_DONTWAIT, and an AttributeError is no OSError: no client of
    rotctld, GS-232 or Easycomm is ever answered there."""

    def no_fionread(fd: int) -> int:
        raise OSError(errno.ENOSYS, "no FIONREAD here")

    monkeypatch.setattr(tcplines, "socket", _NoDontwait())
    monkeypatch.setattr(tcplines, "unread", no_fionread)
    port, _server = start(rig, start_az_deg=0)
    with connect(port) as sock:
        sock.sendall(b"p\n")
        try:
            reply = _replies(sock, 2)
        except (ConnectionError, AssertionError, TimeoutError) as exc:
            reply = repr(exc).encode()
    assert reply.startswith(b"0.00\n"), f"the client was not answered: {reply!r}"


def test_a_target_sent_well_after_a_stop_from_a_new_connection_is_not_refused(
    rig: Rig, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The accept loop's empty-queue floor can go back below a halt: the look before the halt
    sets the floor to the count after it, then (before the halt is counted) the accept loop,
    draining after a program's connection (a script's ``rotctl -m 2 p``, once a second),
    finds the queue empty and sets it to the count read then, the one before the halt. The
    floor stays there until the next drain: the next program's target, sent long after the
    STOP and in the kernel when it is accepted, is refused as sent before it."""
    port, server = start(rig, start_az_deg=0)
    watchers = server._halt_watchers
    assert watchers is not None
    gate, entered = threading.Event(), threading.Event()
    gate.set()

    def between() -> None:  # after the server's look, before the count: another watcher
        if not gate.is_set():
            entered.set()
            gate.wait(slow(10))

    watchers.add(between)
    took, drained = threading.Event(), threading.Event()
    plain_take = tcplines.LineServer._take

    def watched_take(self, listener, waiting, sel):  # type: ignore[no-untyped-def]
        got = plain_take(self, listener, waiting, sel)
        if got and not gate.is_set():
            took.set()  # (the script's connection)
        elif took.is_set():
            drained.set()  # the queue found empty after it
        return got

    monkeypatch.setattr(tcplines.LineServer, "_take", watched_take)
    with connect(port) as stopper:  # the operator's program, connected before
        ask(stopper, b"p\n", b"0.00\n0.00\n")
        gate.clear()
        stopper.sendall(b"S\n")  # (one halt: an MQTT STOP counts its lane copy again later)
        assert entered.wait(slow(5)), "the STOP never reached the watchers"
        with connect(port) as poller:  # a script's connection, accepted meanwhile
            assert drained.wait(slow(5)), "the queue never found empty after it"
            gate.set()
            ask(stopper, b"", b"RPRT 0\n")  # the STOP counted and carried out
            poller.sendall(b"p\n")
            _replies(poller, 2)
    watchers.remove(between)
    take, held, go = plain_take, threading.Event(), threading.Event()

    def busy_take(self, listener, waiting, sel):  # type: ignore[no-untyped-def]
        if not go.is_set():
            held.set()
            go.wait(slow(10))
        return take(self, listener, waiting, sel)

    monkeypatch.setattr(tcplines.LineServer, "_take", busy_take)
    with connect(port) as sock:  # long after the STOP: Gpredict connects and sends its target
        assert held.wait(slow(5))
        sock.sendall(b"P 100 0\n")
        go.set()
        reply = _replies(sock, 1)
    assert reply == b"RPRT 0\n", f"a target sent after the STOP was refused: {reply!r}"
