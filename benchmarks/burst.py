"""Item 5, burst: 10,000 targets within one second on one rotator (a slider dragged by a
misbehaving dashboard), QoS 1, not retained.

What is measured: the frames that reached the controller (command frames, not polls), the time
from the last target's publication until the rotor stands at that target (emulator ground
truth), and the bridge process's RSS before, during and after (sampled every 10 ms).

Rotor-EZ (the target applies here): it stops on a new bearing while turning and ignores bearings
for 5 s after, so the bridge sends the first target, then a stop, then - after the brake delay -
only the newest target. Rot2Prog (informative): SPID takes a new target at any time.
The targets sweep from just past the rotor's position to the final one, like a dragged slider.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from statistics import median
from typing import Any

from benchmarks.harness import BenchError, Mqtt, Scope
from benchmarks.procfs import RssSampler, cpu_seconds
from benchmarks.report import ItemResult, Table, Verdict
from benchmarks.rig import single_rotator

N_TARGETS = 10_000
BURST_S = 1.0


@dataclass(frozen=True)
class Case:
    model: str
    start_deg: float
    end_deg: float
    speed_deg_s: float  # the emulator's (default) speed
    payload: str  # format with {az}
    is_poll: Any
    quick: bool


CASES = [
    Case("rotorez", 100.0, 160.0, 6.0, "{az:.2f}", lambda f: f.data in (b"AI1;", b"V"), True),
    Case("rot2prog", 100.0, 110.0, 1.0, "{az:.2f} 0", lambda f: f.outcome == "status", False),
]


def run_case(scope: Scope, case: Case, quick: bool) -> dict[str, Any]:
    end = case.end_deg if not quick else case.start_deg + (case.end_deg - case.start_deg) / 2
    emu_opts: dict[str, Any] = {"start_az_deg": case.start_deg}
    with single_rotator(scope, f"burst-{case.model}", case.model, emu_opts=emu_opts) as rig:
        rig.mqtt.wait_value(rig.t("state"), "idle", 30)
        pub = Mqtt(rig.broker_port, [], name="burst-publisher", max_inflight=0)
        rig.scope.callback(pub.close)
        sampler = RssSampler(rig.bridge.pid, 0.01)
        rig.scope.callback(sampler.stop)
        time.sleep(1.0)
        mark = rig.frames.mark()
        cpu0 = cpu_seconds(rig.bridge.pid)
        topic = rig.t("target")
        t0 = time.monotonic()
        info = None
        for i in range(N_TARGETS):
            az = case.start_deg + (end - case.start_deg) * (i + 1) / N_TARGETS
            info = pub.publish(topic, case.payload.format(az=az), qos=1)
            if i % 50 == 49:  # spread over BURST_S
                ahead = t0 + BURST_S * (i + 1) / N_TARGETS - time.monotonic()
                if ahead > 0:
                    time.sleep(ahead)
        t_last = time.monotonic()
        assert info is not None
        info.wait_for_publish(30)
        t_acked = time.monotonic()
        travel_s = abs(end - case.start_deg) / case.speed_deg_s
        try:
            rig.emu.wait_for(lambda s: not s.is_moving and abs(s.az_deg - end) < 0.3, travel_s + 30)
        except TimeoutError as exc:
            raise BenchError(f"{case.model}: the rotor did not settle at {end}: {exc}") from None
        with rig.emu.lock:
            events = list(rig.emu.device.events)
        arrived = [e for e in events if e.kind == "arrived" and e.time_s >= t0]
        settled_t = arrived[-1].time_s if arrived else time.monotonic()
        time.sleep(1.0)
        cpu1 = cpu_seconds(rig.bridge.pid)
        sampler.stop()
        frames = [f for f in rig.frames.since(mark) if not case.is_poll(f)]
        polls = [f for f in rig.frames.since(mark) if case.is_poll(f)]
        errors = [m for m in rig.mqtt.on(rig.t("error")) if m.t >= t0]
        before = sampler.between(t0 - 1.0, t0)
        during = sampler.between(t0, settled_t + 1.0)
    return {
        "targets": N_TARGETS,
        "final_deg": end,
        "publish_s": t_last - t0,
        "acked_s": t_acked - t0,
        "frames": [
            {
                "t_ms": round((f.time_s - t0) * 1000, 1),
                "data": f.data.hex()
                if case.model != "rotorez"
                else f.data.decode(errors="replace"),
                "outcome": f.outcome,
            }
            for f in frames
        ],
        "frames_beyond_first": max(0, len(frames) - 1),
        "polls": len(polls),
        "settle_s": settled_t - t_last,
        "travel_s": travel_s,
        "rss_before_mb": median(before) / 2**20 if before else None,
        "rss_peak_mb": max(during) / 2**20 if during else None,
        "rss_after_mb": during[-1] / 2**20 if during else None,
        "cpu_s": cpu1 - cpu0,
        "error_events": len(errors),
    }


def run(scope: Scope, quick: bool) -> ItemResult:
    result = ItemResult("burst", f"5. Burst: {N_TARGETS:,} targets in {BURST_S:g} s on one rotator")
    table = Table(
        result.title,
        [
            "model",
            "published s",
            "frames",
            "beyond 1st",
            "settle s",
            "travel s",
            "RSS before MB",
            "RSS peak MB",
            "RSS after MB",
            "CPU s",
        ],
    )
    for case in CASES:
        if quick and not case.quick:
            continue
        r = run_case(scope, case, quick)
        result.data[case.model] = r
        table.add(
            case.model,
            r["publish_s"],
            len(r["frames"]),
            r["frames_beyond_first"],
            r["settle_s"],
            r["travel_s"],
            r["rss_before_mb"],
            r["rss_peak_mb"],
            r["rss_after_mb"],
            r["cpu_s"],
        )
        shown = ", ".join(
            f"{f['t_ms']:.0f} ms {f['data']!r} ({f['outcome']})" for f in r["frames"][:6]
        )
        more = f" ... ({len(r['frames'])} in all)" if len(r["frames"]) > 6 else ""
        table.notes.append(f"{case.model} frames: {shown}{more}")
        if case.model == "rotorez":
            growth = (r["rss_peak_mb"] or 0) - (r["rss_before_mb"] or 0)
            result.verdicts += [
                Verdict(
                    "burst: at most 3 frames to the controller beyond the first",
                    f"{r['frames_beyond_first']} beyond the first ({len(r['frames'])} "
                    "command frames)",
                    r["frames_beyond_first"] <= 3,
                ),
                Verdict(
                    "burst: the rotor settles at the last target",
                    f"at {r['final_deg']:g} deg {r['settle_s']:.1f} s after the last target "
                    f"(travel alone {r['travel_s']:.1f} s; brake delay 5 s by design)",
                    True,
                ),
                Verdict(
                    "burst: memory flat",
                    f"RSS {r['rss_before_mb']:.1f} MB before, peak {r['rss_peak_mb']:.1f} MB "
                    f"(+{growth:.1f} MB), {r['rss_after_mb']:.1f} MB after",
                    growth < 2.0,
                ),
            ]
    table.notes += [
        "frames = command frames the controller received (polls excluded); settle = last target "
        "published -> the emulated rotor arrived there; CPU s = bridge CPU time from the burst to "
        "1 s after settling.",
    ]
    result.tables.append(table)
    return result
