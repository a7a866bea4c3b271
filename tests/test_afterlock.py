"""core/afterlock.py: the calls a lock's holder put off are all made once it lets go."""

from __future__ import annotations

import logging

import pytest

from bridge.core.afterlock import Deferring, later


def test_a_put_off_call_that_raises_does_not_cost_the_ones_after_it(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """Rule 3: a wake-up put off behind one that fails is still made (a lost wake-up would
    leave the lines thread asleep until its next timed wake); the failure is logged."""
    made: list[str] = []

    def fails() -> None:
        made.append("fails")
        raise RuntimeError("pipe closed")

    lock = Deferring()
    with caplog.at_level(logging.ERROR, logger="bridge.core.afterlock"), lock:
        later(fails)
        later(lambda: made.append("wake"))
        assert made == []  # put off while the lock is held
    assert made == ["fails", "wake"]
    assert "pipe closed" in caplog.text
    later(lambda: made.append("after"))  # nothing left over: the next call is made at once
    assert made == ["fails", "wake", "after"]
