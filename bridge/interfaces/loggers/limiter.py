"""PST replies, rate-limited per address: a spoofed query makes us send to its victim, so no
address gets more than a few replies a second, whoever asks. Pure: a clock in, a decision out.

Rules:
1. One token bucket per address a reply goes to (the sender's IP; every reply goes to its
   port + 1): REPLY_BURST at once, then REPLY_RATE_PER_S. A reply beyond that is dropped and
   counted (``dropped``), never queued: a poller (Hamlib, QLog: one ``AZ?``/``EL?`` a second)
   stays well inside it.
2. At most MAX_SOURCES addresses are remembered; a new one beyond that makes the least
   recently used one forgotten (it starts full again if it comes back). A flood of spoofed
   addresses costs a bounded table, and a datagram gets at most one reply per kind of query
   (AZ?, EL?: datagrams.py), so replies never outnumber the queries that asked.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable

from bridge.core.ratelimit import TokenBucket

REPLY_BURST = 10
REPLY_RATE_PER_S = 5.0
MAX_SOURCES = 1024


class ReplyLimiter:
    def __init__(
        self,
        clock: Callable[[], float],
        burst: int = REPLY_BURST,
        rate_per_s: float = REPLY_RATE_PER_S,
        max_sources: int = MAX_SOURCES,
    ) -> None:
        self._clock = clock
        self._burst = burst
        self._rate = rate_per_s
        self._max = max_sources
        self._buckets: OrderedDict[str, TokenBucket] = OrderedDict()
        self.dropped = 0

    def allow(self, address: str) -> bool:
        """Rule 1: whether a reply may go to ``address`` now (False: drop it, counted)."""
        now = self._clock()
        bucket = self._buckets.get(address)
        if bucket is None:
            if len(self._buckets) >= self._max:  # rule 2
                self._buckets.popitem(last=False)
            bucket = self._buckets[address] = TokenBucket.full(self._burst, self._rate, now)
        else:
            self._buckets.move_to_end(address)
        if bucket.take(now):
            return True
        self.dropped += 1
        return False

    def __len__(self) -> int:
        return len(self._buckets)
