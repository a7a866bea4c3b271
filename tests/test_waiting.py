"""The tests' one factor for deadlines (tests/support/waiting.py): read from the environment,
kept sane, and applied by wait_until."""

from __future__ import annotations

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
