"""Item 2, bearing freshness while turning: how old the bearing a dashboard shows is, against the
emulated rotor's true position, while the rotor turns at constant speed.

Method: the bridge runs with its defaults (moving poll interval 0.2 s) on a paced line; a
recording MQTT client stamps every retained `R/bearing` it receives. The emulator's motion events
give the true trajectory P(t) (linear between its "move" and "arrived" events). On a 1 ms grid
over the turn (from 0.5 s after the start, when the bridge polls at its moving rate):
- age(t): how long ago the true position was last within half a reporting step of the shown
  bearing B (the controller reports whole degrees on a Rotor-EZ, 0.5 deg on a SPID at 2
  pulses/deg), i.e. since when the dashboard has been wrong at the controller's resolution.
- lag(t): (P(t) - B) / speed, the raw delay behind the true position, rounding included.
The limit: one moving poll interval plus one position exchange at the line rate.
SatEL is not measured: it is silent while it slews; the bridge shows an estimate from the
nominal speeds (README), not a reading.
"""

from __future__ import annotations

import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any

from benchmarks.harness import ABORT, BenchError, Scope
from benchmarks.report import ItemResult, Table, Verdict, line_time_s, percentile
from benchmarks.rig import baud_of, single_rotator


@dataclass(frozen=True)
class Case:
    model: str
    target: float  # azimuth to turn to (from 0)
    quick_target: float
    step_deg: float  # the controller's reporting step
    exchange_bytes: int  # query + reply
    payload: str = "{az}"
    emu_opts: dict[str, Any] = field(default_factory=dict)


CASES = [
    Case("rotorez", 120.0, 36.0, 1.0, 4 + 4),
    Case("rot2prog", 20.0, 8.0, 0.5, 13 + 12, "{az} 0"),
    Case("md01", 20.0, 8.0, 0.5, 13 + 12, "{az} 0"),
]
MOVING_POLL_S = 0.2  # the bridge's default
SKIP_START_S = 0.5


def trajectory(events: list[Any], after_t: float) -> tuple[float, float, float, float]:
    """(t0, a0, t1, a1) of the commanded move that started after `after_t`."""
    moves = [e for e in events if e.kind == "move" and e.time_s >= after_t]
    arrivals = [e for e in events if e.kind == "arrived" and e.time_s >= after_t]
    if not moves or not arrivals:
        raise BenchError(f"no complete move in the emulator's events: {events[-5:]}")
    return moves[0].time_s, moves[0].az_deg, arrivals[-1].time_s, arrivals[-1].az_deg


def analyse(
    bearings: list[tuple[float, float]], traj: tuple[float, float, float, float], half_step: float
) -> dict[str, Any]:
    t0, a0, t1, a1 = traj
    v = (a1 - a0) / (t1 - t0)
    sign = 1.0 if v > 0 else -1.0
    speed = abs(v)
    ages: list[float] = []
    lags: list[float] = []
    i = 0
    shown: float | None = None
    t = t0 + SKIP_START_S
    while t <= t1:
        while i < len(bearings) and bearings[i][0] <= t:
            shown = bearings[i][1]
            i += 1
        if shown is not None:
            true = a0 + v * (t - t0)
            # the true position left [shown - h, shown + h] (in the direction of travel) at:
            left_t = t0 + (shown + sign * half_step - a0) / v
            ages.append(max(0.0, t - left_t))
            lags.append(sign * (true - shown) / speed)
        t += 0.001
    if not ages:
        raise BenchError("no bearing was published while the rotor turned")
    return {"speed_deg_s": speed, "ages_s": ages, "lags_s": lags}


def run_case(scope: Scope, case: Case, quick: bool) -> dict[str, Any]:
    target = case.quick_target if quick else case.target
    with single_rotator(
        scope, f"freshness-{case.model}", case.model, emu_opts=case.emu_opts
    ) as rig:
        rig.mqtt.wait_value(rig.t("state"), "idle", 30)
        mark = rig.mqtt.mark()
        t_cmd = time.monotonic()
        rig.mqtt.publish(rig.t("target"), case.payload.format(az=f"{target:g}"))
        speed = 6.0 if case.model == "rotorez" else 1.0  # the emulators' default speeds
        rig.emu.wait_for(
            lambda s: not s.is_moving and abs(s.az_deg - target) < 0.01,
            target / speed + 15,
        )
        time.sleep(MOVING_POLL_S * 3)
        with rig.emu.lock:
            events = list(rig.emu.device.events)
        bearing_topic = rig.t("bearing")
        bearings = [(m.t, float(m.text)) for m in rig.mqtt.on(bearing_topic)]
        del mark
        polls = [f for f in rig.frames.since(0) if f.time_s >= t_cmd and _is_poll(f)]
    traj = trajectory(events, t_cmd)
    out = analyse(bearings, traj, case.step_deg / 2)
    out["publishes"] = len(bearings)
    out["polls"] = len(polls)
    out["turn_s"] = traj[2] - traj[0]
    return out


def _is_poll(frame: Any) -> bool:
    return frame.data == b"AI1;" or frame.outcome == "status"


def run(scope: Scope, quick: bool, models: set[str] | None = None) -> ItemResult:
    result = ItemResult(
        "freshness", "2. Bearing freshness while turning (defaults: moving poll 0.2 s)"
    )
    table = Table(
        result.title,
        [
            "model",
            "baud",
            "speed deg/s",
            "turn s",
            "polls/s",
            "age p50 ms",
            "age p99 ms",
            "age max ms",
            "lag p50 ms",
            "lag p99 ms",
            "limit ms",
        ],
    )
    chosen = [c for c in CASES if (not models or c.model in models)]
    if quick:
        chosen = [c for c in chosen if c.model == "rotorez"]
    outputs: dict[str, dict[str, Any]] = {}
    # the Rotor-EZ alone (its ages are a few ms apart); the SPID turns take 20 s of waiting each
    # and tolerate company
    for case in [c for c in chosen if c.model == "rotorez"]:
        outputs[case.model] = run_case(scope, case, quick)
    others = [c for c in chosen if c.model != "rotorez"]
    if others:
        with ThreadPoolExecutor(max_workers=len(others)) as pool:
            futures = {c.model: pool.submit(run_case, scope, c, quick) for c in others}
            try:
                for model, future in futures.items():
                    outputs[model] = future.result()
            except BaseException:
                ABORT.set()
                raise
    for case in chosen:
        out = outputs[case.model]
        baud = baud_of(case.model, case.emu_opts)
        exchange_s = line_time_s(case.exchange_bytes, baud)
        limit_ms = (MOVING_POLL_S + exchange_s) * 1000
        ages, lags = out.pop("ages_s"), out.pop("lags_s")
        row = {
            "baud": baud,
            "speed_deg_s": out["speed_deg_s"],
            "turn_s": out["turn_s"],
            "polls_per_s": out["polls"] / out["turn_s"],
            "age_p50_ms": percentile(ages, 50) * 1000,
            "age_p99_ms": percentile(ages, 99) * 1000,
            "age_max_ms": max(ages) * 1000,
            "lag_p50_ms": percentile(lags, 50) * 1000,
            "lag_p99_ms": percentile(lags, 99) * 1000,
            "limit_ms": limit_ms,
            "exchange_ms": exchange_s * 1000,
            "publishes": out["publishes"],
        }
        result.data[case.model] = row
        table.add(
            case.model,
            baud,
            row["speed_deg_s"],
            row["turn_s"],
            row["polls_per_s"],
            row["age_p50_ms"],
            row["age_p99_ms"],
            row["age_max_ms"],
            row["lag_p50_ms"],
            row["lag_p99_ms"],
            limit_ms,
        )
        result.verdicts.append(
            Verdict(
                f"{case.model}: freshness p99 within one moving-poll interval plus one exchange",
                f"age p99 {row['age_p99_ms']:.0f} ms vs limit {limit_ms:.0f} ms "
                f"(0.2 s + {exchange_s * 1000:.1f} ms exchange at {baud} baud)",
                row["age_p99_ms"] <= limit_ms,
            )
        )
    table.notes += [
        "age = time since the true position was last within half a reporting step of the shown "
        "bearing (1 deg steps on a Rotor-EZ, 0.5 deg on SPID); lag = (true - shown) / speed, "
        "rounding included; sampled every 1 ms over the turn, from 0.5 s after it started.",
        "limit = moving poll interval (0.2 s) + one position exchange (query + reply) at the line "
        "rate. A Rot2Prog exchange (417 ms at 600 baud) is longer than the poll interval: the "
        "line is the bottleneck there and the bridge polls back to back.",
    ]
    result.tables.append(table)
    return result
