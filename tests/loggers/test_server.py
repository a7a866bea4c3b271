"""LoggerEndpoints on real UDP sockets with stand-in rotators that record what they are asked
(the wiring through the App, mosquitto and emulators is tests/integration/test_logger_udp.py)."""

from __future__ import annotations

import contextlib
import errno
import logging
import math
import os
import select
import socket
import threading
import time
from collections.abc import Iterator
from dataclasses import replace
from typing import Any

import pytest

from bridge.core.errors import RefusalCode, Refused
from bridge.core.model import RotatorStatus, Source, Stop, Target, Toward
from bridge.interfaces.loggers import LoggerEndpoints, server
from bridge.interfaces.loggers.commands import STALE, N1mmEndpoint, N1mmRotor
from bridge.interfaces.loggers.limiter import REPLY_BURST
from bridge.interfaces.loggers.server import PER_WAKEUP, RATE_DATAGRAMS_S
from bridge.pointing import Pointing
from bridge.protocols import REGISTRY
from tests.support.clock import FakeClock
from tests.support.udp_logger import (
    N1MM_STOPS,
    PstClient,
    n1mm_turn,
    pst,
    reserve_pst_ports,
    tag,
    udp_socket,
)
from tests.support.waiting import slow, wait_until


class Recording:
    def __init__(self, rid: str, model: str = "rotorez") -> None:
        self.id, self.spec = rid, REGISTRY[model]
        self.calls: list[Any] = []
        self.peers: list[str | None] = []  # the address each command came from
        self._lock = threading.Lock()
        self.last_halt_s = -math.inf  # when it last carried out a STOP (commands.py rule 8)
        self.halts = 0  # how many (runtime/rotator.py ``halts``)

    @property
    def status(self) -> RotatorStatus:
        """As the bridge's own rotator reads one at 10 (session/status.py: the raw bearing
        beside the bearing, no offset)."""
        return RotatorStatus(self.id, available=True, bearing_deg=10.0, raw_bearing_deg=10.0)

    @property
    def pointing(self) -> Pointing:
        """Its judge's terms, the model's (commands.py ``heading`` asks which way it turns)."""
        return Pointing.of(self.spec)

    def halts_for(self, source: Source) -> int:
        return self.halts

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
        with self._lock:
            if isinstance(command, Stop):  # carried out now (runtime/rotator.py)
                self.last_halt_s = time.monotonic()
                self.halts += 1
            elif since is not None and since != self.halts:  # (mailbox.py rule 10)
                self.calls.append(("refused", "overtaken"))
                raise Refused(RefusalCode.STALE, "overtaken")
            self.peers.append(command.origin.peer if command.origin is not None else None)
            if isinstance(command, Toward):
                self.calls.append(("toward", command.latitude_deg, command.longitude_deg))
                return
            self.calls.append(replace(command, origin=None))  # who sent it: in ``peers``

    def report_refusal(self, message: str, command: str | None, **_kw: Any) -> None:
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


def test_a_stop_with_a_byte_that_is_not_ascii_still_stops_and_a_turn_with_one_moves_nothing() -> (
    None
):
    """A stop is never refused (datagrams.py rule 1): a PST STOP from a logger that put a degree
    sign beside it, and an N1MM stop to every rotor whose band field held a Latin-1 byte, were
    dropped whole as not ASCII, and the rotors turned on. A turn with such a byte still moves
    nothing."""
    tower, yagi = Recording("tower"), Recording("yagi")
    ep = LoggerEndpoints()
    ep.add_pst(tower, port=0)  # type: ignore[arg-type]
    ep.add_n1mm(yagi, "Yagi", port=0)  # type: ignore[arg-type]
    ep.start()
    try:
        pst_port = ep.address(ep.pst[0])[1]
        n1mm_port = ep.address(next(iter(ep.n1mm.values())))[1]
        send(pst_port, "<PST><AZIMUTH>85°</AZIMUTH></PST>".encode("latin-1"))
        send(
            n1mm_port,
            "<N1MMRotor><rotor>Yagi</rotor><goazi>90</goazi><freqband>14°</freqband></N1MMRotor>".encode(
                "latin-1"
            ),
        )
        send(pst_port, "<PST><STOP>1</STOP> °</PST>".encode())
        send(
            n1mm_port,
            "<N1MMRotor><stop><rotor>*</rotor><freqband>14°</freqband></stop></N1MMRotor>".encode(
                "latin-1"
            ),
        )
        wait_until(lambda: tower.calls and yagi.calls, 5, "both stopped")
        assert tower.calls == [Stop(Source.PST)] and yagi.calls == [Stop(Source.N1MM)]
    finally:
        ep.stop()


def test_a_stop_padded_past_2_kib_still_stops_and_a_turn_so_padded_moves_nothing() -> None:
    """A stop is never refused (datagrams.py rule 7): a PST STOP and an N1MM stop padded past
    MAX_DATAGRAM (the socket gives the first 2 KiB and a byte, the rest is lost) were dropped
    whole as over-long, and the rotors turned on. A turn so padded still moves nothing."""
    tower, yagi = Recording("tower"), Recording("yagi")
    ep = LoggerEndpoints()
    ep.add_pst(tower, port=0)  # type: ignore[arg-type]
    ep.add_n1mm(yagi, "Yagi", port=0)  # type: ignore[arg-type]
    ep.start()
    pad = b" " * 3000
    try:
        pst_port = ep.address(ep.pst[0])[1]
        n1mm_port = ep.address(next(iter(ep.n1mm.values())))[1]
        send(pst_port, b"<PST><AZIMUTH>85</AZIMUTH>" + pad + b"</PST>")
        send(n1mm_port, b"<N1MMRotor><rotor>Yagi</rotor><goazi>90</goazi>" + pad + b"</N1MMRotor>")
        send(pst_port, b"<PST><STOP>1</STOP>" + pad + b"</PST>")
        send(n1mm_port, b"<N1MMRotor><stop><rotor>Yagi</rotor></stop>" + pad + b"</N1MMRotor>")
        wait_until(lambda: tower.calls and yagi.calls, 5, "both stopped")
        assert tower.calls == [Stop(Source.PST)] and yagi.calls == [Stop(Source.N1MM)]
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


def test_a_pst_locator_that_is_none_is_refused_naming_it_once() -> None:
    """An attack pass: R/error said "pst: locator 'ZZ99ZZ': locator 'ZZ99ZZ': first character
    must be ..." (the locator named by the refusal and again by the reason)."""
    tower = Recording("tower")
    ep = LoggerEndpoints()
    ep.add_pst(tower, port=0)  # type: ignore[arg-type]
    ep.start()
    try:
        send(ep.address(ep.pst[0])[1], b"<PST><QRA>ZZ99ZZ</QRA></PST>")
        wait_until(lambda: tower.calls, 5, "refused")
        assert tower.calls == [
            ("refused", "pst: locator 'ZZ99ZZ': first character must be a letter A..R, got 'Z'")
        ]
    finally:
        ep.stop()


# -- hardening: each test below failed on the loggers before they served sockets fairly, ----------
# answered once per query kind, refused ambiguous datagrams and survived their own faults


class Faulty(Recording):
    """A rotator whose submit fails on one azimuth (a bug in a feature behind it)."""

    def __init__(self, rid: str, fails_at_deg: float) -> None:
        super().__init__(rid)
        self.fails_at_deg = fails_at_deg

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
        if isinstance(command, Target) and command.az_deg == self.fails_at_deg:
            raise RuntimeError("a bug behind the rotator")
        super().submit(command, described, since=since)


class AzEl(Recording):
    """An az/el rotator at 10 deg, 20 deg: it answers ``EL?`` too."""

    def __init__(self, rid: str) -> None:
        super().__init__(rid, "md01")

    @property
    def status(self) -> RotatorStatus:
        return RotatorStatus(
            self.id, available=True, bearing_deg=10.0, raw_bearing_deg=10.0, elevation_deg=20.0
        )


@contextlib.contextmanager
def reports_sink() -> Iterator[socket.socket]:
    """Where the N1MM position reports of a test go (not 13010: it may be somebody's)."""
    with udp_socket() as sink:
        yield sink


def sink_address(sink: socket.socket) -> tuple[str, int]:
    host, port = sink.getsockname()[:2]
    return host, port


def test_a_datagram_asking_az_hundreds_of_times_gets_one_reply() -> None:
    """A spoofed 2 KiB datagram of 679 ``AZ?`` made 679 replies to its victim."""
    port, replies = reserve_pst_ports()
    rot = AzEl("tower")
    ep = LoggerEndpoints()
    ep.add_pst(rot, port)  # type: ignore[arg-type]
    ep.start()
    try:
        with PstClient(port, replies=replies) as client:
            flood = pst(*["AZ?"] * 679)
            assert len(flood) <= 2048
            client.send(flood)
            client.send(pst("EL?"))  # answered after everything the flood brought
            got = []
            while not (got and got[-1].startswith(b"EL:")):
                reply = client.reply(slow(5))
                assert reply is not None, f"no EL reply after {got[:3]}..."
                got.append(reply)
            assert got == [b"AZ:10\r", b"EL:20\r"]
    finally:
        ep.stop()


def test_replies_to_one_address_are_rate_limited() -> None:
    """Many one-query datagrams from one address: a burst of replies, the rest dropped and
    counted (the clock stands still, nothing refills)."""
    port, replies = reserve_pst_ports()
    ep = LoggerEndpoints(clock=FakeClock())
    ep.add_pst(Recording("tower"), port)  # type: ignore[arg-type]
    ep.start()
    try:
        with PstClient(port, replies=replies) as client:
            for _ in range(30):
                client.send(pst("AZ?"))
            wait_until(lambda: ep.counts["pst"].queries == 30, 5, "30 queries read")
            got = client.drain()
            assert got == [b"AZ:10\r"] * REPLY_BURST
            assert ep.counts["pst"].replies_dropped == 30 - REPLY_BURST
    finally:
        ep.stop()


def test_a_pst_flood_delays_an_n1mm_stop_by_a_few_datagrams_at_most() -> None:
    """One socket was drained to empty before the next: a PST flood kept an N1MM STOP waiting
    behind every datagram of it. The flood is queued before the loggers' thread starts, the
    stop after it; each flood datagram is a numbered target, so the rotator's commands show
    how many of them went before the stop (those read after it are refused: they were sent
    before it, commands.py rule 8)."""
    flood = 150
    rot = Recording("tower")
    ep = LoggerEndpoints()
    ep.add_pst(rot, port=0)  # type: ignore[arg-type]
    with reports_sink() as sink:
        ep.add_n1mm(rot, "Tower", port=0, report_to=sink_address(sink))  # type: ignore[arg-type]
        ep.listen()  # the ports are ours, nobody reads them yet
        try:
            pst_port = ep.address(ep.pst[0])[1]
            n1mm_port = ep.address(next(iter(ep.n1mm.values())))[1]
            with udp_socket() as s:
                for i in range(flood):
                    s.sendto(pst(tag("AZIMUTH", i)), ("127.0.0.1", pst_port))
                s.sendto(N1MM_STOPS["name in stop"]("Tower"), ("127.0.0.1", n1mm_port))
            ep.start()
            wait_until(lambda: len(rot.calls) == flood + 1, 5, "the flood and the stop handled")
            stop_at = rot.calls.index(Stop(Source.N1MM))
            assert stop_at <= PER_WAKEUP, f"the stop came after {stop_at} flood datagrams"
            targets = [c.az_deg for c in rot.calls if isinstance(c, Target)]
            assert targets == [float(i) for i in range(stop_at)]  # in order, none lost
            # the rest reached the system before the stop: none turns the rotor after it
            # (commands.py rule 8)
            assert rot.calls[stop_at + 1 :] == [("refused", f"pst: {STALE}")] * (flood - stop_at)
        finally:
            ep.stop()


AMBIGUOUS_PST = [
    pst(tag("AZIMUTH", 10), tag("AZIMUTH", 200)),  # two azimuths
    pst(tag("AZIMUTH", 10), tag("QRA", "JO62")),  # an azimuth and a locator
    pst(tag("QRA", "JO62"), tag("QRA", "KN34")),
]
AMBIGUOUS_N1MM = [
    b"<N1MMRotor><rotor>Tower</rotor><rotor>Yagi</rotor><goazi>90</goazi></N1MMRotor>",
    b"<N1MMRotor><rotor>Tower</rotor><goazi>10</goazi><goazi>200</goazi></N1MMRotor>",
]


def test_ambiguous_datagrams_move_nothing() -> None:
    tower, yagi = Recording("tower"), Recording("yagi")
    ep = LoggerEndpoints()
    ep.add_pst(tower, port=0)  # type: ignore[arg-type]
    with reports_sink() as sink:
        for rot, name in ((tower, "Tower"), (yagi, "Yagi")):
            ep.add_n1mm(rot, name, port=0, report_to=sink_address(sink))  # type: ignore[arg-type]
        ep.start()
        try:
            pst_port = ep.address(ep.pst[0])[1]
            n1mm_port = ep.address(next(iter(ep.n1mm.values())))[1]
            for datagram in AMBIGUOUS_PST:
                send(pst_port, datagram)
            for datagram in AMBIGUOUS_N1MM:
                send(n1mm_port, datagram)
            send(pst_port, pst(tag("AZIMUTH", 42)))  # after the others on each socket
            send(n1mm_port, b"<N1MMRotor><rotor>Yagi</rotor><goazi>43</goazi></N1MMRotor>")
            wait_until(lambda: tower.calls and yagi.calls, 5, "the good ones")
            assert tower.calls == [Target(42.0, None, Source.PST)]
            assert yagi.calls == [Target(43.0, None, Source.N1MM)]
            assert ep.counts["pst"].malformed == len(AMBIGUOUS_PST)
            assert ep.counts["n1mm"].malformed == len(AMBIGUOUS_N1MM)
        finally:
            ep.stop()


def test_an_n1mm_stop_naming_two_rotors_stops_both() -> None:
    """A stop is never refused: one that names two rotors stops both."""
    tower, yagi, other = Recording("tower"), Recording("yagi"), Recording("other")
    ep = LoggerEndpoints()
    with reports_sink() as sink:
        for rot, name in ((tower, "Tower"), (yagi, "Yagi"), (other, "Other")):
            ep.add_n1mm(rot, name, port=0, report_to=sink_address(sink))  # type: ignore[arg-type]
        ep.start()
        try:
            port = ep.address(next(iter(ep.n1mm.values())))[1]
            send(port, b"<N1MMRotor><rotor>Tower</rotor><stop>Yagi</stop></N1MMRotor>")
            send(port, b"<N1MMRotor><rotor>Other</rotor><goazi>43</goazi></N1MMRotor>")
            wait_until(lambda: other.calls, 5, "the turn after the stop")
            assert tower.calls == [Stop(Source.N1MM)] and yagi.calls == [Stop(Source.N1MM)]
            assert other.calls == [Target(43.0, None, Source.N1MM)]
        finally:
            ep.stop()


def test_n1mm_reports_leave_from_the_configured_address() -> None:
    """The report socket was never bound: the system gave it 0.0.0.0 and a port of its choice,
    open on every interface. Bound to 127.0.0.2, the reports must come from there."""
    with reports_sink() as sink:
        ep = LoggerEndpoints()
        ep.add_n1mm(Recording("tower"), "Tower", 0, "127.0.0.2", sink_address(sink))  # type: ignore[arg-type]
        ep.start()
        try:
            ready, _, _ = select.select([sink], [], [], slow(5))
            assert ready, "no position report"
            data, peer = sink.recvfrom(4096)
            assert data == b"Tower @ 100"
            assert peer[0] == "127.0.0.2"
        finally:
            ep.stop()


def test_a_fault_behind_one_datagram_is_logged_and_the_next_is_served(
    caplog: pytest.LogCaptureFixture,
) -> None:
    rot = Faulty("tower", fails_at_deg=13.0)
    ep = LoggerEndpoints()
    ep.add_pst(rot, port=0)  # type: ignore[arg-type]
    ep.start()
    try:
        port = ep.address(ep.pst[0])[1]
        send(port, pst(tag("AZIMUTH", 13)))
        send(port, pst(tag("AZIMUTH", 14)))
        wait_until(lambda: rot.calls, 5, "the datagram after the fault")
        assert rot.calls == [Target(14.0, None, Source.PST)]
        errors = [r for r in caplog.records if r.levelno >= logging.ERROR]
        assert len(errors) == 1 and "a bug behind the rotator" in caplog.text
    finally:
        ep.stop()


def _thread_cpu_s(name: str) -> float:
    thread = next(t for t in threading.enumerate() if t.name == name)
    with open(f"/proc/self/task/{thread.native_id}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def test_a_socket_that_went_bad_is_dropped_and_reported_once(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """The PST socket's descriptor is replaced under the loggers (it now names /dev/null, so
    reading it fails with ENOTSOCK) while its file stays alive with a datagram waiting: the
    selector keeps saying it is readable. The thread read it again and again, at 100 % of a
    core, and never served the N1MM port beside it."""
    rot = Recording("tower")
    ep = LoggerEndpoints()
    ep.add_pst(rot, port=0)  # type: ignore[arg-type]
    with reports_sink() as sink:
        ep.add_n1mm(rot, "Tower", port=0, report_to=sink_address(sink))  # type: ignore[arg-type]
        ep.start()
        pst_port = ep.address(ep.pst[0])[1]
        n1mm_port = ep.address(next(iter(ep.n1mm.values())))[1]
        pst_fd = next(s.fileno() for s, e in ep._sockets.items() if e is ep.pst[0])
        keeper = os.dup(pst_fd)  # the socket itself lives on
        devnull = os.open(os.devnull, os.O_RDONLY)
        try:
            os.dup2(devnull, pst_fd)
            send(pst_port, pst(tag("AZIMUTH", 1)))  # readable from now on
            send(n1mm_port, N1MM_STOPS["name in stop"]("Tower"))
            wait_until(lambda: rot.calls, 5, "the N1MM stop")
            assert rot.calls == [Stop(Source.N1MM)]
            before = _thread_cpu_s("loggers")
            time.sleep(0.5)  # a measurement window, not a synchronisation
            assert _thread_cpu_s("loggers") - before < 0.1, "the loggers' thread spins"
            said = [r.getMessage() for r in caplog.records if r.levelno >= logging.WARNING]
            assert len(said) == 1 and f":{pst_port} (pst) stopped listening" in said[0]
        finally:
            ep.stop()
            os.close(keeper)
            os.close(devnull)


def _spend_the_budget(ep: LoggerEndpoints, port: int, s: socket.socket) -> None:
    """Junk from ``s`` until its sender's budget is nearly spent (the clock stands still), in
    batches the thread reads before the next goes out (no buffer overflows)."""
    junk, sent = pst(tag("AZIMUTH", "x")), 0
    while sent < int(RATE_DATAGRAMS_S * 0.9):
        for _ in range(45):
            s.sendto(junk, ("127.0.0.1", port))
        sent += 45
        wait_until(lambda n=sent: ep.counts["pst"].malformed >= n, 10, "junk parsed")


def test_a_stop_behind_a_junk_flood_over_budget_is_carried_out() -> None:
    """The thread slept while its budget was spent: the junk filled the system's buffer and a
    PST STOP sent behind it was read seconds later or never (the rotor kept turning). In
    virtual time (the clock stands still, the budget never refills): a sender spends its
    budget, queues more junk and then the STOP; the rotator sees the Stop, the junk over the
    budget is dropped unparsed."""
    clock = FakeClock()
    rot = Recording("tower")
    ep = LoggerEndpoints(clock=clock)
    ep.add_pst(rot, port=0)  # type: ignore[arg-type]
    ep.start()
    try:
        port = ep.address(ep.pst[0])[1]
        with udp_socket() as s:
            _spend_the_budget(ep, port, s)
            for _ in range(100):  # over the budget now
                s.sendto(pst(tag("AZIMUTH", "x")), ("127.0.0.1", port))
            s.sendto(b"<PST><STOP>1</STOP></PST>", ("127.0.0.1", port))
            wait_until(lambda: rot.calls, slow(10), "the STOP carried out")
        assert rot.calls == [Stop(Source.PST)]
        assert ep.over_budget > 0
    finally:
        ep.stop()


def test_a_flood_on_the_n1mm_port_holds_up_no_pst_stop() -> None:
    """A flood on the N1MM port (often bound to the LAN) once put the whole thread to sleep and
    a PST stop for another rotator waited for it (or was lost once the system's buffer
    filled); in virtual time (the clock stands still) the flood goes over its budget and the
    PST stop is carried out all the same (rule 8)."""
    clock = FakeClock()
    tower, yagi = Recording("tower"), Recording("yagi")
    ep = LoggerEndpoints(clock=clock)
    ep.add_pst(tower, port=0)  # type: ignore[arg-type]
    ep.add_n1mm(yagi, "Yagi", port=0, report_to=("127.0.0.1", 9))  # type: ignore[arg-type]
    ep.start()
    try:
        pst_port = ep.address(ep.pst[0])[1]
        n1mm_port = ep.address(next(iter(ep.n1mm.values())))[1]
        aim = b"<N1MMRotor><rotor>Yagi</rotor><goazi>90</goazi></N1MMRotor>"
        with udp_socket() as s:
            for _ in range(int(RATE_DATAGRAMS_S) + 100):
                s.sendto(aim, ("127.0.0.1", n1mm_port))
        wait_until(lambda: ep.over_budget > 0, 10, "the N1MM flood over its budget")
        send(pst_port, pst(tag("STOP", 1)))
        wait_until(lambda: Stop(Source.PST) in tower.calls, 10, "the PST stop carried out")
    finally:
        ep.stop()


def test_a_flood_over_its_senders_budget_is_dropped_and_said_once_others_are_served(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """Rule 8, in virtual time (the clock stands still): a sender past its budget has its
    datagrams dropped unparsed, said once; another sender's target is carried out (the budget
    is per sender); an N1MM stop in any of its forms from the flooding sender is carried out;
    when time passes, the flooding sender is served again."""
    clock = FakeClock()
    rot = Recording("tower")
    ep = LoggerEndpoints(clock=clock)
    ep.add_pst(rot, port=0)  # type: ignore[arg-type]
    with reports_sink() as sink:
        ep.add_n1mm(rot, "Tower", port=0, report_to=sink_address(sink))  # type: ignore[arg-type]
        ep.start()
        try:
            port = ep.address(ep.pst[0])[1]
            n1mm_port = ep.address(next(iter(ep.n1mm.values())))[1]
            with udp_socket() as s, udp_socket() as other:
                _spend_the_budget(ep, port, s)
                for _ in range(50):
                    s.sendto(pst(tag("AZIMUTH", 7)), ("127.0.0.1", port))
                wait_until(lambda: ep.over_budget > 0, 10, "the flood over its budget")
                other.sendto(pst(tag("AZIMUTH", 42)), ("127.0.0.1", port))
                wait_until(lambda: Target(42.0, None, Source.PST) in rot.calls, 10, "42")
                for form in N1MM_STOPS.values():
                    s.sendto(form("Tower"), ("127.0.0.1", n1mm_port))
                stops = len(N1MM_STOPS)
                wait_until(lambda: rot.calls.count(Stop(Source.N1MM)) == stops, 10, "stops")
                read = [c for c in rot.calls if c == Target(7.0, None, Source.PST)]
                assert len(read) < 50  # the rest dropped unparsed
                said = [r for r in caplog.records if "over the budget" in r.getMessage()]
                assert len(said) == 1 and said[0].levelno == logging.WARNING
                clock.t += 10.0
                s.sendto(pst(tag("AZIMUTH", 8)), ("127.0.0.1", port))
                wait_until(lambda: Target(8.0, None, Source.PST) in rot.calls, 10, "read on")
        finally:
            ep.stop()


class Standing(Recording):
    """A rotator that stands at ``bearing_deg``."""

    def __init__(self, rid: str, bearing_deg: float) -> None:
        super().__init__(rid)
        self.bearing_deg = bearing_deg

    @property
    def status(self) -> RotatorStatus:
        return RotatorStatus(
            self.id, available=True, bearing_deg=self.bearing_deg, raw_bearing_deg=self.bearing_deg
        )


def test_a_name_two_rotators_share_by_band_reports_the_heading_of_the_one_on_the_band(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """One antenna per band, both under N1MM's one Rotor Description: each rotator reported its
    own heading under that name, and N1MM's rotor window jumped between the 20 m yagi's 100
    and the 40 m antenna's 250. The name's heading is the antenna's the last turn chose by
    band, and none before a turn has chosen one."""
    monkeypatch.setattr(server, "REPORT_IDLE_S", 0.05)  # the idle reports, many a second
    high, low = Standing("high", 100.0), Standing("low", 250.0)
    with reports_sink() as sink:
        ep = LoggerEndpoints()
        for rot, bands in ((high, ("20m",)), (low, ("40m",))):
            ep.add_n1mm(rot, "Tower", 0, "127.0.0.1", sink_address(sink), bands)  # type: ignore[arg-type]
        ep.start()
        try:
            port = ep.address(next(iter(ep.n1mm.values())))[1]

            def reports(n: int) -> list[bytes]:
                got = []
                while len(got) < n:
                    ready, _, _ = select.select([sink], [], [], slow(5))
                    assert ready, f"{len(got)} position report(s) of {n}"
                    got.append(sink.recv(4096))
                return got

            send(port, n1mm_turn("Tower", 240, freqband="7"))
            assert reports(6) == [b"Tower @ 2500"] * 6  # none before, the 40 m antenna's after
            send(port, n1mm_turn("Tower", 90, freqband="14"))
            wait_until(lambda: high.calls, 5, "the turn on 20 m")
            later = reports(30)
            at = later.index(b"Tower @ 1000")  # reported at once when the band changed
            assert later[at:] == [b"Tower @ 1000"] * (30 - at)
        finally:
            ep.stop()


@contextlib.contextmanager
def bound_not_read() -> Iterator[tuple[Recording, LoggerEndpoints, int, int]]:
    """A rotator on a PST and an N1MM port, bound but not read until ``start``: datagrams
    sent now wait in the system's buffers, as behind a thread that is late (rule 8's tests).
    Yields the rotator, the endpoints, the PST port and the N1MM port."""
    tower = Recording("tower")
    ep = LoggerEndpoints()
    ep.add_pst(tower, 0)  # type: ignore[arg-type]
    ep.add_n1mm(tower, "Tower", port=0)  # type: ignore[arg-type]
    ep.listen()
    try:
        yield tower, ep, ep.address(ep.pst[0])[1], ep.address(next(iter(ep.n1mm.values())))[1]
    finally:
        ep.stop()


def test_a_turn_that_reached_the_system_before_the_rotators_last_stop_is_not_carried_out() -> None:
    """commands.py rule 8: the thread was behind (here: not reading yet), and a logger's turn
    and park, in the system's buffer before the rotator carried out a STOP from another
    interface, were read after it and turned the rotor (an attack pass). They are refused as
    stale; a stop read with them is carried out, and a turn sent after the stop is too."""
    with bound_not_read() as (tower, ep, pst_port, n1mm_port):
        send(pst_port, pst(tag("AZIMUTH", 300)))
        send(pst_port, pst(tag("PARK", 1)))
        send(n1mm_port, n1mm_turn("Tower", 120))
        send(pst_port, pst(tag("STOP", 1)))
        tower.last_halt_s = time.monotonic()  # a STOP another interface carried out
        ep.start()
        wait_until(lambda: len(tower.calls) >= 4, 5, "the four datagrams taken")
        send(pst_port, pst(tag("AZIMUTH", 60)))
        wait_until(lambda: len(tower.calls) >= 5, 5, "the turn after the stop taken")
        assert sorted(tower.calls[:4], key=str) == sorted(
            [
                ("refused", "pst: sent before a STOP or lock ON that came first: not carried out"),
                ("refused", "pst: sent before a STOP or lock ON that came first: not carried out"),
                ("refused", "n1mm: sent before a STOP or lock ON that came first: not carried out"),
                Stop(Source.PST),
            ],
            key=str,
        )
        assert tower.calls[4] == Target(60.0, None, Source.PST)


def test_a_loggers_own_stop_read_late_refuses_only_what_reached_the_system_before_it() -> None:
    """commands.py rule 8 for a stop the loggers' thread reads late itself: the stop's time is
    when it reached the system. A logger's turn sent after its own STOP, both read late, is
    carried out (the stop, read later than the turn reached the system, is no later word), and
    one on the N1MM port that reached the system before the PST stop is refused."""
    with bound_not_read() as (tower, ep, pst_port, n1mm_port):
        send(n1mm_port, n1mm_turn("Tower", 120))
        send(pst_port, pst(tag("STOP", 1)))
        send(pst_port, pst(tag("AZIMUTH", 60)))
        ep.start()
        wait_until(lambda: len(tower.calls) >= 3, 5, "the three datagrams taken")
        calls = tower.calls
        assert calls.index(Stop(Source.PST)) < calls.index(Target(60.0, None, Source.PST))
        assert ("refused", f"n1mm: {STALE}") in calls or calls.index(
            Target(120.0, None, Source.N1MM)
        ) < calls.index(Stop(Source.PST)), calls


class SwitchedAway:
    """server.py's clocks on a loaded host: right after the ``after``th reading of either
    clock, another thread holds the interpreter for GAP_S (the very thread that carries out a
    STOP may be the one that takes it), and both clocks have moved on by then."""

    GAP_S = 30.0

    def __init__(self, after: int = 1) -> None:
        self._shift = 0.0
        self._read = 0
        self._after = after

    def _reading(self, real: float) -> float:
        value = real + self._shift
        self._read += 1
        if self._read == self._after:
            self._shift = self.GAP_S
        return value

    def time(self) -> float:
        return self._reading(time.time())

    def monotonic(self) -> float:
        return self._reading(time.monotonic())


def test_a_turn_read_across_a_thread_switch_is_dated_no_later_than_it_reached_the_system(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """commands.py rule 8, server.py rule 9: the arrival is the wall clock's stamp made
    monotonic by its age, and the loggers' thread may lose the interpreter between its two
    readings of the clocks. With the monotonic clock read only after the wall clock's, a turn
    in the system's buffer before a STOP from another interface was dated as late as the
    switch lasted, after the STOP, and went to the judge (the rotor turned after the STOP)."""
    tower = Recording("tower")
    ep = LoggerEndpoints()
    ep.add_pst(tower, 0)  # type: ignore[arg-type]
    ep.listen()  # bound, not read yet
    monkeypatch.setattr(server, "time", SwitchedAway())
    try:
        port = ep.address(ep.pst[0])[1]
        send(port, pst(tag("AZIMUTH", 300)))
        tower.last_halt_s = time.monotonic()  # a STOP another interface carried out
        ep.start()
        wait_until(lambda: tower.calls, 5, "the turn taken")
        assert tower.calls == [("refused", f"pst: {STALE}")]
    finally:
        ep.stop()


@contextlib.contextmanager
def _stamped_port() -> Iterator[tuple[socket.socket, socket.socket]]:
    """A port asking for the system's stamps, bound while ``_stamping_on`` holds them live
    (rule 9), and a socket to send to it from."""
    holder = server._stamping_on()
    assert holder is not None
    with (
        holder,
        socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as listener,
        socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sender,
    ):
        listener.bind(("127.0.0.1", 0))
        listener.setsockopt(socket.SOL_SOCKET, server._STAMPS, 1)
        yield listener, sender


@pytest.mark.parametrize("switch_after", [1, 2])
def test_a_datagrams_arrival_is_bounded_on_both_sides_whatever_a_thread_switch_does(
    monkeypatch: pytest.MonkeyPatch, switch_after: int
) -> None:
    """server.py rule 9: a move is judged by the earliest its datagram can have reached the
    system, a stop by the latest (commands.py ``Halted``: what came before it is refused).
    A thread switch between the clocks' readings widens the bounds, never moves both past the
    truth: a stop dated early would let a turn sent just before it through."""
    assert server._STAMPS, "the suite runs on Linux, whose sockets stamp datagrams (rule 9)"
    with _stamped_port() as (listener, sender):
        before = time.monotonic()
        sender.sendto(b"<PST><STOP>1</STOP></PST>", listener.getsockname())
        after = time.monotonic()
        assert select.select([listener], [], [], slow(5))[0]
        monkeypatch.setattr(server, "time", SwitchedAway(after=switch_after))
        data, _peer, arrived = server._received(listener)
    assert data == b"<PST><STOP>1</STOP></PST>"
    assert arrived is not None
    tick = 1e-3  # (the wall clock's and the monotonic clock's own steps)
    assert arrived.earliest <= after + tick and arrived.latest >= before - tick, (
        before,
        arrived,
        after,
    )


def test_the_stamps_are_live_before_a_port_is_bound_and_said_when_they_never_come(
    monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    """Rule 9: Linux turns its stamping on for the first socket that asks a moment later (a
    worker thread's), and stamps a datagram that comes meanwhile when it is read; a turn sent
    before another interface's STOP, read after it, was dated after it (a flaky CI run of the
    test below). ``_stamping_on`` holds them on, live, before listen() binds a port: a
    datagram sent to a port it bound then comes back stamped before it is read. One that never
    sees them live (here every stamp looks later than its read) says so and lets the ports
    listen all the same."""
    with _stamped_port() as (listener, sender):
        sender.sendto(b"<PST><AZIMUTH>300</AZIMUTH></PST>", listener.getsockname())
        assert select.select([listener], [], [], slow(5))[0]
        looked = time.monotonic()
        _data, _peer, arrived = server._received(listener)
    assert arrived is not None and arrived.earliest <= looked

    class Behind:  # a wall clock every stamp is ahead of
        monotonic = staticmethod(time.monotonic)
        sleep = staticmethod(time.sleep)

        @staticmethod
        def time() -> float:
            return 0.0

    monkeypatch.setattr(server, "time", Behind)
    with caplog.at_level(logging.WARNING, logger=server.__name__):
        assert server._stamping_on(wait_s=0.05) is None
    assert "did not come on" in caplog.text


class HaltedMeanwhile(Recording):
    """A rotator on which another interface's STOP is carried out while the loggers' own STOP
    goes to the judge (after the loggers looked at the last halt, before this one is put)."""

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
        if isinstance(command, Stop) and command.source is Source.PST and not self.halts:
            super().submit(Stop(Source.MQTT))  # the operator's, from the stop lane
        super().submit(command, described, since=since)


def test_a_stop_from_another_interface_carried_out_beside_a_loggers_stop_is_not_lost() -> None:
    """commands.py rule 8 (``Halted``): a logger's STOP read late counts from when it reached
    the system, unless another interface halted the rotator after that. The operator's STOP,
    carried out while the logger's went to the judge, was lost: the rotator's last halt was
    the logger's, counted from its arrival, and a logger's turn that reached the system before
    the operator's STOP, read after both, turned the rotor after it."""
    tower = HaltedMeanwhile("tower")
    ep = LoggerEndpoints()
    ep.add_pst(tower, 0)  # type: ignore[arg-type]
    ep.listen()  # bound, not read yet
    try:
        port = ep.address(ep.pst[0])[1]
        send(port, pst(tag("STOP", 1)))
        send(port, pst(tag("AZIMUTH", 300)))  # before the operator's STOP, carried out below
        ep.start()
        wait_until(lambda: len(tower.calls) >= 3, 5, "the two datagrams taken")
        assert tower.calls == [
            Stop(Source.MQTT),
            Stop(Source.PST),
            ("refused", f"pst: {STALE}"),
        ], tower.calls
    finally:
        ep.stop()


@pytest.mark.parametrize(
    "option", [socket.SO_REUSEADDR, socket.SO_REUSEPORT], ids=["SO_REUSEADDR", "SO_REUSEPORT"]
)
def test_no_other_program_can_bind_the_n1mm_port_beside_the_bridge(option: int) -> None:
    """server.py rule 10 (an attack pass): the N1MM port was bound with SO_REUSEADDR, as N1MM
    advises; another user bound it the same way and, on Linux, every datagram sent to it went
    to that socket, the operator's STOPs among them (5 of 5). It is the bridge's alone now: the
    other bind is refused, and the STOP still stops."""
    tower = Recording("tower")
    ep = LoggerEndpoints()
    ep.add_n1mm(tower, "Tower", port=0)  # type: ignore[arg-type]
    ep.start()
    try:
        port = ep.address(next(iter(ep.n1mm.values())))[1]
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as thief:
            thief.setsockopt(socket.SOL_SOCKET, option, 1)
            with pytest.raises(OSError) as refused:
                thief.bind(("127.0.0.1", port))
            assert refused.value.errno == errno.EADDRINUSE
        send(port, b"<N1MMRotor><stop><rotor>Tower</rotor></stop></N1MMRotor>")
        wait_until(lambda: tower.calls, 5, "stopped")
        assert tower.calls == [Stop(Source.N1MM)]
    finally:
        ep.stop()


@pytest.mark.parametrize(
    "junk",
    [
        b"<N1MMRotor>" + b"<stop><rotor>x</rotor></stop>" * 60 + b"</N1MMRotor>",
        b"<N1MMRotor><stop>nobody</stop>" + b"*" * 1700 + b"</N1MMRotor>",  # (a cold review)
    ],
    ids=["stops-for-x", "stars-beside-a-stop"],
)
def test_stops_for_a_name_nobody_has_go_over_the_budget_and_a_real_stop_still_stops(
    junk: bytes,
) -> None:
    """Rule 8 (an attack pass): 2 KiB datagrams of ``<stop><rotor>x</rotor></stop>`` went past
    every budget as stops and were each parsed whole, and the operator's N1MM stop waited up to
    1.3 s behind them. In virtual time (the clock stands still, the budget never refills): the
    flood's stops name no rotor of the port, go over their sender's budget unparsed, and the
    real one, for Tower, is carried out."""
    clock = FakeClock()
    tower = Recording("tower")
    ep = LoggerEndpoints(clock=clock)
    ep.add_n1mm(tower, "Tower", port=0, report_to=("127.0.0.1", 9))  # type: ignore[arg-type]
    ep.start()
    try:
        port = ep.address(next(iter(ep.n1mm.values())))[1]
        with udp_socket() as s:
            for _ in range(int(RATE_DATAGRAMS_S) // 4 + 50):  # (each costs 1 + 1.7 KiB)
                s.sendto(junk, ("127.0.0.1", port))
            wait_until(lambda: ep.over_budget > 0, slow(10), "the stops for x over the budget")
            s.sendto(
                b"<N1MMRotor><stop><rotor>Tower</rotor></stop></N1MMRotor>", ("127.0.0.1", port)
            )
            wait_until(lambda: tower.calls, slow(10), "the STOP for Tower carried out")
        assert tower.calls == [Stop(Source.N1MM)]
    finally:
        ep.stop()


@pytest.mark.parametrize(
    "stop",
    [
        b"<N1MMRotor><stop><rotor>Tower</rotor></stop></N1MMRotor>",
        b"<N1MMRotor><stop>Tower</stop></N1MMRotor>",
        b"<N1MMRotor><stop> Tower </stop></N1MMRotor>",
        b"<N1MMRotor><stop><rotor>*</rotor></stop></N1MMRotor>",
        b"<N1MMRotor><Stop><Rotor>Tower</Rotor></Stop>\xb0</N1MMRotor>",
    ],
)
def test_every_form_of_a_stop_for_the_ports_rotor_goes_past_a_spent_budget(stop: bytes) -> None:
    """Rule 8: what ``_may_name`` lets past the budget is every stop parse_n1mm reads as one
    for a rotor of the port (its name as a tag's whole text, or ``*``), a byte not ASCII
    beside it too."""
    assert server._may_name(N1mmEndpoint("127.0.0.1", 12040, [N1mmRotor("Tower", None)]), stop)  # type: ignore[arg-type]
