"""core/handoff.py: the wake-ups a thread owes during a round are given once, when it ends; and
the serial-lines thread's round is such a round (lines.py rule 9)."""

from __future__ import annotations

import logging
import math
import threading
from collections.abc import Callable
from types import SimpleNamespace

import pytest

from bridge.core import handoff
from bridge.runtime.lines import Lines
from tests.support.waiting import slow
from tests.support.workers import StandInWorker


def test_outside_a_round_nothing_is_owed() -> None:
    calls: list[str] = []
    assert handoff.defer("k", lambda: calls.append("k")) is False
    assert calls == []  # the caller wakes at once itself


def test_a_rounds_wake_ups_are_given_once_each_at_its_end_in_the_order_first_owed() -> None:
    calls: list[str] = []
    with handoff.batch():
        for key in ("a", "b", "a", "a", "b"):
            assert handoff.defer(key, lambda key=key: calls.append(key)) is True
        assert calls == []
    assert calls == ["a", "b"]
    assert handoff.defer("a", lambda: calls.append("late")) is False  # the round is over


def test_a_round_that_raises_still_gives_what_it_owes() -> None:
    calls: list[str] = []
    with pytest.raises(RuntimeError), handoff.batch():
        handoff.defer("a", lambda: calls.append("a"))
        raise RuntimeError("a bug in the round")
    assert calls == ["a"]


def test_a_wake_up_that_raises_is_logged_and_the_others_are_given(
    caplog: pytest.LogCaptureFixture,
) -> None:
    calls: list[str] = []

    def broken() -> None:
        raise OSError("closed")

    with caplog.at_level(logging.ERROR, logger="bridge.core.handoff"), handoff.batch():
        handoff.defer("broken", broken)
        handoff.defer("b", lambda: calls.append("b"))
    assert calls == ["b"]
    assert "a wake-up owed at the end of a round failed" in caplog.text


def test_a_round_inside_a_round_is_part_of_the_outer_one() -> None:
    calls: list[str] = []
    with handoff.batch():
        with handoff.batch():
            handoff.defer("a", lambda: calls.append("a"))
        assert calls == []
    assert calls == ["a"]


def test_another_threads_wake_up_is_not_owed_to_this_threads_round() -> None:
    calls: list[str] = []
    answers: list[bool] = []
    with handoff.batch():
        t = threading.Thread(target=lambda: answers.append(handoff.defer("x", lambda: None)))
        t.start()
        t.join()
        handoff.defer("a", lambda: calls.append("a"))
    assert answers == [False]
    assert calls == ["a"]


class RoundWorker(StandInWorker):
    """A worker of lines.py's protocol that is due once (at once) and whose serve runs ``job``."""

    def __init__(
        self, name: str, job: Callable[[], None], go: threading.Event, last: bool = False
    ) -> None:
        self.cfg = SimpleNamespace(rotator_id=name, port=name)
        self.job = job
        # both on the lines before either is due: one round serves both (the last to join
        # sets it, on the lines thread as it joins, before that round asks what each wants;
        # no clock: a busy machine once let the first be served alone, before the second came)
        self.go, self.last = go, last
        self.served = threading.Event()

    def begin(self, now: float, wake: Callable[[], None]) -> None:
        if self.last:
            self.go.set()

    def has_commands(self, ready: set[int]) -> bool:
        return False

    def urgent(self) -> frozenset[int]:
        return frozenset()

    def wants(self, now: float) -> tuple[list[int], float, float]:
        if self.served.is_set():
            return [], math.inf, math.inf
        due = 0.0 if self.go.is_set() else math.inf
        return [], due, due

    def serve(self, now: float, ready: set[int]) -> None:
        self.job()
        self.served.set()


def test_the_lines_round_wakes_the_network_thread_once_after_serving_every_rotator_due() -> None:
    """lines.py rule 9: the statuses of every rotator a round served cost one wake-up, given
    when the round ends, not one per rotator as it is served."""
    wakes: list[str] = []
    seen_by_second: list[list[str]] = []
    given = threading.Event()

    def wake() -> None:
        wakes.append("net")
        given.set()

    def hand_off() -> None:  # a status handed to the MQTT client, as paho_client.py does it
        if not handoff.defer("net", wake):
            wake()

    def second() -> None:
        hand_off()
        seen_by_second.append(list(wakes))

    go = threading.Event()
    a, b = RoundWorker("a", hand_off, go), RoundWorker("b", second, go, last=True)
    lines = Lines()
    lines.add(a)
    lines.add(b)
    try:
        assert given.wait(slow(10)), "the owed wake-up was never given"
        assert a.served.is_set() and b.served.is_set()
        assert seen_by_second == [[]]  # not woken between the two
        assert wakes == ["net"]  # once for both
    finally:
        lines.remove(a)
        lines.remove(b)
