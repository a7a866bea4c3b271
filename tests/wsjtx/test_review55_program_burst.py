"""Review 55: wsjtx/server.py rule 6 calls an instance a program while its statuses come at a
program's pace, "PROGRAM_STATUSES_S a second, as many at once". A program that sends that
many at once (ten, after a quiet spell) is no program: its pace's tokens are then 0 and
``_Pace.program`` asks for more than 0, so until a tenth of a second has passed the room of
the programs heard last (rule 5) is not its, and a flood of another name's statuses in that
moment drops its next status undecoded (the transmission's hold). Nine at once keep it. Real
UDP sockets, virtual time (the clock stands still), as tests/wsjtx/test_attack11_status_flood.py."""

from __future__ import annotations

import socket

import pytest

from bridge.interfaces.wsjtx.server import PROGRAM_STATUSES_S
from tests.support import wait_until
from tests.support import wsjtx as w
from tests.support.waiting import slow
from tests.wsjtx.test_attack11_status_flood import Ears, _read, flood_of_another_name, listening

AT_ONCE = int(PROGRAM_STATUSES_S)  # rule 6: "as many at once"


@pytest.mark.parametrize(
    "burst",
    [
        AT_ONCE - 1,
        AT_ONCE,
    ],
    ids=["nine-at-once", "ten-at-once"],
)
def test_a_program_sending_as_many_statuses_at_once_as_its_pace_allows_keeps_its_room(
    burst: int,
) -> None:
    # (following any program: the room is the programs heard last)
    with listening(Ears()) as (listener, ears, clock, stack):
        wsjtx = stack.enter_context(socket.socket(socket.AF_INET, socket.SOCK_DGRAM))
        for n in range(burst):  # (WSJT-X never sends the same status twice running)
            fields = w.StatusFields(dx_call="K1ABC", rx_df=1000 + n)
            wsjtx.sendto(w.status(fields), listener.address)
        wait_until(lambda: _read(listener) >= burst, slow(10), "WSJT-X heard")
        sent = flood_of_another_name(stack, listener, burst)
        fields = w.StatusFields(dx_call="JA1ABC", transmitting=True)  # the next: it transmits
        wsjtx.sendto(w.status(fields), listener.address)
        wait_until(lambda: _read(listener) >= sent + 1, slow(10), "WSJT-X's status read")
        ours = [h.call for h in ears.got if h.instance == "WSJT-X"]
        assert ours == ["K1ABC"] * burst + ["JA1ABC"], f"WSJT-X's statuses handed on: {ours}"
