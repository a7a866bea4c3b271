"""Attack pass 5 on loggers/server.py rule 9 without kernel stamps (Windows, macOS: where the
remote runs, and dates a logger's turn for its stamp: heartbeat.py rule 10). A datagram found
waiting at a wake-up's first look is dated from "when the socket was last found empty (the
read that found it so)": ``_drained_s``, set only by a read that got EAGAIN. But every wait
that returned without the socket ready also found it empty, right up to its end; those are
not counted. After a quiet spell (the operator not turning for minutes: the select waited, and
timed out, many times), a turn that comes while the thread is busy (serving another logger
port, its N1MM reports; a loaded computer; or a program on the PC that keeps the thread
busy with datagrams to another port) is dated from the read after the *previous* turn,
minutes or hours back. The remote stamps it so: the station refuses it as older than its
expiry (5 s), or as sent before any STOP since (Home Assistant's, an hour ago). The turn
never happens, and the logger got no error (UDP).
"""

from __future__ import annotations

import os
import socket
import time
from typing import Any

import pytest

from bridge.interfaces.loggers import server
from bridge.interfaces.loggers.server import LoggerEndpoints
from tests.support.mosquitto import free_port


class _CappedSelector:
    """The loop's selector, its waits cut short (a wait that times out, as an idle one does
    every REPORT_IDLE_S)."""

    def __init__(self, real: Any, cap_s: float) -> None:
        self.real, self.cap_s = real, cap_s

    def select(self, timeout: float | None = None) -> Any:
        return self.real.select(0 if timeout == 0 else min(timeout or 0, self.cap_s))


def test_a_turn_after_a_quiet_spell_is_not_dated_from_the_turn_before_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(server, "_STAMPS", 0)  # (Windows, macOS: no datagram stamps)

    class Rot:
        id = "tower"

    ep = LoggerEndpoints()
    port = free_port()
    ep.add_pst(Rot(), port)  # type: ignore[arg-type]
    ep.listen()
    seen: list[float | None] = []

    def pst(*args: Any) -> None:
        seen.append(args[-1])  # (seen_s, what the remote stamps the turn with)

    monkeypatch.setattr(ep._commands, "pst", pst)  # noqa: SLF001
    ep._wake_r, ep._wake_w = os.pipe()  # noqa: SLF001
    sel = _CappedSelector(ep._new_selector(), 0.3)  # noqa: SLF001
    out = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        turn = b"<PST><AZIMUTH>100</AZIMUTH></PST>"
        out.sendto(turn, ("127.0.0.1", port))
        time.sleep(0.05)
        ep._turn(sel)  # type: ignore[arg-type]  # noqa: SLF001  (the first turn, read)
        assert len(seen) == 1
        time.sleep(1.0)
        ep._turn(sel)  # type: ignore[arg-type]  # noqa: SLF001  (a quiet wait, timed out)
        known_empty = time.monotonic()  # (that wait returned without the socket ready)
        out.sendto(turn, ("127.0.0.1", port))  # the next turn, while the thread is busy
        time.sleep(0.05)
        ep._turn(sel)  # type: ignore[arg-type]  # noqa: SLF001
        assert len(seen) == 2
        second = seen[1]
        assert second is not None
        assert second >= known_empty - 0.35, (
            f"the turn is dated {known_empty - second:.2f} s before the socket was last seen "
            "empty (the read after the turn before it): after an hour's quiet it goes out "
            "stamped an hour old and the station refuses it"
        )
    finally:
        out.close()
        ep._close_selector()  # noqa: SLF001
        ep._close_sockets()  # noqa: SLF001
        os.close(ep._wake_r)  # noqa: SLF001
        os.close(ep._wake_w)  # noqa: SLF001
