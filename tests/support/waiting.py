"""Waiting on a condition with a deadline: the one polling loop of the tests and benchmarks."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any


def wait_until(
    predicate: Callable[[], Any],
    timeout_s: float = 10.0,
    what: str = "",
    interval_s: float = 0.01,
    *,
    error: type[Exception] = AssertionError,
) -> Any:
    """The first true value of ``predicate()``, asked every ``interval_s``; ``error`` (a failed
    test by default; the benchmarks raise their own) when ``timeout_s`` passes without one."""
    deadline = time.monotonic() + timeout_s
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() > deadline:
            raise error(f"timed out after {timeout_s:g} s waiting for {what or predicate}")
        time.sleep(interval_s)
