"""Attack pass (atkn1): tcplines.py rule 9 promises that a move a client sent before a STOP is
not carried out however late it is read. The server looks at what a connection has sent only
after each read; a client whose thread sleeps over its budget (rule 5) is not looked at while
it sleeps, so a target that reached the kernel during the sleep, before a STOP, is first
counted by the look after the sleep, after the STOP, and taken for sent after it.

The budget is gated here (no clock, no sleep): closed once the client's last reply came, so
its thread is paused with nothing unread; the target and then the STOP come; the gate opens."""

from __future__ import annotations

import threading
from typing import Any

import pytest

from bridge.core.ratelimit import Budget
from bridge.interfaces import tcplines
from tests.integration.test_rotctld_integration import _replies, ask, connect, start
from tests.support.rig import Rig
from tests.support.waiting import slow, wait_until

pytestmark = pytest.mark.hamlib


def mqtt_stop_carried(rig: Rig, emu: Any, server: Any) -> None:
    """An MQTT STOP published, and waited for until the rotor stopped and ``server`` (a TCP or
    pty line server) counted the halt: the stop express may stop the rotor before then."""
    halts = server._halt_count()
    rig.probe.publish("rotor/stop", "")
    emu.wait_for(lambda s: not s.is_moving, slow(10))
    wait_until(lambda: server._halt_count() > halts, slow(5), "the STOP counted")


def read_gate(
    monkeypatch: pytest.MonkeyPatch, module: object = tcplines
) -> tuple[threading.Event, threading.Event]:
    """``module``'s Budget (tcplines or ptylines) gated at the end of each read, nothing
    timed: a client's thread that finishes a read (its ``spend``) while ``gate`` is clear is
    over its budget, asleep, its bytes unread, until the gate is set; ``spent`` is set at every
    read finished. (Gated before a read instead, a gate cleared while the thread was still
    past its last reply, before its next look at the budget, held up the very read a test
    wanted: on a loaded CI machine a pty test's polls were never answered.)"""
    gate, spent = threading.Event(), threading.Event()
    gate.set()

    class Gated(Budget):
        over = False

        def spend(self, cost: float, now: float) -> None:
            super().spend(cost, now)
            self.over = not gate.is_set()
            spent.set()

        def wait_s(self, now: float) -> float:
            if self.over and not gate.is_set():
                return 0.01
            self.over = False
            return super().wait_s(now)

    monkeypatch.setattr(module, "Budget", Gated)
    return gate, spent


def shut_after_read(gate: threading.Event, spent: threading.Event) -> None:
    """``read_gate``'s gate cleared once the read of the command before it (``spent`` cleared
    before that command was sent) has spent its budget: a client's thread then sleeps from the
    end of its next read, the bytes after it unread. (Cleared as soon as the controller moved,
    the gate was sometimes shut before that command's own read, its budget spent after its
    reply: on a loaded CI machine the thread slept before it read the next command.)"""
    assert spent.wait(slow(10)), "the command's read never finished"
    gate.clear()


def test_a_target_sent_while_its_client_is_paused_and_before_a_stop_is_not_carried_out(
    rig: Rig, monkeypatch: pytest.MonkeyPatch
) -> None:
    gate, spent = read_gate(monkeypatch, tcplines)
    port, server = start(rig, start_az_deg=0)
    emu = rig.emus["tower"]
    with connect(port) as sock:
        spent.clear()
        ask(sock, b"P 300 0\n", b"RPRT 0\n")
        emu.wait_for(lambda s: s.is_moving, slow(10))
        shut_after_read(gate, spent)  # over its budget from its next read on (a fast poller's)
        sock.sendall(b"p\n")
        _replies(sock, 2)  # read, looked at and answered: its thread now sleeps, nothing unread
        sock.sendall(b"P 100 0\n")  # sent now, before the STOP: in the kernel, unread
        mqtt_stop_carried(rig, emu, server)  # the STOP carried out
        gate.set()
        reply = _replies(sock, 1)
    assert reply == b"RPRT -9\n", f"a target sent before the STOP was carried out: {reply!r}"


class _GatedAccepts:
    """An accept budget that lets nothing in while its gate is shut (``tokens``, ``rate_per_s``:
    what the accept loop reads to know when to look again)."""

    def __init__(self, gate: threading.Event) -> None:
        self.gate, self.tokens, self.rate_per_s = gate, 0.0, 100.0

    def take(self, now: float) -> bool:
        return self.gate.is_set()


def test_a_target_sent_while_its_connection_waits_its_turn_and_before_a_stop_is_not_carried_out(
    rig: Rig, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The same hole at the accept loop (rule 5: one address starts at most 20 clients a second,
    and every program on the host is 127.0.0.1, a flooding one too): a waiting connection is
    looked at when accepted and not again until its thread's first read, so a target its client
    sent while it waited, before a STOP, is taken for sent after the STOP. (Live, with another
    local program opening connections 50 a second: rotctld's P 100 sent at 0.001 s, an MQTT
    STOP at 0.052 s, carried out at 0.16 s; then M100 went out at 0.28 s and the client read
    RPRT 0.)"""
    gate = threading.Event()
    gate.set()
    accepts = _GatedAccepts(gate)
    monkeypatch.setattr(tcplines.LineServer, "_accept_budget", lambda self, host, now: accepts)
    port, server = start(rig, start_az_deg=0)
    emu = rig.emus["tower"]
    rig.probe.publish("rotor/target", "300")
    emu.wait_for(lambda s: s.is_moving, slow(10))
    gate.clear()  # the address's accept budget spent (by another program's connections)
    with connect(port) as sock:
        wait_until(lambda: len(server.waiting) == 1, slow(5), "the connection waits its turn")
        sock.sendall(b"P 100 0\n")  # sent now, before the STOP
        mqtt_stop_carried(rig, emu, server)  # the STOP carried out
        gate.set()
        reply = _replies(sock, 1)
    assert reply == b"RPRT -9\n", f"a target sent before the STOP was carried out: {reply!r}"
