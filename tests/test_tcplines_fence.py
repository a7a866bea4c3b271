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

    def halt(self) -> None:
        if self.halt_watchers is not None:
            self.halt_watchers()
        between, self.between = self.between, None
        if between is not None:
            between()
        self.halts += 1

    def submit(self, command: Command, described: str | None = None) -> None:
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
    from 8 takes 2 bytes, judged at 0; the next the other 8, judged at 1."""
    looks = Looks()
    looks.read = 8
    looks.seen = deque([(4, 0), (10, 0), (18, 1)])
    assert looks.next_read() == (2, 0)
    looks.read = 10
    assert looks.next_read() == (8, 1)
    assert list(looks.seen) == [(18, 1)]
    looks.read = 18
    looks.seen.append((18, 1))  # (the kernel could not say: Windows)
    most, count = looks.next_read()
    assert count == 1 and most > 18
