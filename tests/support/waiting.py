"""Waiting on a condition with a deadline: the one polling loop of the tests and benchmarks,
and the one factor every deadline of the tests is scaled by.

Rules:
1. A deadline is how long a test waits for what must come (a message, a reply, a process's
   end); it is never what the test asserts. Every deadline in tests/ is ``slow(seconds)`` or
   goes through a helper that applies it (``wait_until``, the probe's waits, the rig's, the
   demo's, ``run_cli``, hamlib.py's ``rotctl_argv`` with Hamlib's own read timeout), so one
   environment variable, ROTOR_TEST_SLOWDOWN (default 1, at least 1), lengthens them all on a
   busy machine; ./tests/run sets it from the machine's load.
2. A quiet period (how long nothing must come, to say that nothing came) is not a deadline and
   is not scaled: made longer it could reach a timer of the bridge that is meant to fire later.
3. A scaled deadline costs nothing when the test passes: the wait ends at the first answer.
4. The load can grow after the suite starts (a second suite beside it): when ./tests/run chose
   the factor itself it says so (ROTOR_TEST_SLOWDOWN_FOLLOW=1), and each deadline is then
   scaled by the larger of that factor and the one the load gives at the moment it is taken.
   A factor the user set (ROTOR_TEST_SLOWDOWN) is used as it is.
"""

from __future__ import annotations

import math
import os
import threading
import time
from collections.abc import Callable
from typing import Any

MAX_SLOWDOWN = 10.0


def _slowdown() -> float:
    """ROTOR_TEST_SLOWDOWN as a number from 1 to MAX_SLOWDOWN (rule 1); 1 when unset."""
    text = os.environ.get("ROTOR_TEST_SLOWDOWN", "").strip()
    try:
        factor = float(text) if text else 1.0
    except ValueError:
        raise RuntimeError(f"ROTOR_TEST_SLOWDOWN={text!r} is not a number") from None
    if math.isnan(factor):
        return 1.0
    return min(max(factor, 1.0), MAX_SLOWDOWN)


SLOWDOWN = _slowdown()
# rule 4: set by ./tests/run when it chose the factor itself (ROTOR_TEST_SLOWDOWN unset)
FOLLOW = os.environ.get("ROTOR_TEST_SLOWDOWN_FOLLOW", "") == "1"
LIVE_MAX = 4.0  # the load's factor at most (as ./tests/run's)
_live: tuple[float, float] = (-math.inf, 1.0)  # (read at, factor)


def _live_factor() -> float:
    """1 + the 1-minute load per core, at most LIVE_MAX, read at most once a second."""
    global _live
    now = time.monotonic()
    if now - _live[0] >= 1.0:
        try:
            load = os.getloadavg()[0]
        except OSError:
            load = 0.0
        _live = (now, min(LIVE_MAX, 1.0 + load / max(1, len(os.sched_getaffinity(0)))))
    return _live[1]


def factor() -> float:
    """The factor now (rules 1 and 4)."""
    return max(SLOWDOWN, _live_factor()) if FOLLOW else SLOWDOWN


def slow(seconds: float) -> float:
    """A deadline of ``seconds`` on a quiet machine, as long as this machine needs (rule 1)."""
    return seconds * factor()


def slow_ms(milliseconds: float) -> float:
    """``slow`` for the APIs that count in milliseconds (Playwright)."""
    return milliseconds * factor()


def wait_until(
    predicate: Callable[[], Any],
    timeout_s: float = 10.0,
    what: str = "",
    interval_s: float = 0.01,
    *,
    error: type[Exception] = AssertionError,
) -> Any:
    """The first true value of ``predicate()``, asked every ``interval_s``; ``error`` (a failed
    test by default; the benchmarks raise their own) when ``slow(timeout_s)`` passes without
    one."""
    deadline = time.monotonic() + slow(timeout_s)
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() > deadline:
            raise error(f"timed out after {slow(timeout_s):g} s waiting for {what or predicate}")
        time.sleep(interval_s)


def refusal_beside_a_fifo(fifo: os.PathLike[str], call: Callable[[], Any], error: type) -> str:
    """What ``call`` raises (an ``error``) with a FIFO nobody writes at ``fifo`` it reads
    (core/readfile.py rule 1: no open may wait for a writer): run on a thread of its own and
    waited for; a call still blocked in its open is let go by a writer's open, whatever
    happens."""
    said: list[str] = []

    def run() -> None:
        try:
            call()
        except error as exc:
            said.append(str(exc))

    runner = threading.Thread(target=run, daemon=True)
    runner.start()
    try:
        wait_until(lambda: said, 5, "the reader to answer")
    finally:
        try:
            os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
        except OSError:  # (ENXIO: no reader left: nothing to let go)
            pass
        runner.join()
    return said[0]
