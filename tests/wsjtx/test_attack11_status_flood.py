"""An eleventh attack pass, on the front ends together: WSJT-X's own statuses drowned by a
flood of statuses of another program's name (bridge/interfaces/wsjtx/server.py rule 5).

Rule 5 keeps room for WSJT-X (an earlier attack pass: eight local sockets flooding the port
with heartbeats took the cap for all senders together, and 8 of WSJT-X's 10 statuses were
dropped, the transmission's hold among them): the senders of the last two statuses were
held to their own budget alone. Any status made its sender one of them, a
status of an instance nobody follows too (follow.py rule 8 ignores those later, in the
session), so a flood of statuses from three local sockets pushed WSJT-X's own out of that
room, spent the cap for all, and WSJT-X's next statuses were dropped undecoded again: the
follow part never heard that the transmission began (the rotor turns while the station
transmits, follow.py rule 3) nor the next partner. Real UDP sockets, virtual time (the clock
stands still, nothing refills), as tests/wsjtx/test_server.py's flood tests.
"""

from __future__ import annotations

import contextlib
import socket
from collections.abc import Callable, Iterator

from bridge.interfaces.wsjtx import WsjtxListener
from bridge.session.follow import Heard
from tests.support import wait_until
from tests.support import wsjtx as w
from tests.support.clock import FakeClock
from tests.support.waiting import slow


class Ears:
    def __init__(self, followed: str | None = None) -> None:
        self.id = "a"
        self.got: list[Heard] = []
        self.followed = followed  # the program its follow part listens to (None: any)

    def heard(self, heard: Heard) -> None:
        self.got.append(heard)


@contextlib.contextmanager
def listening(
    ears: Ears,
) -> Iterator[tuple[WsjtxListener, Ears, FakeClock, contextlib.ExitStack]]:
    """A listener on a free loopback port handing statuses to ``ears``, on a fake clock that
    stands still unless a test moves it (nothing refills); the stack's sockets close before the
    listener stops."""
    clock = FakeClock()
    listener = WsjtxListener(0, "127.0.0.1", clock=clock, rotators=[ears])  # type: ignore[list-item]
    listener.start()
    try:
        with contextlib.ExitStack() as stack:
            yield listener, ears, clock, stack
    finally:
        listener.stop()


def test_wsjtx_is_heard_through_a_flood_of_other_programs_statuses() -> None:
    with listening(Ears()) as (listener, ears, clock, stack):
        wsjtx = stack.enter_context(socket.socket(socket.AF_INET, socket.SOCK_DGRAM))
        wsjtx.sendto(w.status(w.StatusFields(dx_call="K1ABC")), listener.address)
        wait_until(lambda: len(ears.got) == 1, slow(10), "WSJT-X heard")
        sent = 1
        sent = flood_of_another_name(stack, listener, sent)
        transmits_through(wsjtx, listener, sent)
        ours = [h.call for h in ears.got if h.instance == "WSJT-X"]
        assert ours == ["K1ABC", "JA1ABC", "VK2XYZ"], f"WSJT-X's statuses handed on: {ours}"


def flood_of_another_name(
    stack: contextlib.ExitStack,
    listener: WsjtxListener,
    sent: int,
    name: Callable[[int], str] = lambda _n: "JTDX-other",
) -> int:
    """Statuses of another program's name (``JTDX-other``; ``name`` of the n-th datagram if
    given) from eight local sockets, each up to its own budget, in batches the reader keeps
    up with: the cap for all spent between them; ``sent`` counted on (what the listener has
    read by then)."""
    forged: dict[str, bytes] = {}
    k = 0
    for _ in range(8):
        s = stack.enter_context(socket.socket(socket.AF_INET, socket.SOCK_DGRAM))
        for _ in range(6):
            for _ in range(40):
                instance = name(k)
                if instance not in forged:
                    fields = w.StatusFields(dx_call="N0BODY", instance=instance)
                    forged[instance] = w.status(fields)
                s.sendto(forged[instance], listener.address)
                k += 1
            sent += 40
            wait_until(lambda n=sent: _read(listener) >= n, slow(10), "read")
    assert listener.counts.over_budget > 0  # (the cap for all spent)
    return sent


def transmits_through(wsjtx: socket.socket, listener: WsjtxListener, sent: int) -> None:
    """WSJT-X's next two statuses (JA1ABC, then VK2XYZ, each transmitting), until the listener
    has read them (``sent``: what it had to read before them)."""
    for call in ("JA1ABC", "VK2XYZ"):
        wsjtx.sendto(w.status(w.StatusFields(dx_call=call, transmitting=True)), listener.address)
    wait_until(lambda: _read(listener) >= sent + 2, slow(10), "WSJT-X's statuses read")


def _read(listener: WsjtxListener) -> int:
    """The datagrams the listener has read: handed on as statuses, or dropped undecoded."""
    return listener.counts.statuses + listener.counts.over_budget


def test_wsjtx_restarted_on_a_new_socket_keeps_its_room_through_the_flood() -> None:
    """The room is WSJT-X's instance's latest sender: WSJT-X restarted (a new socket, the same
    Id) is heard through the same flood, its first status after the restart taken within
    the shared cap before the flood spends it."""
    with listening(Ears()) as (listener, ears, clock, stack):
        first = stack.enter_context(socket.socket(socket.AF_INET, socket.SOCK_DGRAM))
        first.sendto(w.status(w.StatusFields(dx_call="K1ABC")), listener.address)
        wait_until(lambda: len(ears.got) == 1, slow(10), "WSJT-X heard")
        again = stack.enter_context(socket.socket(socket.AF_INET, socket.SOCK_DGRAM))
        again.sendto(w.status(w.StatusFields(dx_call="G4XYZ")), listener.address)
        wait_until(lambda: len(ears.got) == 2, slow(10), "WSJT-X heard again")
        sent = 2
        sent = flood_of_another_name(stack, listener, sent)
        again.sendto(
            w.status(w.StatusFields(dx_call="JA1ABC", transmitting=True)), listener.address
        )
        sent += 1
        wait_until(lambda: _read(listener) >= sent, slow(10), "WSJT-X's status read")
        ours = [h.call for h in ears.got if h.instance == "WSJT-X"]
        assert ours == ["K1ABC", "G4XYZ", "JA1ABC"], f"WSJT-X's statuses handed on: {ours}"
