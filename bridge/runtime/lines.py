"""One thread for every rotator's serial line: the only code that touches the ports. I/O only.

Each rotator is a Worker (worker.py: its port, back-off and session; a rotator of two boxes,
composite.py, is one worker serving both boxes' workers). This loop asks every
worker what it waits for (file descriptors, a deadline), sleeps in one poll() on all of them
and the loop's own wake pipe, then lets each worker serve what is ready. Sessions decide
(session.py); workers carry out; this loop only waits.

Rules:
1. One thread, however many rotators: a poll round of 32 rotators is one wake-up, not 32
   threads each waking for its own (sessions that poll at the same interval poll at the same
   instants, link.py rule 8), and the statuses of a round reach the MQTT thread in one burst.
2. Nothing here blocks but poll(): writes are one short frame to a non-blocking port (one the
   tty refuses is waited for up to port.py's WRITE_WAIT_S, its rule 6), reads take what is
   there; opening a port and closing a failed one (a wedged USB adapter can take seconds)
   happen on a short-lived thread of their own (worker.py rule 4). Each worker is
   called inside its own guard: one that raises is logged (once per kind), its port closed and
   reopened after its back-off, and every other line goes on; the loop never sleeps for it.
3. Deadlines are met late, never early: poll() counts whole milliseconds, rounded up.
4. ``add`` and ``remove`` may be called from any thread; the thread ends when the last worker
   is removed. A removed worker's port is closed on a thread of its own (worker.py rule 4; a
   wedged adapter's close can take 30 s and must not hold up the other lines), and ``remove``
   waits for it: when it returns the port is closed, or, if closing it outlasts the time given
   to ``remove``, still being closed (a warning says so); either way nothing serves it any more.
   A worker is added once: adding it again is a programming error (ValueError).
   The wake pipe lives as long as the thread: made when the thread starts, closed by the thread
   as it ends, both under the loop's lock, and a wake-up writes to it under that lock too: a
   late wake-up (a port opener's thread, a ``remove`` racing the end) finds it closed and does
   nothing, never raises and never writes to a descriptor number the process has reused.
5. Commands first: the workers whose mailbox is ready are served before the others in a round,
   and a worker with a stop (or lock ON) waiting is served next, even one that came while the
   round was under way: a stop never waits behind other rotators' replies, sky answers and
   status publishing, only behind the one worker being served when it came.
6. A round serves only the workers with something to do: a descriptor of theirs is ready, the
   time they asked to be woken at has come, or a stop waits (rule 5). The others are not
   called: with 16 rotators polled on one grid, most rounds concern a few of them.
7. Times that come within GATHER_S after the first one are met with it, at most GATHER_S
   late: the replies of one poll round come whole over a few milliseconds (each controller
   and adapter takes its own time), and are read in one wake-up, not one each. A worker also
   says how late its time may be met (``wants``' third value; its own time for all but a
   reply held in its port, worker.py rule 2): the wait ends at the last time that comes by
   the earliest of those plus GATHER_S, so a reply that came partly is read in the wake-up
   that takes the others' readings, not in one of its own. A descriptor that becomes ready
   (a stop in a mailbox) still ends the wait at once.
8. Rule 5's look for a stop among the workers not served yet is made before the first of a
   round, and again only when a stop or lock ON was put since the last look (mailbox.py rule
   11) or that look found one (there may be another): not one question to every worker after
   each one served. The look before a round's first is kept across rounds only when it asked
   every worker: a round starts without one when nothing was put since such a whole look
   found none (no worker joined since, and none of its looks found one), so a turning round
   of 16 asks 16 mailboxes only after a stop or lock ON. (A look after the first of a round
   skips the workers served before it, one of which may have a stop put meanwhile: it is
   never kept across rounds, and the next round looks at them all again.)
9. The wake-ups a round owes other threads (the MQTT network thread's, for the statuses it
   was handed) are given once, when the round ends (core/handoff.py): one wake-up for the
   statuses of 16 rotators, not 16. A stop's frame is not among them: it is written to its
   port as the worker is served.
10. The thread keeps one poller for its life: a worker's descriptors are registered when
   what it waits on changes (a reply held or read, a port opened or lost, the worker joining
   or leaving), not all of them anew at every wake-up, and then only the descriptors that
   changed (a held reply's port leaves, the mailbox stays); the poller waits on exactly the
   descriptors the workers asked for this round, each once however many ask for it.
"""

from __future__ import annotations

import logging
import math
import os
import select
import threading
import time
from collections.abc import Callable, Sequence
from collections.abc import Set as AbstractSet
from typing import Any, Protocol

from bridge.core import handoff
from bridge.session import mailbox
from bridge.session.config import WorkerConfig

__all__ = ["Lines"]

log = logging.getLogger(__name__)
_NOTHING: AbstractSet[int] = frozenset()
GATHER_S = 0.002  # rule 7
_READY = select.POLLIN | select.POLLPRI | select.POLLERR | select.POLLHUP | select.POLLNVAL


class Worker(Protocol):
    """What this loop asks of a worker: worker.py's, or a composite rotator's (composite.py)."""

    cfg: WorkerConfig

    def begin(self, now: float, wake: Callable[[], None]) -> None: ...
    def end(self, now: float) -> None: ...
    def wait_closed(self, timeout_s: float) -> bool: ...
    def has_commands(self, ready: set[int]) -> bool: ...
    def urgent(self) -> frozenset[int]: ...
    def wants(self, now: float) -> tuple[list[int], float, float]: ...
    def guarded(self, step: Callable[..., None], now: float, *args: Any) -> None: ...
    def serve(self, now: float, ready: set[int]) -> None: ...


def wake_at(wanted: Sequence[tuple[list[int], float, float]]) -> float:
    """Rule 7: when a round's wait ends, from what each worker ``wants`` (descriptors, the time
    to be woken at, how late that may be met); math.inf: only a descriptor ends it."""
    deadline = latest = math.inf
    for _, until, by in wanted:
        if until < deadline:
            deadline = until
        if by < latest:
            latest = by
    if deadline != math.inf:  # the times that come soon after it come with it
        gathered = max(deadline, latest) + GATHER_S
        for _, until, _ in wanted:
            if deadline < until <= gathered:
                deadline = until
    return deadline


class Lines:
    def __init__(self, clock: Callable[[], float] = time.monotonic) -> None:
        self._clock = clock
        self._lock = threading.Lock()
        self._workers: list[Worker] = []
        self._joining: list[Worker] = []
        self._leaving: dict[Worker, threading.Event] = {}
        self._thread: threading.Thread | None = None
        self._wake_r = self._wake_w = -1  # the wake pipe, open while the thread runs (rule 4)
        self._poller = select.poll()  # rule 10: the thread's, made afresh when it starts
        self._polled: dict[int, int] = {}  # descriptor -> how many workers wait on it
        self._watching: dict[Worker, list[int]] = {}  # what each waits on, as registered
        self._looked: int | None = None  # rule 8: mailbox.halts() at a whole look that found none

    # -- any thread (rule 4) --------------------------------------------------------------------
    def add(self, worker: Worker) -> None:
        """Serve ``worker`` from now on (the thread starts with the first one)."""
        with self._lock:
            if worker in self._joining or worker in self._workers or worker in self._leaving:
                raise ValueError(f"{worker.cfg.rotator_id}: already on the lines")
            self._joining.append(worker)
            if self._thread is None or not self._thread.is_alive():
                if self._wake_r < 0:  # (a thread that died of a bug left its pipe: kept)
                    self._wake_r, self._wake_w = os.pipe()
                    os.set_blocking(self._wake_r, False)
                    os.set_blocking(self._wake_w, False)
                self._thread = threading.Thread(target=self._run, name="serial-lines")
                self._thread.start()
        self._wake()

    def remove(self, worker: Worker, timeout_s: float = 3.0) -> bool:
        """Stop serving ``worker`` and close its port; True once it is served no more, its port
        closed or being closed (rule 4)."""
        deadline = time.monotonic() + timeout_s
        done = threading.Event()
        with self._lock:
            if worker in self._joining:
                self._joining.remove(worker)
                return True
            if worker not in self._workers or self._thread is None:
                return True
            done = self._leaving.setdefault(worker, done)  # a second remove() waits the same
        self._wake()
        if not done.wait(timeout_s):
            return False
        if not worker.wait_closed(max(0.0, deadline - time.monotonic())):
            log.warning(
                "%s: %s is still closing after %g s (a wedged adapter?); it closes on its own",
                worker.cfg.rotator_id,
                worker.cfg.shown_port,
                timeout_s,
            )
        return True

    def _wake(self) -> None:
        with self._lock:  # rule 4: never after the pipe closed
            if self._wake_w < 0:
                return  # no thread to wake
            try:
                os.write(self._wake_w, b"\0")
            except BlockingIOError:
                pass  # full: the loop is going to wake up anyway

    # -- the thread -----------------------------------------------------------------------------
    def _run(self) -> None:
        self._poller = select.poll()  # rule 10: this thread's, with this thread's wake pipe
        self._poller.register(self._wake_r, select.POLLIN)
        self._polled.clear()
        self._watching.clear()
        while self._membership():
            try:
                self._round()
            except Exception:  # a bug here, not in a worker (those are guarded): never a spin
                log.exception("unexpected error in the serial loop")
                time.sleep(0.1)

    def _membership(self) -> bool:
        """Take in joining workers, let leaving ones go; False when none is left."""
        with self._lock:
            joining, self._joining = self._joining, []
            leaving, self._leaving = self._leaving, {}
            self._workers.extend(joining)
            if joining:  # rule 8: a mailbox no look has asked yet
                self._looked = None
            for worker in leaving:
                self._workers.remove(worker)
                self._watch(worker, [])  # rule 10
                del self._watching[worker]
        for worker in joining:
            worker.guarded(worker.begin, self._clock(), self._wake)
        for worker, done in leaving.items():
            worker.guarded(worker.end, self._clock())
            done.set()
        with self._lock:
            if self._workers or self._joining:
                return True
            self._thread = None  # the next add() starts a new one
            os.close(self._wake_r)  # rule 4: this thread polls it no more
            os.close(self._wake_w)
            self._wake_r = self._wake_w = -1
            return False

    def _round(self) -> None:
        now = self._clock()
        workers = self._workers
        wanted = [worker.wants(now) for worker in workers]  # pure arithmetic: nothing to guard
        watching = self._watching
        for worker, (fds, _, _) in zip(workers, wanted, strict=True):
            if watching.get(worker) != fds:  # rule 10: registered only when it changes
                self._watch(worker, fds)
        deadline = wake_at(wanted)
        wait_ms = None if deadline == math.inf else max(0, math.ceil((deadline - now) * 1000))
        ready = {fd for fd, _ in self._poller.poll(wait_ms)}
        if ready and self._wake_r in ready:
            try:
                while os.read(self._wake_r, 4096):
                    pass
            except BlockingIOError:
                pass
        now = self._clock()
        if ready:  # rule 6
            due = [
                w
                for w, (fds, until, _) in zip(workers, wanted, strict=True)
                if now >= until or not ready.isdisjoint(fds)
            ]
            due.sort(key=lambda w: not w.has_commands(ready))  # rule 5
        else:
            due = [w for w, (_, until, _) in zip(workers, wanted, strict=True) if now >= until]
        if due:
            with handoff.batch():  # rule 9
                self._serve_round(due, ready)

    def _watch(self, worker: Worker, fds: list[int]) -> None:
        """Rule 10: the poller waits on ``fds`` for ``worker`` from now on, instead of what it
        waited on for it before; only what changed is told to the poller."""
        polled, poller = self._polled, self._poller
        before = self._watching.get(worker, ())
        now = list(dict.fromkeys(fds))  # each once (a copy: the worker may change its own)
        for fd in before:
            if fd in now:
                continue
            if polled[fd] == 1:
                del polled[fd]
                poller.unregister(fd)
            else:
                polled[fd] -= 1
        for fd in now:
            if fd in before:
                continue
            if fd in polled:
                polled[fd] += 1
            else:
                polled[fd] = 1
                poller.register(fd, _READY)
        self._watching[worker] = now

    def _serve_round(self, due: list[Worker], ready: set[int]) -> None:
        workers = self._workers
        served: set[Worker] = set()
        looked = self._looked  # rule 8: mailbox.halts() at a look that found none
        while due:
            # rule 5: a stop that came while this round served others goes next
            worker, urgent = due[0], _NOTHING
            halts = mailbox.halts()
            if halts != looked:  # (rule 8: none put since a look that found none)
                for other in workers:
                    if other not in served:
                        urgent = other.urgent()
                        if urgent:
                            worker = other
                            break
                looked = None if urgent else halts  # one found: there may be another
                if not served:  # (a whole look: kept for the next round's)
                    self._looked = looked
            if worker is due[0]:
                del due[0]
            elif worker in due:
                due.remove(worker)
            served.add(worker)
            # the clock read for each: a slow step (a burst of statuses to the listeners) must
            # not hand the next a stale time, or a query it writes looks overdue at once
            worker.guarded(worker.serve, self._clock(), ready | urgent if urgent else ready)
