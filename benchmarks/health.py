"""Item health: what rotor health (bridge/session/health.py) costs per poll exchange.

    python -m benchmarks health [--quick]

Health runs on the serial-lines thread, inside the session, after every input: the question is
whether it makes the lines thread's work per poll any dearer. So this item measures exactly
that work, in this process: a Rotor-EZ session against its emulator in virtual time
(tests/engine/virtual.py, the scenario tests' bench), turning back and forth, and the CPU time
(``time.process_time_ns``) spent inside the session's own calls (readings, ticks, commands),
divided by the poll replies it took. The same run is made with health in place and with its
step replaced by nothing, alternating, several rounds each: the spread between rounds of one
kind is the noise the difference is judged against.

Also measured: the cost of one report (the judgement after each move, not per poll).
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable
from typing import Any

from benchmarks.harness import Scope
from benchmarks.report import ItemResult, Table, Verdict
from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

MOVES = 6  # per round: back and forth, 280 deg each at the emulator's 6 deg/s


class Timed:
    """The session's calls, timed (CPU time of this thread's process), and health's step
    inside them."""

    def __init__(self, v: VirtualRotator, with_health: bool, inside: bool) -> None:
        self.ns = 0
        self.health_ns = 0
        self.readings = 0
        session = v.session
        for name in ("bytes_received", "tick", "commands"):
            setattr(session, name, self._wrap(getattr(session, name), name == "bytes_received"))
        if inside:  # perf_counter: a process clock is a system call, dearer than the step
            step = session.health.step

            def timed_step(m: Any, now: float) -> Any:
                t0 = time.perf_counter_ns()
                out = step(m, now)
                self.health_ns += time.perf_counter_ns() - t0
                return out

            session.health.step = timed_step  # type: ignore[method-assign]
        elif not with_health:
            session.health.step = lambda m, now: None  # type: ignore[method-assign]

    def _wrap(self, call: Callable[..., Any], reading: bool) -> Callable[..., Any]:
        def timed(*args: Any) -> Any:
            t0 = time.process_time_ns()
            out = call(*args)
            self.ns += time.process_time_ns() - t0
            if reading and out:
                self.readings += 1
            return out

        return timed


def one_round(with_health: bool, inside: bool = False) -> tuple[float, float, int]:
    """µs of session CPU per poll reply, of it in health's step (``inside``: timed, in a round
    of its own, not compared), and the replies counted."""
    with VirtualRotator("rotorez", emulator={"start_az_deg": 20.0}) as v:
        v.run_until_state(MotionState.IDLE, 30)
        timed = Timed(v, with_health, inside)
        for i in range(MOVES):
            v.target(300 if i % 2 == 0 else 20)
            v.run_until(lambda h: h.truth().is_moving, 30)
            v.run_until(lambda h: h.state is MotionState.IDLE, 120)
        n = max(1, timed.readings)
        return timed.ns / 1000 / n, timed.health_ns / 1000 / n, timed.readings


def report_cost_us() -> float:
    """One report after a move: health_judge's medians and warnings, built once per move."""
    with VirtualRotator("rotorez", emulator={"start_az_deg": 20.0}) as v:
        v.run_until_state(MotionState.IDLE, 30)
        for i in range(12):
            v.target(300 if i % 2 == 0 else 20)
            v.run_until(lambda h: h.truth().is_moving, 30)
            v.run_until(lambda h: h.state is MotionState.IDLE, 120)
        judge = v.session.health._judge
        n = 2000
        t0 = time.process_time_ns()
        for _ in range(n):
            judge.report()
        return (time.process_time_ns() - t0) / 1000 / n


def _iqr(values: list[float]) -> float:
    q = statistics.quantiles(values, n=4) if len(values) >= 2 else [0.0, 0.0, 0.0]
    return q[2] - q[0]


def run(scope: Scope, quick: bool) -> ItemResult:
    rounds = 3 if quick else 15
    result = ItemResult("health", "Rotor health's cost per poll (the session's CPU time)")
    per: dict[bool, list[float]] = {True: [], False: []}
    own: list[float] = []
    replies = 0
    for i in range(rounds):
        for with_health in (False, True) if i % 2 == 0 else (True, False):
            us, _, replies = one_round(with_health)
            per[with_health].append(us)
        own.append(one_round(True, inside=True)[1])
    table = Table(
        f"session CPU per poll reply, µs ({rounds} rounds each, {MOVES} moves and {replies} "
        "replies per round, alternating)",
        ["health", "median", "min", "max", "IQR"],
    )
    for with_health in (False, True):
        values = per[with_health]
        table.add(
            "on" if with_health else "off (step replaced)",
            f"{statistics.median(values):.2f}",
            f"{min(values):.2f}",
            f"{max(values):.2f}",
            f"{_iqr(values):.2f}",
        )
    report_us = report_cost_us()
    inside = statistics.median(own)
    table.notes.append(f"inside health's step (timed in rounds of their own): {inside:.2f} µs/poll")
    table.notes.append(f"one report (after each move, not per poll): {report_us:.0f} µs")
    result.tables.append(table)
    on, off = statistics.median(per[True]), statistics.median(per[False])
    noise = max(_iqr(v) for v in per.values())
    result.verdicts.append(
        Verdict(
            "CPU per poll unchanged within noise",
            f"{on - off:+.2f} µs per poll ({100 * (on - off) / off:+.1f} %), "
            f"noise (IQR) {noise:.2f} µs",
            abs(on - off) <= noise,
        )
    )
    result.verdicts.append(
        Verdict(
            "health's own step under 5 % of the per-poll CPU",
            f"{inside:.2f} µs of {off:.2f} µs ({100 * inside / off:.1f} %)",
            inside < 0.05 * off,
        )
    )
    result.data = {
        "per_poll_us": {"on": per[True], "off": per[False]},
        "health_step_us_per_poll": own,
        "report_us": report_us,
        "replies_per_round": replies,
    }
    return result
