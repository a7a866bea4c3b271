"""Review 33: interfaces/mqtt/remote.py rule 8 after 49e52127 orders a move against a halt by
their seen times alone, and loggers/server.py rule 9 (no kernel stamps: Windows, where the
remote runs) dates each datagram by a lower bound of its own socket's. The two bounds do not
order two sockets' datagrams: one socket's serve loop (PER_WAKEUP reads) dates every datagram
it reads with the bound the wake-up began with, though they came while it carried out the
first (the remote waits for each move's PUBACK), while another socket was found empty by the
look right after the wait, later. PstRotator's turn is being carried out; meanwhile a turn
comes on the other port (N1MM's, or a second PstRotator's), then PstRotator's STOP. The STOP,
read in the same loop, is dated from before the wake-up; the turn, read at the next, from the
look after the wait: after the STOP. The remote lets it go (seen after its last halt) and
stamps it after the STOP, so the station takes it too: the rotor turns after the STOP to a
target that came before it. With kernel stamps (Linux) both are dated when they came."""

from __future__ import annotations

import os
import socket
from typing import Any

import pytest

from bridge.interfaces.loggers import server
from bridge.interfaces.loggers.server import LoggerEndpoints
from tests.support.mosquitto import free_port


def test_a_turn_that_came_before_a_stop_on_another_port_is_not_dated_after_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(server, "_STAMPS", 0)  # (Windows, macOS: no datagram stamps)

    class Rot:
        id = "tower"

    ep = LoggerEndpoints()
    pst_port, other_port = free_port(), free_port()
    rot = Rot()
    ep.add_pst(rot, pst_port)  # type: ignore[arg-type]
    ep.add_pst(rot, other_port)  # type: ignore[arg-type]  # (N1MM's, or a second program's)
    ep.listen()
    out = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    seen: dict[tuple[int, bytes], float | None] = {}
    turn, other_turn, stop = (
        b"<PST><AZIMUTH>100</AZIMUTH></PST>",
        b"<PST><AZIMUTH>250</AZIMUTH></PST>",
        b"<PST><STOP>1</STOP></PST>",
    )

    def pst(e: Any, _sock: Any, _port: Any, _req: Any, _peer: Any, data: bytes, *rest: Any) -> None:
        seen[e.port, data] = rest[-1]  # (seen_s: what the remote judges and stamps it by)
        if data == turn:  # carried out: the remote waits for its PUBACK; meanwhile
            out.sendto(other_turn, ("127.0.0.1", other_port))  # a turn on the other port,
            out.sendto(stop, ("127.0.0.1", pst_port))  # then PstRotator's STOP

    monkeypatch.setattr(ep._commands, "pst", pst)  # noqa: SLF001
    ep._wake_r, ep._wake_w = os.pipe()  # noqa: SLF001
    sel = ep._new_selector()  # noqa: SLF001
    try:
        out.sendto(turn, ("127.0.0.1", pst_port))
        ep._turn(sel)  # type: ignore[arg-type]  # noqa: SLF001  (the turn, then the STOP)
        ep._turn(sel)  # type: ignore[arg-type]  # noqa: SLF001  (the other port's turn)
        stop_s, other_s = seen[pst_port, stop], seen[other_port, other_turn]
        assert stop_s is not None and other_s is not None
        assert other_s <= stop_s, (
            f"the turn that came first is dated {other_s - stop_s:.3f} s after the STOP"
        )
    finally:
        out.close()
        ep._close_selector()  # noqa: SLF001
        ep._close_sockets()  # noqa: SLF001
        os.close(ep._wake_r)  # noqa: SLF001
        os.close(ep._wake_w)  # noqa: SLF001
