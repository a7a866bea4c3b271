"""Item exchange_cpu: the bridge's CPU time per poll exchange, 16 Rotor-EZ turning, this engine
beside older ones, taking turns: by default the engine of 2026-11-26 (EXCHANGE_BASE, the goal per
exchange is set against it) and main when the goals were set (STARTUP_BASE, the start-up goal).

    python -m benchmarks exchange_cpu [--quick] [--against COMMIT[,COMMIT...]]
                                      [--without PART[,PART...]]

Set-up, for each engine: one bridge process (the service as a user runs it: defaults, Home
Assistant discovery on) with 16 emulated Rotor-EZ controllers behind paced lines at 4800 baud
(rig.many_rotators), its own broker. The older engine is the commit's ``bridge/`` out of git,
run with its own import path (benchmarks/engines.py); everything else is this checkout's.
The engines take turns, ROUNDS rounds each (old, older, new, old, older, new, ...), so all
meet the same machine; each round starts its bridge afresh and measures, from /proc
(procfs.tree_cpu_seconds: every thread of the bridge process and of the processes it started,
the stop express's child among them; the older engines start none):

- start-up: the bridge's CPU seconds from its start to all 16 rotators ``online`` (Home
  Assistant discovery on), and to "settled": all 16 ``idle`` and a second more, by when the
  discovery configs it published have come back to it and been read; every engine starts from
  bytecode, as an installed service does (benchmarks/engines.py rule 3);
- idle: the 16 at rest (polled at their idle rate, nothing changing): % of one core, and the
  wake-ups of the threads a second (their voluntary context switches: a count, where the
  CPU each costs is the machine's);
- turning: every rotor turned from its front panel (no command), so the bridge polls each at
  its moving rate (0.2 s) and publishes the bearing after every reply. CPU seconds divided by
  the poll exchanges completed in the window (the ``AI1;`` frames the controllers logged: the
  ground truth, each answered). The MQTT and Home Assistant work a reading causes is part of
  the cost; a reading is what an exchange is for. The emulators transmit their replies as a
  real UART would: each byte when its time on the line is over, one write per byte (the
  "bytes per reply write" note shows it). Also kept (in the data, not the table): the wake-ups
  of the bridge's threads per exchange (their voluntary context switches), which
  benchmarks/floor.py sets beside a minimal engine's.

The machine may be shared: every round carries the load average at its end; a ratio is of the
medians over the rounds (this tree / the older engine).
``--without``: this tree also runs, in the same turns, without a part of a reading
(benchmarks/without.py: ``paho``, ``publishing``); what the part costs per exchange is this
tree's median less that one's.
"""

from __future__ import annotations

import contextlib
import os
import subprocess
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Any

from benchmarks.engines import compiled, engine_at, engine_spawner
from benchmarks.harness import REPO, Scope, check_abort, child_env
from benchmarks.procfs import children
from benchmarks.procfs import tree_cpu_seconds as cpu_seconds
from benchmarks.report import ItemResult, Table, Verdict, percentile
from benchmarks.rig import Rig, many_rotators
from benchmarks.without import PARTS, unknown
from tests.support.process import Spawn

MODEL = "rotorez"
COUNT = 16
POLL = b"AI1;"
EXCHANGE_BASE = "9104bbc"  # the engine of 2026-11-26: the goal per exchange is set against it
STARTUP_BASE = "4825dd5"  # main when the goals were set: the start-up goal is set against it
AGAINST = f"{EXCHANGE_BASE},{STARTUP_BASE}"
NEW = "this tree"
ROUNDS = 3  # per engine
#: start-ups per engine, taking turns: the ROUNDS rounds' own and as many more starts alone (a
#: start-up is a second's CPU, and three of them moved the ratio by a tenth from run to run)
STARTS = 7
EXCHANGE_GOAL = 0.5  # of the old engine's CPU per exchange, at most
STARTUP_GOAL = 0.5  # of the old engine's start-up CPU, at most
IDLE_GOAL_PCT = 0.5  # of a core, 16 at rest
#: every rotor still turns at the end of the window (0 -> 350 deg: 87 s; 6 deg/s default),
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


def wakeups(pid: int) -> int:
    """Voluntary context switches of every live thread of ``pid`` so far: how often its threads
    went to sleep (each a wake-up later)."""
    total = 0
    for tid in os.listdir(f"/proc/{pid}/task"):
        with contextlib.suppress(OSError), open(f"/proc/{pid}/task/{tid}/status") as f:
            for line in f:
                if line.startswith("voluntary_ctxt_switches:"):
                    total += int(line.split()[1])
    return total


def tree_wakeups(pid: int) -> int:
    """``wakeups`` of ``pid`` and of the live processes under it (the stop express's child);
    a child that ended is not counted (a window it ends in counts less: /proc keeps no sum
    of a reaped child's switches)."""
    total = wakeups(pid)
    for kid in children(pid):
        with contextlib.suppress(OSError):
            total += tree_wakeups(kid)
    return total


def _polls_between(rig: Rig, t0: float, t1: float) -> int:
    return sum(
        1
        for line in rig.lines.values()
        for f in line.frames.since(0)
        if f.data == POLL and t0 <= f.time_s < t1
    )


def without_env(parts: str) -> dict[str, str]:
    """The environment of this checkout's bridge without ``parts`` (benchmarks/without.py): as
    every other engine's (harness.child_env), the knock-outs' site first on the import path."""
    env = child_env()
    env["BENCH_WITHOUT"] = parts
    env["PYTHONPATH"] = f"{REPO / 'benchmarks' / 'without_site'}:{env['PYTHONPATH']}"
    return env


def without_spawner(scope: Scope, parts: str) -> Spawn:
    """How a Rig starts this checkout's bridge without ``parts``."""
    env = without_env(parts)

    def spawn(argv: list[str], log: Path) -> subprocess.Popen[bytes]:
        return scope.spawn(argv, log_name=str(log.relative_to(scope.workdir)), env=env)

    return spawn


def one_round(
    scope: Scope, name: str, spawn: Callable[[Scope], Spawn] | None, window_s: float
) -> dict[str, Any]:
    """One engine, started afresh: its start-up, idle and turning costs."""
    specs = [(f"r{i}", MODEL, {"speed_deg_s": SPEED_DEG_S}, {}) for i in range(COUNT)]
    with many_rotators(scope, name, specs, wait_online_s=60, spawn=spawn) as rig:
        assert rig.bridge is not None
        pid = rig.bridge.pid
        startup_cpu_s = cpu_seconds(pid)  # all online (the rig waited for it)
        startup_s = time.monotonic() - rig.bridge.started_t
        topics = [rig.t(rid, "state") for rid in rig.lines]
        rig.mqtt.wait_all(topics, "idle", 60)  # past the brake window assumed at start-up
        time.sleep(1.0)  # discovery's echoes read (an idle second costs a few ms)
        i0, c0, t0 = tree_wakeups(pid), cpu_seconds(pid), time.monotonic()
        settled_cpu_s = c0
        time.sleep(window_s)
        c1, t1, i1 = cpu_seconds(pid), time.monotonic(), tree_wakeups(pid)
        idle_pct = 100 * (c1 - c0) / (t1 - t0)
        idle_polls = _polls_between(rig, t0, t1)
        check_abort()
        counters = [WriteCounter(line.emu) for line in rig.lines.values()]
        for line in rig.lines.values():
            line.emu.manual_rotate(350.0)
        rig.mqtt.wait_all(topics, "moving", 30)
        time.sleep(1.0)  # polling at the moving rate
        w0, c0, t0, th0 = wakeups(pid), cpu_seconds(pid), time.monotonic(), thread_seconds(pid)
        time.sleep(window_s)
        c1, t1, th1, w1 = cpu_seconds(pid), time.monotonic(), thread_seconds(pid), wakeups(pid)
        busiest = sorted((th1[t] - th0[t] for t in th1 if t in th0), reverse=True)[:2]
        polls = _polls_between(rig, t0, t1)
        if polls == 0:
            raise RuntimeError("no poll exchange in the window")
        turning = sum(1 for line in rig.lines.values() if line.emu.state().is_moving)
        if turning < COUNT:
            raise RuntimeError(f"only {turning} of {COUNT} rotors still turned at the end")
        writes = sum(c.writes for c in counters)
        sent = sum(c.bytes for c in counters)
    return {
        "startup_cpu_s": startup_cpu_s,
        "settled_cpu_s": settled_cpu_s,
        "startup_s": startup_s,
        "idle_pct": idle_pct,
        "idle_wakeups_s": (i1 - i0) / (t1 - t0),
        "idle_polls_s": idle_polls / window_s,
        "exchanges": polls,
        "exchanges_s": polls / (t1 - t0),
        "ms_per_exchange": (c1 - c0) / polls * 1000,
        "busiest_threads_ms": [b / polls * 1000 for b in busiest],
        "wakeups_per_exchange": (w1 - w0) / polls,
        "bytes_per_write": sent / writes if writes else float("nan"),
        "load_avg": os.getloadavg()[0],
    }


def one_start(scope: Scope, name: str, spawn: Callable[[Scope], Spawn] | None) -> float:
    """One engine started afresh and ended once all 16 are ``online``: its start-up CPU."""
    specs = [(f"r{i}", MODEL, {"speed_deg_s": SPEED_DEG_S}, {}) for i in range(COUNT)]
    with many_rotators(scope, name, specs, wait_online_s=60, spawn=spawn) as rig:
        assert rig.bridge is not None
        return cpu_seconds(rig.bridge.pid)


def run(
    scope: Scope, quick: bool, against: str | None = None, without: str | None = None
) -> ItemResult:
    """``against``: older commits, comma-separated (default AGAINST); ``without``: parts of a
    reading (benchmarks/without.py), each run as an engine of its own beside this tree."""
    commits = [c.strip() for c in (against or AGAINST).split(",") if c.strip()]
    parts = [p.strip() for p in (without or "").split(",") if p.strip()]
    why = unknown(",".join(parts)) if parts else None
    if why is not None:
        raise ValueError(f"--without: {why}")
    window_s = 5.0 if quick else 10.0
    result = ItemResult("exchange_cpu", f"CPU per reading, this engine beside {', '.join(commits)}")
    engines: dict[str, Callable[[Scope], Spawn] | None] = {}
    for commit in commits:
        root, why = engine_at(scope, commit)
        if root is None:
            raise RuntimeError(f"the engine of {commit} could not be set up: {why}")
        engines[commit] = partial(engine_spawner, root=root)
    compiled(REPO)  # engines.py rule 3: this tree starts from bytecode as the older ones do
    engines[NEW] = None
    for part in parts:
        engines[f"{NEW} without {part}"] = partial(without_spawner, parts=part)
    rounds: dict[str, list[dict[str, Any]]] = {e: [] for e in engines}
    for i in range(ROUNDS):
        for k, (engine, spawn) in enumerate(engines.items()):
            check_abort()
            rounds[engine].append(one_round(scope, f"e{k}-{i}", spawn, window_s))
    starts = {e: [r["startup_cpu_s"] for r in rs] for e, rs in rounds.items()}
    for i in range(ROUNDS, STARTS):
        for k, (engine, spawn) in enumerate(engines.items()):
            check_abort()
            starts[engine].append(one_start(scope, f"s{k}-{i}", spawn))
    table = Table(
        f"{result.title}: 16 Rotor-EZ, {ROUNDS} rounds each, taking turns, {window_s:g} s windows",
        [
            "round",
            "engine",
            "start-up CPU s",
            "settled",
            "idle % core",
            "idle wake-ups/s",
            "exchanges/s",
            "CPU ms/exchange",
            "1st thread",
            "2nd",
            "load avg",
        ],
    )
    for i in range(ROUNDS):
        for engine in engines:
            r = rounds[engine][i]
            table.add(
                i + 1,
                engine,
                f"{r['startup_cpu_s']:.2f}",
                f"{r['settled_cpu_s']:.2f}",
                f"{r['idle_pct']:.2f}",
                f"{r['idle_wakeups_s']:.1f}",
                f"{r['exchanges_s']:.1f}",
                f"{r['ms_per_exchange']:.3f}",
                *(f"{ms:.3f}" for ms in (r["busiest_threads_ms"] + [0.0, 0.0])[:2]),
                f"{r['load_avg']:.2f}",
            )
    keys = ("startup_cpu_s", "settled_cpu_s", "idle_pct", "ms_per_exchange")
    med = {
        e: {k: percentile(sorted(r[k] for r in rs), 50) for k in keys} for e, rs in rounds.items()
    }
    spread = {
        e: {k: (min(r[k] for r in rs), max(r[k] for r in rs)) for k in keys}
        for e, rs in rounds.items()
    }
    for e, cpu in starts.items():  # STARTS: the start-up's median of them all
        med[e]["startup_cpu_s"] = percentile(sorted(cpu), 50)
        spread[e]["startup_cpu_s"] = (min(cpu), max(cpu))
    new = med[NEW]
    ratios = {
        c: {k: new[k] / med[c][k] if med[c][k] else float("nan") for k in keys} for c in commits
    }
    for c in commits:
        table.notes.append(
            f"Medians, {c} -> this tree: {med[c]['ms_per_exchange']:.3f} -> "
            f"{new['ms_per_exchange']:.3f} ms per exchange (x{ratios[c]['ms_per_exchange']:.2f}), "
            f"start-up {med[c]['startup_cpu_s']:.2f} -> {new['startup_cpu_s']:.2f} s CPU "
            f"(x{ratios[c]['startup_cpu_s']:.2f}; settled x{ratios[c]['settled_cpu_s']:.2f}), "
            f"idle {med[c]['idle_pct']:.2f} -> {new['idle_pct']:.2f} % of a core."
        )
    for part in parts:
        less = med[f"{NEW} without {part}"]["ms_per_exchange"]
        table.notes.append(
            f"Without {PARTS[part]}: {less:.3f} ms per exchange; the part costs "
            f"{(new['ms_per_exchange'] - less) * 1000:.0f} us per exchange "
            f"({(new['ms_per_exchange'] - less) / new['ms_per_exchange']:.0%} of this tree's)."
        )
    table.notes += [
        "CPU: the bridge process and the processes it started (the stop express), every "
        "thread (/proc schedstat); exchanges: `AI1;` frames the controllers logged. Start-up: "
        "from the process's start to all 16 `online` (discovery on; each engine from "
        f"bytecode, as installed), the median of {STARTS} starts each in "
        "turns (the rounds' and more alone: "
        + ", ".join(
            f"{e} {spread[e]['startup_cpu_s'][0]:.2f}-{spread[e]['startup_cpu_s'][1]:.2f} s"
            for e in engines
        )
        + "); settled: to all 16 `idle` and a second "
        "more (discovery's own configs read back). "
        "Idle wake-ups/s: the voluntary context switches of every thread of the bridge and of "
        "the stop express's child while at rest, a second (each one a wake-up, its CPU the "
        "machine's). 1st / 2nd thread: the two busiest threads' share while turning, ms per "
        "exchange.",
        "Replies as a UART sends them: "
        + ", ".join(f"{e} {rounds[e][0]['bytes_per_write']:.2f}" for e in engines)
        + " bytes per reply write.",
    ]
    result.tables.append(table)
    result.data = {
        "against": commits,
        "without": parts,
        "rounds": rounds,
        "medians": med,
        "ratios": ratios,
        "spread": spread,
        "starts": starts,
        "window_s": window_s,
    }
    if EXCHANGE_BASE in ratios:
        x = ratios[EXCHANGE_BASE]["ms_per_exchange"]
        result.verdicts.append(
            Verdict(
                f"CPU per poll exchange at most {EXCHANGE_GOAL}x of {EXCHANGE_BASE}'s",
                f"x{x:.2f} ({new['ms_per_exchange']:.3f} / "
                f"{med[EXCHANGE_BASE]['ms_per_exchange']:.3f} ms)",
                x <= EXCHANGE_GOAL,
            )
        )
    if STARTUP_BASE in ratios:
        x = ratios[STARTUP_BASE]["startup_cpu_s"]
        result.verdicts.append(
            Verdict(
                f"start-up CPU (16, discovery on) at most {STARTUP_GOAL}x of {STARTUP_BASE}'s",
                f"x{x:.2f} ({new['startup_cpu_s']:.2f} / "
                f"{med[STARTUP_BASE]['startup_cpu_s']:.2f} s)",
                x <= STARTUP_GOAL,
            )
        )
    lo, hi = spread[NEW]["idle_pct"]
    result.verdicts.append(
        Verdict(
            f"idle, 16 at rest, at most {IDLE_GOAL_PCT} % of a core",
            f"{new['idle_pct']:.2f} % (range {lo:.2f}-{hi:.2f})",
            new["idle_pct"] <= IDLE_GOAL_PCT,
        )
    )
    return result
