"""Loggers' UDP ports under a junk flood (issue 18): "a 10,000-datagram junk flood leaves the
rotator's stop latency on MQTT unchanged".

    .venv/bin/python benchmarks/logger_flood.py                 # 40 stops per condition
    .venv/bin/python benchmarks/logger_flood.py --quick         # 15 stops per condition
    .venv/bin/python -m benchmarks.logger_flood --json flood.json

The set-up: a private mosquitto (its defaults); an emulated Rotor-EZ in this process behind a
line paced at 4800 baud, turning at 90 deg/s with a 0.5 s brake (the bridge is told the same
brake and settles in 0.5 s; otherwise its defaults: moving poll 0.2 s, Home Assistant on); the
bridge as its own service process with both logger endpoints on loopback: PstRotator UDP
(``pst_udp_port``) and N1MM (``n1mm_rotor_name`` "Yagi", ``n1mm_udp_port``, its position
reports to a socket of ours).

One sample: R/target far away, wait until the rotor turns (the emulator's ground truth), then
R/stop (QoS 1, not retained); the latency is from that publish to the complete stop frame ``;``
at the controller (the emulator's log, on our clock), so it includes the stop byte's own
2.1 ms on the line and any exchange in flight (the bridge polls a turning rotor every 0.2 s).
Three conditions, in this order, on one bridge:
- no flood: the baseline;
- paced flood: 10,000 junk datagrams spread evenly over as many stops as the baseline took
  (the rate is 10,000 / the baseline's duration), so every stop meets a stream of junk;
- bursts: before each stop a fresh 10,000-datagram flood as fast as the sender can; the stop
  is published once half of it is out, while the bridge still works through the rest. Its
  control, interleaved with it: the same bursts sent to another process that reads and parses
  them (about as a tolerant server would), so that the sender and a reader keep two cores as
  busy as with the bridge: the row shows what that load alone does to the measurement (our
  process hosts the emulator, the broker needs a core too), the difference between the two
  rows is the bridge's own.
Then N1MM stops (the stop datagram of one of N1MM's forms, sent from our process; the latency
from its sending to ``;``), alone and each behind a burst like the above sent to the PST port
only: one thread serves both ports, and a stop on one must not wait for a flood on the other.
The junk (tests.support.udp_logger's datagram forms, broken the ways the fact sheet names:
oversized, not ASCII, unclosed, NaN/inf/empty/12x numbers, goazi outside 0..360, no rotor,
random bytes) goes alternately to the PST and the N1MM port, from a sender process of its
own (our process hosts the emulator, whose timestamps must not wait for a flood loop).

Also measured: the bridge's CPU (all threads, /proc schedstat) per condition, CPU per junk
datagram, the datagrams the kernel dropped at the bridge's full receive buffer (/proc/net/udp:
the bridge read the rest), and whether any junk moved the rotor (target frames beyond ours).
"""

from __future__ import annotations

import argparse
import json
import os
import random
import re
import select
import signal
import socket
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

if __package__ in (None, ""):  # run as a file: the checkout's top is where benchmarks/ lives
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.harness import ABORT, PYTHON, BenchError, Scope, check_abort  # noqa: E402
from benchmarks.procfs import cpu_seconds  # noqa: E402
from benchmarks.report import ItemResult, Table, Verdict, percentile  # noqa: E402
from benchmarks.rig import Rig, single_rotator  # noqa: E402
from tests.support.ports import free_udp_port  # noqa: E402
from tests.support.udp_logger import (  # noqa: E402
    N1MM_STOPS,
    N1mmListener,
    N1mmSender,
    n1mm_turn,
    pst,
    tag,
)

FLOOD = 10_000
EMU = {"speed_deg_s": 90.0, "brake_delay_s": 0.5, "jitter_deg": 0, "start_az_deg": 10}
BRIDGE = {"brake_delay_s": 0.5, "settle_s": 0.5}
STOP_FRAME = b";"
# "unchanged": within the noise of the baseline; a stop behind a poll in flight already varies
# by a few ms (benchmarks/latency.py, Rotor-EZ "polling")
SAME_MS = 2.0
CONTROL = "bursts to another reader (control)"
N1MM_ALONE = "N1MM stop, no flood"
N1MM_BEHIND = "N1MM stop, PST bursts"
N1MM_STOP_MS = 100.0  # behind a PST flood an N1MM stop waited up to 8 s when one port was read dry


# -- the junk ------------------------------------------------------------------------------------
def junk(rng: random.Random) -> tuple[str, bytes]:
    """One malformed datagram and the port it goes to ("pst" or "n1mm"): never a command."""
    kind = "pst" if rng.random() < 0.5 else "n1mm"
    az = f"{rng.uniform(0, 360):.1f}"
    if kind == "pst":
        good = pst(tag("AZIMUTH", az))
        forms = [
            lambda: pst(tag("AZIMUTH", rng.choice(["NaN", "inf", "", " ", "12x", "0x50", "1e9"]))),
            lambda: good[:-6],  # never closed
            lambda: good + b"trailing",
            lambda: good.replace(b"</AZIMUTH>", b""),  # a tag left open
            lambda: b"<PST>AZ\xdf?</PST>",  # not ASCII
            lambda: b"<PST>" + b" " * rng.randint(2100, 4000) + b"AZ?</PST>",  # oversized
            lambda: b"<PST>" + rng.randbytes(rng.randint(1, 60)) + b"\xff</PST>",
        ]
    else:
        good = n1mm_turn("Yagi", float(az))
        forms = [
            lambda: good.replace(f"{az}</goazi>".encode(), b"nan</goazi>"),
            lambda: good.replace(f"{az}</goazi>".encode(), b"</goazi>"),
            lambda: good.replace(f"{az}</goazi>".encode(), b"400.0</goazi>"),
            lambda: good.replace(b"</N1MMRotor>", b""),
            lambda: good.replace(b"<rotor>Yagi</rotor>", b""),
            lambda: good + b" " * rng.randint(2100, 4000),
            lambda: good.replace(b"Yagi", b"Y\xe4gi"),
        ]
    forms.append(lambda: rng.randbytes(rng.randint(0, 200)) + b"\xff")
    return kind, rng.choice(forms)()


_WRAPPED = re.compile(rb"^\s*<(pst|n1mmrotor)>(.*)</\1>\s*$", re.I | re.S)
_TAGS = re.compile(r"<([a-z]+)>([^<]*)</\1>", re.I)


def eater_main() -> int:
    """The control's reader (a process of its own): reads every datagram at a port of its own
    and parses it about as a tolerant server would, so that a burst keeps a second core as
    busy as the bridge does; prints the port, ends when its stdin closes."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    sock.setblocking(False)
    print(sock.getsockname()[1], flush=True)
    while True:
        ready, _, _ = select.select([sock, sys.stdin], [], [])
        if sys.stdin in ready and not sys.stdin.readline():
            return 0
        while True:
            try:
                data = sock.recv(65536)
            except BlockingIOError:
                break
            m = _WRAPPED.match(data) if len(data) <= 2048 and data.isascii() else None
            for _tag, value in _TAGS.findall(m.group(2).decode()) if m else ():
                try:
                    float(value)
                except ValueError:
                    break


def sender_main(pst_port: int, n1mm_port: int, sink_port: int, seed: int) -> int:
    """The flood sender (a process of its own): commands on stdin, one per line:
    ``paced COUNT RATE``, ``burst COUNT``, ``burst COUNT sink`` (to the control's reader at
    ``sink_port`` instead) and ``burst COUNT pst`` (all of it to the PST port); it prints
    ``half`` once half the datagrams are out and ``done SENT SECONDS`` at the end."""
    rng = random.Random(seed)
    pool = [junk(rng) for _ in range(FLOOD)]
    to = {"pst": ("127.0.0.1", pst_port), "n1mm": ("127.0.0.1", n1mm_port)}
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    print("ready", flush=True)
    for line in sys.stdin:
        words = line.split()
        if not words or words[0] == "quit":
            break
        count = int(words[1])
        rate = float(words[2]) if words[0] == "paced" else 0.0
        dest = {
            "sink": dict.fromkeys(to, ("127.0.0.1", sink_port)),
            "pst": dict.fromkeys(to, to["pst"]),
        }.get(words[-1], to)
        t0 = time.monotonic()
        for i in range(count):
            kind, data = pool[i % len(pool)]
            try:
                sock.sendto(data, dest[kind])
            except OSError:
                pass  # e.g. ICMP from a port that went away: the bridge is gone, we are told
            if i + 1 == count // 2:
                print("half", flush=True)
            if rate and i % 10 == 9:
                ahead = t0 + (i + 1) / rate - time.monotonic()
                if ahead > 0:
                    time.sleep(ahead)
        print(f"done {count} {time.monotonic() - t0:.6f}", flush=True)
    return 0


class Sender:
    def __init__(self, scope: Scope, pst_port: int, n1mm_port: int) -> None:
        self.eater = scope.spawn(
            [PYTHON, "-m", "benchmarks.logger_flood", "--eater"],
            log_name="flood-eater.log",
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
        )
        assert self.eater.stdout is not None
        ready, _, _ = select.select([self.eater.stdout], [], [], 30)
        sink = self.eater.stdout.readline().decode().strip() if ready else ""
        if not sink.isdigit():
            raise BenchError(f"the control's reader did not start: {sink!r}")
        self.sink_port = int(sink)
        argv = [PYTHON, "-m", "benchmarks.logger_flood", "--sender", str(pst_port)]
        self.proc = scope.spawn(
            [*argv, str(n1mm_port), sink],
            log_name="flood-sender.log",
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
        )
        if self.line(30) != "ready":
            raise BenchError("the flood sender did not start")

    def command(self, text: str) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(text.encode() + b"\n")
        self.proc.stdin.flush()

    def line(self, timeout_s: float) -> str | None:
        """Its next line within ``timeout_s`` (None: nothing yet)."""
        assert self.proc.stdout is not None
        ready, _, _ = select.select([self.proc.stdout], [], [], max(0.0, timeout_s))
        if not ready:
            return None
        text = self.proc.stdout.readline().decode().strip()
        if not text and self.proc.poll() is not None:
            raise BenchError(f"the flood sender exited with status {self.proc.returncode}")
        return text

    def done(self, timeout_s: float) -> tuple[int, float]:
        while True:
            text = self.line(timeout_s)
            if text is None:
                raise BenchError("the flood sender did not finish")
            if text.startswith("done"):
                _, sent, seconds = text.split()
                return int(sent), float(seconds)


def udp_drops(port: int) -> int:
    """Datagrams the kernel dropped at the socket bound to ``port`` on 127.0.0.1 (its receive
    buffer was full), from /proc/net/udp."""
    want = f"0100007F:{port:04X}"
    with open("/proc/net/udp") as f:
        for line in f.readlines()[1:]:
            fields = line.split()
            if fields[1] == want:
                return int(fields[-1])
    raise BenchError(f"no UDP socket on 127.0.0.1:{port} in /proc/net/udp")


# -- the measurement ------------------------------------------------------------------------------
@dataclass
class Phase:
    name: str
    latencies_s: list[float]
    wall_s: float
    cpu_s: float
    sent: int = 0
    send_s: float = 0.0
    dropped: int = 0


def one_stop(
    rig: Rig, sender: Sender | None = None, burst: str = "", n1mm: N1mmSender | None = None
) -> float:
    """Turn far, stop while turning: seconds from R/stop's publish (or the N1MM stop datagram's
    sending, with ``n1mm``) to ``;`` at the controller."""
    check_abort()
    az = rig.emu.state().az_deg
    target = 350 if az < 180 else 10
    mark = rig.frames.mark()
    rig.mqtt.publish(rig.t("target"), str(target))
    if rig.frames.wait(lambda f: f.data.startswith(b"AP1"), mark, 10) is None:
        rig.bridge.check()
        raise BenchError(f"the target {target} never reached the controller")
    rig.emu.wait_for(lambda s: s.is_moving and abs(s.az_deg - az) > 3, 5)
    if sender is not None:
        sender.command(f"burst {FLOOD} {burst}")
        while (text := sender.line(10)) != "half":
            if text is None:
                raise BenchError("the flood sender did not get half-way")
    mark = rig.frames.mark()
    t0 = time.monotonic()
    if n1mm is not None:
        n1mm.send(N1MM_STOPS["name in stop"]("Yagi"))
    else:
        rig.mqtt.publish(rig.t("stop"), "STOP")
    frame = rig.frames.wait(lambda f: f.data == STOP_FRAME, mark, 5)
    if frame is None:
        rig.bridge.check()
        raise BenchError("the stop never reached the controller")
    rig.emu.wait_for(lambda s: not s.is_moving, 5)
    return float(frame.time_s - t0)


def measure(scope: Scope, n: int) -> dict[str, Any]:
    pst_port, n1mm_port = free_udp_port(), free_udp_port()
    reports = N1mmListener()
    scope.callback(reports.close)
    rotator = {
        **BRIDGE,
        "pst_udp_port": pst_port,
        "n1mm_rotor_name": "Yagi",
        "n1mm_udp_port": n1mm_port,
        "n1mm_report_to": reports.address,
    }
    with single_rotator(scope, "logger-flood", "rotorez", emu_opts=EMU, rotator=rotator) as rig:
        rig.mqtt.wait_value(rig.t("state"), "idle", 30)
        sender = Sender(rig.scope, pst_port, n1mm_port)
        pid = rig.bridge.pid
        first_frame = rig.frames.mark()
        phases: list[Phase] = []

        def drops() -> int:
            return udp_drops(pst_port) + udp_drops(n1mm_port)

        # no flood
        c0, t0 = cpu_seconds(pid), time.monotonic()
        base = [one_stop(rig) for _ in range(n)]
        phases.append(Phase("no flood", base, time.monotonic() - t0, cpu_seconds(pid) - c0))

        # paced: 10,000 over as long as the baseline took
        rate = FLOOD / phases[0].wall_s
        d0, c0, t0 = drops(), cpu_seconds(pid), time.monotonic()
        sender.command(f"paced {FLOOD} {rate:.3f}")
        paced: list[float] = []
        result: tuple[int, float] | None = None
        while result is None:
            paced.append(one_stop(rig))
            text = sender.line(0)
            while text is not None and not text.startswith("done"):
                text = sender.line(0)
            if text is not None:
                _, sent, seconds = text.split()
                result = int(sent), float(seconds)
        wall = time.monotonic() - t0
        phase = Phase("paced flood", paced, wall, cpu_seconds(pid) - c0, *result)
        phase.dropped = drops() - d0
        phases.append(phase)

        # bursts: a whole flood as fast as it goes before each stop; the control sends the same
        # to another reader (what that load alone does to the measurement), the two
        # interleaved so that both meet the same conditions
        d0, sink_d0 = drops(), udp_drops(sender.sink_port)
        eater_c0 = cpu_seconds(sender.eater.pid)
        bursts: dict[str, list[float]] = {"sink": [], "": []}
        cpu = dict.fromkeys(bursts, 0.0)
        wall = dict.fromkeys(bursts, 0.0)
        sent_total, send_s = dict.fromkeys(bursts, 0), dict.fromkeys(bursts, 0.0)
        for _ in range(n):
            for to in bursts:
                c, t = cpu_seconds(pid), time.monotonic()
                bursts[to].append(one_stop(rig, sender, to))
                sent, seconds = sender.done(30)
                sent_total[to] += sent
                send_s[to] += seconds
                cpu[to] += cpu_seconds(pid) - c
                wall[to] += time.monotonic() - t
        dropped = {"": drops() - d0, "sink": udp_drops(sender.sink_port) - sink_d0}
        eater_cpu_s = cpu_seconds(sender.eater.pid) - eater_c0
        for to, name in (("sink", CONTROL), ("", "bursts")):
            phase = Phase(name, bursts[to], wall[to], cpu[to], sent_total[to], send_s[to])
            phase.dropped = dropped[to]
            phases.append(phase)

        # N1MM stops: alone, then each behind a burst to the PST port (one thread serves both
        # ports: the stop must not wait for the PST port's flood)
        n1mm = N1mmSender(n1mm_port)
        rig.scope.callback(n1mm.close)
        c0, t0 = cpu_seconds(pid), time.monotonic()
        alone = [one_stop(rig, n1mm=n1mm) for _ in range(n)]
        phases.append(Phase(N1MM_ALONE, alone, time.monotonic() - t0, cpu_seconds(pid) - c0))
        d0, c0, t0 = drops(), cpu_seconds(pid), time.monotonic()
        phase = Phase(N1MM_BEHIND, [], 0.0, 0.0)
        for _ in range(n):
            phase.latencies_s.append(one_stop(rig, sender, "pst", n1mm))
            pst_sent, pst_send_s = sender.done(30)
            phase.sent += pst_sent
            phase.send_s += pst_send_s
        phase.wall_s, phase.cpu_s = time.monotonic() - t0, cpu_seconds(pid) - c0
        phase.dropped = drops() - d0
        phases.append(phase)

        sender.command("quit")
        targets = [f for f in rig.frames.since(first_frame) if f.data.startswith((b"AP", b"AM"))]
        stops = sum(len(p.latencies_s) for p in phases)
        rig.bridge.check()
    return {
        "phases": phases,
        "target_frames": len(targets),
        "targets_sent": stops,
        "reports": len(reports.drain()),
        "control_reader_cpu_pct": 100.0 * eater_cpu_s / wall["sink"],
    }


def _ms(v: float) -> float:
    return v * 1000.0


def run(scope: Scope, quick: bool, samples: int | None = None) -> ItemResult:
    n = samples or (15 if quick else 40)
    result = ItemResult("logger_flood", "Loggers' UDP ports: stop latency under a junk flood")
    table = Table(
        result.title + " (Rotor-EZ, 4800 baud; R/stop's publish, or the N1MM stop datagram's "
        "sending, -> ';' at the controller)",
        [
            "condition",
            "stops",
            "junk sent",
            "rate /s",
            "dropped",
            "p50 ms",
            "p99 ms",
            "max ms",
            "bridge CPU %",
            "CPU us/datagram read",
        ],
    )
    m = measure(scope, n)
    phases: list[Phase] = m["phases"]
    base = phases[0]
    base_cpu_per_s = base.cpu_s / base.wall_s
    rows: dict[str, Any] = {}
    for p in phases:
        lat = sorted(p.latencies_s)
        extra_cpu = p.cpu_s - base_cpu_per_s * p.wall_s  # over the baseline's turning and stops
        read = p.sent - p.dropped
        per_datagram = _ms(extra_cpu) * 1000 / read if read else None
        rate = p.sent / p.send_s if p.send_s else None
        row = {
            "stops": len(lat),
            "sent": p.sent,
            "rate_per_s": rate,
            "send_s": p.send_s,
            "dropped_by_kernel": p.dropped,
            "p50_ms": _ms(percentile(lat, 50)),
            "p99_ms": _ms(percentile(lat, 99)),
            "max_ms": _ms(lat[-1]),
            "cpu_pct": 100.0 * p.cpu_s / p.wall_s,
            "cpu_us_per_datagram_read": per_datagram,
            "wall_s": p.wall_s,
            "latencies_ms": [round(_ms(v), 3) for v in p.latencies_s],
        }
        rows[p.name] = row
        table.add(
            p.name,
            row["stops"],
            p.sent or "-",
            f"{rate:,.0f}" if rate else "-",
            p.dropped if p.sent else "-",
            f"{row['p50_ms']:.2f}",
            f"{row['p99_ms']:.2f}",
            f"{row['max_ms']:.2f}",
            f"{row['cpu_pct']:.1f}",
            f"{per_datagram:.1f}" if per_datagram is not None else "-",
        )
    result.data = {
        "conditions": rows,
        "target_frames": m["target_frames"],
        "targets_sent": m["targets_sent"],
        "n1mm_reports": m["reports"],
        "control_reader_cpu_pct": m["control_reader_cpu_pct"],
    }
    table.notes += [
        "rate: the sender's (paced: 10,000 over as long as the baseline's stops took; bursts: "
        f"{FLOOD:,} per stop, as fast as it goes, the stop published half-way); dropped: by the "
        "kernel at the bridge's full receive buffers (/proc/net/udp), the bridge read the rest.",
        "bridge CPU: all its threads over the condition (the turns and stops included); CPU "
        "us/datagram read: the CPU above the baseline's rate, per datagram the bridge read "
        "(sent - dropped).",
    ]
    table.notes.append(
        f"the control's reader used {m['control_reader_cpu_pct']:.1f} % of a core over its "
        f"samples, the bridge {rows['bursts']['cpu_pct']:.1f} % over the bursts' (a burst keeps "
        "each busy for a fraction of its ~1.2 s sample)."
    )
    result.tables.append(table)
    control = {"paced flood": "no flood", "bursts": CONTROL}
    for name, calm_name in control.items():
        r, calm = rows[name], rows[calm_name]
        worse = max(r["p50_ms"] - calm["p50_ms"], r["p99_ms"] - calm["p99_ms"])
        result.verdicts.append(
            Verdict(
                f"{name}: a {FLOOD:,}-datagram junk flood leaves the stop latency on MQTT "
                f"unchanged (p50 and p99 within {SAME_MS:g} ms of {calm_name})",
                f"p50 {r['p50_ms']:.2f} / p99 {r['p99_ms']:.2f} ms against "
                f"{calm['p50_ms']:.2f} / {calm['p99_ms']:.2f} ms",
                worse <= SAME_MS,
            )
        )
    r, calm = rows[N1MM_BEHIND], rows[N1MM_ALONE]
    result.verdicts.append(
        Verdict(
            f"a {FLOOD:,}-datagram junk burst at the PST port holds an N1MM stop on the other "
            f"port by little (p99 under {N1MM_STOP_MS:g} ms)",
            f"p50 {r['p50_ms']:.2f} / p99 {r['p99_ms']:.2f} ms against "
            f"{calm['p50_ms']:.2f} / {calm['p99_ms']:.2f} ms with no flood",
            r["p99_ms"] <= N1MM_STOP_MS,
        )
    )
    moved = m["target_frames"] - m["targets_sent"]
    result.verdicts.append(
        Verdict(
            "no junk datagram moves the rotor",
            f"{m['target_frames']} target frames at the controller for {m['targets_sent']} "
            "targets published",
            moved == 0,
        )
    )
    return result


def _interrupt(signum: int, _frame: Any) -> None:
    raise KeyboardInterrupt(f"signal {signum}")


def main(argv: list[str] | None = None) -> int:
    from benchmarks.__main__ import as_json, environment, preflight, render

    args_in = sys.argv[1:] if argv is None else argv
    if args_in[:1] == ["--sender"]:
        return sender_main(int(args_in[1]), int(args_in[2]), int(args_in[3]), seed=18)
    if args_in[:1] == ["--eater"]:
        return eater_main()
    ap = argparse.ArgumentParser(
        prog="benchmarks/logger_flood.py", description=__doc__.split("\n")[0]
    )
    ap.add_argument("--quick", action="store_true", help="15 stops per condition (40)")
    ap.add_argument("--samples", type=int, help="stops per condition")
    ap.add_argument("--json", type=Path, help="also write the results to this file")
    ap.add_argument("--keep", action="store_true", help="keep the work directory (logs, configs)")
    args = ap.parse_args(args_in)
    problem = preflight()
    if problem:
        print(f"benchmarks: {problem}", file=sys.stderr)
        return 2
    signal.signal(signal.SIGTERM, _interrupt)
    signal.signal(signal.SIGHUP, _interrupt)
    workdir = Path(tempfile.mkdtemp(prefix="rotor-bench-flood-"))
    print(f"rotor-bridge logger flood benchmark; work dir {workdir}", flush=True)
    t0 = time.monotonic()
    try:
        with Scope(workdir) as scope:
            result = run(scope, args.quick, args.samples)
    except KeyboardInterrupt:
        ABORT.set()
        print("\ninterrupted; every process started has been stopped", file=sys.stderr)
        return 130
    finally:
        if not args.keep:
            import shutil

            shutil.rmtree(workdir, ignore_errors=True)
    result.duration_s = time.monotonic() - t0
    result.finished_at = datetime.now(UTC).isoformat(timespec="seconds")
    print("\n" + render(result))
    if args.json:
        command = "benchmarks/logger_flood.py " + " ".join(args_in)
        doc = {
            "command": command.strip(),
            "environment": environment(),
            "items": {"logger_flood": as_json(result, args.quick)},
        }
        args.json.write_text(json.dumps(doc, indent=1, default=str) + "\n")
    return 0


if __name__ == "__main__":
    os.environ.setdefault("PYTHONUNBUFFERED", "1")
    sys.exit(main())
