"""runtime/worker.py rules 1 and 4: when a port that is out is tried again, in virtual time.
Real parts: real pyserial on a path that is missing, then a pseudo-terminal linked there (the
adapter back under its stable name); the times are the worker's own ``now``, from the test.

Nothing owed: the back-off (0.5 s doubling to 10 s). A stop owed (a STOP taken while the port
is out): tried every OWED_RETRY_S instead, and the stop is the first frame once it opens
(attack 23: the owed stop waited out the back-off, up to 10 s after the adapter was back).
An open() that hangs is given up after OPEN_BOUND_S, doubled for each one given up that still
hangs, and the port tried again (attack 23: a wedged adapter's open was waited for for ever;
review 81: so was a second one while the first hung); a replug seen on the path (another device
node) gives the pending one up at once.
"""

from __future__ import annotations

import logging
import os
import select
import threading
from collections.abc import Iterator
from functools import partial
from pathlib import Path

import pytest
import serial

from bridge.app import worker_config
from bridge.core.model import Stop
from bridge.protocols.base import ModelSpec
from bridge.runtime.port import PendingOpen, open_port
from bridge.runtime.worker import NODE_LOOK_S, OPEN_BOUND_S, OWED_RETRY_S, Worker
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


class Wedged:
    """A port opener whose every open() hangs until the test lets it go (a driver wedged for
    good), and then opens the pty it is given: a port the worker gets late."""

    def __init__(self, tty: str) -> None:
        self.tty = tty
        self.gates: list[threading.Event] = []
        self.ports: list[serial.Serial] = []

    def __call__(self, path: str, spec: ModelSpec, baud: int | None) -> serial.Serial:
        gate = threading.Event()
        self.gates.append(gate)
        gate.wait(slow(60))  # a guard, past the test's end (not a deadline it judges)
        port = open_port(self.tty, spec, baud)
        self.ports.append(port)
        return port


def test_hung_opens_are_given_up_after_a_bound_that_doubles_with_each_still_hanging(
    link: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """Rule 4: each abandoned open still inside its open() doubles the next one's bound, so a
    driver wedged for good holds a thread per doubling (log of the time), none waited for for
    ever (review 81)."""
    master, slave = os.openpty()
    wedged = Wedged(os.ttyname(slave))
    settings = RotatorSettings.model_validate(
        {"id": "tower", "model": "rotorez", "port": str(link), **FAST_BRIDGE}
    )
    box, events = Mailbox(), []
    worker = Worker(worker_config(settings), box, lambda s: None, events.append, port_opener=wedged)
    caplog.set_level(logging.WARNING, logger="bridge")

    def served(now: float) -> float:
        worker.guarded(worker.serve, now, set())
        return worker.wants(now)[1]

    def given_up(now: float) -> float:
        """Served at each time the worker asks for until the pending open is given up: when."""
        opening = worker._opening
        while worker._opening is opening:
            now = served(now)
        return now

    try:
        worker.guarded(worker.begin, START, lambda: None)
        # the first open: its path looked at for a replug each NODE_LOOK_S (review 84), and
        # given up at its bound (the gaps below)
        assert served(START) == START + NODE_LOOK_S
        wait_until(lambda: len(wedged.gates) == 1, slow(5), "the first open() hanging")
        starts = [START]
        for hanging in (2, 3, 4):
            starts.append(given_up(starts[-1]))  # given up, and tried again at once
            served(starts[-1])
            wait_until(lambda n=hanging: len(wedged.gates) == n, slow(5), "the next open()")
        gaps = [round(b - a, 6) for a, b in zip(starts, starts[1:], strict=False)]
        assert gaps == [OPEN_BOUND_S, 2 * OPEN_BOUND_S, 4 * OPEN_BOUND_S]
        assert len(wedged.gates) == 4  # one thread a doubling, no more
        wedged.gates[0].set()  # the first comes back late, with a port: closed at once
        wait_until(lambda: wedged.ports and not wedged.ports[0].is_open, slow(5), "closed")
        wedged.gates[3].set()  # the adapter replugged: this one opens
        opening = worker._opening
        assert opening is not None
        wait_until(partial(has_result, opening), slow(5), "the fourth open() back")
        served(starts[-1])
        assert b"AI1;" in written_until(master, b"AI1;")  # asked its bearing again
        hung = [e for e in events if "hung for" in e.message]
        assert len(hung) == 1  # R/error said it once, for three given up
        said = [r for r in caplog.records if "hung for" in r.getMessage()]
        assert [r.levelno for r in said] == [logging.WARNING]
    finally:
        for gate in wedged.gates:
            gate.set()
        worker.guarded(worker.end, START)
        assert worker.wait_closed(slow(5))
        box.close()
        os.close(master)
        os.close(slave)


def written_until(master: int, frame: bytes) -> bytes:
    """What the bridge wrote to the port, read as it comes until ``frame`` is in it (a busy
    machine may hand the reader the connect's version query, ``V``, before the frames after
    it); a guard of slow(5) for each read, not a deadline the test judges."""
    got = b""
    while frame not in got and select.select([master], [], [], slow(5))[0]:
        got += os.read(master, 64)
    return got


class WedgedOn:
    """A port opener whose open() of one device (the wedged adapter's) hangs until the test
    ends, and opens any other device the path names at once."""

    def __init__(self, old: str) -> None:
        self.old = old
        self.gate = threading.Event()
        self.hung = 0

    def __call__(self, path: str, spec: ModelSpec, baud: int | None) -> serial.Serial:
        if os.path.realpath(path) == self.old:
            self.hung += 1
            self.gate.wait(slow(60))  # a guard, past the test's end (not a deadline it judges)
            raise serial.SerialException("the wedged open let go")
        return open_port(path, spec, baud)


def test_a_replug_seen_on_the_path_gives_a_stretched_hung_open_up_at_once(
    link: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """Rule 4: while an abandoned open still hangs, the next one's bound is doubled, but the
    stable name linked to a new device (the adapter replugged) is tried again within
    NODE_LOOK_S, not after the stretched bound."""
    old_master, old_slave = os.openpty()
    master, slave = os.openpty()
    link.symlink_to(os.ttyname(old_slave))  # the wedged adapter
    opener = WedgedOn(os.ttyname(old_slave))
    settings = RotatorSettings.model_validate(
        {"id": "tower", "model": "rotorez", "port": str(link), **FAST_BRIDGE}
    )
    box, events = Mailbox(), []
    worker = Worker(worker_config(settings), box, lambda s: None, events.append, port_opener=opener)

    def served(now: float) -> float:
        worker.guarded(worker.serve, now, set())
        return worker.wants(now)[1]

    try:
        worker.guarded(worker.begin, START, lambda: None)
        now = served(START)
        wait_until(lambda: opener.hung == 1, slow(5), "the first open() hanging")
        first = worker._opening
        while worker._opening is first:  # served at each time asked for, up to the bound
            now = served(now)
        served(now)  # given up at the bound, and tried again at once
        wait_until(lambda: opener.hung == 2, slow(5), "the second open() hanging")
        second = worker._opening
        replug_t = now + OPEN_BOUND_S / 2  # within the second's stretched bound
        while now < replug_t:
            now = served(now)
            assert worker._opening is second  # the same device: waited for
        link.unlink()
        link.symlink_to(os.ttyname(slave))  # pulled and plugged back in: a new device
        while worker._opening is second:
            now = served(now)
        assert now - replug_t <= NODE_LOOK_S
        served(now)
        opening = worker._opening
        assert opening is not None
        wait_until(partial(has_result, opening), slow(5), "the new device's open() back")
        served(now)
        assert b"AI1;" in written_until(master, b"AI1;")  # asked its bearing again
        assert opener.hung == 2  # the new device was never waited for
        assert any("another device now" in e.message for e in events)
    finally:
        opener.gate.set()
        worker.guarded(worker.end, START)
        assert worker.wait_closed(slow(5))
        box.close()
        for fd in (old_master, old_slave, master, slave):
            os.close(fd)
