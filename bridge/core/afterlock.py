"""A lock whose holder's wake-ups wait until it has let go: the stop and lock words' lock
(interfaces/mqtt/halts.py) around a rotator's owner steps (runtime/kept.py rule 5).

Rules:
1. ``Deferring`` is a plain lock (not re-entrant). While a thread holds one or more of them,
   ``later`` keeps the calls it is given (each once, in order) instead of making them; they
   are made on that thread once the outermost has let go. Without one held, ``later`` calls at
   once.
2. What is put off is a wake-up (a byte on a pipe, a thread started): each can give the
   interpreter lock away for milliseconds, and a stop or lock ON waiting for the lock must not
   wait for that too.
3. One put-off call that raises does not cost the others: it is logged and the rest are
   still made (a lost wake-up would leave a thread asleep until its next timed wake).
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable

log = logging.getLogger(__name__)
_held = threading.local()  # this thread's Deferring locks held, and the calls put off


class Deferring:
    """Rule 1."""

    def __init__(self) -> None:
        self._lock = threading.Lock()

    def __enter__(self) -> None:
        self._lock.acquire()
        _held.depth = getattr(_held, "depth", 0) + 1

    def locked(self) -> bool:
        return self._lock.locked()

    def __exit__(self, *exc: object) -> None:
        _held.depth -= 1
        calls: list[Callable[[], None]] = []
        if _held.depth == 0:
            calls, _held.calls = getattr(_held, "calls", []), []
        self._lock.release()
        for call in calls:
            try:
                call()
            except Exception:  # rule 3: the calls after it are still made
                log.exception("a call put off until a lock was let go failed")


def later(call: Callable[[], None]) -> None:
    """Rule 1: ``call`` now, or once this thread's outermost Deferring lock has let go."""
    if not getattr(_held, "depth", 0):
        call()
        return
    calls: list[Callable[[], None]] = _held.__dict__.setdefault("calls", [])
    if call not in calls:
        calls.append(call)
