"""Review 36 of 03b47cf7 (interfaces/loggers/server.py rule 9, where the system gives no
datagram stamps: Windows, macOS). The fix lets a stop date another port's turn before it only
where both ports are for one rotator, "a PST port's, every one named on an N1MM port": an
N1MM port's set is every rotor it serves, not the one the turn names. One N1MM port for two
rotators (a tower, X, and a yagi, Y: N1MM's usual set-up) and X's PstRotator port: X's STOP on
its PST port, and on the N1MM port the yagi's ``300``, its ``STOP``, then its ``200``, all come
during one wait (one bound for every datagram read at that wake-up), X's port served first.
The yagi's 200 is dated just before X's STOP, so before the yagi's own STOP (same bound): the
remote refuses the operator's 200 as seen before the yagi's STOP (remote.py rule 8, which
orders a move against its own rotator's halts alone), and the yagi stays where its STOP left
it: review 34's harm, through an N1MM port that names X too."""

from __future__ import annotations

import os
import socket
import time
from typing import Any

import pytest

from bridge.interfaces.loggers import server
from bridge.interfaces.loggers.server import LoggerEndpoints
from tests.loggers.test_unstamped_order import STOP, turn
from tests.support.mosquitto import free_port


def n1mm_turn(rotor: str, azimuth: int) -> bytes:
    return b"<N1MMRotor><rotor>%s</rotor><goazi>%d</goazi></N1MMRotor>" % (
        rotor.encode(),
        azimuth,
    )


def n1mm_stop(rotor: str) -> bytes:
    return b"<N1MMRotor><stop><rotor>%s</rotor></stop></N1MMRotor>" % rotor.encode()


def one_wake_up(
    monkeypatch: pytest.MonkeyPatch,
    first: tuple[bytes, ...],
    then: tuple[bytes, ...],
    *,
    pst_first: bool = True,
) -> dict[bytes, float | None]:
    """X's PstRotator port and one N1MM port for X (``Tower``) and Y (``Yagi``), no datagram
    stamps (Windows, macOS): ``first`` sent to the port served first (X's PST port, or the
    N1MM port unless ``pst_first``), ``then`` to the other, all during one wait (one bound,
    the look before it); what each datagram carried out was dated (the seen time the remote
    judges and stamps it by)."""
    monkeypatch.setattr(server, "_STAMPS", 0)  # (Windows, macOS: no datagram stamps)

    class X:
        id = "x"

    class Y:
        id = "y"

    ep = LoggerEndpoints()
    pst_port, n1mm_port = free_port(), free_port()
    ep.add_pst(X(), pst_port)  # type: ignore[arg-type]
    ep.add_n1mm(X(), "Tower", port=n1mm_port)  # type: ignore[arg-type]
    ep.add_n1mm(Y(), "Yagi", port=n1mm_port)  # type: ignore[arg-type]
    ep.listen()
    out = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    ep._wake_r, ep._wake_w = os.pipe()  # noqa: SLF001
    seen: dict[bytes, float | None] = {}

    def pst(e: Any, _sock: Any, _port: Any, _req: Any, _peer: Any, data: bytes, *rest: Any) -> None:
        seen[data] = rest[-1]  # (seen_s: what the remote judges and stamps it by)

    def n1mm(_e: Any, _req: Any, data: bytes, *rest: Any) -> None:
        seen[data] = rest[-1]

    monkeypatch.setattr(ep._commands, "pst", pst)  # noqa: SLF001
    monkeypatch.setattr(ep._commands, "n1mm", n1mm)  # noqa: SLF001
    try:
        socks = {ep._sockets[s].port: s for s in ep._sockets}  # noqa: SLF001
        order = (pst_port, n1mm_port) if pst_first else (n1mm_port, pst_port)
        for port, datagrams in zip(order, (first, then), strict=True):
            for data in datagrams:
                out.sendto(data, ("127.0.0.1", port))
        looked = time.monotonic()  # (all came during one wait: one bound, the look before it)
        for port in order:
            ep._serve(socks[port], looked)  # noqa: SLF001
        return seen
    finally:
        out.close()
        ep._close_sockets()  # noqa: SLF001
        os.close(ep._wake_r)  # noqa: SLF001
        os.close(ep._wake_w)  # noqa: SLF001


def test_a_yagi_turn_after_its_own_stop_on_n1mm_is_not_dated_before_it_for_the_towers_stop(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    yagi = (n1mm_turn("Yagi", 300), n1mm_stop("Yagi"), n1mm_turn("Yagi", 200))
    # the tower's STOP on its PST port, served first; the yagi's operator: 300, STOP, then 200
    seen = one_wake_up(monkeypatch, (STOP,), yagi)
    turn_s, stop_s = seen[yagi[2]], seen[yagi[1]]
    assert turn_s is not None and stop_s is not None
    assert turn_s >= stop_s, (
        "the yagi's 200, read after the yagi's STOP on the N1MM port, is dated before that "
        f"STOP (just before the tower's STOP on its PST port): refused ({seen})"
    )


def test_a_tower_turn_on_n1mm_read_after_the_towers_stop_on_its_pst_port_is_dated_before_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The safe side kept for the rotator the turn names: it may have come before the STOP."""
    tower = n1mm_turn("Tower", 300)
    seen = one_wake_up(monkeypatch, (STOP,), (tower,))
    turn_s, stop_s = seen[tower], seen[STOP]
    assert turn_s is not None and stop_s is not None
    assert turn_s < stop_s, f"the tower's 300 is dated after the tower's STOP: carried out ({seen})"


@pytest.mark.parametrize(("named", "before"), [("Yagi", False), ("Tower", True), ("*", True)])
def test_a_pst_turn_is_dated_before_an_n1mm_stop_read_first_only_if_it_stops_the_tower(
    monkeypatch: pytest.MonkeyPatch, named: str, before: bool
) -> None:
    """The N1MM port's stop served first, X's ``AZIMUTH 300`` on its PST port read after it."""
    stop = n1mm_stop(named)
    seen = one_wake_up(monkeypatch, (stop,), (turn(300),), pst_first=False)
    turn_s, stop_s = seen[turn(300)], seen[stop]
    assert turn_s is not None and stop_s is not None
    assert (turn_s < stop_s) is before, (
        f"the tower's 300 after an N1MM STOP for {named!r}: "
        + ("dated after it, carried out" if before else "dated before it, refused")
        + f" ({seen})"
    )
