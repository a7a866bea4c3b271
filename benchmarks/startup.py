"""Item 6, start-up: process start -> retained state and Home Assistant discovery on the broker.

Each run: a fresh broker with a recording client subscribed to everything, a fresh emulated
Rotor-EZ behind a paced line, then `python -m bridge run -c FILE` is started; times are from
just before the process is spawned to the first arrival of each milestone at the recorder.
For context, the bare interpreter start and the import of the bridge are timed the same way.
"""

from __future__ import annotations

import subprocess
import time
from statistics import median
from typing import Any

from benchmarks.harness import PYTHON, Mqtt, Scope, child_env, start_bridge, start_broker
from benchmarks.line import FrameLog
from benchmarks.report import ItemResult, Table, Verdict
from benchmarks.rig import EmuHost, open_line


def _time_command(argv: list[str], runs: int) -> float:
    times = []
    for _ in range(runs):
        t0 = time.monotonic()
        subprocess.run(argv, check=True, env=child_env(), capture_output=True, timeout=60)
        times.append(time.monotonic() - t0)
    return median(times)


def one_run(scope: Scope, i: int, count: int) -> dict[str, float | None]:
    with Scope(scope.workdir / f"run-{count}-{i}") as sc:
        port = start_broker(sc)
        mqtt = Mqtt(port, ["#"], name="startup-recorder")
        sc.callback(mqtt.close)
        if count == 1:
            _emu, _relay, link = open_line(sc, "rotorez", FrameLog())
            paths = [link]
        else:
            host = EmuHost(sc, "rotorez", count)
            paths = [host.link(k) for k in range(count)]
        ids = [f"r{k}" for k in range(count)]
        roots = ["rotor"] if count == 1 else [f"rotor/{rid}" for rid in ids]
        rotators = [
            {"id": rid, "model": "rotorez", "port": str(p)}
            for rid, p in zip(ids, paths, strict=True)
        ]
        mark = mqtt.mark()
        bridge = start_bridge(sc, port, rotators)
        t0 = bridge.started_t
        mqtt.wait_all([f"{r}/state" for r in roots], "idle", 60)
        time.sleep(0.5)
        msgs = mqtt.messages[mark:]
        bridge.check()

    def first(pred: Any) -> float | None:
        for m in msgs:
            if pred(m):
                return m.t - t0
        return None

    def last_of_each(topics_pred: Any, value_pred: Any = lambda m: True) -> float | None:
        """When every topic matching topics_pred has had its first matching message."""
        seen: dict[str, float] = {}
        for m in msgs:
            if topics_pred(m.topic) and value_pred(m) and m.topic not in seen:
                seen[m.topic] = m.t - t0
        return max(seen.values()) if seen else None

    disc = [m for m in msgs if m.topic.startswith("homeassistant/")]
    return {
        "first_message_s": first(lambda m: True),
        "bridge_online_s": first(lambda m: m.topic == "rotor/bridge/state" and m.text == "online"),
        "discovery_s": last_of_each(lambda t: t.startswith("homeassistant/")),
        "discovery_configs": float(len({m.topic for m in disc})),
        "discovery_messages": float(len(disc)),
        "retained_state_s": last_of_each(
            lambda t: t.startswith("rotor/") and "/bridge/" not in t and not t.endswith("/error"),
            lambda m: not m.topic.endswith("/availability") or m.text == "online",
        ),
        "available_s": last_of_each(
            lambda t: t.endswith("/availability"), lambda m: m.text == "online"
        ),
        "bearing_s": last_of_each(lambda t: t.endswith("/bearing")),
        "idle_s": last_of_each(lambda t: t.endswith("/state"), lambda m: m.text == "idle"),
    }


MILESTONES = [
    ("first_message_s", "first message from the bridge"),
    ("bridge_online_s", "B/bridge/state online"),
    ("discovery_s", "all Home Assistant discovery configs"),
    ("available_s", "R/availability online (first reading)"),
    ("bearing_s", "R/bearing"),
    ("retained_state_s", "every retained R/... topic once"),
    ("idle_s", "R/state idle (after the 5 s brake window)"),
]


def run(scope: Scope, quick: bool) -> ItemResult:
    result = ItemResult(
        "startup", "6. Start-up: process start -> state and discovery on the broker"
    )
    runs = 1 if quick else 3
    plan = [(1, runs)] + ([] if quick else [(8, 1), (32, 1)])
    interp = _time_command([PYTHON, "-c", "pass"], 3)
    imports = _time_command([PYTHON, "-c", "import bridge.app, bridge.cli"], 3)
    table = Table(
        result.title,
        ["milestone", *[f"{c} rotator{'s' if c > 1 else ''} ms" for c, _ in plan]],
    )
    results: dict[int, list[dict[str, float | None]]] = {}
    for count, n in plan:
        results[count] = [one_run(scope, i, count) for i in range(n)]

    def med(count: int, key: str) -> float | None:
        values = [r[key] for r in results[count] if r[key] is not None]
        return median(values) if values else None  # type: ignore[type-var]

    def ms(v: float | None) -> str:
        return "-" if v is None else f"{v * 1000:.0f}"

    table.add("python -c pass (interpreter alone)", *[ms(interp) for _ in plan])
    table.add("import bridge.app (interpreter + imports)", *[ms(imports) for _ in plan])
    for key, label in MILESTONES:
        table.add(label, *[ms(med(c, key)) for c, _ in plan])
    table.add(
        "discovery: distinct configs / messages received (count)",
        *[
            f"{med(c, 'discovery_configs'):.0f} / {med(c, 'discovery_messages'):.0f}"
            for c, _ in plan
        ],
    )
    table.notes.append(
        f"median of {runs} run(s) for 1 rotator; times from spawning `python -m bridge run` to "
        "the recorder receiving the message; the Rotor-EZ's state is 'braking' for its 5 s "
        "brake delay after start-up by design (the bridge cannot know whether it just stopped)."
    )
    result.tables.append(table)
    result.data = {
        "interpreter_s": interp,
        "imports_s": imports,
        "runs": {str(c): r for c, r in results.items()},
    }
    state = med(1, "retained_state_s")
    disc = med(1, "discovery_s")
    if state is not None and disc is not None:
        result.verdicts.append(
            Verdict(
                "start-up: retained state and discovery on the broker (reported, no target)",
                f"discovery after {disc:.2f} s, every retained topic after {state:.2f} s "
                f"(interpreter + imports alone {imports:.2f} s)",
                None,
            )
        )
    return result
