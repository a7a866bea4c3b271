"""A clock that stands still until a test moves it: virtual time for pure code that is handed
a ``clock`` (a callable returning seconds)."""

from __future__ import annotations


class FakeClock:
    def __init__(self, t: float = 100.0) -> None:
        self.t = t

    def __call__(self) -> float:
        return self.t
