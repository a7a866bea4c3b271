"""runtime/lines.py: one thread serves every rotator's line, and no rotator can hold up another.

Real parts: ptys driven by the emulators, real pyserial; what goes wrong is the port opener of
one rotator (a bug that raises, an adapter that takes seconds to open), the other's stop must
still reach its controller at once.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import select
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import Any

import pytest
import serial

from bridge import emulators
from bridge.app import worker_config
from bridge.core.errors import Refused
from bridge.core.model import ErrorEvent, Stop, Target
from bridge.emulators.pty import EmulatedPort
from bridge.emulators.spid_models import position_reply
from bridge.protocols.base import ModelSpec
from bridge.runtime.lines import GATHER_S, Lines, wake_at
from bridge.runtime.port import open_port
from bridge.runtime.rotator import Rotator
from bridge.runtime.state_store import StateStore
from bridge.runtime.worker import OPEN_BOUND_S, Worker
from bridge.session.mailbox import Mailbox
from bridge.settings import RotatorSettings
from tests.support import wait_until
from tests.support.rig import FAST_BRIDGE, FAST_ROTOR, FAST_SPID_BRIDGE
from tests.support.waiting import slow
from tests.support.workers import StandInWorker

Opener = Callable[[str, ModelSpec, int], serial.Serial]


@pytest.fixture
def emu(tmp_path: Path) -> Iterator[EmulatedPort]:
    port = emulators.start("rotorez", link=str(tmp_path / "tty"), **FAST_ROTOR)
    yield port
    port.close()


def rotator(rid: str, port: str, lines: Lines, opener: Opener, events: list) -> Rotator:
    settings = RotatorSettings.model_validate(
        {"id": rid, "model": "rotorez", "port": port, **FAST_BRIDGE}
    )
    return Rotator(
        worker_config(settings),
        StateStore(None),
        lambda s: None,
        events.append,
        port_opener=opener,
        lines=lines,
    )


def stop_reaches_the_wire(emu: EmulatedPort, rot: Rotator) -> None:
    """A target, then a stop while it turns: the stop reaches the controller (a deadline, not
    a measure: what holds it up in the tests below holds it until the test lets go)."""
    rot.submit(Target(200.0))
    emu.wait_for(lambda s: s.is_moving, timeout_s=10)
    seen = len(emu.frames())
    rot.submit(Stop())

    def stop_seen(device, _now: float):  # noqa: ANN001
        return [f for f in device.log[seen:] if f.data == b";"]

    emu.wait_until(stop_seen, bool, timeout_s=5.0)


class Counting:
    """A port opener that does ``what`` and counts its calls."""

    def __init__(self, what: Callable[[], None]) -> None:
        self.what, self.calls = what, 0

    def __call__(self, path: str, spec: ModelSpec, baud: int) -> serial.Serial:
        self.calls += 1
        self.what()
        raise AssertionError("unreachable")


def buggy() -> None:
    raise RuntimeError("a bug in the opener")


@pytest.mark.parametrize("trouble", ["a bug", "a wedged adapter"])
def test_one_rotators_trouble_never_holds_up_anothers_stop(
    emu: EmulatedPort, tmp_path: Path, trouble: str
) -> None:
    release, held = threading.Event(), threading.Event()

    def wedged() -> None:  # the adapter's open() hangs until the test lets it go
        held.set()
        release.wait(slow(60))  # a guard, far past the stop's deadline
        buggy()

    bad = Counting(buggy if trouble == "a bug" else wedged)
    lines = Lines()
    events: list[ErrorEvent] = []
    sick = rotator("sick", str(tmp_path / "nowhere"), lines, bad, events)
    assert emu.link is not None
    good = rotator("good", emu.link, lines, open_port, events)
    started = time.monotonic()
    sick.start()
    good.start()
    try:
        wait_until(lambda: good.status.state.value == "idle", 10, "the good rotator idle")
        if trouble == "a wedged adapter":
            wait_until(held.is_set, 10, "the sick rotator's open() hanging")
        stop_reaches_the_wire(emu, good)  # while the trouble goes on: nothing let go of it
        stop_reaches_the_wire(emu, good)
        assert not release.is_set() and not sick.status.available
        with pytest.raises(Refused):
            sick.submit(Target(10.0))  # offline: refused, as with a missing adapter
        calls, window_s = bad.calls, time.monotonic() - started
    finally:
        release.set()
        sick.stop()
        good.stop()
    if trouble == "a bug":
        assert 1 <= bad.calls <= 6  # retried with back-off, not in a spin
    elif window_s < OPEN_BOUND_S:
        assert calls == 1  # still in its one open() the whole time
    else:  # a loaded run outlasted worker.py's bound (rule 4): given up once, no more while
        assert 1 <= calls <= 2  # the first still hangs (the second maybe not begun yet)


def test_a_port_that_will_not_close_holds_up_neither_another_line_nor_the_stop(
    emu: EmulatedPort, tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """A wedged USB adapter's close() waits for its output to drain (up to 30 s): stopping that
    rotator froze every other line, as its port was closed on the lines thread."""
    wedged = emulators.start("rotorez", link=str(tmp_path / "wedged"), **FAST_ROTOR)
    release = threading.Event()
    opened: dict[str, serial.Serial] = {}

    def recording(path: str, spec: ModelSpec, baud: int) -> serial.Serial:
        port = opened[path] = open_port(path, spec, baud)
        if path == wedged.link:
            close = port.close
            port.close = lambda: (release.wait(slow(60)), close())  # type: ignore[method-assign]
        return port

    lines = Lines()
    assert emu.link is not None and wedged.link is not None
    sick = rotator("sick", wedged.link, lines, recording, [])
    good = rotator("good", emu.link, lines, recording, [])
    sick.start()
    good.start()
    try:
        for rot in (sick, good):
            wait_until(lambda r=rot: r.status.state.value == "idle", 10, f"{rot.id} idle")
        with caplog.at_level(logging.WARNING, logger="bridge.runtime.lines"):
            sick.stop(timeout_s=0.5)
        # stop() came back with its close still held (the guard on it is a minute): it did not
        # wait for the close, which goes on on a thread of its own
        assert f"sick: {wedged.link} is still closing after 0.5 s" in caplog.text
        assert opened[wedged.link].is_open
        stop_reaches_the_wire(emu, good)  # meanwhile the other line is served
        assert opened[wedged.link].is_open  # the wedged close was still going on
        good.stop()
        assert not opened[emu.link].is_open  # a port that closes is closed when stop returns
    finally:
        release.set()
        good.stop()
        wedged.close()
    wait_until(lambda: not opened[wedged.link].is_open, 5, "the wedged port closed in the end")


def test_a_rotator_is_started_once(emu: EmulatedPort) -> None:
    assert emu.link is not None
    lines = Lines()
    rot = rotator("t", emu.link, lines, open_port, [])
    rot.start()
    with pytest.raises(ValueError, match="already on the lines"):
        rot.start()
    rot.stop()
    with pytest.raises(RuntimeError, match="cannot start again"):
        rot.start()


class Timed(StandInWorker):
    """A stand-in worker: its serve() takes ``takes_s`` of the clock and notes the time it got."""

    def __init__(
        self, clock: list[float], takes_s: float, served: threading.Event, log: list
    ) -> None:
        self.clock, self.takes_s, self.served, self.log = clock, takes_s, served, log
        self.given: list[float] = []

    def wants(self, now: float) -> tuple[list[int], float, float]:
        return [], now, now  # always due: the round runs at once

    def has_commands(self, ready: set[int]) -> bool:
        return self.takes_s > 0  # the slow one first

    def urgent(self) -> set[int]:
        return set()

    def serve(self, now: float, ready: set[int]) -> None:
        self.given.append(now)
        self.log.append((self, now))
        self.clock[0] += self.takes_s
        if len(self.given) >= 3:
            self.served.set()


def test_each_line_is_served_with_the_time_it_is_served_at() -> None:
    """Benchmark finding: one rotator's 1.5 s pass search left the next with a stale clock; a
    query it wrote then looked overdue at once, was asked twice, the second answer junk."""
    clock = [100.0]
    lines = Lines(lambda: clock[0])
    done = threading.Event()
    log: list[tuple[Timed, float]] = []  # who was served, at what time, in order
    slow_one, quick = Timed(clock, 1.5, threading.Event(), log), Timed(clock, 0.0, done, log)
    lines.add(slow_one)  # type: ignore[arg-type]
    lines.add(quick)  # type: ignore[arg-type]
    try:
        assert done.wait(slow(5))
    finally:
        lines.remove(slow_one)  # type: ignore[arg-type]
        lines.remove(quick)  # type: ignore[arg-type]
    after_slow = [
        (a[1], b[1])
        for a, b in zip(log, log[1:], strict=False)
        if (a[0], b[0]) == (slow_one, quick)
    ]
    assert after_slow
    for s_t, q_t in after_slow:
        assert q_t == s_t + 1.5  # served after the slow one's step, at the time it was then


def served_until(lines: Lines, workers: Iterable[object], done: threading.Event) -> None:
    """The workers served by ``lines`` until ``done`` is set (within a while), then removed."""
    workers = list(workers)
    for w in workers:
        lines.add(w)  # type: ignore[arg-type]
    try:
        assert done.wait(slow(5))
    finally:
        for w in workers:
            lines.remove(w)  # type: ignore[arg-type]


class Urgent(Timed):
    """A stand-in whose mailbox (a real one) gets a stop while another worker is served."""

    def __init__(self, *args: Any) -> None:
        super().__init__(*args)
        self.box = Mailbox()

    def urgent(self) -> set[int]:
        return {-1} if self.box.urgent else set()

    def serve(self, now: float, ready: set[int]) -> None:
        self.box.take()
        super().serve(now, ready)


def test_a_stop_that_comes_during_a_round_is_served_next() -> None:
    """Rule 5: it does not wait behind the other workers of the round (8 sky answers and their
    statuses held a stop 19 ms, benchmarks/sky_stops.py)."""
    clock = [100.0]
    lines = Lines(lambda: clock[0])
    done = threading.Event()
    log: list[tuple[Timed, float]] = []
    stopped = Urgent(clock, 0.0, threading.Event(), log)
    flagged: list[int] = []  # where in the log the stop came (during a round with all three)

    class Busy(Timed):
        def serve(self, now: float, ready: set[int]) -> None:
            everyone = all(w in lines._workers for w in (stopped, second))
            if everyone and not flagged:
                stopped.box.put(Stop(), wake=False)  # a stop put while this one is served
                flagged.append(len(log))
            super().serve(now, ready)
            if flagged and len(log) > flagged[0] + 2:
                done.set()

    first = Busy(clock, 0.001, threading.Event(), log)
    second = Timed(clock, 0.002, threading.Event(), log)
    workers = (first, second, stopped)
    served_until(lines, workers, done)
    k = flagged[0]  # first's turn; before rule 5 the round went on with second
    assert [w for w, _ in log[k : k + 2]] == [first, stopped]


def test_a_round_serves_only_the_lines_with_something_to_do() -> None:
    """Rule 6: a line that waits for nothing ready and whose time has not come is not called."""
    clock = [100.0]
    lines = Lines(lambda: clock[0])
    done = threading.Event()
    log: list[tuple[Timed, float]] = []

    class Waiting(Timed):
        def wants(self, now: float) -> tuple[list[int], float, float]:
            return [], now + 3600.0, now + 3600.0  # nothing to do for an hour

    busy, waiting = Timed(clock, 0.0, done, log), Waiting(clock, 0.0, threading.Event(), log)
    lines.add(waiting)  # type: ignore[arg-type]
    lines.add(busy)  # type: ignore[arg-type]
    try:
        assert done.wait(slow(5))
    finally:
        lines.remove(busy)  # type: ignore[arg-type]
        lines.remove(waiting)  # type: ignore[arg-type]
    assert len(busy.given) >= 3 and waiting.given == []


def test_times_that_come_close_together_are_met_in_one_wake_up() -> None:
    """Rule 7: of two lines due 1 ms apart, the first is served with the second, not at
    its own time (rule 3: neither is served early)."""
    done = threading.Event()
    log: list[tuple[Timed, float]] = []

    class At(Timed):
        def __init__(self, due_s: float) -> None:
            super().__init__([0.0], 0.0, done, log)
            self.due_s = due_s

        def wants(self, now: float) -> tuple[list[int], float, float]:
            due = self.due_s if not self.given else now + 3600.0
            return [], due, due

        def serve(self, now: float, ready: set[int]) -> None:
            self.given.append(now)
            if first.given and second.given:
                done.set()

    start_s = time.monotonic()
    first, second = At(start_s + 0.05), At(start_s + 0.051)
    lines = Lines(time.monotonic)
    served_until(lines, (first, second), done)
    assert first.given[0] >= second.due_s and second.given[0] >= second.due_s


QUIET_S = 3 * 10 / 4800  # link.py rule 9's quiet time at 4800 baud: how late a held reply may be


def _at(until: float, latest: float | None = None) -> tuple[list[int], float, float]:
    return [], until, until if latest is None else latest


def test_a_reply_that_came_partly_is_read_in_the_wake_up_that_takes_the_others_readings() -> None:
    """Rule 7 (link.py rule 7): of 16 rotors polled together, one whose reply came partly
    was read 2 ms later in a wake-up of its own, and its reading taken in another: one or two
    wake-ups more per poll round. A held reply's end may be met up to a quiet time late, so it
    is read with the lines due then; alone, or with nothing due soon enough, it is not held."""
    held = _at(10.0, 10.0 + QUIET_S)  # a reply held in its port until 10.0
    assert wake_at([held]) == 10.0  # alone: read at its time, not later
    assert wake_at([held, _at(10.004)]) == 10.004  # read with the readings taken at 10.004
    late = 10.0 + QUIET_S + GATHER_S + 0.001
    assert wake_at([held, _at(late)]) == 10.0  # no later than a quiet time (and the gathering)
    assert wake_at([_at(10.004), held]) == 10.004  # in whatever order the lines come
    assert wake_at([_at(10.0), _at(9.9, 9.9 + QUIET_S)]) == 9.9  # nothing else is held back


def test_times_are_gathered_as_before_and_nothing_is_met_early() -> None:
    """Rules 3 and 7: a line's time is never met early, one due soon after another is met with
    it, one due later is not; no time at all: only a descriptor ends the wait."""
    assert wake_at([]) == math.inf
    assert wake_at([_at(math.inf)]) == math.inf
    assert wake_at([_at(5.0)]) == 5.0
    assert wake_at([_at(5.0), _at(5.0 + GATHER_S / 2)]) == 5.0 + GATHER_S / 2
    assert wake_at([_at(5.0), _at(5.0 + 2 * GATHER_S)]) == 5.0
    assert wake_at([_at(5.0 + 2 * GATHER_S), _at(5.0)]) == 5.0


def test_with_16_lines_a_lock_on_and_a_stop_put_mid_round_each_go_next() -> None:
    """Rule 8: the look for a stop is skipped only while none was put since the last look that
    found none; a lock ON put while the fifth of 16 is served goes next, and a stop put while
    that lock ON is served goes next after it (not at the end of the round)."""
    clock = [100.0]
    lines = Lines(lambda: clock[0])
    done = threading.Event()
    log: list[tuple[Timed, float]] = []
    put: list[int] = []  # where in the log the lock ON came

    class Busy(Urgent):
        def serve(self, now: float, ready: set[int]) -> None:
            if len(lines._workers) == 16 and not put and log and log[-1][0] is workers[3]:
                workers[12].box.put_lock(True, wake=False)  # while the fifth is served
                put.append(len(log))
            super().serve(now, ready)

    class Locked(Urgent):
        def serve(self, now: float, ready: set[int]) -> None:
            if put and len(log) == put[0] + 1:
                workers[14].box.put(Stop(), wake=False)  # while the lock ON is served
            super().serve(now, ready)
            if put and len(log) > put[0] + 3:
                done.set()

    workers: list[Urgent] = [Urgent(clock, 0.0, threading.Event(), log) for _ in range(16)]
    workers[4] = Busy(clock, 0.0, threading.Event(), log)
    workers[12] = Locked(clock, 0.0, threading.Event(), log)
    served_until(lines, workers, done)
    k = put[0]
    assert [w for w, _ in log[k : k + 4]] == [workers[4], workers[12], workers[14], workers[5]]


def test_with_no_stop_put_no_worker_is_asked_again_after_a_look_that_found_none() -> None:
    """Rule 8: with four workers always due and nothing put, the rounds after a look at them
    all that found no stop ask none of them whether one waits (not 4 a round, nor 4 + 3 + 2 + 1
    after each served)."""
    clock = [100.0]
    lines = Lines(lambda: clock[0])
    done = threading.Event()
    log: list[tuple[Timed, float]] = []
    asked: list[int] = [0]

    class Counted(Urgent):
        def urgent(self) -> set[int]:
            asked[0] += 1
            return super().urgent()

        def serve(self, now: float, ready: set[int]) -> None:
            super().serve(now, ready)
            if len(lines._workers) == 4 and log[-1][0] is workers[0] and not marks:
                marks.append((len(log), asked[0]))  # the first of a round of all four
            elif marks and len(log) == marks[0][0] + 4 * 5:
                marks.append((len(log), asked[0]))  # the first of the fifth round after
                done.set()

    marks: list[tuple[int, int]] = []
    workers: list[Urgent] = [Counted(clock, 0.0, threading.Event(), log) for _ in range(4)]
    served_until(lines, workers, done)
    (k0, a0), (k1, a1) = marks
    assert [w for w, _ in log[k1 - 4 : k1]] == workers[1:] + workers[:1]  # rounds in order
    assert a1 - a0 == 0  # nothing put since a look that found none: no look at all


def test_a_stop_for_a_worker_served_earlier_in_the_round_goes_first_in_the_next() -> None:
    """Rules 5 and 8: a stop put, while the third of four is served, for the second (served
    before it in this round); the look for the rest of the round finds none. The next round
    still looks before its first: the stopped one goes first, behind no other rotator."""
    clock = [100.0]
    lines = Lines(lambda: clock[0])
    done = threading.Event()
    log: list[tuple[Timed, float]] = []
    put: list[int] = []  # where in the log the stop came

    class Putter(Urgent):
        def serve(self, now: float, ready: set[int]) -> None:
            everyone = len(lines._workers) == 4
            super().serve(now, ready)
            if everyone and not put and log[-2][0] is workers[1]:
                workers[1].box.put(Stop(), wake=False)  # the second: served this round
                put.append(len(log))
            if put and len(log) >= put[0] + 8:
                done.set()

    workers: list[Urgent] = [Urgent(clock, 0.0, threading.Event(), log) for _ in range(2)]
    workers.append(Putter(clock, 0.0, threading.Event(), log))
    workers.append(Urgent(clock, 0.0, threading.Event(), log))
    served_until(lines, workers, done)
    k = put[0]
    assert [w for w, _ in log[k : k + 2]] == [workers[3], workers[1]]


def test_a_worker_that_joins_with_a_stop_waiting_goes_first_in_its_first_round() -> None:
    """Rule 8: a look that found no stop is kept across rounds only for the workers it asked;
    one that joins later, with a stop put in its mailbox before (and after that look), is
    looked at before the first of the next round and served first."""
    clock = [100.0]
    lines = Lines(lambda: clock[0])
    done = threading.Event()
    log: list[tuple[Timed, float]] = []
    rounds_after: list[int] = []  # where in the log the put came

    workers: list[Urgent] = [Urgent(clock, 0.0, threading.Event(), log) for _ in range(3)]
    late = Urgent(clock, 0.0, threading.Event(), log)

    class Putter(Urgent):
        def serve(self, now: float, ready: set[int]) -> None:
            super().serve(now, ready)
            if not rounds_after and len(log) > 6:
                late.box.put(Stop(), wake=False)  # before it joins, in this round
                rounds_after.append(len(log))
            elif rounds_after and len(log) == rounds_after[0] + 6:
                lines.add(late)  # type: ignore[arg-type]  # two rounds after: looked since
            elif late in lines._workers and len(log) > rounds_after[0] + 12:
                done.set()

    workers[0] = Putter(clock, 0.0, threading.Event(), log)
    starts: list[int] = []  # where in the log each round began
    serve_round = lines._serve_round

    def marked(due: list[Any], ready: set[int]) -> None:
        starts.append(len(log))
        serve_round(due, ready)

    lines._serve_round = marked  # type: ignore[method-assign]
    try:
        served_until(lines, workers, done)
    finally:
        lines.remove(late)  # type: ignore[arg-type]
    first = next(i for i, (w, _) in enumerate(log) if w is late)
    assert first in starts  # the first served of its round (it joined last: it came last)


def _pipe_inodes() -> set[int]:
    """The inodes of this process's open pipes."""
    found = set()
    for fd in _pipes():
        try:
            found.add(os.fstat(fd).st_ino)
        except OSError:
            pass  # closed since
    return found


def _pipes() -> set[int]:
    """This process's open pipe descriptors (the lines' wake pipe is one pair of them)."""
    found = set()
    for name in os.listdir("/proc/self/fd"):
        try:
            if os.readlink(f"/proc/self/fd/{name}").startswith("pipe:"):
                found.add(int(name))
        except OSError:
            pass  # closed while listed (the listing's own descriptor, another thread's)
    return found


def test_lines_started_and_stopped_leave_no_descriptor_and_a_late_wake_up_does_nothing() -> None:
    """Rule 4: each Lines kept its wake pipe open for good, two descriptors per bridge started
    and stopped in one process. A wake-up from another thread (a port opener's) racing the end,
    or coming after it, neither raises nor writes to the closed pipe's number, reused since."""
    wakes: list[Callable[[], None]] = []

    class Idle(Timed):
        def wants(self, now: float) -> tuple[list[int], float, float]:
            return [], now + 3600.0, now + 3600.0

        def begin(self, now: float, wake: Callable[[], None]) -> None:
            wakes.append(wake)

    errors: list[BaseException] = []
    done = threading.Event()

    def waking() -> None:  # another thread, waking the lines as they start and stop
        while not done.is_set():
            for wake in list(wakes[-2:]):
                try:
                    wake()
                except BaseException as exc:  # noqa: BLE001
                    errors.append(exc)
            time.sleep(0)  # let the lines thread have the GIL between rounds of wake-ups

    waker = threading.Thread(target=waking)
    waker.start()
    made: set[int] = set()  # the wake pipes' inodes (another test's thread may open pipes
    try:  # of its own meanwhile: the process's count of pipes said nothing for sure)
        for i in range(20):
            lines = Lines()
            worker = Idle([0.0], 0.0, threading.Event(), [])
            lines.add(worker)  # type: ignore[arg-type]
            wait_until(lambda i=i: len(wakes) > i, 5, "the worker begun")
            made |= {os.fstat(fd).st_ino for fd in (lines._wake_r, lines._wake_w)}
            assert lines.remove(worker)  # type: ignore[arg-type]
            # (its wake pipe is closed just after the thread lets go of ``_thread``: waiting
            # for that alone, a review saw the pipe still open once, under -n 2)
            wait_until(lambda lines=lines: lines._wake_r < 0, 5, "the lines thread ended")
    finally:
        done.set()
        waker.join()
    assert errors == []
    assert made and not made & _pipe_inodes()
    reused_r, reused_w = os.pipe()  # most likely the numbers the last wake pipe had
    try:
        os.set_blocking(reused_r, False)
        wakes[-1]()  # the last worker's wake-up, long after its lines ended
        with pytest.raises(BlockingIOError):
            os.read(reused_r, 1)  # nothing written to whatever pipe has the number now
    finally:
        os.close(reused_r)
        os.close(reused_w)


def test_a_line_is_woken_by_what_it_waits_on_now_and_not_by_what_it_waited_on_before() -> None:
    """Rule 10: the poller is kept and only told what changed. A line that waited on one
    descriptor and now waits on another (a reply held, then read) is woken by the new one and
    not by the old one, left readable; a line that leaves wakes the loop no more."""
    served: list[set[int]] = []
    woke = threading.Event()
    a_r, a_w = os.pipe()
    b_r, b_w = os.pipe()

    class Switching(Timed):
        def wants(self, now: float) -> tuple[list[int], float, float]:
            return ([a_r] if not served else [b_r]), now + 3600.0, now + 3600.0

        def has_commands(self, ready: set[int]) -> bool:
            return False

        def serve(self, now: float, ready: set[int]) -> None:
            served.append(ready & {a_r, b_r})  # (the loop's own wake pipe aside)
            if b_r in ready:
                os.read(b_r, 1)  # what it waits on now is read, as a port's bytes are
            woke.set()

    line = Switching([0.0], 0.0, threading.Event(), [])
    lines = Lines()
    lines.add(line)  # type: ignore[arg-type]
    try:
        os.write(a_w, b"x")  # what it waits on first: it is served
        assert woke.wait(slow(5))
        woke.clear()
        assert served == [{a_r}]
        # a_r stays readable: were it still watched, every round would serve the line
        os.write(b_w, b"y")
        assert woke.wait(slow(5))
        woke.clear()
        assert served == [{a_r}, {b_r}]
        os.write(b_w, b"z")  # and again: the new one still wakes it
        assert woke.wait(slow(5))
        assert served[2] == {b_r}
        assert lines.remove(line)  # type: ignore[arg-type]
        assert line not in lines._watching and b_r not in lines._polled
    finally:
        lines.remove(line)  # type: ignore[arg-type]
        for fd in (a_r, a_w, b_r, b_w):
            os.close(fd)


@contextlib.contextmanager
def worker_on_a_pty(model: str, extra: dict[str, Any]) -> Iterator[tuple[Worker, int, Mailbox]]:
    """A rotator's worker on a pseudo-terminal, its port open at virtual time 100.0: the
    worker, the controller's end of the pty and the mailbox. Ended and closed afterwards."""
    master, slave = os.openpty()
    settings = RotatorSettings.model_validate(
        {"id": "az", "model": model, "port": os.ttyname(slave), **extra}
    )
    box = Mailbox()
    worker = Worker(worker_config(settings), box, lambda s: None, lambda e: None)
    try:
        worker.guarded(worker.begin, 100.0, lambda: None)
        worker.guarded(worker.serve, 100.0, set())  # the port is opened on a thread of its own
        opening = worker._opening
        assert opening is not None
        wait_until(lambda: opening.result is not None, slow(5), "the port opened")
        yield worker, master, box
    finally:
        worker.guarded(worker.end, 100.0)
        assert worker.wait_closed(slow(5))
        os.close(master)
        os.close(slave)
        box.close()


def polled(worker: Worker, master: int, now: float, query: bytes) -> float:
    """Serve from ``now`` at each time the worker asks for until it writes ``query``: when."""
    written = b""
    for _ in range(10):
        worker.guarded(worker.serve, now, set())
        while _readable(master):
            written += os.read(master, 64)
        if written.endswith(query):
            return now
        now = max(now, worker.wants(now)[1])
    raise AssertionError(f"no poll: {written!r}")


def test_a_worker_says_its_held_reply_may_be_read_up_to_a_quiet_time_late() -> None:
    """worker.py rule 2 with lines.py rule 7: the worker tells the loop, after it polled, that
    it waits on its mailbox alone until the reply can be whole, and that the read may come up
    to a quiet time (three byte times at 4800 baud) later; nothing else of it is ever late."""
    with worker_on_a_pty("rotorez", FAST_BRIDGE) as (worker, master, box):
        now = 100.0
        fds, until, latest = worker.wants(now)
        assert until == latest == now  # the port is there: at once, never later
        now = polled(worker, master, now, b"AI1;")
        fds, until, latest = worker.wants(now)
        byte_s = 10 / 4800
        assert fds == [box.fileno()]  # the reply is held in the port (rule 2)
        assert until == worker.session.hold_reads_until() > now
        assert latest == pytest.approx(until + 3 * byte_s)


def _readable(fd: int) -> bool:
    return bool(select.select([fd], [], [], 0)[0])


def test_a_worker_whose_hold_ended_with_nothing_read_waits_for_the_reply_next_time() -> None:
    """worker.py rule 2 with link.py rule 7: a USB adapter that hands a Rotor-EZ's replies
    over 3 ms after the hold on them ended. The worker reads the port at the hold's end, finds
    nothing, says so to the session and watches the port; the reply is read as it comes. After
    two such replies the hold on the next lasts those 3 ms (and a byte time) longer."""
    byte_s = 10 / 4800
    with worker_on_a_pty("rotorez", FAST_BRIDGE) as (worker, master, _box):
        now, holds = 100.0, []
        for _ in range(2):  # the connection's first reading, and the one that confirms it
            now = polled(worker, master, now, b"AI1;")  # (controller.py rule 9), in time
            os.write(master, b";123")
            wait_until(lambda: _readable(worker._fd), slow(5), "the reply in the port")
            now = worker.wants(now)[1]  # the hold's end: the reply read
            worker.guarded(worker.serve, now, {worker._fd})
            now += 0.05
            worker.guarded(worker.serve, now, set())  # its quiet time over: taken or doubted
        assert worker.status.bearing_deg == 123
        now = worker.wants(now)[1]  # the next poll
        for _ in range(3):
            now = polled(worker, master, now, b"AI1;")
            holds.append(worker.wants(now)[1] - now)
            now += holds[-1]
            worker.guarded(worker.serve, now, set())  # the hold's end: nothing in the port
            fds, _, _ = worker.wants(now)
            assert len(fds) == 2  # the mailbox and the port: watched for the reply now
            now += 0.003
            os.write(master, b";123")
            wait_until(lambda: _readable(worker._fd), slow(5), "the reply in the port")
            worker.guarded(worker.serve, now, {worker._fd})
            now += 0.05
            worker.guarded(worker.serve, now, set())  # its quiet time over: the reading taken
            assert worker.status.bearing_deg == 123
            now = worker.wants(now)[1]  # the next poll
        assert holds[1] == pytest.approx(holds[0])
        now = polled(worker, master, now, b"AI1;")
        assert worker.wants(now)[1] - now == pytest.approx(holds[0] + 0.003 + byte_s)


def test_a_stop_taken_during_a_hold_is_written_as_soon_as_the_reply_in_the_port_is_whole() -> None:
    """worker.py rules 2 and 6 with link.py rules 3 and 7: a Rot2Prog takes no frame while it
    replies, so a stop waits for the reply; the reply has come whole into the port before the
    hold on it ends (here at once). A stop put then is written in the serve that takes it: the
    worker asks the session about the hold again after the commands, reads the port and the
    stop goes, not at the hold's end."""
    query, stop = b"\x57" + bytes(10) + b"\x1f\x20", b"\x57" + bytes(10) + b"\x0f\x20"
    with worker_on_a_pty("rot2prog", FAST_SPID_BRIDGE) as (worker, master, box):
        now = polled(worker, master, 100.0, query)
        fds, hold, _ = worker.wants(now)
        assert fds == [box.fileno()] and hold > now + 0.1  # 25 bytes at 600 baud held
        os.write(master, position_reply(worker.cfg.spec, 123.0, 45.0, 2))
        wait_until(lambda: _readable(worker._fd), slow(5), "the reply in the port")
        box.put(Stop(), wake=True)
        worker.guarded(worker.serve, now + 0.01, {box.fileno()})
        sent = b""
        while _readable(master):
            sent += os.read(master, 64)
        assert sent == stop
