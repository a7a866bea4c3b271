"""commands.py rule 8, front.py rule 3: a logger's STOP goes to ``submit`` with the latest it
can have come (``read_s``), which the remote orders another program's moves by (remote.py rule
8: a move goes after it only if seen after that). With the system's datagram stamps (Linux)
that is the stamp, however late the loggers' thread read the STOP: a Gpredict ``P`` that came
after the STOP but before its read is not refused. Without stamps, none is said: the remote
takes the moment the STOP is handed over."""

from __future__ import annotations

import threading
import time
from typing import Any

import pytest

from bridge.core.model import Stop
from bridge.interfaces.loggers import server
from bridge.interfaces.loggers.server import LoggerEndpoints
from tests.loggers.test_server import Recording, send
from tests.support.udp_logger import pst, tag
from tests.support.waiting import slow, wait_until


class Bounds(Recording):
    """Records each stop's seen and read bounds."""

    def __init__(self, rid: str) -> None:
        super().__init__(rid)
        self.stops: list[tuple[Any, Any]] = []

    def submit(
        self,
        command: Any,
        described: str | None = None,
        *,
        since: Any = None,
        seen_s: Any = None,
        reader: Any = None,
        read_s: Any = None,
    ) -> None:
        if isinstance(command, Stop):
            self.stops.append((seen_s, read_s))
        super().submit(command, described, since=since)


@pytest.mark.parametrize("kernel_stamps", [True, False], ids=["linux", "no-kernel-stamps"])
def test_a_stop_read_late_goes_with_when_it_came(
    monkeypatch: pytest.MonkeyPatch, kernel_stamps: bool
) -> None:
    if not kernel_stamps:
        monkeypatch.setattr(server, "_STAMPS", 0)  # (Windows, macOS: no datagram stamps)
    gate, waiting = threading.Event(), threading.Event()
    gate.set()
    received = server._received

    def gated(sock: Any) -> Any:
        if not gate.is_set():
            waiting.set()
            gate.wait(slow(30))
        return received(sock)

    monkeypatch.setattr(server, "_received", gated)
    tower = Bounds("tower")
    ep = LoggerEndpoints()
    ep.add_pst(tower, port=0)  # type: ignore[arg-type]
    ep.start()
    try:
        port = ep.address(ep.pst[0])[1]
        gate.clear()
        send(port, pst(tag("STOP", 1)))
        assert waiting.wait(slow(10)), "the loggers' thread woke for the STOP"
        opened = time.monotonic()  # the STOP is read after this
        gate.set()
        wait_until(lambda: tower.stops, 5, "the STOP carried out")
        ((seen, read),) = tower.stops
        if kernel_stamps:
            assert read is not None and seen <= read < opened, (seen, read, opened)
        else:
            assert read is None and seen < opened
    finally:
        ep.stop()
