"""A quick measure: a STOP's latency beside a TCP flood into the GS-232 port, beside a DX cluster
node sending hostile lines, and with none (the control), on one bridge in one run.

    .venv/bin/python -m benchmarks.stop_beside_floods            # 30 stops a phase
    .venv/bin/python -m benchmarks.stop_beside_floods --stops 60
    .venv/bin/python -m benchmarks.stop_beside_floods --only half   # the half-command rows alone

Run from another checkout (``cd OTHER && /path/.venv/bin/python -m benchmarks.stop_beside_floods``)
it measures that checkout's bridge: the bridge process takes the current directory's code first.

The set-up: a private mosquitto; one bridge as its own process with one Rotor-EZ emulated in this
process behind a line paced at 4800 baud (benchmarks/rig.py), its GS-232 and rotctld ports on,
and a DX cluster client to a node that a process of its own plays (it prompts ``login:``, then
sends lines). One sample is target_flood's: the rotor turned from its front panel, R/stop published
(QoS 1), the latency to the stop frame ``;`` at the controller.

Phases: no load (R/stop; then a stop on a new connection to each TCP port: rotctld's ``S``,
GS-232's ``S``, timed from the connect); 16 TCP clients in a process of their own, each
streaming bytes with no line end into the GS-232 port as fast as the port takes them (a client
the bridge closes connects again at once); the node sending ``DX de`` lines of spaces with no
time (511 bytes) as fast as the bridge reads them; the node sending ordinary spots as fast as
the bridge reads them; a client of MQTT 5 publishing to ``R/lock``, once a second, a word that
is no lock word carrying 120,000 user properties (3.7 MB: paho's reading of them held a
connection for minutes, and ``R/lock`` is read by the connections that carry stops;
interfaces/mqtt/paho_client.py rule 10); then, for each TCP port, a program of its own holding
HALF_HELD connections to it, each with half a command sent (rotctld's ``P 1``, GS-232's ``M1``,
no line end), HALF_THREADS threads opening new ones as fast as they connect and closing the
oldest (an attack pass: the accept queue full, the operator's stop on a new connection 0.1-0.2
s late), the stop sent on a new connection to that port. A stop's connection reset or refused
on its way in is opened again at once and timed from the first try (``resets``: how often).
"""

from __future__ import annotations

import argparse
import socket
import subprocess
import sys
import tempfile
import threading
import time
from collections import deque
from pathlib import Path
from typing import Any

from benchmarks.harness import PYTHON, BenchError, Mqtt, Scope, start_bridge, start_broker
from benchmarks.line import FrameLog
from benchmarks.procfs import cpu_seconds
from benchmarks.report import percentile
from benchmarks.rig import open_line
from benchmarks.target_flood import BRIDGE, EMU, one_stop
from tests.dxcluster.cty_sample import CTY_DAT
from tests.support.mosquitto import free_port
from tests.support.mqtt import mqtt5_publish, raw_mqtt5

HOSTILE = b"DX de K1ABC: 14000 DL1ABC " + b" " * 480 + b"x\r\n"
SPOT = b"DX de EA5WU:     14025.0  JA1ABC       cq up 2                        1829Z\r\n"
CLIENTS = 16
HALF_HELD = 100  # half-command connections held open, the oldest closed for each new one
HALF_THREADS = 4  # threads opening them
CROWD = 120_000  # user properties in one message of the crowded phase


# -- the loads (processes of their own) -----------------------------------------------------------
def tcp_flood_main(port: int) -> int:
    """CLIENTS threads, each streaming bytes with no line end, reconnecting when closed."""
    junk = b"x" * 65536

    def one() -> None:
        while True:
            try:
                with socket.create_connection(("127.0.0.1", port), timeout=30) as s:
                    while True:
                        s.sendall(junk)
            except OSError:
                time.sleep(0.001)

    for _ in range(CLIENTS):
        threading.Thread(target=one, daemon=True).start()
    print("started", flush=True)
    sys.stdin.readline()
    return 0


def half_main(port: int, half: bytes) -> int:
    """HALF_THREADS threads, each connecting and sending ``half`` (half a command, no line
    end) as fast as it can, the newest HALF_HELD connections held open, the oldest closed."""
    held: deque[socket.socket] = deque()
    lock = threading.Lock()

    def one() -> None:
        while True:
            try:
                s = socket.create_connection(("127.0.0.1", port), timeout=2)
                s.sendall(half)
            except OSError:
                continue
            with lock:
                held.append(s)
                old = held.popleft() if len(held) > HALF_HELD else None
            if old is not None:
                old.close()

    for _ in range(HALF_THREADS):
        threading.Thread(target=one, daemon=True).start()
    print("started", flush=True)
    sys.stdin.readline()
    return 0


class TcpStop:
    """A stop sent on a new connection to a TCP front end (``line``, at 127.0.0.1:``port``); the
    connection is kept open until the next one is sent, or ``close``. A connection reset or
    refused on its way in is opened again at once, as a program does (counted: ``resets``)."""

    def __init__(self, port: int, line: bytes) -> None:
        self.port, self.line = port, line
        self._conn: socket.socket | None = None
        self.resets = 0

    def __call__(self) -> None:
        self.close()
        for _ in range(10):
            try:
                self._conn = socket.create_connection(("127.0.0.1", self.port), timeout=30)
                self._conn.sendall(self.line)
                return
            except (ConnectionResetError, ConnectionRefusedError, BrokenPipeError):
                self.resets += 1
                self.close()
        raise BenchError(f"the stop's connection to {self.port} reset ten times in a row")

    def close(self) -> None:
        if self._conn is not None:
            self._conn.close()
            self._conn = None


def crowd_main(port: int, topic: str) -> int:
    """An MQTT 5 client publishing ``topic`` a junk word with CROWD user properties, once a
    second (a packet made once, sent raw: paho's own packing of them takes minutes)."""
    packet = mqtt5_publish(topic, [(f"k{i}", "v" * 20) for i in range(CROWD)], b"junk")
    with raw_mqtt5(port, "crowd") as send:
        print("started", flush=True)
        while True:
            send(packet)
            time.sleep(1.0)


def node_main(port: int, mode_file: str) -> int:
    """A cluster node: ``login:``, then lines as fast as the client reads them; which lines is
    read from ``mode_file`` (quiet, hostile or spots) before each batch."""
    srv = socket.create_server(("127.0.0.1", port))
    print("started", flush=True)
    while True:
        conn, _ = srv.accept()
        try:
            conn.sendall(b"Welcome\r\nlogin: ")
            conn.recv(100)
            while True:
                with open(mode_file) as f:
                    mode = f.read().strip()
                if mode == "hostile":
                    conn.sendall(HOSTILE * 8)
                elif mode == "spots":
                    conn.sendall(SPOT * 64)
                else:
                    time.sleep(0.05)
        except OSError:
            conn.close()


def _spawn(scope: Scope, args: list[str], log_name: str) -> subprocess.Popen[bytes]:
    proc = scope.spawn(
        [PYTHON, "-m", "benchmarks.stop_beside_floods", *args],
        log_name=log_name,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
    )
    assert proc.stdout is not None
    if proc.stdout.readline().strip() != b"started":
        raise BenchError(f"{log_name}: did not start")
    return proc


# -- the measurement ------------------------------------------------------------------------------
def measure(scope: Scope, n: int, only: tuple[str, ...] = ()) -> dict[str, Any]:
    broker_port = start_broker(scope)
    gs232_port, rotctld_port, node_port = free_port(), free_port(), free_port()
    mode = scope.workdir / "node-mode"
    mode.write_text("quiet")
    _spawn(scope, ["--node", str(node_port), str(mode)], "node.log")
    frames = FrameLog()
    emu, _relay, link = open_line(scope, "rotorez", frames, EMU, name="tty-m")
    specs = [{"id": "m", "model": "rotorez", "port": str(link), "gs232_port": gs232_port}]
    specs[0].update(rotctld_port=rotctld_port, **BRIDGE)
    cty = scope.workdir / "cty.dat"
    cty.write_text(CTY_DAT)
    dx = {"enabled": True, "host": "127.0.0.1", "port": node_port, "login": "N0CALL"}
    dx["cty_file"] = str(cty)
    bridge = start_bridge(scope, broker_port, specs, sections={"dxcluster": dx})
    mqtt = Mqtt(broker_port, ["rotor/#"], name="rec-floods")  # one rotator: R is the base
    scope.callback(mqtt.close)
    mqtt.wait_value("rotor/state", "idle", 60)
    results: dict[str, Any] = {}

    stops = {"rotctld": TcpStop(rotctld_port, b"S\n"), "GS-232": TcpStop(gs232_port, b"S\r")}
    for each in stops.values():
        scope.callback(each.close)

    def wanted(name: str) -> bool:
        return not only or any(word in name for word in only)

    def phase(name: str, send: TcpStop | None = None) -> None:
        if not wanted(name):
            return
        c0, t0 = cpu_seconds(bridge.pid), time.monotonic()
        resets = send.resets if send is not None else 0
        lat = sorted(one_stop(emu, frames, mqtt, "rotor", bridge, send) for _ in range(n))
        if send is not None:
            send.close()
            resets = send.resets - resets
        cpu = 100.0 * (cpu_seconds(bridge.pid) - c0) / (time.monotonic() - t0)
        ms = [v * 1000 for v in lat]
        results[name] = {
            "p50_ms": percentile(ms, 50),
            "p99_ms": percentile(ms, 99),
            "max_ms": ms[-1],
            "cpu_pct": cpu,
            "resets": resets,
        }
        print(f"  {name}: {results[name]}", file=sys.stderr, flush=True)

    phase("no load")
    for port, send in stops.items():
        phase(f"no load: {port} S, new connection", send)
    if wanted(f"{CLIENTS} TCP clients flooding GS-232"):
        flood = _spawn(scope, ["--tcp-flood", str(gs232_port)], "tcp-flood.log")
        time.sleep(2.0)  # the flood under way
        phase(f"{CLIENTS} TCP clients flooding GS-232")
        assert flood.stdin is not None
        flood.stdin.close()
        flood.wait(10)
    for load in ("spots", "hostile"):  # hostile last: the old parser never caught up with it
        if not wanted(f"DX node: {load} lines"):
            continue
        mode.write_text(load)
        time.sleep(2.0)
        phase(f"DX node: {load} lines")
    mode.write_text("quiet")
    if wanted("MQTT 5: R/lock, 120,000 user properties/s"):
        crowd = _spawn(scope, ["--crowd", str(broker_port), "rotor/lock"], "crowd.log")
        time.sleep(2.0)
        phase("MQTT 5: R/lock, 120,000 user properties/s")
        crowd.kill()
    halves = {"rotctld": (rotctld_port, b"P 1"), "GS-232": (gs232_port, b"M1")}
    for port, (number, half) in halves.items():
        if not wanted(f"{HALF_HELD} half commands: {port} S"):
            continue
        load = _spawn(scope, ["--half", str(number), half.decode()], f"half-{number}.log")
        time.sleep(2.0)
        phase(f"{HALF_HELD} half commands: {port} S", stops[port])
        assert load.stdin is not None
        load.stdin.close()
        load.wait(10)
    bridge.check()
    return results


def main() -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.stop_beside_floods")
    parser.add_argument("--stops", type=int, default=30)
    parser.add_argument(
        "--only",
        nargs="+",
        default=(),
        metavar="WORD",
        help="run only the loads whose name holds one of these words (e.g. --only half 'no load')",
    )
    parser.add_argument("--tcp-flood", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--node", nargs=2, help=argparse.SUPPRESS)
    parser.add_argument("--crowd", nargs=2, help=argparse.SUPPRESS)
    parser.add_argument("--half", nargs=2, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.half is not None:
        return half_main(int(args.half[0]), args.half[1].encode())
    if args.tcp_flood is not None:
        return tcp_flood_main(args.tcp_flood)
    if args.crowd is not None:
        return crowd_main(int(args.crowd[0]), args.crowd[1])
    if args.node is not None:
        return node_main(int(args.node[0]), args.node[1])
    with Scope(Path(tempfile.mkdtemp(prefix="stop-beside-floods-"))) as scope:
        results = measure(scope, args.stops, tuple(args.only))
    print(f"{'load':40} {'p50 ms':>8} {'p99 ms':>8} {'max ms':>8} {'CPU %':>6} {'resets':>6}")
    for name, r in results.items():
        print(
            f"{name:40} {r['p50_ms']:8.1f} {r['p99_ms']:8.1f} {r['max_ms']:8.1f} "
            f"{r['cpu_pct']:6.0f} {r['resets']:6d}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
