"""Where the suite's CPU goes: each test's CPU-seconds, its own process and its children's,
recorded when ROTOR_TEST_CPU names a file (off otherwise), and a report of the top consumers.

    ROTOR_TEST_CPU=/tmp/cpu.jsonl .venv/bin/python -m pytest tests/x -n 2
    .venv/bin/python -m tests.support.cpu /tmp/cpu.jsonl        # by file, fixture, test

Rules:
1. A test's cost is the change of ``getrusage`` (user + system, RUSAGE_SELF + RUSAGE_CHILDREN)
   over its setup, call and teardown, each phase apart. A child's CPU is counted when it is
   reaped: a broker stopped in the test's teardown is the test's; one a session fixture keeps
   is charged to the test whose teardown ends the session (shown as such, never lost).
2. RUSAGE_SELF counts every thread of the worker: a thread a test left running is charged to
   the tests after it (a cost worth finding too).
3. Each xdist worker appends to ``<file>.<worker>``, one JSON line per test; the report reads
   them all. Nothing here changes what a test does.
"""

from __future__ import annotations

import json
import os
import resource
import sys
import threading
from collections import defaultdict
from collections.abc import Generator, Iterable
from pathlib import Path
from typing import Any

import pytest

ENV = "ROTOR_TEST_CPU"


def _children_s() -> float:
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return kids.ru_utime + kids.ru_stime


def _cpu_s() -> float:
    own = resource.getrusage(resource.RUSAGE_SELF)
    return own.ru_utime + own.ru_stime + _children_s()


def _open_fds() -> int:
    try:
        return len(os.listdir("/proc/self/fd"))
    except OSError:
        return -1


class CpuRecorder:
    """The pytest plugin (rule 3): registered by tests/conftest.py when ROTOR_TEST_CPU is set."""

    def __init__(self, path: str) -> None:
        worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
        self.path = Path(f"{path}.{worker}")
        self.phases: dict[str, float] = {}
        self.failed: list[str] = []

    def _timed(self, phase: str) -> Generator[None, Any, Any]:
        before = _cpu_s()
        try:
            return (yield)
        finally:
            self.phases[phase] = _cpu_s() - before

    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_setup(self, item: pytest.Item) -> Generator[None, Any, None]:
        yield from self._timed("setup")

    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_call(self, item: pytest.Item) -> Generator[None, Any, None]:
        yield from self._timed("call")

    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_teardown(self, item: pytest.Item) -> Generator[None, Any, None]:
        yield from self._timed("teardown")

    def pytest_runtest_logreport(self, report: pytest.TestReport) -> None:
        if report.failed:
            self.failed.append(report.when)

    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_protocol(self, item: pytest.Item) -> Generator[None, Any, None]:
        self.phases = {}
        self.failed = []
        children = _children_s()
        yield
        record = {
            "test": item.nodeid,
            "file": item.nodeid.split("::")[0],
            "fixtures": sorted(getattr(item, "fixturenames", ())),
            **{k: round(v, 4) for k, v in self.phases.items()},
            "children": round(_children_s() - children, 4),  # of the three phases' sum
            "failed": self.failed,  # the phases that failed: a cost is read beside its outcome
            # what the worker holds after the test: a count that only grows is a leak
            "fds": _open_fds(),
            "threads": threading.active_count(),
        }
        with self.path.open("a") as out:
            out.write(json.dumps(record) + "\n")


def register(config: pytest.Config) -> None:
    path = os.environ.get(ENV, "").strip()
    if path:
        config.pluginmanager.register(CpuRecorder(path), "rotor-cpu")


def _records(base: Path) -> Iterable[dict[str, Any]]:
    for f in sorted(base.parent.glob(base.name + ".*")):
        for line in f.read_text().splitlines():
            yield {**json.loads(line), "worker": f.suffix}


def report(base: Path, top: int = 25) -> str:
    by_file: dict[str, list[float]] = defaultdict(lambda: [0.0, 0, 0.0])
    by_fixture: dict[str, list[float]] = defaultdict(lambda: [0.0, 0, 0.0])
    tests: list[tuple[float, str]] = []
    total = children = 0.0
    fds_before: dict[str, int] = {}  # a worker's open descriptors after its last test
    fds_grown: dict[str, int] = defaultdict(int)  # by file: descriptors its tests left open
    for r in _records(base):
        cost = r.get("setup", 0.0) + r.get("call", 0.0) + r.get("teardown", 0.0)
        total += cost
        by_file[r["file"]][0] += cost
        by_file[r["file"]][1] += 1
        by_file[r["file"]][2] += r.get("children", 0.0)
        children += r.get("children", 0.0)
        for name in r["fixtures"]:
            by_fixture[name][0] += cost
            by_fixture[name][1] += 1
            by_fixture[name][2] += r.get("children", 0.0)
        tests.append((cost, r["test"]))
        held = r.get("fds", -1)
        if held >= 0 and r["worker"] in fds_before:
            fds_grown[r["file"]] += held - fds_before[r["worker"]]
        fds_before[r["worker"]] = held
    lines = [
        f"{len(tests)} tests, {total:.1f} CPU-s in the tests (workers + their children), "
        f"{children:.1f} of it in child processes"
    ]

    def table(title: str, rows: dict[str, list[float]]) -> None:
        lines.append(f"\n{title}: CPU-s, tests, CPU-s per test, CPU-s in child processes")
        for name, (cost, n, kids) in sorted(rows.items(), key=lambda kv: -kv[1][0])[:top]:
            kept = f"{kids:8.1f}" if kids else ""
            lines.append(f"{cost:8.1f} {int(n):5d} {cost / n:6.2f}{kept}  {name}")

    table("by file", by_file)
    table("by fixture (a test counts for each fixture it uses)", by_fixture)
    leaks = [(n, f) for f, n in fds_grown.items() if n > 0]
    lines.append("\nfiles whose tests left descriptors open in the worker: descriptors")
    lines.extend(f"{n:8d}  {f}" for n, f in sorted(leaks, reverse=True)[:top])
    lines.append("\ntests: CPU-s")
    lines.extend(f"{cost:8.2f}  {name}" for cost, name in sorted(tests, reverse=True)[:top])
    return "\n".join(lines)


if __name__ == "__main__":
    print(report(Path(sys.argv[1]), int(sys.argv[2]) if len(sys.argv) > 2 else 25))
