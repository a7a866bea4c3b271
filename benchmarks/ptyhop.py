"""The host's own pty hop, measured beside a benchmark: how long a byte written to a pty takes
to reach the reader on the other side, on this machine, now.

Why: the bridge's serial port in a benchmark is a pty, and a pty hands written bytes to its
reader from a kernel worker thread (the tty flip buffer's work on the unbound workqueue, at
nice 0). On a busy machine that worker waits for a CPU behind every other program: tens of ms
at times, while a pipe written at the same moment is read within 0.05 ms. A real serial
adapter takes the byte in the writer's own system call; the hop is the host's, not the
bridge's, and a stop measured to the controller's frame includes it. This probe says how large
it was while a load ran, beside the load's stops.

    python -m benchmarks.ptyhop OUT    # until its input ends; then OUT: [[t, seconds], ...]

Rules:
1. One thread, no interpreter lock shared with anything: every delay it sees is the kernel's
   (the worker waiting for a CPU) or this process's own wait for one (it runs at the priority
   its parent gave it: harness rule 5, as the controllers).
2. One byte every PERIOD_S, the next only after the last was read; ``t`` is when it was
   written (time.monotonic, the benchmarks' clock).
"""

from __future__ import annotations

import json
import os
import select
import subprocess
import sys
import time
import tty
from pathlib import Path

from benchmarks.harness import PYTHON, Scope
from benchmarks.report import percentile

PERIOD_S = 0.005


def main(out: str) -> None:
    master, slave = os.openpty()
    for fd in (master, slave):
        tty.setraw(fd)
    samples: list[tuple[float, float]] = []
    while True:
        t = time.monotonic()
        os.write(slave, b";")
        select.select([master], [], [], 5.0)
        samples.append((t, time.monotonic() - t))
        os.read(master, 64)
        ready, _, _ = select.select([sys.stdin], [], [], PERIOD_S)
        if ready and not sys.stdin.readline():
            break
    Path(out).write_text(json.dumps(samples))


class PtyHop:
    """The probe as a process of its own in ``scope``; ``finish`` ends it and keeps its samples,
    ``between(t0, t1)`` says the hop's p99 and max (ms) over that time."""

    def __init__(self, scope: Scope) -> None:
        self.out = scope.workdir / "ptyhop.json"
        argv = [PYTHON, "-m", "benchmarks.ptyhop", str(self.out)]
        self.proc = scope.spawn(argv, log_name="ptyhop.log", stdin=subprocess.PIPE, hardware=True)
        self.samples: list[tuple[float, float]] = []

    def finish(self, timeout_s: float = 10.0) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.close()
        self.proc.wait(timeout_s)
        if self.out.exists():
            self.samples = [(t, d) for t, d in json.loads(self.out.read_text())]

    def between(self, t0: float, t1: float) -> tuple[float, float] | None:
        ms = sorted(d * 1000.0 for t, d in self.samples if t0 <= t <= t1)
        return (percentile(ms, 99), ms[-1]) if ms else None


if __name__ == "__main__":
    main(sys.argv[1])
