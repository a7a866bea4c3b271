"""LoggerEndpoints on real UDP sockets with stand-in rotators that record what they are asked
(the wiring through the App, mosquitto and emulators is tests/integration/test_logger_udp.py)."""

from __future__ import annotations

import socket
import threading
from typing import Any

from bridge.loggers import LoggerEndpoints
from bridge.model import RotatorStatus, Source, Stop, Target
from bridge.protocols import REGISTRY
from tests.support.waiting import wait_until


class Recording:
    def __init__(self, rid: str, model: str = "rotorez") -> None:
        self.id, self.spec = rid, REGISTRY[model]
        self.calls: list[Any] = []
        self._lock = threading.Lock()

    @property
    def status(self) -> RotatorStatus:
        return RotatorStatus(self.id, available=True, bearing_deg=10.0)

    def submit(self, command: Any, described: str | None = None) -> None:
        with self._lock:
            self.calls.append(command)

    def report_refusal(self, message: str, command: str | None) -> None:
        with self._lock:
            self.calls.append(("refused", message))


def send(port: int, data: bytes) -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.sendto(data, ("127.0.0.1", port))


def test_an_n1mm_stop_for_every_rotor_stops_every_rotator_on_the_port() -> None:
    """Cold review M4: a stop to '*' was ignored when two rotators shared the port."""
    tower, yagi = Recording("tower"), Recording("yagi")
    ep = LoggerEndpoints()
    ep.add_n1mm(tower, "Tower", port=0)  # type: ignore[arg-type]
    ep.add_n1mm(yagi, "Yagi", port=0)  # type: ignore[arg-type]
    ep.start()
    try:
        port = ep.address(next(iter(ep.n1mm.values())))[1]
        send(port, b"<N1MMRotor><rotor>*</rotor><goazi>90</goazi></N1MMRotor>")  # ambiguous
        send(port, b"<N1MMRotor><stop><rotor>*</rotor></stop></N1MMRotor>")
        wait_until(lambda: tower.calls and yagi.calls, 5, "both stopped")
        assert tower.calls == [Stop(Source.N1MM)] and yagi.calls == [Stop(Source.N1MM)]
    finally:
        ep.stop()


def test_a_pst_azimuth_beyond_hamlibs_range_is_refused_not_folded() -> None:
    """Cold review: any finite azimuth was folded, 99999 became 279."""
    tower = Recording("tower")
    ep = LoggerEndpoints()
    ep.add_pst(tower, port=0)  # type: ignore[arg-type]
    ep.start()
    try:
        port = ep.address(ep.pst[0])[1]
        for value in (b"99999", b"-181", b"450.5", b"-180", b"450"):
            send(port, b"<PST><AZIMUTH>" + value + b"</AZIMUTH></PST>")
        wait_until(lambda: len(tower.calls) == 5, 5, "all five handled")
        refused = [c for c in tower.calls if isinstance(c, tuple)]
        assert len(refused) == 3 and all("outside -180..450" in m for _r, m in refused)
        assert [c.az_deg for c in tower.calls if isinstance(c, Target)] == [180.0, 90.0]
    finally:
        ep.stop()
