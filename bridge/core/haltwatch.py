"""Those told just before a rotator counts a halt (a STOP or a lock ON), from whichever thread
brought it: the TCP front ends' and the console's look at what each connection has sent by
then (interfaces/tcplines.py rule 9, interfaces/web/looks.py).

Rules:
1. ``HaltWatchers()`` is called by the owner of a halt count (session/mailbox.py, the remote's
   rotator) right before it counts a halt, outside its own lock: every watcher added is called
   in turn, on that thread. What a watcher sees of the count is the count before this halt (or
   a later one, if another thread's halt came between: that errs toward refusing).
2. A watcher that raises is logged (once per kind of error, at most every 10 s) and the others
   are still called; the halt is counted however they fare. A watcher must be quick and must
   not count a halt itself.
3. ``add`` and ``remove`` may be called from any thread; a call that is under way goes on with
   the watchers it began with.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable

__all__ = ["HaltWatchers"]

log = logging.getLogger(__name__)
_LOG_S = 10.0  # rule 2


class HaltWatchers:
    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._each: tuple[Callable[[], None], ...] = ()
        self._logged: dict[type, float] = {}  # rule 2: when each kind of error was last said

    def add(self, watcher: Callable[[], None]) -> None:
        with self._lock:
            self._each = (*self._each, watcher)

    def remove(self, watcher: Callable[[], None]) -> None:
        with self._lock:
            self._each = tuple(w for w in self._each if w is not watcher)

    def __call__(self) -> None:
        """Rule 1 (the tuple read once: rule 3)."""
        for watcher in self._each:
            try:
                watcher()
            except Exception as exc:  # rule 2: the halt is counted all the same
                now = time.monotonic()
                with self._lock:
                    said = self._logged.get(type(exc), -_LOG_S)
                    if now - said < _LOG_S:
                        continue
                    self._logged[type(exc)] = now
                log.exception("a look before a halt failed (the halt is counted): %s", exc)
