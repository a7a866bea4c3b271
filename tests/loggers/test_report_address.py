"""N1MM position reports to an address given by name (``n1mm_report_to = "n1mm-pc.lan:13010"``):
looked up on a thread of its own, never on the loggers' thread (server.py rule 6, resolver.py).
Real UDP sockets; the name server is a stand-in lookup the test answers when it chooses (the
bridge as its own process with a silent name server is
test_attack29_report_name_lookup_holds_the_stop.py)."""

from __future__ import annotations

import logging
import select
import socket
import threading
from collections.abc import Callable

import pytest

from bridge.core.model import Source, Stop
from bridge.interfaces.loggers import LoggerEndpoints, resolver
from tests.loggers.test_server import Recording, reports_sink, send, sink_address
from tests.support.udp_logger import pst, tag
from tests.support.waiting import slow, wait_until

QUIET_S = 0.3  # a quiet period, no deadline: what would have come by then


class NameServer:
    """A lookup that waits until the test answers (``answer``), or fails (``fail``): which
    threads asked, and how often."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._answered = threading.Event()
        self._answer: str | Exception = OSError("no answer")
        self.threads: list[str] = []

    def lookup(self, host: str, port: int) -> str:
        with self._lock:
            self.threads.append(threading.current_thread().name)
        self._answered.wait()
        with self._lock:
            answer = self._answer
        if isinstance(answer, Exception):
            raise answer
        return answer

    def answer(self, address: str | Exception) -> None:
        with self._lock:
            self._answer = address
        self._answered.set()

    def asked(self) -> int:
        with self._lock:
            return len(self.threads)


def report_within(sink: socket.socket, wait_s: float) -> bytes | None:
    ready, _, _ = select.select([sink], [], [], wait_s)
    return sink.recvfrom(4096)[0] if ready else None


def endpoints(lookup: Callable[[str, int], str], port: int) -> tuple[LoggerEndpoints, Recording]:
    """A rotator on a PstRotator port and N1MM's, reporting to ``n1mm-pc.lan:port``."""
    rot = Recording("tower")
    ep = LoggerEndpoints(lookup=lookup)
    ep.add_pst(rot, port=0)  # type: ignore[arg-type]
    ep.add_n1mm(rot, "Tower", port=0, report_to=("n1mm-pc.lan", port))  # type: ignore[arg-type]
    return ep, rot


def test_a_report_name_the_name_server_has_not_answered_holds_no_stop(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """The name server silent: a PstRotator STOP is carried out at once, the reports are
    dropped (said once), and go out as soon as the name is found, to its address."""
    dns = NameServer()
    with reports_sink() as sink:
        ep, rot = endpoints(dns.lookup, sink_address(sink)[1])
        ep.start()
        try:
            wait_until(lambda: dns.asked() == 1, slow(5), "the name looked up")
            send(ep.address(ep.pst[0])[1], pst(tag("STOP", 1)))
            wait_until(lambda: rot.calls, slow(5), "the STOP, while the lookup hangs")
            assert rot.calls == [Stop(Source.PST)]
            assert report_within(sink, QUIET_S) is None  # no address yet: none sent
            dns.answer("127.0.0.1")
            assert report_within(sink, slow(5)) == b"Tower @ 100"
        finally:
            ep.stop()
            dns.answer(OSError("stopping"))
    assert "loggers" not in dns.threads, dns.threads
    dropped = [r for r in caplog.records if "dropped until the name is found" in r.message]
    assert len(dropped) == 1 and dropped[0].levelno == logging.WARNING


def test_a_report_name_is_found_by_the_systems_own_lookup() -> None:
    """``localhost``, as /etc/hosts names it: the reports reach it."""
    with reports_sink() as sink:
        ep = LoggerEndpoints()
        ep.add_n1mm(
            Recording("tower"), "Tower", port=0, report_to=("localhost", sink_address(sink)[1])
        )  # type: ignore[arg-type]
        ep.start()
        try:
            assert report_within(sink, slow(5)) == b"Tower @ 100"
        finally:
            ep.stop()


def test_a_lookup_that_fails_later_keeps_the_address_found_before(
    monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    """The name server down after the name was found: the reports still go there, the failure
    said once."""
    monkeypatch.setattr(resolver, "REFRESH_S", 0.01)  # (looked up again at once: no deadline)
    monkeypatch.setattr(resolver, "RETRY_S", 0.01)  # (likewise)
    monkeypatch.setattr("bridge.interfaces.loggers.server.REPORT_IDLE_S", 0.05)  # (likewise)
    answers: list[str | Exception] = ["127.0.0.1"]
    lookups = 0

    def lookup(host: str, port: int) -> str:
        nonlocal lookups
        lookups += 1
        answer = answers[0] if lookups == 1 else OSError("the name server is down")
        if isinstance(answer, Exception):
            raise answer
        return answer

    with reports_sink() as sink:
        ep, _rot = endpoints(lookup, sink_address(sink)[1])
        ep.start()
        try:
            assert report_within(sink, slow(5)) == b"Tower @ 100"
            wait_until(lambda: lookups >= 5, slow(5), "lookups failing")
            while report_within(sink, 0) is not None:  # (what came before: drained)
                pass
            assert report_within(sink, slow(5)) == b"Tower @ 100"  # sent there still
        finally:
            ep.stop()
    failed = [r for r in caplog.records if "could not be looked up" in r.message]
    assert len(failed) == 1 and "they still go to 127.0.0.1" in failed[0].message


def test_an_address_in_digits_is_never_looked_up() -> None:
    dns = NameServer()
    with reports_sink() as sink:
        ep = LoggerEndpoints(lookup=dns.lookup)
        ep.add_n1mm(Recording("tower"), "Tower", port=0, report_to=sink_address(sink))  # type: ignore[arg-type]
        ep.start()
        try:
            assert report_within(sink, slow(5)) == b"Tower @ 100"
        finally:
            ep.stop()
            dns.answer(OSError("stopping"))
    assert dns.asked() == 0
