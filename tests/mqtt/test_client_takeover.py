"""Rule 7 of bridge/mqtt/client.py in virtual time: two bridges with one client id back off
instead of fighting; anything else keeps paho's quick reconnects. (Two real processes on a real
broker: tests/faults/test_broker.py.)"""

from __future__ import annotations

from bridge.mqtt.client import (
    FLAP_COUNT,
    STABLE_S,
    TAKEOVER_FIRST_S,
    TAKEOVER_MAX_S,
    TakeoverGuard,
)


def test_a_takeover_backs_off_doubling_up_to_a_minute() -> None:
    g = TakeoverGuard()
    now = 0.0
    delays = []
    for _ in range(7):
        g.connected(now)
        now += 1.0
        assert g.disconnected(now, "taken over")
        delays.append(g.backoff_s)
        now += g.backoff_s
    assert delays == [TAKEOVER_FIRST_S, 10, 20, 40, TAKEOVER_MAX_S, TAKEOVER_MAX_S, TAKEOVER_MAX_S]


def test_a_connection_that_lasts_ends_the_episode() -> None:
    g = TakeoverGuard()
    g.connected(0.0)
    assert g.disconnected(1.0, "taken over")
    g.reported = True
    g.connected(10.0)
    assert g.disconnected(10.0 + TAKEOVER_MAX_S + 1, "other")  # still fighting
    g.connected(100.0)
    assert not g.disconnected(100.0 + STABLE_S, "dropped")  # a broker crash, much later
    assert (g.backoff_s, g.reported) == (0, False)
    g.connected(1000.0)
    assert g.disconnected(1001.0, "taken over")  # a new episode is reported again
    assert (g.backoff_s, g.reported) == (TAKEOVER_FIRST_S, False)


def test_without_a_reason_code_repeated_drops_count_as_a_takeover() -> None:
    """Both sides of the fight: the one kicked at once, and the one kicked after the other's
    growing back-off (its connections last longer, but never STABLE_S)."""
    for lasted in ([1.0] * FLAP_COUNT, [1.0, TAKEOVER_FIRST_S, STABLE_S - 1][:FLAP_COUNT]):
        g = TakeoverGuard()
        now = 0.0
        verdicts = []
        for seconds in lasted:
            g.connected(now)
            now += seconds
            verdicts.append(g.disconnected(now, "dropped"))
            now += 1.0
        assert verdicts == [False] * (FLAP_COUNT - 1) + [True], lasted
        assert g.backoff_s == TAKEOVER_FIRST_S


def test_a_broker_that_goes_away_in_between_is_no_takeover() -> None:
    g = TakeoverGuard()
    now = 0.0
    for _ in range(3 * FLAP_COUNT):
        g.connected(now)
        now += 1.0
        assert not g.disconnected(now, "dropped")
        g.connect_failed()  # refused or unreachable: the broker restarts
        now += 2.0
    assert g.backoff_s == 0


def test_keepalive_timeouts_and_other_reasons_are_no_evidence() -> None:
    g = TakeoverGuard()
    now = 0.0
    for i in range(3 * FLAP_COUNT):
        g.connected(now)
        now += 1.0
        assert not g.disconnected(now, "other" if i % (FLAP_COUNT - 1) == 0 else "dropped")
        now += 1.0
    assert g.backoff_s == 0


def simulate_two_bridges(minutes: float, v5: bool) -> tuple[list[float], list[float]]:
    """Two bridges with one client id on one broker: each accepted connection kicks the other.

    paho's side: a kicked bridge waits its back-off (1 s, paho's minimum, outside an episode)
    and connects again; the broker accepts every connection. Returns the connect times.
    """
    guards = [TakeoverGuard(), TakeoverGuard()]
    due = [0.0, 0.4]  # the second one starts a little later
    holder: int | None = None
    connects: list[list[float]] = [[], []]
    end = minutes * 60
    while min(due) < end:
        who = 0 if due[0] <= due[1] else 1
        now = due[who]
        due[who] = float("inf")
        if holder is not None:  # the broker drops the older connection
            g = guards[holder]
            if g.disconnected(now, "taken over" if v5 else "dropped"):
                due[holder] = now + g.backoff_s
            else:
                due[holder] = now + 1.0
        guards[who].connected(now)
        connects[who].append(now)
        holder = who
    return connects[0], connects[1]


def per_window(times: list[float], start: float, end: float, width_s: int = 60) -> list[int]:
    """Connections in every window of width_s (5 s apart) between start and end."""
    stops = range(int(start), int(end) - width_s + 1, 5)
    return [sum(1 for t in times if w <= t < w + width_s) for w in stops]


def test_two_bridges_with_one_client_id_make_a_bounded_number_of_connections() -> None:
    for v5 in (True, False):
        a, b = simulate_two_bridges(10, v5)
        for mine in (a, b):
            # neither spins: a handful in the first minute, then at most one a minute ...
            assert max(per_window(mine, 0, 60)) <= 6, (v5, a, b)
            assert max(per_window(mine, 120, 600)) <= 1, (v5, a, b)
            # ... and neither gives up: they take turns, one connection each in two minutes
            assert min(per_window(mine, 120, 600, width_s=2 * TAKEOVER_MAX_S + 1)) >= 1, (v5, a, b)
