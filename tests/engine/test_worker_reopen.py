"""runtime/worker.py rule 1: when a port that is out is tried again, in virtual time. Real parts:
real pyserial on a path that is missing, then a pseudo-terminal linked there (the adapter back
under its stable name); the times are the worker's own ``now``, handed in by the test.

Nothing owed: the back-off (0.5 s doubling to 10 s). A stop owed (a STOP taken while the port
is out): tried every OWED_RETRY_S instead, and the stop is the first frame once it opens
(attack 23: the owed stop waited out the back-off, up to 10 s after the adapter was back).
"""

from __future__ import annotations

import os
import select
from collections.abc import Iterator
from functools import partial
from pathlib import Path

import pytest

from bridge.app import worker_config
from bridge.core.model import Stop
from bridge.runtime.port import PendingOpen
from bridge.runtime.worker import OWED_RETRY_S, Worker
from bridge.session.mailbox import Mailbox
from bridge.settings import RotatorSettings
from tests.support import wait_until
from tests.support.rig import FAST_BRIDGE
from tests.support.waiting import slow

START = 100.0


@pytest.fixture
def link(tmp_path: Path) -> Path:
    return tmp_path / "by-id-tower"  # the adapter's stable name; out (missing) at first


@pytest.fixture
def worker(link: Path) -> Iterator[Worker]:
    settings = RotatorSettings.model_validate(
        {"id": "tower", "model": "rotorez", "port": str(link), **FAST_BRIDGE}
    )
    box = Mailbox()
    worker = Worker(worker_config(settings), box, lambda s: None, lambda e: None)
    worker.guarded(worker.begin, START, lambda: None)
    try:
        yield worker
    finally:
        worker.guarded(worker.end, START)
        assert worker.wait_closed(slow(5))
        box.close()


def has_result(opening: PendingOpen) -> bool:
    return opening.result is not None


def next_try(worker: Worker, now: float, ready: frozenset[int] = frozenset()) -> float:
    """Serve the worker (``ready`` at first) at each time it asks for until it tries the port:
    that time (the try's outcome handed back at that same virtual time)."""
    for _ in range(10):
        worker.guarded(worker.serve, now, set(ready))
        ready = frozenset()
        opening = worker._opening
        if opening is not None:
            wait_until(partial(has_result, opening), slow(5), "the try over")
            worker.guarded(worker.serve, now, set())
            return now
        now = max(now, worker.wants(now)[1])
    raise AssertionError("the port was not tried")


def test_a_port_that_is_out_is_tried_on_the_back_off_while_nothing_is_owed(
    worker: Worker,
) -> None:
    tries = [next_try(worker, START)]
    for _ in range(6):
        tries.append(next_try(worker, tries[-1]))
    gaps = [round(b - a, 6) for a, b in zip(tries, tries[1:], strict=False)]
    assert gaps == [0.5, 1.0, 2.0, 4.0, 8.0, 10.0]
    assert not worker.status.available and not worker.status.stop_owed


def test_a_stop_owed_has_the_port_tried_promptly_and_goes_out_first(
    worker: Worker, link: Path
) -> None:
    now = START
    for _ in range(6):  # out long enough for the back-off to reach 10 s
        now = next_try(worker, now)
    pressed = now + 1.0  # the STOP, 1 s after the last try: the next one 9 s away
    box = worker._mailbox
    box.put(Stop())  # served at ``pressed``: owed, the port out
    tried = next_try(worker, pressed, frozenset({box.fileno()}))
    assert worker.status.stop_owed
    assert tried == pressed  # the last try was longer ago than OWED_RETRY_S: at once
    tries = [tried]
    for _ in range(3):
        tries.append(next_try(worker, tries[-1]))
    gaps = [round(b - a, 6) for a, b in zip(tries, tries[1:], strict=False)]
    assert gaps == [OWED_RETRY_S] * 3  # the back-off does not grow while the stop is owed
    master, slave = os.openpty()
    try:
        link.symlink_to(os.ttyname(slave))  # the adapter back under its stable name
        back = tries[-1] + 0.01
        opened = next_try(worker, back)
        assert opened - back <= OWED_RETRY_S
        assert select.select([master], [], [], slow(5))[0]
        assert os.read(master, 64).startswith(b";")  # the owed stop is the first frame
        assert not worker.status.stop_owed
    finally:
        worker.guarded(worker.end, START)
        assert worker.wait_closed(slow(5))
        os.close(master)
        os.close(slave)
