"""A thread's round of hand-offs: wake-ups of other threads owed during a round, given once
at its end.

The serial-lines thread serves every rotator in rounds (runtime/lines.py); a round of 16
turning rotors hands the MQTT network thread 16 statuses. Waking that thread for each one (a
system call here, a wake-up and a round of its loop there, and the two threads taking the
interpreter lock from each other in between) cost more than the statuses themselves. Inside a
round the wake-ups are owed instead and given once when it ends.

Rules:
1. ``batch()`` marks the calling thread's round; ``defer(key, wake)`` inside it owes ``wake``
   (once per key, however often it is owed) and returns True; outside a round, or on another
   thread, it returns False and the caller wakes at once. Nothing but wake-ups goes here: what
   is owed only tells another thread to look at what was already handed to it.
2. A round's wake-ups are given when it ends, however it ends (an exception included), in the
   order first owed; one that raises is logged and the others are still given.
3. Rounds do not nest: a ``batch()`` inside one is part of the outer one.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable, Hashable

__all__ = ["batch", "defer"]

log = logging.getLogger(__name__)
_local = threading.local()


class _Round:
    """Rule 2: one ``batch()``; a plain context manager, not a generator's (a round is entered
    at every wake-up of the serial-lines thread)."""

    __slots__ = ("_outer",)

    def __init__(self) -> None:
        self._outer = False

    def __enter__(self) -> None:
        if getattr(_local, "owed", None) is not None:  # rule 3
            return
        self._outer = True
        _local.owed = {}

    def __exit__(self, *exc: object) -> None:
        if not self._outer:
            return
        owed: dict[Hashable, Callable[[], None]] = _local.owed
        _local.owed = None
        for wake in owed.values():
            try:
                wake()
            except Exception:
                log.exception("a wake-up owed at the end of a round failed")


def batch() -> _Round:
    """Rule 2: the calling thread's wake-ups owed until this ends, then given once each."""
    return _Round()


def defer(key: Hashable, wake: Callable[[], None]) -> bool:
    """Rule 1: True if ``wake`` is owed to the end of this thread's round."""
    owed: dict[Hashable, Callable[[], None]] | None = getattr(_local, "owed", None)
    if owed is None:
        return False
    owed.setdefault(key, wake)
    return True
