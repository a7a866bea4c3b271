"""The pty line server (interfaces/ptylines.py) on real pseudo-terminals, with the GS-232B session
onto a stand-in rotator: what a serial client opening the link sees, byte for byte."""

from __future__ import annotations

import errno
import os
import select
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from bridge.core.model import MotionState, Origin, RotatorStatus, Source, Stop, Target
from bridge.interfaces.gs232 import Gs232Session, gs232_pty
from bridge.interfaces.ptylines import PtyLineServer
from bridge.interfaces.tcplines import RATE_BYTES_S, READ_BYTES, REPLY_COST
from bridge.protocols import REGISTRY
from tests.support import wait_until
from tests.support.clock import FakeClock
from tests.support.waiting import slow


@dataclass
class StandIn:
    """What the GS-232 session uses of a rotator; records what it is asked to do."""

    id: str = "tower"
    spec = REGISTRY["rotorez"]
    bearing_deg: float = 42.0
    submitted: list[Target | Stop] = field(default_factory=list)

    @property
    def status(self) -> RotatorStatus:
        return RotatorStatus(
            self.id, MotionState.IDLE, self.bearing_deg, connected=True, available=True
        )

    def submit(
        self,
        command: Target | Stop,
        described: str | None = None,
        *,
        since: int | None = None,
        seen_s: float | None = None,
        reader: object = None,
    ) -> (
        None
    ):  # (since, seen_s, reader: a subclass that counts halts is handed them, front.py rule 3)
        self.submitted.append(command)


class Client:
    """A serial client on the link: opens it as a program opens a port."""

    def __init__(self, path: str) -> None:
        self.fd = os.open(path, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)

    def ask(self, data: bytes, reply_ends: bytes = b"\n", timeout_s: float = 5.0) -> bytes:
        os.write(self.fd, data)
        return self.read(reply_ends, slow(timeout_s))

    def read(self, reply_ends: bytes = b"\n", timeout_s: float = 5.0) -> bytes:
        buf = b""
        deadline = time.monotonic() + timeout_s
        while not buf.endswith(reply_ends):
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([self.fd], [], [], left)[0]:
                break
            buf += os.read(self.fd, 4096)
        return buf

    def drain(self) -> bytes:
        buf = b""
        while select.select([self.fd], [], [], 0)[0]:
            buf += os.read(self.fd, 4096)
        return buf

    def close(self) -> None:
        os.close(self.fd)


@pytest.fixture
def served(tmp_path: Path) -> Iterator[tuple[PtyLineServer, StandIn, str]]:
    rot = StandIn()
    path = str(tmp_path / "rotor-gs232")
    server = gs232_pty(rot, path)
    server.start()
    yield server, rot, path
    server.stop()


def test_a_client_on_the_link_reads_and_turns(
    served: tuple[PtyLineServer, StandIn, str],
) -> None:
    server, rot, path = served
    assert os.readlink(path) == server.slave_name
    c = Client(path)
    try:
        assert c.ask(b"C2\r") == b"AZ=042  EL=000\r\n"
        assert c.ask(b"W120 000\r\rC\r") == b"AZ=042\r\n"  # W answers nothing
        assert rot.submitted == [
            Target(120, None, Source.GS232, origin=Origin(Source.GS232))
        ]  # no peer
    finally:
        c.close()


def test_a_client_that_closes_and_opens_again_is_served_and_nothing_spins(
    served: tuple[PtyLineServer, StandIn, str],
) -> None:
    server, _, path = served
    for _ in range(3):
        c = Client(path)
        assert c.ask(b"C\r") == b"AZ=042\r\n"
        c.close()
    before = server.wakeups
    # the wait is the thing under test: nobody has the slave open, and the thread must sleep
    time.sleep(0.5)
    assert server.wakeups - before <= 1  # at most the one that discards unread bytes (rule 6)
    c = Client(path)
    try:
        assert c.ask(b"C\r") == b"AZ=042\r\n"
    finally:
        c.close()


def test_junk_gets_the_error_prompt_and_the_next_line_is_served(
    served: tuple[PtyLineServer, StandIn, str],
) -> None:
    _, rot, path = served
    c = Client(path)
    try:
        assert c.ask(b"GET / HTTP/1.1\r") == b"?>\r\n"
        assert c.ask(b"\xff\x00" * 100 + b"\r") == b"?>\r\n"  # overlong, not ASCII
        assert c.ask(b"W1234 000\r") == b"?>\r\n"  # not a command (four digits)
        assert c.ask(b"C\r") == b"AZ=042\r\n"
        assert rot.submitted == []
    finally:
        c.close()


def test_a_half_line_of_a_vanished_client_is_dropped(tmp_path: Path) -> None:
    rot = StandIn()
    path = str(tmp_path / "gs")
    server = PtyLineServer(
        "tower",
        path,
        lambda: Gs232Session(rot),
        label="gs232",
        key="gs232",
        useful_within_s=0.2,
    )
    server.start()
    try:
        c = Client(path)
        os.write(c.fd, b"W12")
        c.close()
        # the wait is the thing under test: the unfinished command's time passing
        wait_until(lambda: server.wakeups >= 2, 5, "the unfinished command dropped")
        c = Client(path)
        assert c.ask(b"C\r") == b"AZ=042\r\n"  # not "W12C": the old half line is gone
        c.close()
        assert rot.submitted == []
    finally:
        server.stop()


def test_replies_nobody_reads_are_dropped_without_blocking(
    served: tuple[PtyLineServer, StandIn, str],
) -> None:
    server, _, path = served
    c = Client(path)
    lines = 0  # each line the server got, whole or cut short, gets one reply (or a drop)
    try:
        for _ in range(2000):  # 16 bytes a reply: more than the pty holds
            try:
                lines += b"C2\r"[: os.write(c.fd, b"C2\r")].count(b"\r")
            except BlockingIOError:
                select.select([], [c.fd], [], 1)
        wait_until(lambda: server.replies_dropped > 0, 10, "a reply dropped")
        # the server may still be answering the C2s it has read, each reply dropped while the
        # pty is full: so the client reads until every line has had its reply or its drop,
        # and only then asks C, whose reply then has room (on a busy machine the server could
        # otherwise reach C while the client had not yet made room, and drop it by rule 5)
        read = bytearray()

        def all_answered() -> bool:
            read.extend(c.drain())
            return read.count(b"\n") + server.replies_dropped >= lines

        pace_s = lines * (len(b"C2\r") + REPLY_COST) / RATE_BYTES_S  # rule 9's, at most
        wait_until(all_answered, 10 + pace_s, f"the {lines} lines answered or dropped")
        assert read.count(b"\n") + server.replies_dropped == lines  # one reply per line
        os.write(c.fd, b"C\r")
        assert c.read(b"AZ=042\r\n", timeout_s=slow(10)) == b"AZ=042\r\n"
    finally:
        c.close()


def test_a_file_that_is_not_a_link_is_refused_and_left_alone(tmp_path: Path) -> None:
    path = tmp_path / "ttyS9"
    path.write_text("mine")
    server = gs232_pty(StandIn(), str(path))
    with pytest.raises(OSError) as caught:
        server.start()
    assert caught.value.errno == errno.EEXIST
    assert str(path) in str(caught.value.strerror) and "gs232_pty" in str(caught.value.strerror)
    assert path.read_text() == "mine"


def test_a_leftover_link_is_replaced_and_the_link_goes_at_stop(tmp_path: Path) -> None:
    path = tmp_path / "rotor-gs232"
    path.symlink_to("/dev/pts/nonesuch")
    server = gs232_pty(StandIn(), str(path))
    server.start()
    assert os.readlink(path) == server.slave_name
    server.stop()
    assert not os.path.lexists(path)


def test_a_link_someone_else_put_there_is_left_at_stop(tmp_path: Path) -> None:
    path = tmp_path / "rotor-gs232"
    server = gs232_pty(StandIn(), str(path))
    server.start()
    os.unlink(path)
    path.symlink_to("/dev/null")
    server.stop()
    assert os.readlink(path) == "/dev/null"


def test_a_missing_directory_names_the_path(tmp_path: Path) -> None:
    path = tmp_path / "nonesuch" / "rotor-gs232"
    with pytest.raises(OSError, match=r"gs232 for rotator 'tower': cannot link a pty at .*"):
        gs232_pty(StandIn(), str(path)).start()


def test_what_a_client_left_unread_is_not_the_next_ones(tmp_path: Path) -> None:
    """Hamlib's GS-232B reads a reply up to its CR and leaves the LF (rule 6)."""
    rot = StandIn()
    path = str(tmp_path / "gs")
    server = PtyLineServer(
        "tower", path, lambda: Gs232Session(rot), label="gs232", key="gs232", stale_s=0.3
    )
    server.start()
    try:
        c = Client(path)
        os.write(c.fd, b"C\r")
        assert select.select([c.fd], [], [], slow(5))[0]
        assert os.read(c.fd, 7) == b"AZ=042\r"  # the LF left unread
        c.close()
        # the wait is the thing under test: the unread byte's time passing
        wait_until(lambda: server.stale_dropped == 1, 5, "the LF discarded")
        c = Client(path)  # opens without flushing its input
        assert c.ask(b"C\r") == b"AZ=042\r\n"  # not "\n" first
        c.close()
    finally:
        server.stop()


def test_a_session_that_raises_does_not_end_the_link(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """Rule 8: a fault behind a line is logged and the next client's line is served."""
    rot = StandIn()
    made: list[int] = []

    class Faulty(Gs232Session):
        def feed(self, data: bytes) -> list[bytes]:  # type: ignore[override]
            if len(made) == 1:  # the first session breaks on its first bytes
                made.append(0)
                raise RuntimeError("a bug behind the line")
            return super().feed(data)

    def session() -> Gs232Session:
        made.append(1)
        return Faulty(rot)

    path = str(tmp_path / "gs")
    server = PtyLineServer("tower", path, session, label="gs232", key="gs232")
    server.start()
    try:
        c = Client(path)
        try:
            os.write(c.fd, b"C\r")
            wait_until(lambda: server.faults == 1, 5, "the fault")
            assert c.ask(b"C\r") == b"AZ=042\r\n"  # a fresh session serves the link
        finally:
            c.close()
        assert "a bug behind the line" in caplog.text
    finally:
        server.stop()


def test_a_client_asking_faster_than_the_budget_is_read_no_faster(tmp_path: Path) -> None:
    """Rule 9, in virtual time (the clock stands still): a program asking as fast as it can
    write is answered up to the pty's budget, then not read (the server sleeps on its stop
    pipe); its questions wait in the pty, and when time passes they are answered, in order."""
    clock = FakeClock()
    rot = StandIn()
    path = str(tmp_path / "rotor-gs232")
    server = PtyLineServer(
        rot.id, path, lambda: Gs232Session(rot), label="gs232", key="gs232", clock=clock
    )
    server.start()
    client = Client(path)
    try:
        per_read = READ_BYTES // 2  # "C\r": answered "AZ=042\r\n"
        reads = int(RATE_BYTES_S // (READ_BYTES + REPLY_COST * per_read)) + 1
        os.write(client.fd, b"C\r" * per_read * (reads + 3))
        answered = client.read(b"\n", 5)
        wait_until(lambda: server.paused > 0, 10, "the server paused")
        answered += client.drain()
        assert answered == b"AZ=042\r\n" * per_read * reads  # the budget's reads, no more
        clock.t += 1.0  # the rest, three reads, within the second's budget
        want = b"AZ=042\r\n" * per_read * 3
        more = b""
        while len(more) < len(want) and (chunk := client.read(b"\n", 10)):
            more += chunk
        assert more == want
    finally:
        client.close()
        server.stop()


def test_a_link_whose_path_is_not_utf8_is_served_claimed_and_named_in_utf8(
    tmp_path: Path,
) -> None:
    """Review 76: a path may be any bytes (a home folder's name: settings/base.py rule 3). The
    claim hashes its bytes (rule 1; the text's ``encode()`` raised UnicodeEncodeError, the
    station's and the remote's start alike), so a second server there is still refused, and
    what is said of the path is UTF-8 text, the byte escaped."""
    folder = tmp_path / "h\udce9"  # b"h\xe9": a Latin-1 name, as os.environ holds it
    folder.mkdir()
    path = str(folder / "rotor-gs232")
    first, second = gs232_pty(StandIn(), path), gs232_pty(StandIn(), path)
    first.start()
    try:
        c = Client(path)
        try:
            assert c.ask(b"C\r") == b"AZ=042\r\n"
        finally:
            c.close()
        with pytest.raises(OSError) as caught:
            second.listen()
        assert caught.value.errno == errno.EADDRINUSE
        said = str(caught.value.strerror)
        assert "h\\udce9/rotor-gs232" in said and said.encode()  # UTF-8: no lone surrogate
    finally:
        first.stop()
    assert not os.path.lexists(path)
