"""Item 4, footprint: CPU (% of one core) and memory of the bridge (its process and the stop
express's child process, interfaces/mqtt/express.py rule 1) with 1, 8 and 32
emulated Rotor-EZ controllers, idle and while every rotor turns; beside it one rotctld per
rotator (Hamlib's way to serve several), summed.

The bridge runs as the service does (`python -m bridge run -c FILE`, defaults: idle poll 1 s,
moving poll 0.2 s, Home Assistant discovery on); the controllers live in a separate emulator host
process behind paced lines, so the numbers are the bridge's own. "Moving": every rotor is turned
from its front panel (no command), the bridge sees it turn, polls at its moving rate and
publishes the bearing. rotctld gets what a glue script would do for the same service: ask `p`
once a second per rotator when idle, back to back while moving (rotctld needs ~0.5 s per `p`:
Hamlib's post-write delay). The glue (in this process) is not counted.

CPU from /proc/PID/task/*/schedstat over the window; RSS from /proc/PID/status; PSS (shared
pages divided among the processes sharing them, fairer for many rotctld) from smaps_rollup.
"""

from __future__ import annotations

import threading
import time
from typing import Any

from benchmarks.hamlib import RotctlConnection, start_rotctld
from benchmarks.harness import Mqtt, Scope, start_bridge, start_broker, wait_until
from benchmarks.procfs import Usage, children, measure_usage
from benchmarks.report import ItemResult, Table, Verdict
from benchmarks.rig import EmuHost

SIZES = (1, 8, 32)
MODEL = "rotorez"
HAMLIB = 401


def bridge_usage(scope: Scope, count: int, window_s: float, quick: bool) -> dict[str, Usage]:
    with Scope(scope.workdir / f"bridge-{count}") as sc:
        port = start_broker(sc)
        host = EmuHost(sc, MODEL, count)
        ids = [f"r{i}" for i in range(count)]
        root = "rotor" if count == 1 else None
        topics = [root or f"rotor/{rid}" for rid in ids]
        mqtt = Mqtt(port, [f"{t}/state" for t in topics] + [f"{t}/availability" for t in topics])
        sc.callback(mqtt.close)
        rotators = [
            {"id": rid, "model": MODEL, "port": str(host.link(i))} for i, rid in enumerate(ids)
        ]
        bridge = start_bridge(sc, port, rotators)
        mqtt.wait_all([f"{t}/availability" for t in topics], "online", 60)
        if not quick:  # past the brake window assumed at start-up (5 s on a Rotor-EZ)
            mqtt.wait_all([f"{t}/state" for t in topics], "idle", 60)
        time.sleep(1.0)
        idle = measure_usage([bridge.pid, *children(bridge.pid)], window_s)  # (its stop express)
        host.command("rotate 350")
        mqtt.wait_all([f"{t}/state" for t in topics], "moving", 30)
        time.sleep(0.5)
        moving = measure_usage([bridge.pid, *children(bridge.pid)], window_s)
        still_moving = sum(1 for _, m in host.states() if m)
        bridge.check()
        if still_moving < count:
            raise RuntimeError(f"only {still_moving} of {count} rotors still turned")
    return {"idle": idle, "moving": moving}


def rotctld_usage(scope: Scope, count: int, window_s: float) -> dict[str, Usage]:
    with Scope(scope.workdir / f"rotctld-{count}") as sc:
        host = EmuHost(sc, MODEL, count)
        ports = []
        for i in range(count):
            port = start_rotctld(sc, HAMLIB, str(host.link(i)), 4800, f"rotctld-{i}")
            ports.append(port)
        pids = _pids_of(sc, "rotctld")
        mode = {"interval_s": 1.0}
        stop = threading.Event()
        errors: list[str] = []

        def glue(port: int) -> None:
            conn = RotctlConnection(port)
            try:
                while not stop.is_set():
                    t0 = time.monotonic()
                    conn.send("p")
                    lines = conn.read_lines(2)
                    if not lines[0] or lines[0].startswith("RPRT"):
                        errors.append(f"p -> {lines}")
                    stop.wait(max(0.0, mode["interval_s"] - (time.monotonic() - t0)))
            except OSError as exc:
                if not stop.is_set():
                    errors.append(str(exc))
            finally:
                conn.close()

        threads = [threading.Thread(target=glue, args=(p,), daemon=True) for p in ports]
        for t in threads:
            t.start()
        sc.callback(lambda: [t.join(5) for t in threads])
        sc.callback(stop.set)
        time.sleep(1.5)
        idle = measure_usage(pids, window_s)
        host.command("rotate 350")
        mode["interval_s"] = 0.0
        wait_until(lambda: all(m for _, m in host.states()), 10, "all rotors turning", 0.1)
        time.sleep(1.0)
        moving = measure_usage(pids, window_s)
        if errors:
            raise RuntimeError(f"rotctld glue errors: {errors[:3]}")
    return {"idle": idle, "moving": moving}


def _pids_of(scope: Scope, prefix: str) -> list[int]:
    return [p.pid for p in scope.processes if p.args[0] == prefix]  # type: ignore[index]


def run(scope: Scope, quick: bool) -> ItemResult:
    window = 2.0 if quick else 8.0
    result = ItemResult("footprint", "4. Footprint: CPU (% of one core) and memory")
    table = Table(
        result.title + f" over {window:g} s windows",
        ["rotators", "process", "state", "CPU %", "RSS MB", "PSS MB"],
    )
    data: dict[str, Any] = {}
    for count in SIZES if not quick else SIZES[1:]:
        b = bridge_usage(scope, count, window, quick)
        h = rotctld_usage(scope, count, window)
        for who, usage in (("bridge", b), (f"rotctld x{count}", h)):
            for state in ("idle", "moving"):
                u = usage[state]
                table.add(count, who, state, f"{u.cpu_pct:.2f}", u.rss_mb, u.pss_mb)
                data[f"{count}/{who.split()[0]}/{state}"] = {
                    "cpu_pct": u.cpu_pct,
                    "rss_mb": u.rss_mb,
                    "pss_mb": u.pss_mb,
                    "window_s": u.window_s,
                }
    table.notes += [
        "bridge: its Python process (paho thread + one thread for all serial lines) and the stop "
        "express's (a second interpreter with its own broker connection), summed; rotctld: one "
        "process per rotator, summed (RSS counts the shared Hamlib/libc pages once per process; "
        "PSS shares them out).",
        "idle: bridge polls each rotor once a second (default), the glue asks rotctld `p` once a "
        "second; moving: every rotor turns, bridge polls every 0.2 s (default), glue asks `p` "
        "back to back (~0.5 s each in rotctld).",
    ]
    result.tables.append(table)
    result.data = data
    i8 = data.get("8/bridge/idle")
    if i8:
        result.verdicts.append(
            Verdict(
                "8 rotators idle: bridge under 1 % of one core",
                f"{i8['cpu_pct']:.2f} % (moving: {data['8/bridge/moving']['cpu_pct']:.2f} %)",
                i8["cpu_pct"] < 1.0,
            )
        )
    m32 = [data.get(f"32/bridge/{s}") for s in ("idle", "moving")]
    if all(m32):
        worst = max(m["rss_mb"] for m in m32 if m)
        result.verdicts.append(
            Verdict(
                "32 rotators: bridge under 80 MB RSS",
                f"{m32[0]['rss_mb']:.1f} MB idle, {m32[1]['rss_mb']:.1f} MB moving",  # type: ignore[index]
                worst < 80.0,
            )
        )
    return result
