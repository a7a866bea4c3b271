"""COLD REVIEW 34 (505a912c): interfaces/loggers/server.py rule 9, where the system gives no
datagram stamps (Windows, macOS: where the remote runs).

The rule: "a datagram read after a stop from the same socket keeps its date: one socket's
datagrams are read in the order they came (``AZIMUTH 300``, ``STOP``, ``AZIMUTH 200`` ends at
200)". But a turn is dated just before ANY stop another socket gave that was read after its
bound (``_before_halts``), whichever rotator that stop was for and though its own port gave a
stop before it. Two rotators, each with its PstRotator port: rotator X's STOP, and on Y's port
``AZIMUTH 300``, ``STOP``, ``AZIMUTH 200``, all come while the loop waits (one bound, the look
before the wait, for every datagram read at that wake-up), X's port served first. Y's
``AZIMUTH 200`` is dated before X's STOP's date, so before Y's own STOP (same bound): the
remote refuses it as seen before Y's STOP (remote.py rule 8, SEEN_BEFORE_HALT), and Y stays
where its STOP left it, though its operator's 200 came after that STOP on the same port. X's
STOP says nothing of Y's turns.
"""

from __future__ import annotations

import os
import socket
import time
from collections.abc import Iterator
from typing import Any

import pytest

from bridge.interfaces.loggers import server
from bridge.interfaces.loggers.server import LoggerEndpoints
from tests.loggers.test_unstamped_order import STOP, Rig, turn
from tests.support.mosquitto import free_port


@pytest.fixture
def two(monkeypatch: pytest.MonkeyPatch) -> Iterator[Rig]:
    """As test_unstamped_order.py's rig, each port another rotator's (X's, then Y's)."""
    monkeypatch.setattr(server, "_STAMPS", 0)  # (Windows, macOS: no datagram stamps)

    class X:
        id = "x"

    class Y:
        id = "y"

    ep = LoggerEndpoints()
    ports = free_port(), free_port()
    ep.add_pst(X(), ports[0])  # type: ignore[arg-type]
    ep.add_pst(Y(), ports[1])  # type: ignore[arg-type]
    ep.listen()
    out = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    ep._wake_r, ep._wake_w = os.pipe()  # noqa: SLF001
    r = Rig(ep, ports, out, ep._new_selector())  # noqa: SLF001

    def pst(e: Any, _sock: Any, _port: Any, _req: Any, _peer: Any, data: bytes, *rest: Any) -> None:
        r.seen[e.port, data] = rest[-1]  # (seen_s: what the remote judges and stamps it by)

    monkeypatch.setattr(ep._commands, "pst", pst)  # noqa: SLF001
    try:
        yield r
    finally:
        out.close()
        ep._close_selector()  # noqa: SLF001
        ep._close_sockets()  # noqa: SLF001
        os.close(ep._wake_r)  # noqa: SLF001
        os.close(ep._wake_w)  # noqa: SLF001


def test_a_turn_after_its_own_ports_stop_is_not_dated_before_it_for_another_rotators_stop(
    two: Rig,
) -> None:
    x, y = two.ports
    two.send(x, STOP)  # rotator X's STOP
    for data in (turn(300), STOP, turn(200)):  # rotator Y's operator: 300, STOP, then 200
        two.send(y, data)
    looked = time.monotonic()  # (all came during one wait: one bound, the look before it)
    two.ep._serve(two.sock(x), looked)  # noqa: SLF001  (X's port served first)
    two.ep._serve(two.sock(y), looked)  # noqa: SLF001
    assert two.dated(y, turn(200)) >= two.dated(y, STOP), (
        "rotator Y's AZIMUTH 200, read after Y's STOP on Y's own port, is dated before that "
        "STOP (just before rotator X's STOP, read first): the remote refuses it as seen "
        f"before Y's STOP ({two.seen})"
    )
