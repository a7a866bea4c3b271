"""A thread that runs jobs in the order given, started by the first one and ended after a
quiet spell: the sky worker's and the state file's writer (skywork.py, state_store.py).

Rules:
1. ``put`` never blocks and may be called from any thread; jobs run one at a time, in order.
2. A job that raises is logged; the thread goes on with the next.
3. The thread ends after ``idle_s`` without a job and starts again with the next ``put``: no
   job is ever left in the queue with no thread to run it (the check and the end are one step
   under the lock ``put`` takes).
4. ``queue`` puts a job in line without starting the thread, for a caller under a lock of its
   own (starting a thread waits until it runs, milliseconds on a busy machine); it calls
   ``wake`` once it has let go, and rule 3 holds again from then on.
"""

from __future__ import annotations

import logging
import queue
import threading
from collections.abc import Callable

log = logging.getLogger(__name__)


class OnDemandThread:
    def __init__(self, name: str, idle_s: float = 30.0) -> None:
        self._name = name
        self._idle_s = idle_s
        self._jobs: queue.SimpleQueue[Callable[[], None]] = queue.SimpleQueue()
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None

    def put(self, job: Callable[[], None]) -> None:
        self.queue(job)
        self.wake()

    def queue(self, job: Callable[[], None]) -> None:
        """Rule 4: in line, in order; ``wake`` starts the thread if none runs."""
        self._jobs.put(job)

    def wake(self) -> None:
        """Rule 4: a thread for the jobs in line, if none runs (nothing in line: none)."""
        with self._lock:
            if self._thread is None and not self._jobs.empty():
                self._thread = threading.Thread(target=self._run, name=self._name, daemon=True)
                self._thread.start()

    def _run(self) -> None:
        while True:
            try:
                job = self._jobs.get(timeout=self._idle_s)
            except queue.Empty:
                with self._lock:  # rule 3
                    if self._jobs.empty():
                        self._thread = None
                        return
                continue
            try:
                job()
            except Exception:  # rule 2
                log.exception("%s: a job failed", self._name)
