"""interfaces/loggers/server.py rule 9, where the system does not stamp datagrams (Windows,
macOS: where the remote runs): each socket's dates are lower bounds, which do not order two
sockets' datagrams. A datagram that is no stop, read after a stop from another socket for the
same rotator and not proven to have come after it (its socket found empty after that stop was
read), is dated just before that stop, so the remote refuses it as seen before the STOP
(remote.py rule 8), even where that is before a stop on its own port too; one socket's
datagrams come in the order they were sent, so a turn read after a stop from the same port
keeps its date (``AZIMUTH 300``, ``STOP``, ``AZIMUTH 200`` ends at 200), and a turn sent
after the stop was read goes on as dated (PstRotator tracking on after a STOP)."""

from __future__ import annotations

import contextlib
import os
import socket
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import pytest

from bridge.interfaces.loggers import server
from bridge.interfaces.loggers.server import HALTS_KEPT, LoggerEndpoints
from tests.support.mosquitto import free_port

STOP = b"<PST><STOP>1</STOP></PST>"


def turn(azimuth: int) -> bytes:
    return b"<PST><AZIMUTH>%d</AZIMUTH></PST>" % azimuth


@dataclass
class Rig:
    ep: LoggerEndpoints
    ports: tuple[int, int]  # PstRotator's, and another program's, for one rotator
    out: socket.socket
    sel: Any
    seen: dict[tuple[int, bytes], float | None] = field(default_factory=dict)

    def send(self, port: int, data: bytes) -> None:
        self.out.sendto(data, ("127.0.0.1", port))

    def sock(self, port: int) -> socket.socket:
        endpoint = next(e for e in self.ep.pst if e.port == port)
        sock = self.ep._socket_of(endpoint)  # noqa: SLF001
        assert sock is not None
        return sock

    def dated(self, port: int, data: bytes) -> float:
        seen_s = self.seen[port, data]
        assert seen_s is not None, "dated by the system's stamp: this test is for none"
        return seen_s


@contextlib.contextmanager
def pst_ports(monkeypatch: pytest.MonkeyPatch, ids: tuple[str, str]) -> Iterator[Rig]:
    """Two PstRotator ports, for the rotators ``ids`` (one rotator's twice, or two), with no
    datagram stamps (Windows, macOS); what each datagram is dated by noted in ``seen``."""
    monkeypatch.setattr(server, "_STAMPS", 0)

    @dataclass
    class Rot:
        id: str

    ep = LoggerEndpoints()
    ports = free_port(), free_port()
    rots = {rid: Rot(rid) for rid in ids}  # (one object where both ports are one rotator's)
    for port, rid in zip(ports, ids, strict=True):
        ep.add_pst(rots[rid], port)  # type: ignore[arg-type]
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


@pytest.fixture
def rig(monkeypatch: pytest.MonkeyPatch) -> Iterator[Rig]:
    with pst_ports(monkeypatch, ("tower", "tower")) as r:
        yield r


def test_a_turn_read_after_another_ports_stop_in_the_same_wake_up_is_dated_before_it(
    rig: Rig,
) -> None:
    """Both waited at one look: the other port's turn may have come after the STOP's port
    was found empty, before the STOP came, or after it: not proven after it."""
    pst, other = rig.ports
    rig.send(other, turn(250))
    rig.send(pst, STOP)
    looked = time.monotonic()  # (both waiting, found so by one look: one bound for both)
    rig.ep._serve(rig.sock(pst), looked)  # noqa: SLF001  (the STOP's port served first)
    rig.ep._serve(rig.sock(other), looked)  # noqa: SLF001
    assert rig.dated(other, turn(250)) < rig.dated(pst, STOP)


def test_a_turn_after_a_stop_on_its_own_port_keeps_its_date(rig: Rig) -> None:
    """One port's datagrams come in the order sent: ``AZIMUTH 300``, ``STOP``, ``AZIMUTH
    200`` read in one go end at 200 (the last turn no earlier than the STOP), also with a
    STOP on the other port read before them (and the port found empty after that)."""
    pst, other = rig.ports
    rig.send(other, STOP)
    rig.ep._turn(rig.sel)  # noqa: SLF001
    rig.ep._look(rig.sel)  # noqa: SLF001  (the look every wake-up begins with)
    for data in (turn(300), STOP, turn(200)):
        rig.send(pst, data)
    rig.ep._turn(rig.sel)  # noqa: SLF001
    assert rig.dated(pst, turn(200)) >= rig.dated(pst, STOP)
    assert rig.dated(pst, turn(200)) >= rig.dated(other, STOP)


def test_a_turn_sent_after_another_ports_stop_was_read_is_dated_after_it(rig: Rig) -> None:
    """PstRotator's tracking on after a STOP from another program: once the loop has found
    the port empty after the STOP was read, what comes there is dated after the STOP."""
    pst, other = rig.ports
    rig.send(pst, STOP)
    rig.ep._turn(rig.sel)  # noqa: SLF001
    rig.ep._look(rig.sel)  # noqa: SLF001  (the look every wake-up begins with)
    rig.send(other, turn(120))
    rig.ep._turn(rig.sel)  # noqa: SLF001
    assert rig.dated(other, turn(120)) > rig.dated(pst, STOP)


def test_a_turn_not_proven_after_a_run_of_stops_is_dated_before_the_first(rig: Rig) -> None:
    """More stops than are remembered one by one (HALTS_KEPT), each read in a wake-up of its
    own: a turn on the other port whose bound is before them all is dated before the first."""
    pst, other = rig.ports
    rig.send(other, turn(80))
    bound = time.monotonic()  # (the other port last found empty: before every STOP)
    for n in range(HALTS_KEPT + 3):
        data = STOP.replace(b"1", b"%d" % (n + 1))  # (one key each in ``seen``)
        rig.send(pst, data)
        rig.ep._serve(rig.sock(pst), time.monotonic())  # noqa: SLF001
    rig.ep._serve(rig.sock(other), bound)  # noqa: SLF001
    first = rig.dated(pst, STOP)
    assert rig.dated(other, turn(80)) < first
    assert len(rig.ep._halts_read[rig.sock(pst)]) <= HALTS_KEPT  # noqa: SLF001


def test_for_one_rotator_a_stop_on_the_other_port_still_dates_the_turn_before_it(
    rig: Rig,
) -> None:
    """The same wake-up with both ports one rotator's (PstRotator's and another program's):
    the other port's STOP may have come after the ``AZIMUTH 200`` (review 33), so the turn is
    dated before it, and refused as seen before a STOP, though that is before its own port's
    STOP too: the safe side, a STOP the last word."""
    pst, other = rig.ports
    rig.send(other, STOP)
    for data in (turn(300), STOP, turn(200)):
        rig.send(pst, data)
    looked = time.monotonic()
    rig.ep._serve(rig.sock(other), looked)  # noqa: SLF001  (the other port served first)
    rig.ep._serve(rig.sock(pst), looked)  # noqa: SLF001
    assert rig.dated(pst, turn(200)) < rig.dated(other, STOP)
