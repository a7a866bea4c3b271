"""A cold review of the halt watchers (tcplines.py rule 9) found three holes left; each test
failed before the fix.

1. A read that holds bytes sent before a STOP and bytes sent after it: the move before the STOP
   is judged at the look that counted the read's last byte (after the STOP) and carried out.
2. A connection still in the kernel's accept queue when the STOP comes is not in ``_looks``: no
   watcher looks at it, and the look at its accept (after the STOP) takes what it sent before
   the STOP for sent after it.
3. ``Fence.halting`` counts as the connection's own every halt counted between its ``before``
   and its ``after``: an MQTT STOP counted while the client's own S is on its way in is taken
   for the client's own, and a move it sent before that MQTT STOP is carried out (with
   TCP_NODELAY, as Hamlib's client: Nagle held the target back until after the STOP, 40 %).

Gates model scheduling only (a thread paused, the accept loop busy); no sleeps."""

from __future__ import annotations

import socket
import threading

import pytest

from bridge.core import haltwatch
from bridge.interfaces import tcplines
from tests.integration.test_attack_fence_pause import (
    mqtt_stop_carried,
    read_gate,
    shut_after_read,
)
from tests.integration.test_rotctld_integration import _replies, ask, connect, start
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until

pytestmark = pytest.mark.hamlib


def test_a_target_sent_before_a_stop_and_read_with_a_poll_sent_after_it_is_not_carried_out(
    rig: Rig, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The commit's own paused-client scenario, with one ``p`` (a poll: Gpredict sends one a
    second) sent after the STOP and before the client's thread wakes: one read takes both."""
    gate, spent = read_gate(monkeypatch, tcplines)
    port, server = start(rig, start_az_deg=0)
    emu = rig.emus["tower"]
    with connect(port) as sock:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)  # (as Hamlib's client)
        spent.clear()
        ask(sock, b"P 300 0\n", b"RPRT 0\n")
        emu.wait_for(lambda s: s.is_moving, slow(10))
        shut_after_read(gate, spent)
        sock.sendall(b"p\n")
        _replies(sock, 2)  # its thread now sleeps over its budget, nothing unread
        (theirs,) = list(server._clients)  # the server's end of this connection
        sock.sendall(b"P 100 0\n")  # before the STOP
        mqtt_stop_carried(rig, emu, server)  # the STOP carried out
        sock.sendall(b"p\n")  # after the STOP: a poll, moves nothing
        wait_until(lambda: tcplines.unread(theirs.fileno()) == 10, slow(5), "both in the kernel")
        gate.set()
        reply = _replies(sock, 1)  # (the poll's reply may come in the same recv)
    assert reply.startswith(b"RPRT -9\n"), f"a target sent before the STOP went: {reply!r}"


def test_a_target_sent_while_its_connection_is_in_the_accept_queue_before_a_stop_is_refused(
    rig: Rig, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The accept loop busy (a connection flood: ACCEPT_BATCH a wake-up, a few syscalls each)
    while a client connects and sends its target; an MQTT STOP; then the loop takes it."""
    gate = threading.Event()
    gate.set()
    held = threading.Event()
    take = tcplines.LineServer._take

    def busy_take(self, listener, waiting, sel):  # type: ignore[no-untyped-def]
        if not gate.is_set():
            held.set()
            gate.wait(slow(10))
        return take(self, listener, waiting, sel)

    monkeypatch.setattr(tcplines.LineServer, "_take", busy_take)
    port, _server = start(rig, start_az_deg=0)
    emu = rig.emus["tower"]
    rig.probe.publish("rotor/target", "300")
    emu.wait_for(lambda s: s.is_moving, slow(10))
    gate.clear()
    with connect(port) as sock:  # in the kernel's queue: the handshake is the kernel's
        held.wait(slow(5))
        sock.sendall(b"P 100 0\n")  # sent now, before the STOP
        mqtt_stop_carried(rig, emu, _server)  # the STOP carried out
        gate.set()
        reply = _replies(sock, 1)
    assert reply == b"RPRT -9\n", f"a target sent before the STOP was carried out: {reply!r}"


def test_an_mqtt_stop_counted_while_the_clients_own_stop_is_on_its_way_is_not_taken_for_its_own(
    rig: Rig, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The client's S read and on its way to the mailbox (``Fence.halting`` has read
    ``before``), its thread paused there; the client sends a target; an MQTT STOP is counted;
    the client's S goes on. Both halts were once taken for its own, and the target, sent before
    the MQTT STOP, judged as if only the client's own stop came after it."""
    port, _server = start(rig, start_az_deg=0)
    emu = rig.emus["tower"]
    gate = threading.Event()
    gate.set()
    held = threading.Event()
    call = haltwatch.HaltWatchers.__call__

    def paused_call(self):  # type: ignore[no-untyped-def]
        if not gate.is_set() and threading.current_thread().name.startswith("rotctld"):
            held.set()
            gate.wait(slow(10))
        return call(self)

    monkeypatch.setattr(haltwatch.HaltWatchers, "__call__", paused_call)
    with connect(port) as sock:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)  # (as Hamlib's client: no
        # Nagle holding the target back until the S is acknowledged, after the MQTT STOP)
        ask(sock, b"P 300 0\n", b"RPRT 0\n")
        emu.wait_for(lambda s: s.is_moving, slow(10))
        gate.clear()
        base = _server._halt_count()  # type: ignore[misc]
        sock.sendall(b"S\n")
        assert held.wait(slow(5)), "the client's stop never reached the watchers"
        sock.sendall(b"P 100 0\n")  # after its own S, before the MQTT STOP
        rig.probe.publish("rotor/stop", "")
        wait_until(
            lambda: _server._halt_count() > base,  # type: ignore[misc]  # (its lane copy)
            slow(5),
            "the MQTT STOP counted (the client's own S still on its way)",
        )
        gate.set()
        replies = _replies(sock, 2)
    assert replies == b"RPRT 0\nRPRT -9\n", (
        f"a target sent before the MQTT STOP was carried out: {replies!r}"
    )
