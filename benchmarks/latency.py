"""Item 1, command latency: MQTT publish of a command -> the complete command frame received by the
emulated controller, through a real mosquitto, the bridge as its own process and a real pty.
Beside it: the frame's own transmission time at the line rate (the limit) and Hamlib's rotctld
driving the same emulator model (TCP command -> frame).

What a "command" is: two kinds, because the bridge treats them differently on purpose.
- Stops, for every model: never held, written at once (on a half-duplex line right after the
  exchange in flight). Rotor-EZ/RotorCard `;`, DCU-1 `AS1;`, SPID the 13-byte stop frame (which
  the controller answers with its position), SatEL `s`.
- Targets, where they are not held by design, each sent as an isolated command: at least
  targets.BURST_QUIET_S after the previous target went out (the bridge holds a stream of targets
  until it pauses, on purpose). RotorCard `AP1xxx<CR>`, sent once the bridge reports the rotor
  idle (its emulated rotor turns at 1000 deg/s so it settles between samples); Rot2Prog and
  MD-01 the 13-byte set frame (SPID takes a target at any time; each is 1 deg further on).
  Not on a Rotor-EZ or DCU-1: a target is held there for the 5 s brake delay after any motion
  (README), so it measures the brake, not the bridge. Not on a SatEL: silent while it slews.

Conditions: "idle" = the default poll intervals (SPID targets: both 1 s, so that a turning rotor
does not speed up polling); "polling" = both poll intervals 1 ms: the bridge polls flat out and
an exchange is (nearly) always in flight. A random pause after every frame spreads the commands
over the poll cycle.

Issue 15, a stop right behind another command, to a mosquitto with its default settings (Nagle
on: it holds a second small packet until the bridge has acknowledged the first, and Linux delays
the acknowledgement of a packet the bridge does not answer by up to 40 ms); timed from the stop's
publish. Each stop comes a second after the one before (apart_s), as a stop that adds nothing to
the last one is not written at all. "0-3 ms after a target": the bridge answers a target with
its status (QoS 0) within a few milliseconds, and that answer carries the acknowledgement; the
target goes out on the line first, so the stop may wait behind its 7 bytes (14.6 ms at 4800
baud), counted in the verdict's limit. "0-3 ms after a refused target" (999, out of range): the
answer is an error event at QoS 1, and the broker's PUBACK for it is the packet the bridge does
not answer, so the broker's hold lasts until the bridge's delayed ACK unless the bridge
acknowledges at once (bridge/interfaces/mqtt/client.py rule 9). While retained state went out at QoS
1, every target was answered that way.

Every controller sits behind a paced line (line.PacedRelay): the host's bytes reach it when
their last bit would have at the line rate, queued behind anything still being sent, and the
emulators pace their replies. So a latency includes the frame's own transmission (the "line"
column, the limit) and any wait for the line; "beyond" is p99 minus that limit.
"""

from __future__ import annotations

import random
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any

from benchmarks.hamlib import rotctld_cases, run_rotctld_case
from benchmarks.harness import ABORT, BenchError, Scope, check_abort
from benchmarks.report import ItemResult, Table, Verdict, line_time_s, percentile
from benchmarks.rig import baud_of, single_rotator

FLAT_OUT = {"idle_poll_interval_s": 0.001, "moving_poll_interval_s": 0.001}
WARMUP = 3  # commands sent before the measured ones (first-use costs, not steady state)


NODELAY = "set_tcp_nodelay true\n"


@dataclass(frozen=True)
class Lead:
    """Another command published before each measured one (not timed itself)."""

    command: str  # MQTT leaf topic
    payload: Callable[[int], str]
    gap_s: tuple[float, float] = (0.0, 0.003)  # from its publish to the next publish


@dataclass(frozen=True)
class Condition:
    name: str
    rotator: dict[str, Any]
    gap_s: tuple[float, float]  # random pause after each frame (and after idle, if awaited)
    broker_conf: str = ""  # extra mosquitto.conf lines (default: mosquitto's own defaults)
    quick: bool = True  # also run with --quick
    leads: tuple[Lead, ...] = ()  # published in this order before each measured command


@dataclass(frozen=True)
class Case:
    model: str
    command: str  # MQTT leaf topic: "stop" or "target"
    frame: bytes  # a representative complete frame (its transmission time is the limit)
    label: str
    match: Callable[[Any], bool]
    conditions: tuple[Condition, ...]
    payload: Callable[[int], str] = lambda i: "STOP"
    emu_opts: dict[str, Any] = field(default_factory=dict)
    await_idle: bool = False  # send each command only once the bridge reports idle
    reply_bytes: int = 0  # a poll's reply: waited out before a command on a half-duplex line
    poll: Callable[[Any], bool] = lambda f: False
    quick: bool = True  # also run with --quick
    slow: bool = False  # run side by side with the other slow rows (waiting dominates)


def _spid_set(f: Any) -> bool:
    return f.outcome.startswith("set")


def _spid_payload(el: bool) -> Callable[[int], str]:
    return lambda i: f"{10 + i} 10" if el else f"{10 + i}"


def isolation_s() -> float:
    """How long after a target was sent the next one counts as a new command, not as part of a
    stream the bridge holds back on purpose (targets.BURST_QUIET_S)."""
    from bridge.session import targets

    return float(targets.BURST_QUIET_S)


_EZ_POLL = lambda f: f.data == b"AI1;"  # noqa: E731
_STATUS_POLL = lambda f: f.outcome == "status"  # noqa: E731
_GS232_POLL = lambda f: f.outcome == "query"  # noqa: E731
_EASYCOMM_POLL = lambda f: f.data == b"AZ" and f.outcome == "query"  # noqa: E731
_SPID_FRAME = bytes(13)
_RT21_SET = b"AP1100.5\r;"
_RC2800_SET = b"A100.5\r"
_PROSISTEL_SET = b"\x02AG100\r"
AFTER_TARGET = Lead("target", lambda i: "110" if i % 2 else "100")
AFTER_REFUSED = Lead("target", lambda i: "999")  # out of range: an error event (QoS 1)
_SPID_IDLE = {"idle_poll_interval_s": 1.0, "moving_poll_interval_s": 1.0, "settle_s": 2.0}


def apart_s() -> tuple[float, float]:
    """The pause between two stops to a rotor at rest, each a stop of its own: a stop that comes
    within the brake window of another, with nothing sent and no turning seen since, adds
    nothing on the wire (session/stops.py rule 1), so such stops are spaced past that window,
    which with no brake delay is STOP_MERGE_MIN_S."""
    from bridge.session import stops

    return (stops.STOP_MERGE_MIN_S + 0.02, stops.STOP_MERGE_MIN_S + 0.08)


# the brake delay does not change when an idle rotor's stop reaches the controller; without it
# stops merge for 1 s, not the Rotor-EZ's 5 s, and 60 of them take a minute
NO_BRAKE = {"brake_delay_s": 0.0}


def _spid_stop(model: str, reply: int) -> Case:
    baud = baud_of(model)
    reply_s = line_time_s(reply, baud)
    exchange_s = line_time_s(13 + reply, baud)
    apart = apart_s()
    return Case(
        model,
        "stop",
        _SPID_FRAME,
        "stop (13 B)",
        lambda f: f.outcome == "stop",
        (
            # spaced so that no stop merges into the one before (apart_s); the pause varies by
            # a whole exchange when polling, so commands land at any phase of it
            Condition("idle", {}, (apart[0], apart[1] + reply_s)),
            Condition("polling", FLAT_OUT, (apart[0], apart[1] + exchange_s), quick=False),
        ),
        poll=_STATUS_POLL,
        quick=model == "md01",
    )


def _spid_target(model: str, reply: int, quick: bool) -> Case:
    iso = isolation_s() + 0.02
    exchange_s = line_time_s(13 + reply, baud_of(model))
    return Case(
        model,
        "target",
        _SPID_FRAME,
        "target (set, 13 B)",
        _spid_set,
        (
            # the pause varies by half the 1 s poll period, or the commands lock to its phase
            Condition("idle", _SPID_IDLE, (iso, iso + 0.5)),
            Condition("polling", FLAT_OUT, (iso, iso + exchange_s + 0.02), quick=False),
            *(
                [
                    Condition(
                        "idle, nodelay broker",
                        _SPID_IDLE,
                        (iso, iso + 0.5),
                        broker_conf=NODELAY,
                        quick=False,
                    )
                ]
                if model == "md01"
                else []
            ),
        ),
        payload=_spid_payload(model != "rot1prog"),
        reply_bytes=reply,
        poll=_STATUS_POLL,
        quick=quick,
    )


def cases() -> list[Case]:
    """Stops (never held: the urgent path) for every model; targets where they are not held by
    design, each sent as an isolated command (see isolation_s)."""
    apart = apart_s()  # stops to a rotor at rest: each one on the wire
    iso = isolation_s() + 0.02
    return [
        Case(
            "rotorez",
            "stop",
            b";",
            "stop ;",
            lambda f: f.data == b";",
            (
                Condition("idle", NO_BRAKE, apart),
                Condition("polling", {**FLAT_OUT, **NO_BRAKE}, apart),
                # issue 15: a stop right behind another command
                Condition("0-3 ms after a target", NO_BRAKE, apart, leads=(AFTER_TARGET,)),
                Condition("0-3 ms after a refused target", NO_BRAKE, apart, leads=(AFTER_REFUSED,)),
            ),
            poll=_EZ_POLL,
        ),
        Case(
            "rotorcard",
            "target",
            b"AP1100\r",
            "target AP1xxx<CR>",
            lambda f: f.data.startswith(b"AP1"),
            (
                Condition(
                    "idle", {"moving_poll_interval_s": 0.02, "settle_s": 0.05}, (iso, iso + 0.04)
                ),
            ),
            payload=lambda i: "110" if i % 2 else "100",
            emu_opts={"speed_deg_s": 1000.0},
            await_idle=True,
            poll=_EZ_POLL,
            slow=True,
        ),
        Case(
            "dcu1",
            "stop",
            b"AS1;",
            "stop AS1;",
            lambda f: f.data == b"AS1;",
            (Condition("idle", {}, (0.02, 0.05)),),
            quick=False,
        ),
        _spid_stop("rot2prog", 12),
        _spid_stop("rot1prog", 5),
        _spid_stop("md01", 12),
        _spid_target("rot2prog", 12, False),
        _spid_target("md01", 12, False),
        Case(
            "gs232b",
            "stop",
            b"S\r",
            "stop S<CR>",
            lambda f: f.outcome == "stop",
            (Condition("idle", {}, apart), Condition("polling", FLAT_OUT, apart)),
            poll=_GS232_POLL,
        ),
        Case(
            "gs232b",
            "target",
            b"W100 010\r",
            "target Wxxx yyy<CR>",
            lambda f: f.outcome == "move",
            (Condition("idle", {}, (iso, iso + 0.5)),),
            payload=_spid_payload(True),
            poll=_GS232_POLL,
        ),
        Case(
            "easycomm2",
            "stop",
            b"SA SE\n",
            "stop SA SE<LF>",
            lambda f: f.outcome == "stop",
            (Condition("idle", {}, apart), Condition("polling", FLAT_OUT, apart)),
            poll=_EASYCOMM_POLL,
        ),
        Case(
            "easycomm2",
            "target",
            b"AZ100.0 EL10.0\n",
            "target AZxx.x ELyy.y<LF>",
            lambda f: f.outcome == "move",
            (Condition("idle", {}, (iso, iso + 0.5)),),
            payload=_spid_payload(True),
            poll=_EASYCOMM_POLL,
        ),
        Case(
            "satel",
            "stop",
            b"s",
            "stop s",
            lambda f: f.data == b"s",
            (
                Condition("idle", {}, apart),
                Condition("polling", FLAT_OUT, apart),
                Condition("idle, nodelay broker", {}, apart, broker_conf=NODELAY),
            ),
            poll=_STATUS_POLL,
            quick=False,
        ),
        *_rt21(iso, apart),
        *_rc2800(iso, apart),
        *_prosistel(iso, apart),
    ]


def _stop_and_target(
    model: str,
    stop: tuple[bytes, str],
    target: tuple[bytes, str],
    *,
    payload: Callable[[int], str],
    poll: Callable[[Any], bool],
) -> Callable[[float, tuple[float, float]], list[Case]]:
    """A model's stop and target rows: each a (frame, label); ``payload`` the i-th target's
    message, ``poll`` which logged frame is its query. Returns what builds them for an isolation
    time and a stop spacing."""

    def build(iso: float, apart: tuple[float, float]) -> list[Case]:
        polled = poll
        return [
            Case(
                model,
                "stop",
                stop[0],
                stop[1],
                lambda f: f.outcome == "stop",
                (Condition("idle", {}, apart), Condition("polling", FLAT_OUT, apart)),
                poll=polled,
            ),
            Case(
                model,
                "target",
                target[0],
                target[1],
                lambda f: f.outcome == "move",
                (Condition("idle", {}, (iso, iso + 0.5)),),
                payload=payload,
                poll=polled,
            ),
        ]

    return build


# the Green Heron RT-21: a stop ``;`` and a heading that runs at its CR
_rt21 = _stop_and_target(
    "rt21",
    (b";", "stop ;"),
    (_RT21_SET, "target AP1ddd.d<CR>;"),
    payload=lambda i: f"{10 + i}.5",
    poll=lambda f: f.data == b"BI1;",
)
# the M2 RC2800: the azimuth's stop (the elevation's goes 200 ms later) and a bearing's first
# frame (to the axis last addressed; the other's 200 ms later); its query as logged is ``A``
_rc2800 = _stop_and_target(
    "rc2800",
    (b"A\rS\r", "stop A<CR>S<CR>"),
    (_RC2800_SET, "target A/Eddd.d<CR>"),
    payload=lambda i: f"{10 + i}.5 10",
    poll=lambda f: f.data == b"A",
)
# the Prosistel D: the hard stop G999 and a bearing G in whole degrees, each STX-framed
_prosistel = _stop_and_target(
    "prosistel",
    (b"\x02AG999\r", "stop STX AG999<CR>"),
    (_PROSISTEL_SET, "target STX AGddd<CR>"),
    payload=lambda i: f"{10 + i}",
    poll=lambda f: f.outcome == "query",
)


def run_bridge_case(
    scope: Scope, case: Case, cond: Condition, n: int, rng: random.Random
) -> dict[str, Any]:
    name = f"latency-{case.model}-{case.command}-{cond.name}".replace(" ", "").replace(",", "-")
    with single_rotator(
        scope,
        name,
        case.model,
        emu_opts=case.emu_opts,
        rotator=cond.rotator,
        broker_conf=cond.broker_conf,
    ) as rig:
        state = rig.t("state")
        if case.await_idle:
            rig.mqtt.wait(lambda m: m.topic == state and m.text == "idle", 30, "idle")
        latencies: list[float] = []
        first = rig.frames.mark()
        t_first = time.monotonic()
        last_frame_t = time.monotonic()
        for i in range(n + WARMUP):
            check_abort()
            # the pause is counted from the previous command's frame at the controller
            pause = last_frame_t + rng.uniform(*cond.gap_s) - time.monotonic()
            if pause > 0:
                time.sleep(pause)
            mark_frames, mark_mqtt = rig.frames.mark(), rig.mqtt.mark()
            for lead in cond.leads:
                rig.mqtt.publish(rig.t(lead.command), lead.payload(i))
                _pause(rng.uniform(*lead.gap_s))
            t0 = time.monotonic()
            rig.mqtt.publish(rig.t(case.command), case.payload(i))
            frame = rig.frames.wait(case.match, mark_frames, 5.0)
            if frame is None:
                rig.bridge.check()
                raise BenchError(f"{case.model}: command {i} never reached the controller")
            last_frame_t = frame.time_s
            if i >= WARMUP:
                latencies.append(frame.time_s - t0)
            if case.await_idle:
                rig.mqtt.wait(
                    lambda m: m.topic == state and m.text == "idle", 10, "idle", mark_mqtt
                )
        elapsed = time.monotonic() - t_first
        polls = sum(1 for f in rig.frames.since(first) if case.poll(f))
    return {"latencies_s": latencies, "polls_per_s": polls / elapsed}


def _pause(s: float) -> None:
    """Milliseconds, kept to the tenth: time.sleep alone may overshoot by more than that."""
    end = time.monotonic() + s
    while (left := end - time.monotonic()) > 0:
        if left > 0.0005:
            time.sleep(left - 0.0005)


# -- the item -----------------------------------------------------------------------------------
def _ms(v: float) -> float:
    return v * 1000.0


#: rows dominated by slow lines or by Hamlib's sleeps: run side by side (milliseconds of CPU
#: contention do not matter against hundreds of milliseconds on the line)
SLOW_MODELS = {"rot2prog", "rot1prog"}
N_DEFAULT = {  # stops to a rotor at rest are a second apart (apart_s): 60 of each
    ("rotorez", "stop"): 60,
    ("rot2prog", "stop"): 60,
    ("rot1prog", "stop"): 60,
    ("md01", "stop"): 60,
    ("satel", "stop"): 60,
    ("rot2prog", "target"): 60,
    ("rotorcard", "target"): 100,
    ("md01", "target"): 100,
}


@dataclass(frozen=True)
class Task:
    key: str
    cells: list[Any]  # model, via, command, condition
    line_ms: float
    run: Callable[[], dict[str, Any]]
    slow: bool


def tasks(scope: Scope, quick: bool, models: set[str] | None) -> list[Task]:
    out: list[Task] = []
    seed = 8
    for case in cases():
        if (models and case.model not in models) or (quick and not case.quick):
            continue
        frame_ms = _ms(line_time_s(len(case.frame), baud_of(case.model, case.emu_opts)))
        n = 30 if quick else N_DEFAULT.get((case.model, case.command), 200)
        for cond in case.conditions:
            if quick and not cond.quick:
                continue
            seed += 1
            rng = random.Random(seed)
            out.append(
                Task(
                    f"bridge/{case.model}/{case.command}/{cond.name}",
                    [case.model, "bridge", case.label, cond.name],
                    frame_ms,
                    lambda case=case, cond=cond, n=n, rng=rng: run_bridge_case(
                        scope, case, cond, n, rng
                    ),
                    case.slow or case.model in SLOW_MODELS or case.command == "target",
                )
            )
    for rc in rotctld_cases():
        if (models and rc.model not in models) or (quick and rc.hamlib == 901):
            continue
        frames = {"rotorez": b";", "rotorcard": b"AM1;", "rot2prog": _SPID_FRAME}
        frames["rt21"], frames["prosistel"] = _RT21_SET, _PROSISTEL_SET
        frames["rc2800"] = _RC2800_SET
        frame = {**frames, "gs232b": b"W100 010\r", "easycomm2": b"AZ100.0 EL10.0\n"}[rc.model]
        frame_ms = _ms(line_time_s(len(frame), baud_of(rc.model, rc.emu_opts)))
        for condition in rc.conditions:
            if quick and condition != "idle":
                continue
            seed += 1
            rng = random.Random(seed)
            out.append(
                Task(
                    f"rotctld/{rc.model}/{condition}",
                    [rc.model, f"rotctld {rc.hamlib}", rc.label, condition],
                    frame_ms,
                    lambda rc=rc, condition=condition, rng=rng: run_rotctld_case(
                        scope, rc, condition, 3 if quick else 20, rng
                    ),
                    not (rc.hamlib == 401 and condition == "idle"),  # a few ms: measured alone
                )
            )
    return out


def run(scope: Scope, quick: bool, models: set[str] | None = None) -> ItemResult:
    result = ItemResult(
        "latency", "1. Command latency: MQTT publish -> complete frame at the controller"
    )
    table = Table(
        result.title,
        [
            "model",
            "via",
            "command",
            "condition",
            "n",
            "line ms",
            "polls/s",
            "p50 ms",
            "p99 ms",
            "max ms",
            "beyond ms",
        ],
    )
    todo = tasks(scope, quick, models)
    outputs: dict[str, dict[str, Any]] = {}
    for task in todo:
        if not task.slow:
            outputs[task.key] = task.run()
    slow = [t for t in todo if t.slow]
    if slow:
        with ThreadPoolExecutor(max_workers=len(slow)) as pool:
            futures = {t.key: pool.submit(t.run) for t in slow}
            try:
                for key, future in futures.items():
                    outputs[key] = future.result()
            except BaseException:
                ABORT.set()  # the other rows stop at their next sample and clean up
                raise
    rows: dict[str, Any] = {}
    for task in todo:
        out = outputs[task.key]
        lat = out["latencies_s"]
        model, via, command, condition = task.cells
        r = {
            "model": model,
            "via": via,
            "command": command,
            "condition": condition,
            "n": len(lat),
            "line_ms": task.line_ms,
            "polls_per_s": out.get("polls_per_s"),
            "p50_ms": _ms(percentile(lat, 50)),
            "p99_ms": _ms(percentile(lat, 99)),
            "max_ms": _ms(max(lat)),
            "samples_ms": [round(_ms(x), 3) for x in lat],
        }
        if "first_frame_s" in out:
            r["first_frame_p50_ms"] = (
                _ms(percentile(out["first_frame_s"], 50)) if out["first_frame_s"] else None
            )
            r["rprt_p50_ms"] = _ms(percentile(out["rprt_s"], 50))
        rows[task.key] = r
        table.add(
            model,
            via,
            command,
            condition,
            r["n"],
            task.line_ms,
            "-" if r["polls_per_s"] is None else r["polls_per_s"],
            r["p50_ms"],
            r["p99_ms"],
            r["max_ms"],
            r["p99_ms"] - task.line_ms,
        )
    table.notes += _notes(rows)
    result.tables.append(table)
    result.data = rows
    result.verdicts += verdicts(rows)
    return result


def _notes(rows: dict[str, Any]) -> list[str]:
    notes = [
        "latency = time the controller had the complete frame - publish time (one monotonic "
        "clock), through a line paced at its rate both ways; 'line' = the frame's own "
        "transmission time (the limit); 'beyond' = p99 - line.",
        "percentiles are nearest-rank; polls/s = the bridge's position queries during the run; "
        "'nodelay broker' = mosquitto with set_tcp_nodelay true (default false); '0-3 ms after "
        "...': each stop published 0-3 ms after another command, timed from the stop's publish, "
        "the target going out first (7 B); 'refused': 999, answered by an error at QoS 1; "
        "stops to a rotor at rest come a second apart (a stop that adds nothing to the one "
        "before is not written).",
        "half-duplex lines (SPID, SatEL): a command waits for the exchange in flight (Rot2Prog: "
        "13 B query 217 ms + 12 B reply 200 ms at 600 baud); full-duplex Rotor-EZ: a stop waits "
        "only for a query still in the UART (AI1; = 8.3 ms).",
        "rotctld: Hamlib sleeps 500 ms after every write (post_write_delay, real Hamlib 4.5.4 "
        "behaviour): P on a Rotor-EZ/RotorCard writes AP1xxx;, sleeps, then AM1; (the frame that "
        "moves the rotor, measured), then sleeps again before answering RPRT; 'polling' = a "
        "second connection asks p back to back, as a dashboard glue must; rotctld serves one "
        "command at a time. Before each rotctld S the rotor is turned from the front panel (an "
        "idle Rotor-EZ answers a stop with a banner, which costs Hamlib's next read a 1.5 s "
        "flush).",
    ]
    rc = rows.get("rotctld/rotorcard/idle")
    if rc and rc.get("first_frame_p50_ms") is not None:
        notes.append(
            f"rotctld 402 P: AP1xxx; arrived after {rc['first_frame_p50_ms']:.1f} ms (p50), "
            f"AM1; after {rc['p50_ms']:.1f} ms, RPRT after {rc['rprt_p50_ms']:.0f} ms."
        )
    return notes


def verdicts(rows: dict[str, Any]) -> list[Verdict]:
    out: list[Verdict] = []
    ez = [rows.get(f"bridge/rotorez/stop/{c}") for c in ("idle", "polling")]
    if all(ez):
        beyond = [r["p99_ms"] - r["line_ms"] for r in ez if r]
        out.append(
            Verdict(
                "Rotor-EZ 4800 baud: latency p99 within 10 ms of the frame's transmission time",
                f"stop p99 {ez[0]['p99_ms']:.1f} ms idle, {ez[1]['p99_ms']:.1f} ms polling "
                f"(frame {ez[0]['line_ms']:.1f} ms): {beyond[0]:.1f} / {beyond[1]:.1f} ms beyond",
                max(beyond) <= 10.0,
            )
        )
    for lead, ahead_ms in (("a target", 1000 * line_time_s(7, 4800)), ("a refused target", 0.0)):
        after = rows.get(f"bridge/rotorez/stop/0-3 ms after {lead}")
        if after:
            limit_ms = after["line_ms"] + ahead_ms
            out.append(
                Verdict(
                    f"a stop 0-3 ms after {lead} (mosquitto defaults): p99 within 10 ms of "
                    "the line time of what goes out",
                    f"stop p99 {after['p99_ms']:.1f} ms (p50 {after['p50_ms']:.1f} ms; "
                    f"line {limit_ms:.1f} ms)",
                    after["p99_ms"] <= limit_ms + 10.0,
                )
            )

    def on_line(r: dict[str, Any]) -> float:
        return float(r["p99_ms"])

    pairs = [
        (
            "targets (RotorCard, same protocol): bridge idle vs rotctld 402 P idle",
            "bridge/rotorcard/target/idle",
            "rotctld/rotorcard/idle",
        ),
        (
            "targets: bridge idle vs rotctld 402 P while a glue polls p",
            "bridge/rotorcard/target/idle",
            "rotctld/rotorcard/polling",
        ),
        (
            "stops (Rotor-EZ): bridge idle vs rotctld 401 S idle",
            "bridge/rotorez/stop/idle",
            "rotctld/rotorez/idle",
        ),
        (
            "stops (Rotor-EZ) while polling: bridge vs rotctld 401 S while a glue polls p",
            "bridge/rotorez/stop/polling",
            "rotctld/rotorez/polling",
        ),
    ]
    for what, b, h in pairs:
        if b in rows and h in rows:
            ratio = on_line(rows[h]) / on_line(rows[b])
            out.append(
                Verdict(
                    f"latency >= 10x lower than rotctld's, {what}",
                    f"p99 {on_line(rows[b]):.1f} ms vs {on_line(rows[h]):.1f} ms = {ratio:.1f}x",
                    ratio >= 10.0,
                )
            )
    return out
