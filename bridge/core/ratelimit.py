"""A token bucket: a burst at once, then a steady rate. Pure: the time is handed in.

Rules:
1. A bucket starts full (``burst`` tokens) and refills at ``rate_per_s`` up to ``burst``,
   never beyond: a quiet spell buys one burst, not more.
2. ``take`` spends one token if there is one; a refusal costs nothing.
3. A ``Budget`` is a bucket that may go into debt: what a reader read and ran is charged after
   it ran, and the reader waits (``wait_s``) until it is in credit again; it holds a second's
   worth at most (docs/architecture.md, "Why no front end can starve a stop").
4. ``SourceBudgets`` give every source (a UDP sender's address and port) a budget of its own,
   asked before the work (``allow``) and charged after it (``spend``), so that one sender's
   flood never uses up another's; a debt is held to a second's worth (a sender that paid for
   a flood is in credit again a second after it ends). A source's budget and the budget of
   all of them together must both be in credit: a flood spread over many source ports buys
   no more than ``total_per_s``. At most ``max_sources`` are remembered, the least recently
   heard forgotten first (a source that comes back starts with a second's worth again).
   ``in_credit`` asks whether a source's own budget is in credit, and changes nothing.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Hashable
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


@dataclass
class _Account:
    tokens: float
    t: float

    def refill(self, rate_per_s: float, now: float) -> None:
        gained = max(0.0, now - self.t) * rate_per_s
        self.tokens = min(rate_per_s, self.tokens + gained)
        self.t = now


class SourceBudgets:
    """Rule 4. Pure: the time is handed in."""

    def __init__(
        self, per_source_s: float, total_per_s: float, max_sources: int, now: float
    ) -> None:
        self.per_source_s = per_source_s
        self.total_per_s = total_per_s
        self._max = max_sources
        self._total = _Account(total_per_s, now)
        self._sources: OrderedDict[Hashable, _Account] = OrderedDict()

    def allow(self, source: Hashable, now: float) -> bool:
        """Whether ``source`` may have its work done now (else: drop it)."""
        self._total.refill(self.total_per_s, now)
        account = self._account(source, now)
        return account.tokens > 0 and self._total.tokens > 0

    def allow_own(self, source: Hashable, now: float) -> bool:
        """Whether ``source`` may have its work done now within its own budget alone, whatever
        the others' together have spent (a sender a caller keeps room for: spent as any)."""
        return self._account(source, now).tokens > 0

    def in_credit(self, source: Hashable, now: float) -> bool:
        """Whether ``source``'s own budget is in credit now (one not remembered is: it would
        start with a second's worth); asks only, remembers and forgets nothing."""
        account = self._sources.get(source)
        if account is None:
            return True
        gained = max(0.0, now - account.t) * self.per_source_s
        return min(self.per_source_s, account.tokens + gained) > 0

    def spend(self, source: Hashable, cost: float, now: float) -> None:
        """Charge the work done for ``source`` (its debt held to a second's worth)."""
        for account, rate in (
            (self._account(source, now), self.per_source_s),
            (self._total, self.total_per_s),
        ):
            account.refill(rate, now)
            account.tokens = max(-rate, account.tokens - cost)

    def _account(self, source: Hashable, now: float) -> _Account:
        account = self._sources.get(source)
        if account is None:
            if len(self._sources) >= self._max:
                self._sources.popitem(last=False)
            account = self._sources[source] = _Account(self.per_source_s, now)
        else:
            self._sources.move_to_end(source)
            account.refill(self.per_source_s, now)
        return account

    def __len__(self) -> int:
        return len(self._sources)
