"""A token bucket: a burst at once, then a steady rate. Pure: the time is handed in.

Rules:
1. A bucket starts full (``burst`` tokens) and refills at ``rate_per_s`` up to ``burst``,
   never beyond: a quiet spell buys one burst, not more.
2. ``take`` spends one token if there is one; a refusal costs nothing.
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
