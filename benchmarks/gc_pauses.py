"""A quick measure: the garbage collector's pauses in a running bridge, with and without the
freeze the service does after start-up (app.py ``run``).

    .venv/bin/python -m benchmarks.gc_pauses            # 60 s each way
    .venv/bin/python -m benchmarks.gc_pauses --seconds 20

The bridge runs in this process (two emulated rotators, Home Assistant on, a private
mosquitto); every collection is timed through ``gc.callbacks`` while targets arrive at 40 a
second, and a full collection is timed at the end: that is the pause a stop can meet when the
collector's third generation comes due (every 30-40 s on a busy bridge).
"""

from __future__ import annotations

import argparse
import gc
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from tests.support import Probe
from tests.support.mosquitto import Mosquitto
from tests.support.rig import Rig


def one(freeze: bool, seconds: float) -> None:
    tmp = Path(tempfile.mkdtemp(prefix="gc-pauses-"))
    broker = Mosquitto(tmp).start()
    probe = Probe(broker.port)
    rig = Rig(tmp, broker, probe)
    rig.add("tower", "rotorez")
    rig.add("mast", "rot2prog")
    rig.sections = {"homeassistant": {"enabled": True}}
    try:
        rig.start()
        rig.ready("tower", 30)
        gc.collect()
        if freeze:
            gc.freeze()
        pauses: dict[int, list[float]] = {0: [], 1: [], 2: []}
        began = [0.0]

        def timed(phase: str, info: dict[str, Any]) -> None:
            if phase == "start":
                began[0] = time.perf_counter()
            else:
                pauses[info["generation"]].append((time.perf_counter() - began[0]) * 1000)

        gc.callbacks.append(timed)
        end, i = time.monotonic() + seconds, 0
        while time.monotonic() < end:
            probe.publish("rotor/tower/target", str(10 + i % 300))
            i += 1
            time.sleep(0.025)
        gc.callbacks.remove(timed)
        full = []
        for _ in range(5):
            t = time.perf_counter()
            gc.collect()
            full.append((time.perf_counter() - t) * 1000)
        said = "frozen" if freeze else "not frozen"
        print(f"{said}: {gc.get_freeze_count()} objects frozen")
        for gen, p in pauses.items():
            p.sort()
            if p:
                print(
                    f"  gen {gen}: {len(p)} collections, median {p[len(p) // 2]:.2f} ms, "
                    f"max {p[-1]:.2f} ms"
                )
        print(f"  a full collection: {', '.join(f'{v:.1f}' for v in full)} ms")
    finally:
        gc.unfreeze()
        rig.stop()
        probe.close()
        broker.stop()


def main() -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.gc_pauses")
    parser.add_argument("--seconds", type=float, default=60.0)
    args = parser.parse_args()
    one(False, args.seconds)
    one(True, args.seconds)
    return 0


if __name__ == "__main__":
    sys.exit(main())
