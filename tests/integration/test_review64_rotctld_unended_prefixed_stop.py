"""Review 64 of b239ee87 (rotctld: a bare ``S`` or ``p`` as a connection's first bytes goes at
once): the line server lets through at once only a first line made of ``singles`` (``S``,
``p``), so the same stop asked in rotctld's extended form, ``+S`` (or with a separator prefix,
``;S``), sent as a connection's first bytes without a line end, is still held for the HTTP
check until a line end that never comes: no answer, no stop, and the rotor turns on to its
target. rotctld 4.5.4 (``rotctld -m 1``, checked by hand in this review) answers ``+S`` on a
fresh connection ``stop:`` ``RPRT 0`` at once and stops, as it does a bare ``S`` (and ``;S``
with ``stop:;RPRT 0``, ``S`` followed by a space or a tab, ``+\\stop`` and a space: each held
here too); the script that sends the extended form to read the named answer is the attack 17
script with a ``+``."""

from __future__ import annotations

import socket

from tests.integration.test_rotctld_integration import ask, connect, start
from tests.support.rig import Rig
from tests.support.waiting import slow


def _answer(sock: socket.socket) -> bytes:
    """What comes back to a command (nothing when no answer comes while the client waits)."""
    try:
        return sock.recv(64)
    except TimeoutError:
        return b""


def test_an_extended_s_as_a_connections_first_command_stops_at_once(rig: Rig) -> None:
    port, _ = start(rig, start_az_deg=10)  # 290 degrees to go: over 7 s
    emu = rig.emus["tower"]
    with connect(port) as tracker:
        ask(tracker, b"P 300 0\n", b"RPRT 0\n")
        emu.wait_for(lambda s: s.is_moving, slow(10))
        with connect(port) as operator:
            operator.sendall(b"+S")  # whole to rotctld: answered and carried out at once
            assert _answer(operator) == b"stop:\nRPRT 0\n"
            emu.wait_for(lambda s: not s.is_moving, slow(10))
    assert emu.state().az_deg < 290  # stopped on its way, not arrived
