"""Remote operation: ``rotor-bridge remote``'s rotctld port, far from the station, against Hamlib's
rotctld driving the same emulated controller directly.

Set-up: a RotorCard (the Rotor-EZ protocol without a brake; its emulated rotor turns at
1000 deg/s, so it settles between samples) behind a paced 4800-baud line, the station's bridge
as its own service process on a private mosquitto on loopback, and ``rotor-bridge remote`` as
its own process on the same broker (rotctld endpoint on loopback). The client speaks rotctld
over TCP, as Gpredict does.

- ``P``: the client's write -> the first frame the controller received (the bridge's target is
  one frame, ``AP1xxx<CR>``; Hamlib's rotctld 402 writes ``AP1xxx;``, sleeps 500 ms, then
  ``AM1;``, the frame that starts the rotor). Each P is sent once the bridge reports idle, at
  least the bridge's burst quiet time after the one before (a stream of targets is held on
  purpose: benchmarks/latency.py).
- ``p``: the client's write -> the answer's last byte. The remote answers from the station's
  retained status (no controller on the way); Hamlib's rotctld asks the controller each time.
"""

from __future__ import annotations

import os
import random
import time
from typing import Any

from benchmarks.hamlib import RotctlConnection, rotctld_cases, run_rotctld_case, start_rotctld
from benchmarks.harness import PYTHON, BenchError, Scope, check_abort, check_alive, wait_until
from benchmarks.line import FrameLog
from benchmarks.report import ItemResult, Table, Verdict, percentile
from benchmarks.rig import baud_of, open_line, single_rotator
from tests.support.mosquitto import free_port

MODEL, HAMLIB = "rotorcard", 402
EMU = {"speed_deg_s": 1000.0}
ROTATOR = {"moving_poll_interval_s": 0.02, "settle_s": 0.05}  # as latency.py's RotorCard targets
OPERATOR = "BENCH"


def _us(v: float) -> float:
    return v * 1e6


def _ms(v: float) -> float:
    return v * 1e3


def start_remote(scope: Scope, broker_port: int) -> int:
    """``python -m bridge remote`` on the broker; its rotctld port once it listens."""
    port = free_port()
    conf = scope.workdir / "remote.toml"
    conf.write_text(
        f'operator = "{OPERATOR}"\n[mqtt]\nhost = "127.0.0.1"\nport = {broker_port}\n'
        f'base_topic = "rotor"\n[[endpoints]]\nrotctld_port = {port}\n'
    )
    proc = scope.spawn([PYTHON, "-m", "bridge", "remote", "-c", str(conf)], log_name="remote.log")

    def listening() -> bool:
        check_alive(proc, "rotor-bridge remote", scope.workdir / "remote.log")
        try:
            c = RotctlConnection(port)
        except OSError:
            return False
        c.close()
        return True

    wait_until(listening, 30, "the remote's rotctld port", 0.05)
    return port


def remote_case(scope: Scope, n_set: int, n_get: int, rng: random.Random) -> dict[str, Any]:
    from bridge.session import targets

    quiet_s = float(targets.BURST_QUIET_S) + 0.02
    with single_rotator(
        scope, "remote-station", MODEL, emu_opts=EMU, rotator=ROTATOR, homeassistant=False
    ) as rig:
        state = rig.t("state")
        rig.mqtt.wait(lambda m: m.topic == state and m.text == "idle", 30, "idle")
        with Scope(scope.workdir / "remote") as sc:
            port = start_remote(sc, rig.broker_port)
            conn = RotctlConnection(port)
            sc.callback(conn.close)
            conn.send("p")  # the first answer: the station's status has come
            if len(conn.read_lines(2)) != 2:
                raise BenchError("the remote did not answer p")
            first: list[float] = []
            rprt: list[float] = []
            at_broker: list[float] = []  # the command seen by a subscriber on the broker
            target = rig.t("target")
            for i in range(n_set + 3):
                check_abort()
                time.sleep(rng.uniform(quiet_s, quiet_s + 0.04))
                mark, mark_mqtt = rig.frames.mark(), rig.mqtt.mark()
                t0 = time.monotonic()
                conn.send(f"P {110 if i % 2 else 100} 0")
                answer = conn.read_lines(1)[0]
                t_reply = time.monotonic()
                if answer != "RPRT 0":
                    raise BenchError(f"the remote answered P with {answer!r}")
                frame = rig.frames.wait(lambda f: f.data.startswith(b"AP1"), mark, 5.0)
                if frame is None:
                    raise BenchError(f"P {i} never reached the controller")
                if i >= 3:  # first-use costs are not steady state
                    first.append(frame.time_s - t0)
                    rprt.append(t_reply - t0)
                    seen = rig.mqtt.wait(lambda m: m.topic == target, 5, "the command", mark_mqtt)
                    at_broker.append(seen.t - t0)
                rig.mqtt.wait(
                    lambda m: m.topic == state and m.text == "idle", 10, "idle", mark_mqtt
                )
            get: list[float] = []
            for _ in range(n_get):
                check_abort()
                t0 = time.monotonic()
                conn.send("p")
                lines = conn.read_lines(2)
                get.append(time.monotonic() - t0)
                if len(lines) != 2 or lines[0].startswith("RPRT"):
                    raise BenchError(f"the remote answered p with {lines!r}")
    return {"first_frame_s": first, "rprt_s": rprt, "at_broker_s": at_broker, "p_s": get}


def hamlib_get(scope: Scope, n: int) -> list[float]:
    """Hamlib's rotctld 402 answering ``p`` on the same emulated controller (paced line)."""
    with Scope(scope.workdir / "rotctld-p") as sc:
        frames = FrameLog()
        _emu, _relay, link = open_line(sc, MODEL, frames, EMU)
        port = start_rotctld(sc, HAMLIB, str(link), baud_of(MODEL), "rotctld")
        conn = RotctlConnection(port)
        sc.callback(conn.close)
        conn.send("p")  # Hamlib flushes the power-on byte on its first read (1.5 s)
        conn.read_lines(2)
        out: list[float] = []
        for _ in range(n):
            check_abort()
            t0 = time.monotonic()
            conn.send("p")
            lines = conn.read_lines(2)
            out.append(time.monotonic() - t0)
            if len(lines) != 2 or lines[0].startswith("RPRT"):
                raise BenchError(f"rotctld answered p with {lines!r}")
        return out


def run(scope: Scope, quick: bool) -> ItemResult:
    result = ItemResult(
        "remote", "Remote operation: the remote's rotctld port vs Hamlib's rotctld, same controller"
    )
    rng = random.Random(26)
    remote = remote_case(scope, 20 if quick else 100, 300 if quick else 2000, rng)
    case = next(c for c in rotctld_cases() if c.model == MODEL)
    hamlib = run_rotctld_case(scope, case, "idle", 3 if quick else 20, rng)
    hamlib_p = hamlib_get(scope, 5 if quick else 20)

    def row(values: list[float], unit: Any) -> list[Any]:
        return [
            len(values),
            round(unit(percentile(values, 50)), 3),
            round(unit(percentile(values, 99)), 3),
            round(unit(max(values)), 3),
        ]

    moves = Table(
        "P -> the controller's first frame (ms), RotorCard at 4800 baud, broker on loopback",
        ["via", "frame", "n", "p50 ms", "p99 ms", "max ms"],
    )
    moves.add("remote -> broker -> bridge", "AP1xxx<CR>", *row(remote["first_frame_s"], _ms))
    moves.add(
        "  of it: remote -> broker", "(a subscriber has it)", *row(remote["at_broker_s"], _ms)
    )
    moves.add(f"rotctld {HAMLIB}", "AP1xxx;", *row(hamlib["first_frame_s"], _ms))
    moves.add(f"rotctld {HAMLIB}", "AM1; (starts it)", *row(hamlib["latencies_s"], _ms))
    moves.notes += [
        "the client's write -> the frame's last byte at the controller (one monotonic clock), "
        "through a line paced at 4800 baud (AP1100<CR> takes 14.6 ms of it); the remote's "
        f"RPRT 0 came after {_us(percentile(remote['rprt_s'], 50)):.0f} us (p50), rotctld's "
        f"after {_ms(percentile(hamlib['rprt_s'], 50)):.0f} ms; 'remote -> broker': the "
        "command's arrival at another subscriber of the broker (the recorder), part of the row "
        "above; the rest is the bridge's own latency (item latency).",
        f"load average at the end: {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores "
        "(a shared machine: tails move with it).",
    ]
    reads = Table("p answered (us)", ["via", "source", "n", "p50 us", "p99 us", "max us"])
    reads.add("remote", "the station's retained status", *row(remote["p_s"], _us))
    reads.add(f"rotctld {HAMLIB}", "asks the controller", *row(hamlib_p, _us))
    result.tables += [moves, reads]

    p99_remote = percentile(remote["first_frame_s"], 99)
    am1 = percentile(hamlib["latencies_s"], 99)
    ap1 = percentile(hamlib["first_frame_s"], 99) if hamlib["first_frame_s"] else float("nan")
    get_remote, get_hamlib = percentile(remote["p_s"], 50), percentile(hamlib_p, 50)
    result.data = {
        "remote_first_frame_ms": [round(_ms(x), 3) for x in remote["first_frame_s"]],
        "remote_rprt_ms": [round(_ms(x), 3) for x in remote["rprt_s"]],
        "remote_at_broker_ms": [round(_ms(x), 3) for x in remote["at_broker_s"]],
        "remote_p_us_p50": _us(percentile(remote["p_s"], 50)),
        "remote_p_us_p99": _us(percentile(remote["p_s"], 99)),
        "rotctld_first_frame_ms": [round(_ms(x), 3) for x in hamlib["first_frame_s"]],
        "rotctld_moving_frame_ms": [round(_ms(x), 3) for x in hamlib["latencies_s"]],
        "rotctld_p_ms": [round(_ms(x), 3) for x in hamlib_p],
        "ratio_p99_moving_frame": am1 / p99_remote,
        "ratio_p99_first_frame": ap1 / p99_remote,
        "ratio_p50_p": get_hamlib / get_remote,
    }
    result.verdicts += [
        Verdict(
            "remote P -> the frame that moves the rotor, against Hamlib's rotctld on the "
            "controller itself (p99; reported, no goal set)",
            f"{_ms(p99_remote):.1f} ms vs {_ms(am1):.1f} ms (AM1;) = {am1 / p99_remote:.1f}x; "
            f"vs rotctld's first frame AP1xxx; {_ms(ap1):.1f} ms = {ap1 / p99_remote:.1f}x",
            None,
        ),
        Verdict(
            "remote p answered within 1 ms (p99)",
            f"p50 {_us(get_remote):.0f} us, p99 {_us(percentile(remote['p_s'], 99)):.0f} us; "
            f"rotctld p50 {_ms(get_hamlib):.0f} ms ({get_hamlib / get_remote:.0f}x)",
            percentile(remote["p_s"], 99) <= 0.001,
        ),
    ]
    return result
