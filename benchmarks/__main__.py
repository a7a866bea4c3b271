"""`python -m benchmarks`: run the benchmarks, print one table per item, write results.json.

    python -m benchmarks                      # everything (about 25 minutes on 2 cores)
    python -m benchmarks --quick              # fewer samples, shorter windows (about 10 minutes)
    python -m benchmarks latency burst        # a subset (items: see --help)
    python -m benchmarks latency --models rotorez,rot2prog
    python -m benchmarks exchange_cpu --against 9104bbc   # beside older commits' engines
    python -m benchmarks exchange_cpu --without paho      # ... and what a part of a reading costs
    ./benchmarks/run [same arguments]         # installs mosquitto, rotctld and the venv first

Every process started (brokers, bridges, rotctld, emulator hosts) is ended on the way out,
also on Ctrl-C, SIGTERM or an error. Results of the items that ran replace theirs in the JSON
file; the other items' earlier results are kept (each item says when and how it ran).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import platform
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import traceback
from datetime import UTC, datetime
from pathlib import Path
from types import FrameType
from typing import Any

from benchmarks import (
    burst,
    console,
    exchange_cpu,
    footprint,
    freshness,
    health,
    latency,
    line_use,
    remote,
    sky_stops,
    startup,
    stop_under_load,
    target_flood,
)
from benchmarks.harness import ABORT, Scope
from benchmarks.line import ALL_LATENESS_S
from benchmarks.report import ItemResult, percentile

ITEMS = {
    "latency": latency.run,
    "freshness": freshness.run,
    "line": line_use.run,
    "footprint": footprint.run,
    "burst": burst.run,
    "startup": startup.run,
    "target_flood": target_flood.run,
    "sky_stops": sky_stops.run,
    "exchange_cpu": exchange_cpu.run,
    "console": console.run,
    "remote": remote.run,
    "health": health.run,
    "stop_under_load": stop_under_load.run,
}
DEFAULT_JSON = Path(__file__).resolve().parent / "results.json"


def preflight() -> str | None:
    """What is missing to run at all (the benchmark's own set-up is ./benchmarks/run)."""
    missing = []
    if not any(Path(p).exists() for p in ("/usr/sbin/mosquitto", "/usr/local/sbin/mosquitto")):
        if shutil.which("mosquitto") is None:
            missing.append("mosquitto (Debian package mosquitto)")
    if shutil.which("rotctld") is None:
        missing.append("Hamlib's rotctld (Debian package libhamlib-utils)")
    if not missing:
        return None
    return (
        "missing: " + "; ".join(missing) + ". ./benchmarks/run installs them "
        "(sudo apt-get install mosquitto libhamlib-utils)"
    )


def _interrupt(signum: int, _frame: FrameType | None) -> None:
    raise KeyboardInterrupt(f"signal {signum}")


def _version(argv: list[str]) -> str:
    try:
        out = subprocess.run(argv, capture_output=True, text=True, timeout=10)
        text = (out.stdout or out.stderr).strip().splitlines()
        return text[0] if text else "?"
    except (OSError, subprocess.TimeoutExpired):
        return "not found"


def environment() -> dict[str, Any]:
    import os

    model = "?"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    digest = hashlib.sha1()
    for f in sorted((Path(__file__).resolve().parent.parent / "bridge").rglob("*.py")):
        digest.update(f.read_bytes())
    return {
        "bridge_sources_sha1": digest.hexdigest()[:12],  # which code these numbers are from
        "python": platform.python_version(),
        "cpus": os.cpu_count(),
        "cpu": model,
        "kernel": platform.release(),
        "hamlib": _version(["rotctld", "--version"]),
        "mosquitto": _version(["/usr/sbin/mosquitto", "-h"]),
    }


def line_lateness() -> dict[str, float]:
    """How late the paced lines delivered bytes (their own scheduling error), over the run."""
    values = sorted(ALL_LATENESS_S)
    if not values:
        return {}
    return {
        "deliveries": len(values),
        "p50_ms": round(percentile(values, 50) * 1000, 3),
        "p99_ms": round(percentile(values, 99) * 1000, 3),
        "max_ms": round(values[-1] * 1000, 3),
    }


def render(result: ItemResult) -> str:
    parts = [t.render() for t in result.tables]
    if result.verdicts:
        parts.append("targets:\n" + "\n".join(v.render() for v in result.verdicts))
    if result.error:
        parts.append(f"ERROR: {result.error}")
    parts.append(f"({result.duration_s:.0f} s)")
    return "\n".join(parts)


def as_json(result: ItemResult, quick: bool) -> dict[str, Any]:
    return {
        "title": result.title,
        "run_at": result.finished_at,
        "quick": quick,
        "duration_s": round(result.duration_s, 1),
        "error": result.error,
        "tables": [t.as_json() for t in result.tables],
        "targets": [
            {"target": v.target, "measured": v.measured, "met": v.met} for v in result.verdicts
        ],
        "data": result.data,
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks", description=__doc__.split("\n")[0])
    ap.add_argument(
        "items", nargs="*", metavar="ITEM", help=f"items to run (default all): {', '.join(ITEMS)}"
    )
    ap.add_argument("--quick", action="store_true", help="fewer samples, shorter windows")
    ap.add_argument("--models", help="comma-separated models for latency/freshness/line")
    ap.add_argument(
        "--against",
        metavar="COMMIT",
        help=f"exchange_cpu: older engines beside this one (default {exchange_cpu.AGAINST})",
    )
    ap.add_argument(
        "--without",
        metavar="PART",
        help="exchange_cpu: this tree also without these parts of a reading, comma-separated "
        "(paho, publishing: benchmarks/without.py)",
    )
    ap.add_argument("--json", type=Path, default=DEFAULT_JSON, help="results file")
    ap.add_argument("--keep", action="store_true", help="keep the work directory (logs, configs)")
    args = ap.parse_args(argv)
    unknown = [i for i in args.items if i not in ITEMS]
    if unknown:
        ap.error(f"unknown item(s) {', '.join(unknown)}; choose from {', '.join(ITEMS)}")
    items = args.items or list(ITEMS)
    models = set(args.models.split(",")) if args.models else None
    problem = preflight()
    if problem:
        print(f"benchmarks: {problem}", file=sys.stderr)
        return 2

    signal.signal(signal.SIGTERM, _interrupt)
    signal.signal(signal.SIGHUP, _interrupt)
    workdir = Path(tempfile.mkdtemp(prefix="rotor-bench-"))
    results: dict[str, ItemResult] = {}
    started = time.monotonic()
    status = 0
    print(
        f"rotor-bridge benchmarks{' (quick)' if args.quick else ''}; work dir {workdir}", flush=True
    )
    try:
        for key in items:
            result = ItemResult(key, key)
            t0 = time.monotonic()
            try:
                with Scope(workdir / key) as scope:
                    run = ITEMS[key]
                    if key in ("latency", "freshness", "line"):
                        result = run(scope, args.quick, models)  # type: ignore[operator]
                    elif key == "exchange_cpu":
                        result = exchange_cpu.run(scope, args.quick, args.against, args.without)
                    else:
                        result = run(scope, args.quick)  # type: ignore[operator]
            except KeyboardInterrupt:
                raise
            except Exception as exc:  # one item failing must not lose the others
                result.error = f"{type(exc).__name__}: {exc}"
                traceback.print_exc()
                status = 1
            result.duration_s = time.monotonic() - t0
            result.finished_at = datetime.now(UTC).isoformat(timespec="seconds")
            results[key] = result
            print("\n" + render(result), flush=True)
    except KeyboardInterrupt:
        ABORT.set()
        print("\ninterrupted; every process started has been stopped", file=sys.stderr)
        status = 130
    finally:
        if results:
            write_json(args.json, results, args.quick)
            late = line_lateness()
            if late:
                print(
                    f"\npaced lines delivered bytes late by p50 {late['p50_ms']:.2f} ms, "
                    f"p99 {late['p99_ms']:.2f} ms, max {late['max_ms']:.1f} ms "
                    f"({late['deliveries']} deliveries)"
                )
            print(f"results: {args.json} ({time.monotonic() - started:.0f} s in all)")
        if args.keep:
            print(f"work dir kept: {workdir}")
        else:
            shutil.rmtree(workdir, ignore_errors=True)
    return status


def write_json(path: Path, results: dict[str, ItemResult], quick: bool) -> None:
    doc: dict[str, Any] = {}
    if path.exists():
        try:
            doc = json.loads(path.read_text())
        except (OSError, json.JSONDecodeError):
            doc = {}
    doc["command"] = "python -m benchmarks" + (" --quick" if quick else "")
    doc["environment"] = environment()
    doc["paced_line_lateness_ms"] = line_lateness()
    doc.setdefault("items", {})
    for key, result in results.items():
        doc["items"][key] = as_json(result, quick)
    order = [k for k in ITEMS if k in doc["items"]]
    doc["items"] = {k: doc["items"][k] for k in order}
    path.write_text(json.dumps(doc, indent=1, default=str) + "\n")


if __name__ == "__main__":
    sys.exit(main())
