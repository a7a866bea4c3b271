"""Readings of another process from /proc: CPU time, RSS, PSS; a sampler for peaks."""

from __future__ import annotations

import contextlib
import os
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass

from benchmarks.harness import BenchError


def _status_kb(pid: int, key: str) -> int:
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith(key + ":"):
                return int(line.split()[1])
    raise BenchError(f"{key} not in /proc/{pid}/status")


def rss_bytes(pid: int) -> int:
    return _status_kb(pid, "VmRSS") * 1024


def pss_bytes(pid: int) -> int:
    """Proportional set size: shared library pages divided among the processes that map them."""
    try:
        with open(f"/proc/{pid}/smaps_rollup") as f:
            for line in f:
                if line.startswith("Pss:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return rss_bytes(pid)


def cpu_seconds(pid: int) -> float:
    """CPU time of all live threads, from schedstat (ns resolution); falls back to ticks."""
    total_ns = 0
    try:
        for tid in os.listdir(f"/proc/{pid}/task"):
            with contextlib.suppress(OSError), open(f"/proc/{pid}/task/{tid}/schedstat") as f:
                total_ns += int(f.read().split()[0])
        if total_ns:
            return total_ns / 1e9
    except OSError:
        pass
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def children(pid: int) -> list[int]:
    """The live processes ``pid``'s threads started (each thread's children, from /proc)."""
    out: list[int] = []
    with contextlib.suppress(OSError):
        for tid in os.listdir(f"/proc/{pid}/task"):
            with contextlib.suppress(OSError), open(f"/proc/{pid}/task/{tid}/children") as f:
                out += [int(k) for k in f.read().split()]
    return out


def reaped_cpu_seconds(pid: int) -> float:
    """CPU time of the processes ``pid`` started that ended and were reaped (its ``cutime`` and
    ``cstime``: theirs and their own reaped children's), in clock ticks' resolution."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[13]) + int(fields[14])) / os.sysconf("SC_CLK_TCK")


def tree_cpu_seconds(pid: int) -> float:
    """CPU time of ``pid`` and of every process under it, alive or ended and reaped: the
    bridge's cost with the stop express's child (interfaces/mqtt/express.py rule 1), a second
    interpreter of its own, and the children before it (a restarted express: review 154)."""
    total = cpu_seconds(pid)
    with contextlib.suppress(OSError, IndexError, ValueError):
        total += reaped_cpu_seconds(pid)
    for kid in children(pid):
        with contextlib.suppress(OSError, BenchError):
            total += tree_cpu_seconds(kid)
    return total


@dataclass
class Usage:
    cpu_pct: float  # % of one core over the window
    rss_mb: float  # at the end of the window (sum over pids)
    pss_mb: float
    window_s: float


def measure_usage(
    pids: Sequence[int], window_s: float, stop: threading.Event | None = None
) -> Usage:
    c0 = sum(cpu_seconds(p) for p in pids)
    t0 = time.monotonic()
    if stop is None:
        time.sleep(window_s)
    else:
        stop.wait(window_s)
    c1 = sum(cpu_seconds(p) for p in pids)
    elapsed = time.monotonic() - t0
    rss = sum(rss_bytes(p) for p in pids)
    pss = sum(pss_bytes(p) for p in pids)
    return Usage(100.0 * (c1 - c0) / elapsed, rss / 2**20, pss / 2**20, elapsed)


class RssSampler:
    """Samples one process's RSS in a thread (for peaks during a burst)."""

    def __init__(self, pid: int, interval_s: float = 0.01) -> None:
        self.pid = pid
        self.samples: list[tuple[float, int]] = []
        self._stop = threading.Event()
        self._interval_s = interval_s
        self._thread = threading.Thread(target=self._run, daemon=True, name="rss-sampler")
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.is_set():
            with contextlib.suppress(OSError, BenchError):
                self.samples.append((time.monotonic(), rss_bytes(self.pid)))
            self._stop.wait(self._interval_s)

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(2)

    def between(self, t0: float, t1: float) -> list[int]:
        return [v for t, v in self.samples if t0 <= t <= t1]
