"""Attack 17 on the rotctld port: a stop that is a connection's first command, sent without a
line end. To rotctld ``S`` is whole as it comes (one character, no argument): rotctld 4.5.4
answers ``S`` on a fresh connection ``RPRT 0`` and stops at once, with no CR or LF after it
(checked against ``rotctld -m 1``). The shared line server holds a connection's first line
until its end to look for HTTP (interfaces/tcplines.py rule 2; its ``singles`` let a DCU-1's
one-byte commands through, rotctld had none), so the operator's ``S`` from a script or a
Node-RED TCP node that sends the bare word and waits for the answer is neither answered nor
carried out, and the rotor turns on to its target; one that closes after sending it loses
the stop for good. Review 64: the same held for ever the extended forms rotctld answers at once
too, ``+S`` with ``stop:`` and ``RPRT 0``, ``;S`` with ``stop:;RPRT 0``."""

from __future__ import annotations

import socket

import pytest

from tests.integration.test_rotctld_integration import ask, connect, start
from tests.support.rig import Rig
from tests.support.waiting import slow


def _answer(sock: socket.socket) -> bytes:
    """What comes back to a command (nothing when no answer comes while the client waits)."""
    try:
        return sock.recv(64)
    except TimeoutError:
        return b""


@pytest.mark.parametrize(
    ("stop", "answer"),
    [(b"S", b"RPRT 0\n"), (b"+S", b"stop:\nRPRT 0\n"), (b";S", b"stop:;RPRT 0\n")],
    ids=["S", "+S", ";S"],
)
def test_a_bare_s_as_a_connections_first_command_stops_at_once(
    rig: Rig, stop: bytes, answer: bytes
) -> None:
    port, _ = start(rig, start_az_deg=10)  # 290 degrees to go: over 7 s
    emu = rig.emus["tower"]
    with connect(port) as tracker:
        ask(tracker, b"P 300 0\n", b"RPRT 0\n")
        emu.wait_for(lambda s: s.is_moving, slow(10))
        with connect(port) as operator:
            operator.sendall(stop)  # whole to rotctld: answered and carried out at once
            assert _answer(operator) == answer
            emu.wait_for(lambda s: not s.is_moving, slow(10))
    assert emu.state().az_deg < 290  # stopped on its way, not arrived
