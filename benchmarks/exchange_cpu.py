"""Item exchange_cpu: the bridge's CPU time per poll exchange, 16 Rotor-EZ turning.

    python -m benchmarks exchange_cpu [--quick]

Set-up: one bridge process (the service as a user runs it: defaults, Home Assistant discovery
on) with 16 emulated Rotor-EZ controllers behind paced lines at 4800 baud (rig.many_rotators).
Every rotor is turned from its front panel (no command), so the bridge polls each at its moving
rate (0.2 s) and publishes the bearing after every reply. The emulators transmit their replies
as a real UART would: each byte when its time on the line is over, one write per byte (the
"bytes per reply write" column shows it).

Measured over a fixed window, several times: the bridge process's CPU time (every thread, from
/proc: procfs.cpu_seconds) divided by the poll exchanges completed in the window (the `AI1;`
frames the controllers logged: the ground truth, each answered). The MQTT and Home Assistant work
a reading causes is part of the cost; a reading is what an exchange is for.
"""

from __future__ import annotations

import contextlib
import os
import time
from typing import Any

from benchmarks.harness import Scope
from benchmarks.procfs import cpu_seconds
from benchmarks.report import ItemResult, Table, Verdict, percentile
from benchmarks.rig import Rig, many_rotators

MODEL = "rotorez"
COUNT = 16
POLL = b"AI1;"
TARGET_MS = 0.2
#: every rotor still turns at the end of the last window (0 -> 350 deg: 87 s; 6 deg/s default),
#: and fast enough that every poll sees it move (at 2 deg/s some polls saw no change)
SPEED_DEG_S = 4.0


class WriteCounter:
    """Counts the controller's non-empty transmissions and their bytes (wraps its sans-IO device:
    what the pty thread writes, one os.write per non-empty due_output)."""

    def __init__(self, port: Any) -> None:
        self.writes = 0
        self.bytes = 0
        with port.lock:
            dev = port.device
            due_output = dev.due_output

            def counted(now: float) -> bytes:
                out: bytes = due_output(now)
                if out:
                    self.writes += 1
                    self.bytes += len(out)
                return out

            dev.due_output = counted


def thread_seconds(pid: int) -> dict[str, float]:
    """CPU time of each live thread of ``pid`` (schedstat), by thread id."""
    out = {}
    for tid in os.listdir(f"/proc/{pid}/task"):
        with contextlib.suppress(OSError), open(f"/proc/{pid}/task/{tid}/schedstat") as f:
            out[tid] = int(f.read().split()[0]) / 1e9
    return out


def _polls_between(rig: Rig, t0: float, t1: float) -> int:
    return sum(
        1
        for line in rig.lines.values()
        for f in line.frames.since(0)
        if f.data == POLL and t0 <= f.time_s < t1
    )


def measure(scope: Scope, windows: int, window_s: float) -> dict[str, Any]:
    specs = [(f"r{i}", MODEL, {"speed_deg_s": SPEED_DEG_S}, {}) for i in range(COUNT)]
    with many_rotators(scope, "exchange-cpu", specs, wait_online_s=60) as rig:
        topics = [rig.t(rid, "state") for rid in rig.lines]
        rig.mqtt.wait_all(topics, "idle", 60)  # past the brake window assumed at start-up
        counters = [WriteCounter(line.emu) for line in rig.lines.values()]
        for line in rig.lines.values():
            line.emu.manual_rotate(350.0)
        rig.mqtt.wait_all(topics, "moving", 30)
        time.sleep(1.0)  # polling at the moving rate
        pid = rig.bridge.pid
        runs = []
        for _ in range(windows):
            c0, t0, th0 = cpu_seconds(pid), time.monotonic(), thread_seconds(pid)
            time.sleep(window_s)
            c1, t1, th1 = cpu_seconds(pid), time.monotonic(), thread_seconds(pid)
            busiest = sorted((th1[t] - th0[t] for t in th1 if t in th0), reverse=True)[:2]
            polls = _polls_between(rig, t0, t1)
            if polls == 0:
                raise RuntimeError("no poll exchange in the window")
            runs.append(
                {
                    "cpu_s": c1 - c0,
                    "window_s": t1 - t0,
                    "exchanges": polls,
                    "ms_per_exchange": (c1 - c0) / polls * 1000,
                    "cpu_pct": 100 * (c1 - c0) / (t1 - t0),
                    "busiest_threads_ms": [b / polls * 1000 for b in busiest],
                }
            )
        turning = sum(1 for line in rig.lines.values() if line.emu.state().is_moving)
        if turning < COUNT:
            raise RuntimeError(f"only {turning} of {COUNT} rotors still turned at the end")
        writes = sum(c.writes for c in counters)
        sent = sum(c.bytes for c in counters)
    return {"runs": runs, "bytes_per_write": sent / writes if writes else float("nan")}


def run(scope: Scope, quick: bool) -> ItemResult:
    windows, window_s = (3, 5.0) if quick else (6, 10.0)
    result = ItemResult("exchange_cpu", "CPU per poll exchange (16 Rotor-EZ turning)")
    m = measure(scope, windows, window_s)
    runs = m["runs"]
    table = Table(
        f"{result.title}: {windows} windows of {window_s:g} s",
        ["window", "exchanges", "exchanges/s", "CPU %", "CPU ms/exchange", "1st thread", "2nd"],
    )
    for i, r in enumerate(runs, start=1):
        table.add(
            i,
            r["exchanges"],
            f"{r['exchanges'] / r['window_s']:.1f}",
            f"{r['cpu_pct']:.2f}",
            f"{r['ms_per_exchange']:.3f}",
            *(f"{ms:.3f}" for ms in (r["busiest_threads_ms"] + [0.0, 0.0])[:2]),
        )
    values = sorted(r["ms_per_exchange"] for r in runs)
    median = percentile(values, 50)
    table.notes += [
        f"CPU: the bridge process, every thread (/proc schedstat); exchanges: `AI1;` frames the "
        f"controllers logged. Median {median:.3f} ms, range {values[0]:.3f}-{values[-1]:.3f} ms.",
        f"Replies as a UART sends them: {m['bytes_per_write']:.2f} bytes per reply write.",
        "1st / 2nd thread: the two busiest threads' share, ms per exchange (the serial lines' "
        "thread, then paho's network thread).",
    ]
    result.tables.append(table)
    result.data = {"runs": runs, "median_ms": median, "bytes_per_write": m["bytes_per_write"]}
    result.verdicts.append(
        Verdict(
            f"CPU per poll exchange at most {TARGET_MS} ms",
            f"median {median:.3f} ms (range {values[0]:.3f}-{values[-1]:.3f})",
            median <= TARGET_MS,
        )
    )
    return result
