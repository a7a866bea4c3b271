"""A stand-in for a worker of runtime/lines.py (its ``Worker`` protocol): what a test worker
does not care about (its start, its end, its port's close, its guard) done as nothing, so that
a test's worker says only what it is for."""

from __future__ import annotations

from collections.abc import Callable


class StandInWorker:
    def begin(self, now: float, wake: Callable[[], None]) -> None:
        pass

    def end(self, now: float) -> None:
        pass

    def wait_closed(self, timeout_s: float) -> bool:
        return True

    def guarded(self, step: Callable[..., object], *args: object) -> None:
        step(*args)
