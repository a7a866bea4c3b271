"""Command latency: MQTT publish of a stop/target -> complete frame received by the emulated
controller (replies paced at 4800 baud), through a real mosquitto and a real pty.

    .venv/bin/python -m benchmarks.command_latency [--n 200]

Stops are used because they are never held back (a target may wait for a brake delay by
design); the path is the same for every command: paho thread -> mailbox -> worker -> wire.
Measured idle (bridge polling once a second) and "polling" (0.05 s poll interval, so a poll
exchange is usually in flight when the command arrives). Not a test: prints numbers.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import threading
import time
from pathlib import Path

from bridge import emulators
from bridge.app import App
from bridge.mosquitto import Mosquitto
from bridge.settings import Settings
from tests.support import Probe


def run(n: int, idle_poll_s: float) -> list[float]:
    tmp = Path(tempfile.mkdtemp())
    broker = Mosquitto(tmp / "broker").start()
    got = threading.Event()
    frames: list[float] = []

    def on_frame(frame) -> None:  # noqa: ANN001
        if frame.data in (b";", b"AS1;"):
            frames.append(frame.time_s)
            got.set()

    emu = emulators.start("rotorez", link=str(tmp / "tty"), on_frame=on_frame, jitter_deg=0)
    settings = Settings(
        mqtt={"port": broker.port},
        rotators=[
            {
                "id": "t",
                "model": "rotorez",
                "port": str(tmp / "tty"),
                "idle_poll_interval_s": idle_poll_s,
                "moving_poll_interval_s": min(idle_poll_s, 0.2),
            }
        ],
        state_file=tmp / "state.json",
    )
    app = App(settings)
    app.start()
    probe = Probe(broker.port, "rotor/availability")
    probe.wait_value("rotor/availability", "online")
    latencies = []
    try:
        for _ in range(n):
            got.clear()
            t0 = time.monotonic()
            probe.client.publish("rotor/stop", b"STOP", qos=0)
            if not got.wait(2):
                raise RuntimeError("stop frame never arrived")
            latencies.append(frames[-1] - t0)
            time.sleep(0.013)  # spread the commands over the poll cycle
    finally:
        probe.close()
        app.stop()
        emu.close()
        broker.stop()
    return latencies


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=200)
    args = ap.parse_args()
    frame_s = 10 / 4800  # one byte, ';'
    print(f"frame transmission time (limit): {frame_s * 1000:.2f} ms")
    for label, poll in (("idle", 1.0), ("polling", 0.05)):
        lat = sorted(run(args.n, poll))

        def p(q: float, lat: list[float] = lat) -> float:
            return lat[min(len(lat) - 1, int(q * len(lat)))] * 1000

        print(
            f"{label:8s} n={len(lat)} p50={p(0.5):.2f} ms p99={p(0.99):.2f} ms "
            f"max={lat[-1] * 1000:.2f} ms mean={statistics.mean(lat) * 1000:.2f} ms"
        )


if __name__ == "__main__":
    main()
