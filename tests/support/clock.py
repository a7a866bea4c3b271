"""A clock that stands still until a test moves it: virtual time for pure code that is handed
a ``clock`` (a callable returning seconds)."""

from __future__ import annotations

import time


class FakeClock:
    def __init__(self, t: float = 100.0) -> None:
        self.t = t

    def __call__(self) -> float:
        return self.t


DAY_UNIX = 20454 * 86400.0  # 2026-01-01T00:00:00Z: the day of the tests' DX cluster spots


def wall_at(hhmm: str) -> float:
    """The unix time of ``hhmm`` (UTC) on DAY_UNIX: a bridge's wall clock at which a spot of
    that time is live (interfaces/dxcluster/book.py rule 2: a spot's age is by its own time,
    the day the bridge's), so a test's spots are the same whatever time of day it runs."""
    return DAY_UNIX + int(hhmm[:2]) * 3600.0 + int(hhmm[2:]) * 60.0


class RunningWall:
    """A wall clock that reads ``hhmm`` of DAY_UNIX when made and goes on as the monotonic
    clock does: for a bridge or a DX cluster client running in real time (tests/support/rig.py
    ``Rig.wall``)."""

    def __init__(self, hhmm: str) -> None:
        self._start = wall_at(hhmm)
        self._t0 = time.monotonic()

    def __call__(self) -> float:
        return self._start + time.monotonic() - self._t0
