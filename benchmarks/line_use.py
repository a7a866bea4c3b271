"""Item 3, line use: how much of the serial line the bridge can use when asked to poll as fast as
it can, and how much its default idle polling uses.

Flat out: both poll intervals 1 ms, rotor idle, one rotator per bridge, on a line paced at its
rate both ways. The bridge keeps at most one query open (worker rule 3), so the most a line can
carry is one exchange (query + reply bytes at 10 bits each) after another: capacity =
baud / (10 * exchange bytes) polls/s. Measured: polls/s and the bytes that crossed the line. The
rest of each cycle is the controller's turnaround (2 ms in the emulators, an assumption) and the
bridge's (from the last reply byte to the next query).

Idle: every model on one bridge with the default settings (each model's default idle poll,
derived to take at most 5 % of its line), bytes per second in each direction after start-up, as a
share of the line's capacity in that direction.
"""

from __future__ import annotations

import time
from typing import Any

from benchmarks.harness import Scope
from benchmarks.report import ItemResult, Table, Verdict, line_time_s
from benchmarks.rig import baud_of, many_rotators, single_rotator

FLAT_OUT = {"idle_poll_interval_s": 0.001, "moving_poll_interval_s": 0.001}
CONTROLLER_TURNAROUND_S = 0.002  # the emulators' processing_delay_s default
# (label, model, emulator options)
FLAT_CASES: list[tuple[str, str, dict[str, Any]]] = [
    ("rotorez", "rotorez", {}),
    ("rotorez, ctrl 0 ms", "rotorez", {"processing_delay_s": 0.0}),
    ("rot2prog", "rot2prog", {}),
    ("rot1prog", "rot1prog", {}),
    ("md01", "md01", {}),
    ("md01, ctrl 0 ms", "md01", {"processing_delay_s": 0.0}),
    ("satel", "satel", {}),
]
#: bytes of one position exchange (query + reply), from the protocol documents
EXCHANGE_BYTES = {
    "rotorez": 4 + 4,
    "rotorcard": 4 + 4,
    "rot2prog": 13 + 12,
    "rot1prog": 13 + 5,
    "md01": 13 + 12,
    "satel": 1 + 165,
}
IDLE_MODELS = ["rotorez", "rotorcard", "dcu1", "rot2prog", "rot1prog", "md01", "satel"]


def _is_poll(frame: Any) -> bool:
    return frame.data == b"AI1;" or frame.outcome == "status"


def flat_out(
    scope: Scope, label: str, model: str, emu_opts: dict[str, Any], window_s: float
) -> dict[str, Any]:
    name = "line-" + label.replace(" ", "").replace(",", "-")
    with single_rotator(
        scope, name, model, emu_opts=emu_opts, rotator=FLAT_OUT, count_bytes=True
    ) as rig:
        time.sleep(1.0)  # past the connect traffic (version, banner, options)
        assert rig.counter is not None
        mark = rig.frames.mark()
        out0, in0 = rig.counter.snapshot()
        t0 = time.monotonic()
        time.sleep(window_s)
        t1 = time.monotonic()
        out1, in1 = rig.counter.snapshot()
        frames = [f for f in rig.frames.since(mark) if t0 <= f.time_s <= t1]
    polls = [f.time_s for f in frames if _is_poll(f)]
    others = len(frames) - len(polls)
    baud = baud_of(model)
    exchange_bytes = EXCHANGE_BYTES[model]
    exchange_s = line_time_s(exchange_bytes, baud)
    # whole cycles only: from the first poll in the window to the last
    rate = (len(polls) - 1) / (polls[-1] - polls[0]) if len(polls) > 2 else 0.0
    cycle_s = 1 / rate if rate else float("inf")
    return {
        "baud": baud,
        "polls_per_s": rate,
        "exchange_bytes": exchange_bytes,
        "measured_bytes_per_poll": (out1 - out0 + in1 - in0) / max(1, len(polls)),
        "capacity_polls_per_s": 1 / exchange_s,
        "line_use": rate * exchange_s,
        "line_and_controller_use": rate
        * (exchange_s + emu_opts.get("processing_delay_s", CONTROLLER_TURNAROUND_S)),
        "controller_turnaround_ms": 1000
        * emu_opts.get("processing_delay_s", CONTROLLER_TURNAROUND_S),
        "bridge_turnaround_ms": (
            cycle_s - exchange_s - emu_opts.get("processing_delay_s", CONTROLLER_TURNAROUND_S)
        )
        * 1000,
        "other_frames": others,
        "window_s": t1 - t0,
    }


def idle_traffic(scope: Scope, window_s: float, models: list[str]) -> dict[str, Any]:
    specs = [(m, m, {}, {}) for m in models]
    with many_rotators(scope, "line-idle", specs) as rig:
        time.sleep(2.0)  # past start-up
        before = {rid: line.counter.snapshot() for rid, line in rig.lines.items()}
        t0 = time.monotonic()
        time.sleep(window_s)
        elapsed = time.monotonic() - t0
        after = {rid: line.counter.snapshot() for rid, line in rig.lines.items()}
    out: dict[str, Any] = {}
    for rid in models:
        to_dev = (after[rid][0] - before[rid][0]) / elapsed
        from_dev = (after[rid][1] - before[rid][1]) / elapsed
        per_dir = baud_of(rid) / 10  # bytes/s one direction can carry
        out[rid] = {
            "baud": baud_of(rid),
            "to_controller_bytes_s": to_dev,
            "from_controller_bytes_s": from_dev,
            "share_to": to_dev / per_dir,
            "share_from": from_dev / per_dir,
            "window_s": elapsed,
        }
    return out


def run(scope: Scope, quick: bool, models: set[str] | None = None) -> ItemResult:
    result = ItemResult("line", "3. Line use")
    window = 2.0 if quick else 4.0
    flat = Table(
        "3a. Polling flat out (both poll intervals 1 ms, rotor idle)",
        [
            "model",
            "baud",
            "exchange B",
            "polls/s",
            "capacity/s",
            "line use %",
            "line+ctrl %",
            "ctrl turn ms",
            "bridge turn ms",
        ],
    )
    chosen = [c for c in FLAT_CASES if not models or c[1] in models]
    if quick:
        chosen = [c for c in chosen if c[0] in ("rotorez", "rotorez, ctrl 0 ms")]
    for label, model, emu_opts in chosen:
        r = flat_out(scope, label, model, emu_opts, window)
        result.data.setdefault("flat_out", {})[label] = r
        flat.add(
            label,
            r["baud"],
            r["exchange_bytes"],
            r["polls_per_s"],
            r["capacity_polls_per_s"],
            100 * r["line_use"],
            100 * r["line_and_controller_use"],
            r["controller_turnaround_ms"],
            r["bridge_turnaround_ms"],
        )
        ctrl = r["controller_turnaround_ms"]
        result.verdicts.append(
            Verdict(
                f"{label}: >= 90 % of the line's capacity when polling flat out",
                f"{r['polls_per_s']:.1f} polls/s of {r['capacity_polls_per_s']:.1f} = "
                f"{100 * r['line_use']:.1f} %"
                + (
                    f" (line + the controller's {ctrl:g} ms turnaround: "
                    f"{100 * r['line_and_controller_use']:.1f} %)"
                    if ctrl
                    else ""
                ),
                r["line_use"] >= 0.9,
            )
        )
    flat.notes += [
        "capacity = baud / (10 bits * exchange bytes): one exchange after another, nothing else; "
        "line use = polls/s / capacity; line+ctrl also counts the controller's turnaround (2 ms "
        "in the emulators, an assumption; 'ctrl 0 ms' rows set it to 0 to show the bridge "
        "alone); bridge turn = the rest of each cycle (last reply byte -> next query out, "
        "including the paced line's own scheduling). polls/s from the first to the last poll "
        "of the window.",
    ]
    result.tables.append(flat)

    idle_models = [m for m in IDLE_MODELS if not models or m in models]
    idle = idle_traffic(scope, 5.0 if quick else 20.0, idle_models)
    result.data["idle"] = idle
    table = Table(
        "3b. Idle polling traffic with the defaults (model idle polls), all models on one bridge",
        ["model", "baud", "to ctrl B/s", "from ctrl B/s", "% of line (to)", "% of line (from)"],
    )
    for model, r in idle.items():
        table.add(
            model,
            r["baud"],
            r["to_controller_bytes_s"],
            r["from_controller_bytes_s"],
            f"{100 * r['share_to']:.2f}",
            f"{100 * r['share_from']:.2f}",
        )
    table.notes.append(
        "% of line = bytes/s / (baud / 10), per direction; a request/response exchange keeps the "
        "line busy for the sum. The DCU-1 cannot report: never polled."
    )
    result.tables.append(table)
    busy = {
        m: (r["to_controller_bytes_s"] + r["from_controller_bytes_s"]) * 10 / r["baud"]
        for m, r in idle.items()
    }
    small = [m for m, b in busy.items() if b < 0.05]
    large = [m for m, b in busy.items() if b >= 0.05]
    result.data["idle_line_busy"] = busy
    detail = ", ".join(f"{m} {100 * b:.1f} %" for m, b in busy.items())
    result.verdicts.append(
        Verdict(
            "idle polling traffic negligible (line busy < 5 %, both directions)",
            f"line busy {detail}" + (f"; not negligible: {', '.join(large)}" if large else ""),
            not large if small else None,
        )
    )
    return result
