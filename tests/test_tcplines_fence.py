"""The TCP fence's bookkeeping (interfaces/tcplines.py rule 9), sans sockets: which halts are a
connection's own, and where a read must stop so that none holds bytes from both sides of a
halt. The rotator here is a counter with its watchers; the integration tests
(tests/integration/test_review_fence_holes.py) prove the same through a live bridge."""

from __future__ import annotations

import threading
from collections import deque
from collections.abc import Callable

import pytest

from bridge.core.errors import Refused
from bridge.core.haltwatch import HaltWatchers
from bridge.core.model import Command, Origin, Source, Stop, Target
from bridge.interfaces.tcplines import Fence, Looks


class Counter:
    """A rotator that counts its halts, tells its watchers first (mailbox.py rule 10), and
    may let ``between`` run after the watchers and before the count (another thread's halt
    landing while this one is on its way)."""

    def __init__(self, watched: bool = True) -> None:
        self.halts = 0
        self.halt_watchers: HaltWatchers | None = HaltWatchers() if watched else None
        self.between: Callable[[], None] | None = None
        self.moved: list[Command] = []
        self.refused: list[str] = []
        self.seen: list[float | None] = []

    def halt(self) -> None:
        if self.halt_watchers is not None:
            self.halt_watchers()
        between, self.between = self.between, None
        if between is not None:
            between()
        self.halts += 1

    def submit(
        self,
        command: Command,
        described: str | None = None,
        *,
        since: int | None = None,
        seen_s: float | None = None,
        reader: object = None,
    ) -> None:
        self.seen.append(seen_s)  # (front.py rule 3: when its bytes were seen)
        if isinstance(command, Stop):
            self.halt()
        else:
            self.moved.append(command)

    def report_refusal(
        self, message: str, command: str | None, *, origin: Origin | None = None
    ) -> None:
        self.refused.append(message)


def _other_thread_halt(rot: Counter) -> None:
    worker = threading.Thread(target=rot.halt)
    worker.start()
    worker.join()


def _move(fence: Fence) -> bool:
    """The fence's judgement of a target: True if it went to the judge."""
    try:
        fence.move(Target(100.0, source=Source.ROTCTLD), "P 100 0")
    except Refused:
        return False
    return True


@pytest.mark.parametrize("watched", [True, False])
def test_a_move_after_the_connections_own_stop_in_the_same_read_goes(watched: bool) -> None:
    rot = Counter(watched)
    fence = Fence(rot)  # type: ignore[arg-type]
    fence.arrived = rot.halts  # one read: P 300 0, S, P 200 0
    assert _move(fence)
    fence.halting(lambda: rot.submit(Stop(Source.ROTCTLD)))
    assert _move(fence), "its own stop refused the move it sent after it"


def test_a_move_sent_before_a_halt_is_refused() -> None:
    rot = Counter()
    fence = Fence(rot)  # type: ignore[arg-type]
    fence.arrived = rot.halts
    _other_thread_halt(rot)
    assert not _move(fence)
    assert rot.refused and not rot.moved


def test_another_threads_halt_counted_while_the_own_stop_is_on_its_way_is_not_its_own() -> None:
    """Another thread's halt counted between the own stop's watchers and its count: the
    number the own stop was told is below its real one, and a move sent before the other
    halt is refused (counting every halt meanwhile as its own let it through)."""
    rot = Counter()
    fence = Fence(rot)  # type: ignore[arg-type]
    fence.arrived = rot.halts  # the move's bytes: seen before either halt
    rot.between = lambda: _other_thread_halt(rot)
    fence.halting(lambda: rot.submit(Stop(Source.ROTCTLD)))
    assert rot.halts == 2
    assert not _move(fence), "another's halt was taken for the connection's own"


def test_another_threads_halt_counted_first_then_the_own_stop_still_lets_later_moves_go() -> None:
    rot = Counter()
    fence = Fence(rot)  # type: ignore[arg-type]
    _other_thread_halt(rot)
    fence.arrived = rot.halts  # seen after the other halt
    fence.halting(lambda: rot.submit(Stop(Source.ROTCTLD)))
    assert _move(fence)


def test_a_stop_that_raises_before_it_is_counted_leaves_no_number_to_be_taken_for_its_own() -> None:
    rot = Counter()
    fence = Fence(rot)  # type: ignore[arg-type]
    fence.arrived = rot.halts

    def failing() -> None:
        assert rot.halt_watchers is not None
        rot.halt_watchers()
        raise RuntimeError("the queue refused it")

    with pytest.raises(RuntimeError):
        fence.halting(failing)
    _other_thread_halt(rot)  # takes the number the failed stop was told
    assert not _move(fence)


def test_no_read_takes_bytes_past_what_the_oldest_unread_look_counted() -> None:
    """Looks: 10 bytes at count 0 (the halt's watcher), then 18 at count 1 (after it): a read
    from 8 takes 2 bytes, judged at 0; the next the other 8, judged at 1; each with its
    look's since when."""
    looks = Looks(since_s=0.5)
    looks.read = 8
    looks.seen = deque([(4, 0, 1.0), (10, 0, 2.0), (18, 1, 3.0)])
    assert looks.next_read() == (2, 0, 2.0)
    looks.read = 10
    assert looks.next_read() == (8, 1, 3.0)
    assert list(looks.seen) == [(18, 1, 3.0)]
    looks.read = 18
    looks.seen.append((18, 1, 4.0))  # (the kernel could not say: Windows)
    most, count, since = looks.next_read()
    assert count == 1 and most > 18
    assert since == 0.5  # (bytes no look counted: since the connection was last found empty)


@pytest.mark.parametrize("fionread", [True, False], ids=["linux", "windows"])
def test_bytes_are_dated_from_when_the_connection_was_last_found_empty(
    monkeypatch: pytest.MonkeyPatch, fionread: bool
) -> None:
    """Looks (tcplines.py rule 9, since when): bytes its thread waited for came at the look
    that found them; bytes that came while it did not watch (over its budget, busy) came at
    any time since the connection was last known to hold nothing unread: the kernel's count
    at a look, or (Windows, no FIONREAD) a read that took less than it asked for. A read
    that filled what it asked for leaves the rest dated as they were (review 24: on Windows
    they were dated by that read's look, after a STOP they came before)."""
    import socket

    from bridge.interfaces import tcplines

    if not fionread:

        def no_fionread(fd: int) -> int:
            raise OSError("no FIONREAD here")

        monkeypatch.setattr(tcplines, "unread", no_fionread)
    ours, peer = socket.socketpair()
    with ours, peer:
        looks = Looks(since_s=0.0)

        def read(looked_s: float) -> bytes:  # (as LineServer's thread reads, after a look)
            most, _, _ = looks.next_read()
            asked = min(most, 64)
            data = ours.recv(asked)
            looks.read += len(data)
            if len(data) < asked:
                looks.drained(looked_s)
            return data

        peer.sendall(b"p\n")
        waited_s = looks.look(ours.fileno(), 0, waited=True)  # its thread waited: came now
        assert looks.next_read()[2] == waited_s
        assert read(waited_s) == b"p\n"
        peer.sendall(b"p\n" * 40 + b"P 200 0\n")  # while its thread slept over its budget
        later_s = looks.look(ours.fileno(), 0)
        assert looks.next_read()[2] == waited_s < later_s  # since last found empty
        assert len(read(later_s)) == 64  # (filled: more may wait)
        last_s = looks.look(ours.fileno(), 0)
        assert looks.next_read()[2] == waited_s, "the bytes past the first read keep their date"
        rest = read(last_s)
        assert rest.endswith(b"P 200 0\n")
