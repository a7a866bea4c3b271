"""The PST replies' rate limit (bridge/interfaces/loggers/limiter.py), in virtual time: a spoofed
query makes the bridge send to its victim, so one address gets a burst and then a few a second."""

from __future__ import annotations

from bridge.interfaces.loggers.limiter import ReplyLimiter
from tests.support.clock import FakeClock as Clock


def test_a_burst_then_the_rate_and_the_rest_dropped_and_counted() -> None:
    clock = Clock()
    lim = ReplyLimiter(clock, burst=10, rate_per_s=5.0)
    assert [lim.allow("10.0.0.9") for _ in range(12)] == [True] * 10 + [False] * 2
    clock.t += 0.2  # one token back
    assert [lim.allow("10.0.0.9") for _ in range(2)] == [True, False]
    clock.t += 60.0  # a quiet minute refills to the burst, never beyond
    assert sum(lim.allow("10.0.0.9") for _ in range(20)) == 10
    assert lim.dropped == 2 + 1 + 10


def test_a_poller_once_a_second_is_never_dropped() -> None:
    """Hamlib and QLog ask AZ? and EL? once a second: two replies a second, for an hour."""
    clock = Clock()
    lim = ReplyLimiter(clock)
    for _ in range(3600):
        assert lim.allow("127.0.0.1") and lim.allow("127.0.0.1")
        clock.t += 1.0
    assert lim.dropped == 0


def test_each_address_has_its_own_bucket() -> None:
    clock = Clock()
    lim = ReplyLimiter(clock, burst=2, rate_per_s=1.0)
    assert [lim.allow("victim") for _ in range(3)] == [True, True, False]
    assert lim.allow("poller")  # the victim's flood costs nobody else a reply


def test_a_flood_of_spoofed_addresses_keeps_a_bounded_table() -> None:
    clock = Clock()
    lim = ReplyLimiter(clock, burst=2, rate_per_s=1.0, max_sources=100)
    assert all(lim.allow(f"10.0.{i // 256}.{i % 256}") for i in range(10_000))
    assert len(lim) == 100
    # the one most recently used is still remembered, the first long forgotten
    assert lim.allow("10.0.39.15") and not lim.allow("10.0.39.15")
    assert lim.allow("10.0.0.0") and lim.allow("10.0.0.0")
