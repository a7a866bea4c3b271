"""A token bucket: a burst at once, then a steady rate. Pure: the time is handed in.

Rules:
1. A bucket starts full (``burst`` tokens) and refills at ``rate_per_s`` up to ``burst``,
   never beyond: a quiet spell buys one burst, not more.
2. ``take`` spends one token if there is one; a refusal costs nothing.
3. A ``Budget`` is a bucket that may go into debt: what a reader read and ran is charged after
   it ran, and the reader waits (``wait_s``) until it is in credit again; it holds a second's
   worth at most (docs/architecture.md, "Why no front end can starve a stop").
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass
class TokenBucket:
    burst: float
    rate_per_s: float
    tokens: float
    t: float  # when ``tokens`` was counted

    @classmethod
    def full(cls, burst: float, rate_per_s: float, now: float) -> TokenBucket:
        return cls(burst, rate_per_s, burst, now)

    def take(self, now: float) -> bool:
        """Rule 2: whether one more may go now."""
        self.tokens = min(self.burst, self.tokens + max(0.0, now - self.t) * self.rate_per_s)
        self.t = now
        if self.tokens < 1.0:
            return False
        self.tokens -= 1.0
        return True


class Budget:
    """Rule 3. Pure: the time is handed in."""

    def __init__(self, rate_per_s: float, now: float) -> None:
        self.rate_per_s = rate_per_s
        self._tokens = rate_per_s  # a second's worth at once
        self._t = now

    def spend(self, cost: float, now: float) -> None:
        self._refill(now)
        self._tokens -= cost

    def wait_s(self, now: float) -> float:
        """How long until the client is in credit again (0: read it now)."""
        self._refill(now)
        return 0.0 if self._tokens > 0 else (1.0 - self._tokens) / self.rate_per_s

    def _refill(self, now: float) -> None:
        gained = max(0.0, now - self._t) * self.rate_per_s
        self._tokens = min(self.rate_per_s, self._tokens + gained)
        self._t = now
