"""ratelimit.SourceBudgets (rule 4), in virtual time: the time is handed in."""

from __future__ import annotations

from bridge.core.ratelimit import SourceBudgets


def test_one_senders_flood_leaves_anothers_budget_whole() -> None:
    budgets = SourceBudgets(10.0, 100.0, 8, now=0.0)
    while budgets.allow("flood", 0.0):
        budgets.spend("flood", 1.0, 0.0)
    budgets.spend("flood", 1.0, 0.0)  # one datagram into debt
    assert budgets.allow("other", 0.0)
    assert not budgets.allow("flood", 0.05)  # 0.5 of a token back: still in debt
    assert budgets.allow("flood", 0.2)


def test_a_debt_is_held_to_a_seconds_worth() -> None:
    budgets = SourceBudgets(10.0, 1000.0, 8, now=0.0)
    for _ in range(500):  # what is charged whatever the budget (a stop)
        budgets.spend("stops", 1.0, 0.0)
    assert not budgets.allow("stops", 0.9)
    assert budgets.allow("stops", 1.01)


def test_many_source_ports_buy_no_more_than_the_total() -> None:
    budgets = SourceBudgets(10.0, 30.0, 1000, now=0.0)
    served = 0
    for port in range(100):
        if budgets.allow(("127.0.0.1", port), 0.0):
            budgets.spend(("127.0.0.1", port), 1.0, 0.0)
            served += 1
    assert served == 30


def test_at_most_max_sources_are_remembered_the_oldest_forgotten() -> None:
    budgets = SourceBudgets(1.0, 1000.0, 3, now=0.0)
    for source in "abcd":
        budgets.spend(source, 5.0, 0.0)
    assert len(budgets) == 3
    assert budgets.allow("a", 0.0)  # forgotten: a second's worth again
    assert not budgets.allow("d", 0.0)


def test_in_credit_asks_and_changes_nothing() -> None:
    budgets = SourceBudgets(10.0, 1000.0, 2, now=0.0)
    budgets.spend("flood", 15.0, 0.0)  # half a second into debt
    budgets.spend("other", 1.0, 0.0)
    assert not budgets.in_credit("flood", 0.4)
    assert budgets.in_credit("flood", 0.6)
    assert budgets.in_credit("never heard", 0.0)  # (it would start with a second's worth)
    assert len(budgets) == 2  # nothing remembered for it, nothing forgotten
    assert not budgets.allow("flood", 0.4)  # the debt left as it was by the questions
