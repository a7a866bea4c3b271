"""Stops while the sky is computed: the latency of R/stop (MQTT publish -> the stop frame complete
at the controller) to an idle rotator of a bridge whose other rotators are made to search passes.

    python -m benchmarks sky_stops            # 60 stops per load
    python -m benchmarks sky_stops --quick    # 20

One bridge (its own process, a [station] at JO62qm and a [tracking] tle_file of SATELLITES
synthetic satellites) with 12 MD-01s (115200 baud, each behind a line paced at that rate, in
this process): 8 trackers, 3 flooded, and the one that is stopped. Two loads, one after the
other:
- "8 start tracking": every round, the 8 trackers get R/track with the elements of a satellite
  new to the bridge (JSON, one per round, the same for all 8: what tracking.py's benchmark
  does once), then 0-50 ms later the stop is published.
- "3 get 20 R/track/s": a client publishes R/track by name (the file's satellites in turn) to
  each of the 3 flooded rotators 20 times a second, and the stops are published meanwhile.
Stops are at least STOP_GAP_S apart (a second stop within a second of the first, to a rotor
that is not turning, is merged by the bridge and puts nothing on the wire: session.py rule 5).
The latency includes the 13-byte frame's own time on the line (1.1 ms at 115200 baud).

Before the sky worker, the pass searches and position windows ran on the one thread that writes
every stop: a stop waited behind them.
"""

from __future__ import annotations

import json
import random
import threading
import time
from pathlib import Path
from typing import Any

from benchmarks.harness import BenchError, Mqtt, Scope, check_abort, start_bridge, start_broker
from benchmarks.line import FrameLog
from benchmarks.report import ItemResult, Table, Verdict, line_time_s, percentile
from benchmarks.rig import open_line
from tests.support.sky import synthetic_tle

STATION = (52.52, 13.29)  # JO62qm
TRACKERS = [f"t{i}" for i in range(8)]
FLOODED = [f"n{i}" for i in range(3)]
STOPPED = "s"
SATELLITES = 40
FLOOD_PER_S = 20.0  # R/track to each flooded rotator
STOP_GAP_S = 1.2
TARGET_MS = 10.0
WARMUP = 2


def tle_file(path: Path, epoch: float) -> list[str]:
    """SATELLITES synthetic LEOs, spread in RAAN and anomaly; their names."""
    names, text = [], []
    for i in range(SATELLITES):
        name = f"BENCH {i:02d}"
        line1, line2 = synthetic_tle(
            name,
            epoch,
            inclination_deg=97.5,
            raan_deg=9.0 * i,
            mean_anomaly_deg=37.0 * i,
            catalog=90000 + i,
        )
        names.append(name)
        text.append(f"{name}\n{line1}\n{line2}\n")
    path.write_text("".join(text))
    return names


def round_tle(i: int) -> str:
    """The JSON R/track of a satellite the bridge has not seen (round i)."""
    line1, line2 = synthetic_tle(
        "NEW",
        time.time(),
        inclination_deg=97.5,
        raan_deg=(53.0 * i) % 360.0,
        mean_anomaly_deg=(71.0 * i) % 360.0,
        catalog=80000 + i,
    )
    return json.dumps({"tle": [f"NEW {i}", line1, line2]})


def stop_latencies(
    mqtt: Mqtt, frames: FrameLog, n: int, before_each: Any, rng: random.Random
) -> list[float]:
    """n stops (after WARMUP) to the stopped rotor, ``before_each(i)`` run before each."""
    out: list[float] = []
    last = 0.0
    for i in range(n + WARMUP):
        check_abort()
        time.sleep(max(0.0, last + STOP_GAP_S - time.monotonic()))
        before_each(i)
        time.sleep(rng.uniform(0.0, 0.05))
        mark = frames.mark()
        t0 = time.monotonic()
        mqtt.publish(f"rotor/{STOPPED}/stop", "STOP")
        frame = frames.wait(lambda f: f.outcome == "stop", mark, 5.0)
        if frame is None:
            raise BenchError(f"stop {i} never reached the controller")
        last = frame.time_s
        if i >= WARMUP:
            out.append(frame.time_s - t0)
    return out


class Flood:
    """R/track by name to each flooded rotor FLOOD_PER_S times a second, on a thread."""

    def __init__(self, port: int, names: list[str]) -> None:
        self.mqtt = Mqtt(port, ["rotor/n0/tracking"], name="flood")
        self.names = names
        self.sent = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="flood", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        period = 1.0 / FLOOD_PER_S
        t = time.monotonic()
        while not self._stop.is_set():
            for rid in FLOODED:
                self.mqtt.publish(f"rotor/{rid}/track", self.names[self.sent % len(self.names)])
                self.sent += 1
            t += period
            self._stop.wait(max(0.0, t - time.monotonic()))

    def close(self) -> None:
        self._stop.set()
        self._thread.join(5)
        self.mqtt.close()


def run(scope: Scope, quick: bool) -> ItemResult:
    n = 20 if quick else 60
    rng = random.Random(23)
    result = ItemResult("sky_stops", "Stops while the sky is computed for other rotators")
    table = Table(
        f"R/stop to an idle MD-01 (publish -> stop frame at the controller), {n} stops per load",
        ["load", "stops", "p50 ms", "p99 ms", "max ms", "line ms"],
    )
    line_ms = line_time_s(13, 115200) * 1000.0
    with Scope(scope.workdir / "sky_stops") as inner:
        port = start_broker(inner)
        names = tle_file(inner.workdir / "sats.tle", time.time())
        stopped = FrameLog()
        settings = []
        for rid in [*TRACKERS, *FLOODED, STOPPED]:
            frames = stopped if rid == STOPPED else FrameLog()
            _emu, _relay, path = open_line(inner, "md01", frames, {}, name=f"tty-{rid}")
            settings.append({"id": rid, "model": "md01", "port": str(path)})
        sections = {
            "station": {"latitude_deg": STATION[0], "longitude_deg": STATION[1]},
            "tracking": {"tle_file": str(inner.workdir / "sats.tle")},
        }
        bridge = start_bridge(inner, port, settings, homeassistant=False, sections=sections)
        mqtt = Mqtt(port, ["rotor/+/availability", "rotor/+/error"], name="sky-stops")
        inner.callback(mqtt.close)
        try:
            mqtt.wait_all([f"rotor/{r['id']}/availability" for r in settings], "online", 60)
        except BenchError:
            bridge.check()
            raise
        time.sleep(2.0)  # past the start-up stop's merge window

        def track_all(i: int) -> None:
            payload = round_tle(i)
            for rid in TRACKERS:
                mqtt.publish(f"rotor/{rid}/track", payload)

        loads: dict[str, list[float]] = {}
        loads["8 start tracking"] = stop_latencies(mqtt, stopped, n, track_all, rng)
        for rid in TRACKERS:
            mqtt.publish(f"rotor/{rid}/track", "off")
        flood = Flood(port, names)
        try:
            time.sleep(1.0)
            loads["3 get 20 R/track/s"] = stop_latencies(mqtt, stopped, n, lambda i: None, rng)
        finally:
            flood.close()
        bridge.check()
    for load, values in loads.items():
        ms = [v * 1000.0 for v in values]
        p99 = percentile(ms, 99)
        table.add(load, len(ms), percentile(ms, 50), p99, max(ms), line_ms)
        result.verdicts.append(
            Verdict(f"{load}: stop p99 <= {TARGET_MS:g} ms", f"p99 {p99:.1f} ms", p99 <= TARGET_MS)
        )
        result.data[load] = {"latencies_ms": ms}
    table.notes.append(
        f"stops {STOP_GAP_S:g} s or more apart, each 0-50 ms after the load's commands; "
        f"the flood: R/track by name ({SATELLITES} satellites in turn) to each of 3 rotors "
        f"{FLOOD_PER_S:g} times a second"
    )
    result.tables.append(table)
    return result
