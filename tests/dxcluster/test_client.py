"""The DX cluster client alone (no broker, no rotator), against the fake node on loopback: a
node that never prompts is left after LOGIN_WAIT_S (its clock is the test's) and tried again; a
node that cannot be reached is tried again; stop() ends both threads. And its aim thread,
against a recording rotator: the newest spot's place, else the entity, else a refusal."""

from __future__ import annotations

import json
import socket
import threading
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from bridge.core import geo
from bridge.core.errors import Refused
from bridge.core.model import Origin, Source, Stop, Toward
from bridge.interfaces.dxcluster.book import Book
from bridge.interfaces.dxcluster.client import (
    LOGIN_WAIT_S,
    RATE_BYTES_S,
    READ_BYTES,
    DxCluster,
)
from bridge.interfaces.dxcluster.cty import parse_dat
from bridge.interfaces.dxcluster.spots import Spot
from bridge.runtime.rotator import STALE_MESSAGE
from tests.dxcluster.cty_sample import CTY_DAT
from tests.engine.test_halt_epoch import START_AZ, Bench, on_a_thread
from tests.support import wait_until
from tests.support.clock import FakeClock, RunningWall, wall_at
from tests.support.cluster import FakeCluster, Session
from tests.support.waiting import slow

SPOT = b"DX de EA5WU:     14025.0  JA1ABC       cq up 2                        1829Z\r\n"


class JumpingClock:
    """Each reading LOGIN_WAIT_S later than the one before: the first quiet read is already
    past the prompt's deadline (virtual time for the wait; the socket's read is real)."""

    def __init__(self) -> None:
        self.t = 0.0

    def __call__(self) -> float:
        self.t += LOGIN_WAIT_S
        return self.t


@pytest.fixture
def published() -> Iterator[list[str]]:
    yield []


def client(port: int, published: list[str], clock: JumpingClock | None = None) -> DxCluster:
    book = Book(parse_dat(CTY_DAT), (52.5, 13.4), wall=RunningWall("1830"))  # SPOT's time
    dx = DxCluster("127.0.0.1", port, "G4ABC", book, published.append, backoff_s=0.01)
    if clock is not None:
        dx.clock = clock
    return dx


def test_no_prompt_in_time_is_a_failure_and_the_client_tries_again(
    published: list[str],
) -> None:
    def silent(s: Session) -> None:  # never prompts; waits until the client hangs up
        s.conn.settimeout(slow(30))
        while s.conn.recv(1024):
            pass

    cluster = _failing_then_prompting(silent, published)
    assert json.loads(published[0]) == {"spots": []}  # the run before's spots cleared
    assert not cluster.errors, cluster.errors


def _failing_then_prompting(first: Callable[[Session], None], published: list[str]) -> FakeCluster:
    """A node whose first session is ``first`` (it never prompts) and whose second prompts and
    sends SPOT: the client gives the first up once, logs in to the second, and publishes."""

    def prompt(s: Session) -> None:
        s.send(b"login: ")
        cluster.logins.append(s.read_line())
        s.send(SPOT)
        cluster.done.wait(slow(30))

    cluster = FakeCluster([first, prompt])
    dx = client(cluster.port, published, JumpingClock())
    dx.start()
    try:
        wait_until(lambda: any("JA1ABC" in p for p in published), 20, "the spot published")
        assert cluster.logins == [b"G4ABC"]
        assert (dx.counts.failures, dx.counts.connects) == (1, 1)
    finally:
        dx.stop()
        cluster.close()
    return cluster


def test_a_node_that_talks_but_never_prompts_is_left_too(published: list[str]) -> None:
    """A node that keeps sending (a banner, junk, a byte at a time) and never asks for the
    call sign never leaves the client a quiet second: the prompt's deadline must hold anyway,
    or the client sits on it for ever, with no spot and nothing in the log."""

    done = threading.Event()

    def chatty(s: Session) -> None:  # a byte every 0.1 s (the behaviour under test) until hung up
        try:
            while not done.wait(0.1):  # a poll, not a deadline
                s.send(b".")
        except OSError:
            pass

    try:
        cluster = _failing_then_prompting(chatty, published)
    finally:
        done.set()
    assert not cluster.errors, cluster.errors


def test_a_node_that_cannot_be_reached_is_tried_again_and_stop_ends_it(
    published: list[str],
) -> None:
    with socket.socket() as probe:  # a port with nothing listening on it
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    dx = client(port, published)
    dx.start()
    wait_until(lambda: dx.counts.failures >= 3, 20, "three refused connections")
    threads = list(dx._threads)
    assert len(threads) == 2
    dx.stop()
    assert not any(t.is_alive() for t in threads)
    assert dx.counts.connects == 0


class Asked:
    """The two calls the aim thread makes of a rotator, recorded."""

    def __init__(self) -> None:
        self.calls: list[tuple[object, ...]] = []
        self.halts = 0  # the halt count (runtime/rotator.py)
        self.tickets = 0  # places in the order of commands taken (mailbox.py rule 10a)

    def ticket(self) -> int:
        self.tickets += 1
        return self.tickets

    def check_motion(self, origin: Origin) -> None:
        """Nothing refuses motion here (the real judge's: test_call_overtaken.py)."""

    def submit(
        self,
        command: Toward,
        described: str,
        *,
        since: int | None = None,
        ticket: int | None = None,
    ) -> None:
        lat, lon, long_path = command.latitude_deg, command.longitude_deg, command.long_path
        assert since == 0  # the count when it was asked goes to the judge (rule 4)
        assert ticket is not None and 0 < ticket <= self.tickets  # ... and its place (rule 4)
        self.calls.append(("go", lat, lon, command.source, described, long_path, command.origin))

    def report_refusal(self, message: str, command: str | None, *, origin: Origin) -> None:
        self.calls.append(("refused", message, command, origin))


def test_the_aim_thread_turns_to_the_newest_spot_else_the_entity_else_refuses(
    published: list[str],
) -> None:
    dx = client(9, published)  # never started as a telnet client: the book is filled here
    dx.book.add(Spot("JA1ABC", 14025.0, "G4ABC", "1829", "FT8 PM95vq"))
    rot, who = Asked(), Origin(Source.MQTT, "G4ABC")
    thread = threading.Thread(target=dx._aim_loop, daemon=True)
    thread.start()
    for call, long_path in (("JA1ABC", False), ("VK3ABC", True), ("QQ1ABC", False)):
        dx.aim(rot, call, long_path, f"target {call}", who)  # type: ignore[arg-type]
    wait_until(lambda: len(rot.calls) == 3, 10, "three answers")
    lat, lon = geo.parse_locator("PM95VQ")
    assert rot.calls == [
        ("go", lat, lon, Source.DXCLUSTER, "target JA1ABC", False, who),  # the spot's locator
        ("go", -23.70, 132.33, Source.DXCLUSTER, "target VK3ABC", True, who),  # the entity
        ("refused", "QQ1ABC: not spotted and in no entity of the cty file", "target QQ1ABC", who),
    ]
    dx._stop.set()
    dx._aims.put(None)
    thread.join(slow(5))
    assert not thread.is_alive()


class Waits(threading.Event):
    """The client's stop event, its back-off waits recorded and not waited (virtual time):
    set after ``n`` of them."""

    def __init__(self, n: int) -> None:
        super().__init__()
        self.n = n
        self.waited: list[float] = []

    def wait(self, timeout: float | None = None) -> bool:
        if timeout is not None:
            self.waited.append(timeout)
            if len(self.waited) >= self.n:
                self.set()
        return self.is_set()


def test_the_back_off_doubles_from_one_second_to_a_minute(published: list[str]) -> None:
    with socket.socket() as probe:  # a port with nothing listening on it
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    dx = client(port, published)
    dx.backoff_s = 1.0
    waits = Waits(9)
    dx._stop = waits
    dx._run()  # on this thread: it returns when the event is set
    assert waits.waited == [1, 2, 4, 8, 16, 32, 60, 60, 60]
    assert dx.counts.failures == 9


def test_spots_age_out_of_b_spots_while_the_node_cannot_be_reached(
    published: list[str],
) -> None:
    """Book rule 2 (none older than max_age_s) holds while the node is down: the pruning
    and B/spots must not wait for a session that never comes (a node down for hours left
    its last spots retained on B/spots, and a call target used them)."""
    with socket.socket() as probe:  # a port with nothing listening on it
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    now = [0.0]
    book = Book(
        parse_dat(CTY_DAT),
        (52.5, 13.4),
        max_age_s=1800.0,
        clock=lambda: now[0],
        wall=lambda: wall_at("1830"),
    )
    book.add(Spot("JA1ABC", 14025.0, "EA5WU", "1829", "cq"))
    dx = DxCluster("127.0.0.1", port, "G4ABC", book, published.append, backoff_s=1.0)
    dx._publish()  # the spot on B/spots, as a session before the node went down left it
    now[0] = 3 * 3600.0  # three hours later, the node still down
    dx._stop = Waits(3)
    dx._run()  # on this thread: three refused connections, their waits not waited
    assert json.loads(published[-1]) == {"spots": []}
    assert book.newest("JA1ABC") is None


def test_a_stop_after_the_call_was_asked_overtakes_it(published: list[str]) -> None:
    """Rule 4: a call queued before a STOP is never turned to after it."""
    dx = client(9, published)
    dx.book.add(Spot("JA1ABC", 14025.0, "G4ABC", "1829", "FT8 PM95vq"))
    rot, who = Asked(), Origin(Source.MQTT, "G4ABC")
    dx.aim(rot, "JA1ABC", False, "target JA1ABC", who)  # type: ignore[arg-type]
    rot.halts += 1  # the STOP, before the aim thread took the call
    dx._turn(dx._aims.get_nowait())  # type: ignore[arg-type]
    assert rot.calls == [
        ("refused", "JA1ABC: a stop came after it was asked: not turned", "target JA1ABC", who)
    ]


def test_a_node_sending_faster_than_its_budget_is_read_no_faster(published: list[str]) -> None:
    """Rule 5, in virtual time (the clock stands still): a node pouring spots out as fast as
    TCP takes them is read up to the session's budget and then not at all (the thread sleeps,
    the node's bytes wait in the kernel), however long it pours; when time passes, the
    client reads on. A node that could keep the thread busy would hold the GIL beside a stop."""
    lines = 4 * int(RATE_BYTES_S) // len(SPOT)
    poured = threading.Event()

    def pouring(s: Session) -> None:
        s.send(b"login: ")
        s.read_line()
        s.send(SPOT * lines)  # four budgets' worth: returns once the kernel took the rest
        poured.set()
        cluster.done.wait(slow(30))

    cluster = FakeCluster([pouring])
    clock = FakeClock()
    dx = client(cluster.port, published)
    dx.clock = clock
    dx.start()
    try:
        wait_until(lambda: dx.counts.paused > 0, 20, "the client paused")
        read = dx.counts.spots
        # a second's budget, and one read's worth into debt (each line costs more than its bytes)
        per_second = (RATE_BYTES_S + READ_BYTES) / len(SPOT)
        assert 0 < read <= per_second < lines / 2
        assert dx.counts.paused > 0 and dx.counts.spots == read  # still: nothing more read
        clock.t += 1000.0  # a second's budget back (the bucket holds no more)
        wait_until(lambda: dx.counts.spots > read, 20, "more read")
        wait_until(lambda: dx.counts.paused > 1, 20, "paused again")
        assert dx.counts.spots - read <= per_second
    finally:
        dx.stop()
        cluster.close()
    assert not cluster.errors, cluster.errors


def test_a_stop_during_the_look_up_overtakes_the_call(tmp_path: Path) -> None:
    """Rule 4, an attack pass: the aim thread compared the last halt's time with the call's
    before its look-up, and a STOP put during the look-up (rotctld's, on a thread of its own)
    was overtaken: the call asked before it went to the controller after it."""
    bench = Bench(tmp_path)
    try:
        book = Book(parse_dat(CTY_DAT), (52.52, 13.40), wall=lambda: wall_at("1234"))
        book.add(Spot("JA1ABC", 14025.0, "G4ABC", "1234", "FT8 PM95vq"))
        dx = DxCluster("127.0.0.1", 9, "G4ABC", book, lambda doc: None)
        who = Origin(Source.MQTT, "G4ABC")
        dx.aim(bench.rot, "JA1ABC", False, "target JA1ABC", who)
        newest = book.newest

        def looked_up(call: str) -> Spot | None:  # the aim thread is in its look-up ...
            found = newest(call)  # ... when an operator's STOP comes on another thread
            on_a_thread(lambda: bench.rot.submit(Stop(Source.ROTCTLD), "rotctld S"))
            return found

        book.newest = looked_up  # type: ignore[method-assign]
        with pytest.raises(Refused):
            dx._turn(dx._aims.get_nowait())  # type: ignore[arg-type]
        bench.v._take()
        bench.v.run_for(20)
        assert bench.sets() == []  # no set frame reached the controller
        assert bench.v.truth().az_deg == pytest.approx(START_AZ, abs=0.5)
        assert bench.events[-1].message == STALE_MESSAGE  # said on R/error
    finally:
        bench.close()


class _TricklingNode:
    """A node as the client's socket sees it: ``login:``, then one byte a read, for ever (a
    hostile node sending each byte in a segment of its own, paced just under the byte budget,
    wakes the client once per byte)."""

    def __init__(self) -> None:
        self.reads = 0
        self._prompted = False
        self._at = 0
        self._closed = threading.Event()

    def recv(self, _size: int) -> bytes:
        if self._closed.is_set():
            return b""
        self.reads += 1
        if not self._prompted:
            self._prompted = True
            return b"login: "
        self._at += 1
        return SPOT[self._at % len(SPOT) : self._at % len(SPOT) + 1]

    def sendall(self, _data: bytes) -> None:
        pass

    def shutdown(self, _how: int) -> None:
        self._closed.set()

    def close(self) -> None:
        self._closed.set()

    def settimeout(self, _t: float) -> None:
        pass

    def setsockopt(self, *_args: object) -> None:
        pass


def test_a_node_sending_a_byte_a_segment_wakes_the_client_a_bounded_number_of_times(
    published: list[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Rule 5, in virtual time (the clock stands still): each read is charged, not only its
    bytes. A node that sent its bytes one segment each, paced just under RATE_BYTES_S, woke
    the client some 30,000 times a second (each wake-up Python's work under the interpreter
    lock: a fifth of a core measured at a byte every 60 us, beside the stop's threads)."""
    node = _TricklingNode()
    monkeypatch.setattr(
        "bridge.interfaces.dxcluster.client.socket.create_connection", lambda *a, **k: node
    )
    dx = client(1, published)
    dx.clock = FakeClock()
    dx.start()
    try:
        wait_until(lambda: dx.counts.paused > 0, 20, "the client paused")
        assert node.reads <= RATE_BYTES_S / 32  # a second's budget buys at most ~1000 reads
    finally:
        dx.stop()


def test_a_node_that_logs_in_sends_a_spot_and_hangs_up_says_so_rarely_in_the_log(
    published: list[str], caplog: pytest.LogCaptureFixture
) -> None:
    """A node (or whoever poses as one) that prompts, sends one spot and closes, over and over:
    its spot resets the back-off (rule 2), so the client logs in about once a second for as
    long as it goes on. The failures were said once a minute, but each login was a line of its
    own: 86,400 lines a day in the log. Now the logins are said like the failures."""

    def one_spot(s: Session) -> None:
        s.send(b"login: ")
        s.read_line()
        s.send(SPOT)

    cluster = FakeCluster([one_spot] * 6)
    dx = client(cluster.port, published)
    caplog.set_level("INFO", logger="bridge.interfaces.dxcluster.client")
    dx.start()
    try:
        wait_until(lambda: dx.counts.connects >= 6, 20, "six logins")
    finally:
        dx.stop()
        cluster.close()
    said = [r for r in caplog.records if "logged in" in r.getMessage()]
    assert len(said) == 1, [r.getMessage() for r in said]
