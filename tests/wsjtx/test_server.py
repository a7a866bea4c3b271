"""The WSJT-X listener (bridge/wsjtx/server.py) on real UDP sockets: statuses reach every
rotator, junk is counted and logged rarely, a fault behind a datagram is contained, a port
in use is an error naming it."""

from __future__ import annotations

import logging
import socket

import pytest

from bridge.engine.follow import Heard
from bridge.wsjtx import WsjtxListener
from bridge.wsjtx.server import JUNK_LOG_S, RATE_DATAGRAMS_S
from tests.support import wait_until
from tests.support import wsjtx as w
from tests.support.clock import FakeClock


class Ears:
    def __init__(self, rid: str, fail: bool = False) -> None:
        self.id = rid
        self.got: list[Heard] = []
        self.fail = fail

    def heard(self, heard: Heard) -> None:
        if self.fail:
            raise RuntimeError("a bug behind the datagram")
        self.got.append(heard)


def test_statuses_reach_every_rotator_and_junk_is_counted_and_logged_rarely(
    caplog: pytest.LogCaptureFixture,
) -> None:
    clock = FakeClock()
    broken, a, b = Ears("broken", fail=True), Ears("a"), Ears("b")
    listener = WsjtxListener(0, "127.0.0.1", clock=clock, rotators=[broken, a, b])  # type: ignore[list-item]
    listener.start()
    caplog.set_level(logging.INFO, "bridge.wsjtx.server")
    try:
        to = listener.address
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            for _ in range(5):
                sock.sendto(b"junk", to)
            sock.sendto(w.heartbeat(), to)
            sock.sendto(w.status(w.StatusFields(dx_call="JA1ABC", dx_grid="PM95")), to)
            wait_until(lambda: a.got and b.got, 10, "both rotators hear the status")
            assert a.got == b.got == [Heard("JA1ABC", "PM95", False, "WSJT-X")]
            counts = listener.counts
            assert (counts.malformed, counts.ignored, counts.statuses) == (5, 1, 1)
            assert counts.faults == 1  # the broken rotator's, and the others heard it all the same
            junk_lines = [r for r in caplog.records if "malformed" in r.getMessage()]
            assert len(junk_lines) == 1  # once per JUNK_LOG_S, with the count since
            clock.t += JUNK_LOG_S + 1
            sock.sendto(b"more junk", to)
            wait_until(lambda: listener.counts.malformed == 6, 10, "the sixth counted")
            junk_lines = [r for r in caplog.records if "malformed" in r.getMessage()]
            assert len(junk_lines) == 2 and "5 malformed" in junk_lines[-1].getMessage()
    finally:
        listener.stop()


def test_a_port_in_use_is_an_error_naming_it() -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as taken:
        taken.bind(("127.0.0.1", 0))
        port = taken.getsockname()[1]
        with pytest.raises(OSError, match=f"WSJT-X UDP port 127.0.0.1:{port}"):
            WsjtxListener(port, "127.0.0.1").listen()


def test_a_flood_is_read_no_faster_than_the_budget_and_said_once(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """Rule 5, in virtual time (the clock stands still): a program flooding the port with
    statuses is read up to a second's budget, then not at all (each status it read would wake
    the serial-lines thread through the mailboxes); said once; when time passes it is read on."""
    clock = FakeClock()
    ears = Ears("a")
    listener = WsjtxListener(0, "127.0.0.1", clock=clock, rotators=[ears])  # type: ignore[list-item]
    listener.start()
    try:
        status = w.status(w.StatusFields(dx_call="JA1ABC", dx_grid="PM95"))
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            for _ in range(int(RATE_DATAGRAMS_S) + 100):
                sock.sendto(status, listener.address)
            wait_until(lambda: listener.counts.paused > 0, 10, "the listener paused")
            heard = len(ears.got)
            assert heard <= RATE_DATAGRAMS_S + 1  # a second's worth, one into debt
            assert len(ears.got) == heard  # and nothing more while the clock stands still
            said = [r for r in caplog.records if "faster than" in r.getMessage()]
            assert len(said) == 1
            clock.t += 10.0
            wait_until(lambda: len(ears.got) > heard, 10, "read on")
    finally:
        listener.stop()
