"""The floor under exchange_cpu: what a poll exchange costs a process that does nothing but the
exchange and its publishing (benchmarks/floor_engine.py), beside the bridge of this tree and an
older engine, taking turns, in one run.

    python -m benchmarks.floor [--quick] [--against COMMIT] [--rounds N] [--variants V,...]

The scenario is exchange_cpu's: 16 emulated Rotor-EZ in this process behind paced lines at
4800 baud (benchmarks/rig.py's open_line; replies a byte at a time, as a UART sends them), each
turned from its front panel at SPEED_DEG_S, a private mosquitto, a recording client on
``rotor/#``. The bridges run exchange_cpu's own round (exchange_cpu.one_round: the bridge as a
user runs it, Home Assistant discovery on); the floor's engines run the same lines and broker
with a round of their own here: CPU seconds of the engine's process (every thread, /proc) over
a window of 16 turning, divided by the ``AI1;`` frames the controllers logged in it. The
engines take turns, round by round, so all meet the same machine; every round carries the load
average at its end. The floor's variants (VARIANTS): paho driven from the one thread or on its
own (``loop_start``), replies read by pyserial or ``os.read``, a status per reading or none.

Rules:
1. Nothing of the bridge runs in the floor's engine; it shares with the bridge only what the
   scenario needs (the lines, the broker, paho, pyserial).
2. A floor round that did not see every rotor still turning at its end, or no exchange, is an
   error, as in exchange_cpu.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Any

from benchmarks.engines import engine_at, engine_spawner
from benchmarks.exchange_cpu import (
    COUNT,
    EXCHANGE_BASE,
    MODEL,
    POLL,
    SPEED_DEG_S,
    one_round,
    thread_seconds,
    wakeups,
)
from benchmarks.harness import PYTHON, BenchError, Mqtt, Scope, check_abort, start_broker
from benchmarks.line import FrameLog
from benchmarks.procfs import cpu_seconds
from benchmarks.report import Table, percentile
from benchmarks.rig import TOPIC, open_line
from tests.support.process import Spawn

#: the floor's engines: their options (floor_engine.py's command line)
VARIANTS: dict[str, list[str]] = {
    "floor": ["--paho", "inline", "--read", "os", "--status", "on"],
    "floor-paho-thread": ["--paho", "thread", "--read", "os", "--status", "on"],
    "floor-pyserial": ["--paho", "inline", "--read", "pyserial", "--status", "on"],
    "floor-no-status": ["--paho", "inline", "--read", "os", "--status", "off"],
    "floor-no-mqtt": ["--mqtt", "off"],
    "floor-bytes": ["--gather", "bytes"],
    "floor-gather-20ms": ["--gather-ms", "20"],
    "floor-4-idle-wakes": ["--extra-wakes", "4"],
    "floor-paho-thread-pyserial": [
        "--paho",
        "thread",
        "--read",
        "pyserial",
        "--status",
        "on",
    ],
}
NEW = "this tree"


def floor_round(scope: Scope, name: str, options: list[str], window_s: float) -> dict[str, Any]:
    """One floor engine, started afresh on 16 turning Rotor-EZ: its CPU per exchange."""
    with Scope(scope.workdir / name) as s:
        port = start_broker(s)
        mqtt = Mqtt(port, [f"{TOPIC}/#"], name=f"rec-{name}")
        s.callback(mqtt.close)
        lines = {}
        for i in range(COUNT):
            rid = f"r{i}"
            frames = FrameLog()
            emu, _relay, path = open_line(
                s, MODEL, frames, {"speed_deg_s": SPEED_DEG_S}, name=f"tty-{rid}"
            )
            lines[rid] = (emu, frames, path)
        argv = [PYTHON, "-m", "benchmarks.floor_engine", "--port", str(port), "--base", TOPIC]
        argv += ["--client-id", f"floor-{name}", *options]
        for rid, (_emu, _frames, path) in lines.items():
            argv += ["--rotator", f"{rid}={path}"]
        proc = s.spawn(argv, log_name="floor.log")
        mqtt.wait_all([f"{TOPIC}/{rid}/availability" for rid in lines], "online", 30)
        for emu, _frames, _path in lines.values():
            emu.manual_rotate(350.0)
        bearings = [f"{TOPIC}/{rid}/bearing" for rid in lines]
        t = time.monotonic()
        silent = "--mqtt" in options and options[options.index("--mqtt") + 1] == "off"
        for topic in [] if silent else bearings:  # polling: its readings come
            mqtt.wait_for(topic, after=t, timeout_s=30)
        time.sleep(1.0)  # polling, as in exchange_cpu's round
        pid = proc.pid
        w0, c0, t0, th0 = wakeups(pid), cpu_seconds(pid), time.monotonic(), thread_seconds(pid)
        time.sleep(window_s)
        c1, t1, th1, w1 = cpu_seconds(pid), time.monotonic(), thread_seconds(pid), wakeups(pid)
        if proc.poll() is not None:
            raise BenchError(f"the floor's engine exited with status {proc.returncode}")
        busiest = sorted((th1[k] - th0[k] for k in th1 if k in th0), reverse=True)[:2]
        polls = sum(
            1
            for _emu, frames, _path in lines.values()
            for f in frames.since(0)
            if f.data == POLL and t0 <= f.time_s < t1
        )
        if polls == 0:  # rule 2
            raise BenchError("no poll exchange in the window")
        turning = sum(1 for emu, _f, _p in lines.values() if emu.state().is_moving)
        if turning < COUNT:
            raise BenchError(f"only {turning} of {COUNT} rotors still turned at the end")
        published = sum(1 for topic in bearings for m in mqtt.on(topic) if t0 <= m.t < t1)
        stats = [m for m in mqtt.on(f"{TOPIC}/floor/stats") if t0 <= m.t < t1]
        wakes = reads = float("nan")
        if len(stats) >= 2:  # the engine's counts a second apart: per exchange at the rate seen
            (w0, r0), (w1, r1) = (map(int, stats[i].text.split()) for i in (0, -1))
            done = polls / (t1 - t0) * (stats[-1].t - stats[0].t)
            wakes, reads = (w1 - w0) / done, (r1 - r0) / done
    return {
        "exchanges_s": polls / (t1 - t0),
        "ms_per_exchange": (c1 - c0) / polls * 1000,
        "busiest_threads_ms": [b / polls * 1000 for b in busiest],
        "wakeups_per_exchange": (w1 - w0) / polls,
        "bearings_per_exchange": published / polls,
        "wakes_per_exchange": wakes,
        "reads_per_exchange": reads,
        "load_avg": os.getloadavg()[0],
    }


def measure(
    scope: Scope, against: list[str], variants: list[str], rounds: int, window_s: float
) -> dict[str, list[dict[str, Any]]]:
    """Every engine's rounds, taken in turns: the older engines, this tree, the floor's."""
    runs: dict[str, Callable[[str], dict[str, Any]]] = {}
    for commit in against:
        root, why = engine_at(scope, commit)
        if root is None:
            raise BenchError(f"the engine of {commit} could not be set up: {why}")
        spawn: Callable[[Scope], Spawn] = partial(engine_spawner, root=root)
        runs[commit] = partial(lambda n, sp: one_round(scope, n, sp, window_s), sp=spawn)
    runs[NEW] = lambda n: one_round(scope, n, None, window_s)
    for v in variants:
        runs[v] = partial(lambda n, opts: floor_round(scope, n, opts, window_s), opts=VARIANTS[v])
    out: dict[str, list[dict[str, Any]]] = {e: [] for e in runs}
    for i in range(rounds):
        for k, (engine, run) in enumerate(runs.items()):
            check_abort()
            r = run(f"e{k}-{i}")
            out[engine].append(r)
            print(
                f"round {i + 1} {engine}: {r['ms_per_exchange']:.3f} ms/exchange, "
                f"{r['exchanges_s']:.1f} exchanges/s, "
                f"threads' wake-ups/exchange {r['wakeups_per_exchange']:.2f}, "
                f"bearings/exchange {r.get('bearings_per_exchange', float('nan')):.2f}, "
                f"wake-ups/exchange {r.get('wakes_per_exchange', float('nan')):.2f}, "
                f"reads/exchange {r.get('reads_per_exchange', float('nan')):.2f}, "
                f"load {r['load_avg']:.2f}",
                flush=True,
            )
    return out


def report(out: dict[str, list[dict[str, Any]]], base: str | None, window_s: float) -> Table:
    rounds = len(next(iter(out.values())))
    table = Table(
        f"The floor: CPU per poll exchange, 16 Rotor-EZ turning, {rounds} rounds each in turns, "
        f"{window_s:g} s windows",
        [
            "engine",
            "ms/exchange (median)",
            "range",
            "1st thread",
            "2nd",
            "wake-ups/exchange",
            "x of base",
            "load avg",
        ],
    )
    med = {e: percentile(sorted(r["ms_per_exchange"] for r in rs), 50) for e, rs in out.items()}
    for engine, rs in out.items():
        ms = [r["ms_per_exchange"] for r in rs]
        threads = [(r["busiest_threads_ms"] + [0.0, 0.0])[:2] for r in rs]
        loads = [r["load_avg"] for r in rs]
        table.add(
            engine,
            f"{med[engine]:.3f}",
            f"{min(ms):.3f}-{max(ms):.3f}",
            f"{percentile(sorted(t[0] for t in threads), 50):.3f}",
            f"{percentile(sorted(t[1] for t in threads), 50):.3f}",
            f"{percentile(sorted(r['wakeups_per_exchange'] for r in rs), 50):.2f}",
            f"x{med[engine] / med[base]:.2f}" if base in med else "",
            f"{min(loads):.2f}-{max(loads):.2f}",
        )
    table.notes.append(
        "CPU: the engine's process, every thread (/proc schedstat), over the ``AI1;`` frames the "
        "controllers logged in the window; 1st / 2nd thread: the two busiest threads, medians; "
        "wake-ups: the voluntary context switches of all its threads in the window."
    )
    return table


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.floor")
    ap.add_argument("--quick", action="store_true", help="5 s windows (else 10 s)")
    ap.add_argument("--against", default=EXCHANGE_BASE, help="older engines, comma-separated")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--variants", default=",".join(VARIANTS), help="the floor's engines")
    args = ap.parse_args(argv)
    against = [c.strip() for c in args.against.split(",") if c.strip()]
    variants = [v.strip() for v in args.variants.split(",") if v.strip()]
    unknown = [v for v in variants if v not in VARIANTS]
    if unknown:
        ap.error(f"unknown variant(s) {unknown}; choose from {list(VARIANTS)}")
    window_s = 5.0 if args.quick else 10.0
    with Scope(Path(tempfile.mkdtemp(prefix="floor-"))) as scope:
        out = measure(scope, against, variants, args.rounds, window_s)
    base = against[0] if against else None
    print(report(out, base, window_s).render())
    return 0


if __name__ == "__main__":
    sys.exit(main())
