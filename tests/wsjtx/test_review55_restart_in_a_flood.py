"""Review 55: wsjtx/server.py rule 5 keeps budget room for the latest sender of the program a
rotator follows (``Rotator.followed``), and says a restarted WSJT-X (a new socket, the same
Id) keeps it. It does only if the restarted WSJT-X's first status gets through the cap for all
senders together: the room is a sender, learnt from a status handed on, and a status from a
socket not in it is held to the shared cap. A flood that runs on (no status forged: heartbeats
from eight local sockets, the attack pass rule 5 answers) keeps the shared cap spent, so
WSJT-X restarted during it (or its UDP server setting changed: a new socket) is never heard
again while the flood lasts, though a rotator follows WSJT-X by name: the transmission's hold
and the next partners missed. The same WSJT-X not restarted is heard through it. Real UDP
sockets, virtual time moving on between the flood's bursts (each burst spends what the cap
for all gained meanwhile), as tests/wsjtx/test_attack11_status_flood.py."""

from __future__ import annotations

import socket

import pytest

from bridge.interfaces.wsjtx import WsjtxListener
from tests.support import wait_until
from tests.support import wsjtx as w
from tests.support.waiting import slow
from tests.wsjtx.test_attack11_status_flood import Ears, listening

CALLS = ("JA1ABC", "VK2XYZ", "ZL1AAA")  # WSJT-X's statuses during the flood, transmitting


def _read(listener: WsjtxListener) -> int:
    """The datagrams the listener has read: statuses and heartbeats handed on or ignored, or
    dropped undecoded."""
    c = listener.counts
    return c.statuses + c.ignored + c.over_budget


def _burst(flooders: list[socket.socket], listener: WsjtxListener, sent: int) -> int:
    """Forty heartbeats from each flooding socket (within its own budget), read before the
    next socket's; ``sent`` counted on."""
    junk = w.heartbeat("flood")
    for s in flooders:
        for _ in range(40):
            s.sendto(junk, listener.address)
        sent += 40
        wait_until(lambda n=sent: _read(listener) >= n, slow(10), "the flood read")
    return sent


@pytest.mark.parametrize(
    "restarted",
    [
        False,
        True,
    ],
    ids=["same-socket", "restarted-in-the-flood"],
)
def test_wsjtx_followed_is_heard_through_a_flood_that_runs_on(restarted: bool) -> None:
    # (a rotator follows WSJT-X (follow.py rule 8))
    with listening(Ears(followed="WSJT-X")) as (listener, ears, clock, stack):
        wsjtx = stack.enter_context(socket.socket(socket.AF_INET, socket.SOCK_DGRAM))
        wsjtx.sendto(w.status(w.StatusFields(dx_call="K1ABC")), listener.address)
        wait_until(lambda: _read(listener) >= 1, slow(10), "WSJT-X heard")
        sent = 1
        flooders = [
            stack.enter_context(socket.socket(socket.AF_INET, socket.SOCK_DGRAM)) for _ in range(8)
        ]
        while listener.counts.over_budget == 0:  # the flood begins: the cap for all spent
            sent = _burst(flooders, listener, sent)
        if restarted:  # WSJT-X restarted: the same Id from a socket of its own
            wsjtx = stack.enter_context(socket.socket(socket.AF_INET, socket.SOCK_DGRAM))
        for call in CALLS:
            clock.t += 0.1  # the flood runs on: what the cap gained is spent again
            sent = _burst(flooders, listener, sent)
            fields = w.StatusFields(dx_call=call, transmitting=True)
            wsjtx.sendto(w.status(fields), listener.address)
            sent += 1
            wait_until(lambda n=sent: _read(listener) >= n, slow(10), "WSJT-X's status read")
        ours = [h.call for h in ears.got if h.instance == "WSJT-X"]
        assert ours == ["K1ABC", *CALLS], f"WSJT-X's statuses handed on: {ours}"
