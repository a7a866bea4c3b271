"""A halt's place in line across two connections (mqtt/fence.py), pure."""

from __future__ import annotations

from bridge.mqtt.fence import MATCH_S, Fence


def test_the_first_copy_of_a_halt_is_carried_out_and_the_other_dropped() -> None:
    f = Fence()
    assert f.halt("r", "stop", lane=True, now=0.0)
    assert f.holds("r", 0.1)  # a target read now on the main connection came before the stop
    assert not f.halt("r", "stop", lane=False, now=0.2)  # the main connection's copy
    assert not f.holds("r", 0.3)  # a target after it is obeyed
    assert f.halt("r", "stop", lane=False, now=1.0)  # the lane down: the main copy comes first
    assert not f.holds("r", 1.1)
    assert not f.halt("r", "stop", lane=True, now=1.2)


def test_copies_pair_up_oldest_first_and_one_that_never_comes_is_not_waited_for() -> None:
    f = Fence()
    assert f.halt("r", "stop", True, 0.0) and f.halt("r", "stop", True, 0.5)
    assert not f.halt("r", "stop", False, 1.0)
    assert f.holds("r", 1.0)  # the second stop's copy is still owed
    assert not f.halt("r", "stop", False, 1.5)
    assert not f.holds("r", 1.6)
    assert f.halt("r", "lock", True, 2.0)  # the main connection lost this copy
    assert f.holds("r", 2.0 + MATCH_S - 0.1) and not f.holds("r", 2.0 + MATCH_S + 0.1)
    assert f.halt("r", "stop", False, 20.0)  # the other connection's copies are per kind
    assert not f.holds("other", 20.0)
