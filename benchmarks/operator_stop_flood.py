"""A quick measure: the operator's stop through a TCP front end (the GS-232 port) while another
program on the same host opens and closes connections to it as fast as it can.

    .venv/bin/python -m benchmarks.operator_stop_flood                 # 40 stops
    .venv/bin/python -m benchmarks.operator_stop_flood --stops 80 --root /tmp/old

``--root``: the ``bridge/`` package of another tree (``git archive COMMIT bridge | tar -x -C
DIR``) is measured instead of this checkout's, for a side-by-side run.

The set-up: the port's line server (interfaces/tcplines.py) for a rotator that records what it is
given, in this process, made as the bridge makes it for the stops (``halts``: a connection whose
first commands hold a stop goes ahead of its address's budget); a flooding process of its own
with two threads, each connecting (non-blocking) and closing at once, without end. Each sample:
the operator connects, sends ``S`` (stop) and ``C`` (where is it), and reads the answer: from
the connect to the answer, which comes after the stop was carried out. A stop the kernel kept
out of a full queue of connections comes after its handshake's retry (1 s, then 2 s, 4 s
later): the count over 0.9 s says it.
"""

from __future__ import annotations

import argparse
import importlib
import socket
import subprocess
import sys
import time
from types import SimpleNamespace
from typing import Any

from benchmarks.report import percentile

FLOOD = """
import socket, sys, threading
port = int(sys.argv[1])
def flood():
    while True:
        s = socket.socket()
        s.setblocking(False)
        s.connect_ex(("127.0.0.1", port))
        s.close()
threads = [threading.Thread(target=flood, daemon=True) for _ in range(2)]
for t in threads:
    t.start()
sys.stdin.read()
"""


class Tower:
    """What a GS-232 session uses of a rotator: at 120 degrees, what it is given counted."""

    id = "tower"
    spec = SimpleNamespace(has_elevation=False, can_report_position=True)

    def __init__(self) -> None:
        self.status = SimpleNamespace(bearing_deg=120.0, elevation_deg=0.0, available=True)
        self.stops = 0

    def submit(self, command: Any, described: str | None = None) -> None:
        self.stops += type(command).__name__ == "Stop"


def one_stop(port: int) -> float:
    t0 = time.monotonic()
    with socket.create_connection(("127.0.0.1", port), timeout=60) as operator:
        operator.sendall(b"S\rC\r")
        got = b""
        while not got.endswith(b"\r\n"):
            chunk = operator.recv(64)
            if not chunk:
                raise RuntimeError(f"the port closed the operator's connection ({got!r})")
            got += chunk
    return time.monotonic() - t0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--stops", type=int, default=40)
    ap.add_argument("--root", help="measure the bridge/ package of this tree instead")
    args = ap.parse_args(argv)
    if args.root:
        sys.path.insert(0, args.root)
    gs232 = importlib.import_module("bridge.interfaces.gs232")
    parser = importlib.import_module("bridge.interfaces.gs232.parser")
    tcplines = importlib.import_module("bridge.interfaces.tcplines")
    tower = Tower()
    server = tcplines.LineServer(
        "tower",
        0,
        "127.0.0.1",
        lambda: gs232.Gs232Session(tower),
        label="gs232",
        key="gs232",
        halts=parser.gs232_holds_stop,  # as the bridge makes the port: a stop goes first
    )
    server.start()
    flood = subprocess.Popen([sys.executable, "-c", FLOOD, str(server.port)], stdin=subprocess.PIPE)
    try:
        time.sleep(1.0)  # the flood under way (its queue full, with 128 places)
        samples = []
        for _ in range(args.stops):
            samples.append(one_stop(server.port))
            time.sleep(0.05)
    finally:
        flood.kill()
        flood.wait()
        server.stop()
    if tower.stops != args.stops:
        raise RuntimeError(f"{tower.stops} stops carried out of {args.stops}")
    ms = sorted(s * 1000 for s in samples)
    print(
        f"{tcplines.__file__}: {len(ms)} stops beside a connect-and-close flood: "
        f"p50 {percentile(ms, 50):.0f} ms, p90 {percentile(ms, 90):.0f} ms, "
        f"max {ms[-1]:.0f} ms; over 0.9 s: {sum(m > 900 for m in ms)}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
