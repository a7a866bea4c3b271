"""The tests' one factor for deadlines (tests/support/waiting.py): read from the environment,
kept sane, and applied by wait_until."""

from __future__ import annotations

import os
import time

import pytest

from tests.support import waiting


@pytest.mark.parametrize(
    ("given", "factor"),
    [
        (None, 1.0),
        ("", 1.0),
        ("2.5", 2.5),
        ("0.3", 1.0),
        ("1e9", waiting.MAX_SLOWDOWN),
        ("nan", 1.0),
    ],
)
def test_the_factor_comes_from_the_environment_at_least_1_and_capped(
    monkeypatch: pytest.MonkeyPatch, given: str | None, factor: float
) -> None:
    if given is None:
        monkeypatch.delenv("ROTOR_TEST_SLOWDOWN", raising=False)
    else:
        monkeypatch.setenv("ROTOR_TEST_SLOWDOWN", given)
    assert waiting._slowdown() == factor


def test_a_factor_that_is_no_number_is_an_error_not_a_guess(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setenv("ROTOR_TEST_SLOWDOWN", "busy")
    with pytest.raises(RuntimeError, match="ROTOR_TEST_SLOWDOWN='busy' is not a number"):
        waiting._slowdown()


def test_wait_until_waits_the_scaled_deadline(monkeypatch: pytest.MonkeyPatch) -> None:
    """A lower bound only: the wait lasted at least the scaled deadline before it gave up."""
    monkeypatch.setattr(waiting, "SLOWDOWN", 4.0)
    assert waiting.slow(0.5) == 2.0 and waiting.slow_ms(5_000) == 20_000
    started = time.monotonic()
    with pytest.raises(AssertionError, match=r"timed out after 0.2 s waiting for nothing"):
        waiting.wait_until(lambda: False, 0.05, "nothing")
    assert time.monotonic() - started >= 0.2


def test_the_factor_follows_the_load_when_tests_run_chose_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """waiting.py rule 4: a suite started on a quiet machine (factor 1) gets longer deadlines
    once a second suite loads the machine; never shorter than the factor it started with, never
    more than LIVE_MAX from the load; a factor the user chose is kept as it is."""
    cores = len(os.sched_getaffinity(0))
    load = [0.0]
    monkeypatch.setattr(waiting.os, "getloadavg", lambda: (load[0], 0.0, 0.0))
    monkeypatch.setattr(waiting, "SLOWDOWN", 1.5)
    monkeypatch.setattr(waiting, "FOLLOW", True)

    def factor_at(one_minute_load: float) -> float:
        load[0] = one_minute_load
        monkeypatch.setattr(waiting, "_live", (-float("inf"), 1.0))  # read it again now
        return waiting.slow(1.0)

    assert factor_at(0.0) == 1.5  # the factor it started with
    assert factor_at(2.0 * cores) == 3.0  # 1 + 2 a core
    assert factor_at(50.0 * cores) == waiting.LIVE_MAX
    assert waiting.slow_ms(1_000) == waiting.LIVE_MAX * 1_000
    monkeypatch.setattr(waiting, "FOLLOW", False)
    assert factor_at(50.0 * cores) == 1.5  # the user's own
