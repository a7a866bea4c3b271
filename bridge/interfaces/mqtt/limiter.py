"""Error events, rate-limited per rotator (``R/error``), so a flood of refusals cannot crowd out
state or grow the broker's queue. Pure: a clock in, a decision out.

Rules:
1. A token bucket per topic: a burst at once, then a steady rate (``mqtt.error_events_per_s``);
   what comes beyond that is not published, only counted.
2. The next event that is published says how many were left out since the last one
   (``suppressed`` in its JSON, and in its message), so nothing is lost without a trace.
3. A flood leaves nothing behind: a count per topic, no queue.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass

from bridge.core.ratelimit import TokenBucket

BURST = 50
RATE_PER_S = 10.0


@dataclass
class _Bucket:
    bucket: TokenBucket
    suppressed: int = 0


class EventLimiter:
    def __init__(
        self, clock: Callable[[], float], burst: int = BURST, rate_per_s: float = RATE_PER_S
    ):
        self._clock = clock
        self._burst = burst
        self._rate = rate_per_s
        self._lock = threading.Lock()  # events come from the lines, paho's and rotctld's threads
        self._buckets: dict[str, _Bucket] = {}

    def admit(self, topic: str) -> int | None:
        """None: leave this event out (rule 1); else how many were left out before it."""
        now = self._clock()
        with self._lock:
            b = self._buckets.get(topic)
            if b is None:
                b = self._buckets[topic] = _Bucket(TokenBucket.full(self._burst, self._rate, now))
            if not b.bucket.take(now):
                b.suppressed += 1
                return None
            left_out, b.suppressed = b.suppressed, 0
            return left_out
