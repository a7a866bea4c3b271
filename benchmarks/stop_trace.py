"""Where an outlier stop waits inside the bridge: timestamps (time.monotonic, the clock of the
benchmark's emulator logs) at the stop's steps, patched into a bridge process started with
``STOP_TRACE=<file>`` and ``benchmarks/stoptrace_site`` first on PYTHONPATH (its
sitecustomize imports this module). Written to the file as JSON when the bridge exits:

- ``msg``: a connection's on_message for a ``/stop`` topic (``lane`` or ``main``), with the
  thread that ran it;
- ``carry``: Halts.carry (under Halts._lock: the decision carried out), with the main
  connection's thread's schedstat and its own thread's;
- ``put``: the Stop in the mailbox (Mailbox.put returned);
- ``serve``: the lines thread starts serving a worker whose mailbox holds a stop;
- ``write``: a frame written to a port (the stop frame ``;`` only), with the port's path (a
  stop is matched to its own rotor's write, not another's: the backlog's rotor gets stops too);
- ``gc``: every collection (generation, start, end) and the main connection's message count;
- ``lockwait``: a wait of 0.5 ms or more for Halts._lock (who waited, in what; who held it);
- ``xwrite``: the stop express wrote a rotator's stop frame (its own stamp, said to the bridge:
  the express is another process, interfaces/mqtt/express.py);
- every thread's name is given to the kernel (its ``comm`` in /proc/<pid>/task), to read
  per-thread CPU from outside while a load runs;
- ``put`` and ``serve`` carry the serial-lines thread's schedstat (ns on a CPU, ns runnable
  but waiting for one) and the process's CPU time; ``msg`` the reading thread's schedstat.

``python -m benchmarks.stop_trace TRACE SAMPLES [MS]``: each stop over MS (9) against its publish,
how long its line was still busy after the publish with bytes the bridge wrote before it (the
line's floor, benchmarks/line.py rule 7), when the broker delivered it (benchmarks/delivery.py),
and, where the benchmark wrote ``TRACE.lines.json``
(stop_under_load's focused mode), what the stop's line carried from 50 ms before the publish to
its frame: the relay's reads of the bridge's bytes and deliveries to the controller, and the
controller's frames. Then each load's SLOWEST stops cut step by step (``_split``): the broker's
delivery, the bridge's first write of the stop frame after it, the pty's hop to the line, the
byte on the line, and how late the controller stamped it (the instrument's own wait).
"""

from __future__ import annotations

import atexit
import gc
import json
import math
import os
import sys
import threading
import time
from collections import deque
from pathlib import Path
from typing import Any

EVENTS: list[tuple[Any, ...]] = []
_now = time.monotonic
LINES_TID = [0]  # the serial-lines thread's native id, once it served a stop
MAIN_TID = [0]  # the main connection's paho thread's, once it read a message


def _sched(tid: int | None = None) -> tuple[int, int]:
    """(ns on a CPU, ns runnable but waiting for one) of a thread, from the kernel."""
    path = f"/proc/self/task/{tid}/schedstat" if tid else "/proc/thread-self/schedstat"
    try:
        with open(path) as f:
            run, wait, _ = f.read().split()
        return int(run), int(wait)
    except (OSError, ValueError):
        return 0, 0


def _name_threads() -> None:
    """Each Python thread's name given to the kernel too (the first 15 bytes, the thread's
    ``comm``), so that per-thread CPU and scheduling read from /proc/<pid>/task name the
    bridge's threads (the sky worker, the lines thread, paho's) while a load runs."""
    import ctypes

    try:
        prctl = ctypes.CDLL(None, use_errno=True).prctl
    except (OSError, AttributeError):
        return
    bootstrap = threading.Thread._bootstrap_inner  # type: ignore[attr-defined]

    def _bootstrap_inner(self: threading.Thread) -> None:
        prctl(15, self.name.encode()[:15], 0, 0, 0)  # PR_SET_NAME
        bootstrap(self)

    threading.Thread._bootstrap_inner = _bootstrap_inner  # type: ignore[attr-defined]


def install(path: str) -> None:
    _name_threads()
    from bridge.core.model import Stop
    from bridge.interfaces.mqtt import connection, halts
    from bridge.runtime import worker
    from bridge.session import mailbox

    ev = EVENTS.append
    counts = {"main": 0}

    import socket
    import struct

    import paho.mqtt.client as paho

    so_timestampns = getattr(socket, "SO_TIMESTAMPNS", 35)  # Linux
    offset = time.time() - time.monotonic()  # a kernel stamp (real time) on our clock
    arrived: dict[int, float] = {}
    sock_recv = paho.Client._sock_recv

    def _sock_recv(self: Any, bufsize: int) -> bytes:
        """The stop lane's reads: when the kernel had the bytes (SO_TIMESTAMPNS)."""
        sock = self._sock
        if not self._client_id.endswith(b"-stop") or not isinstance(sock, socket.socket):
            return sock_recv(self, bufsize)  # type: ignore[no-any-return]
        if id(sock) not in arrived:
            sock.setsockopt(socket.SOL_SOCKET, so_timestampns, 1)
            arrived[id(sock)] = 0.0
        data, anc, _flags, _addr = sock.recvmsg(bufsize, socket.CMSG_SPACE(16))
        for level, kind, raw in anc:
            if level == socket.SOL_SOCKET and kind == so_timestampns:
                sec, ns = struct.unpack("qq", raw[:16])
                arrived[id(sock)] = sec + ns / 1e9 - offset
        return data

    paho.Client._sock_recv = _sock_recv  # type: ignore[method-assign]

    on_message = connection.Connection._on_message

    def _on_message(self: Any, client: Any, userdata: Any, msg: Any) -> None:
        t = _now()
        if msg.topic.endswith("/stop"):
            kind = "lane" if type(self).__name__ == "StopLane" else "main"
            main = _sched(MAIN_TID[0]) if kind == "lane" else (0, 0)
            stamp = arrived.get(id(client._sock), 0.0)
            name = threading.current_thread().name
            ev(("msg", t, kind, msg.topic, name, *_sched(), *main, stamp))
        else:
            counts["main"] += 1
            if not MAIN_TID[0] and type(self).__name__ != "StopLane":
                MAIN_TID[0] = threading.get_native_id()
        on_message(self, client, userdata, msg)

    connection.Connection._on_message = _on_message  # type: ignore[method-assign]

    class _Lock:
        """Halts._lock, saying each wait of 0.5 ms or more, and who held the lock then."""

        def __init__(self) -> None:
            self._lock = threading.Lock()
            self.holder = ("", "")
            self.taken = {"main": 0}

        def acquire(self, blocking: bool = True, timeout: float = -1) -> bool:
            t = _now()
            held = self.holder
            got = self._lock.acquire(blocking, timeout)
            waited = _now() - t
            name = threading.current_thread().name
            caller = sys._getframe(1)
            if caller.f_code.co_name == "__enter__" and caller.f_back is not None:
                caller = caller.f_back
            self.holder = (name, caller.f_code.co_name)
            if waited >= 0.0005:
                ev(("lockwait", t, waited, name, self.holder[1], *held))
            return got

        def release(self) -> None:
            self._lock.release()

        def __enter__(self) -> bool:
            return self.acquire()

        def __exit__(self, *exc: object) -> None:
            self._lock.release()

    init = halts.Halts.__init__

    def _init(self: Any, *a: Any, **k: Any) -> None:
        init(self, *a, **k)
        self._lock = _Lock()

    halts.Halts.__init__ = _init  # type: ignore[method-assign]

    carry = halts.Halts.carry

    def _carry(self: Any, rot: Any, kind: str, *a: Any, **k: Any) -> None:
        name = threading.current_thread().name
        ev(("carry", _now(), rot.id, kind, name, *_sched(MAIN_TID[0]), *_sched()))
        carry(self, rot, kind, *a, **k)

    halts.Halts.carry = _carry  # type: ignore[method-assign]

    put = mailbox.Mailbox.put

    def _put(self: Any, command: Any, **k: Any) -> bool:
        t = _now()
        done = put(self, command, **k)
        if isinstance(command, Stop):
            ev(("put", t, _now(), id(self), *_sched(LINES_TID[0]), time.process_time()))
        return done

    mailbox.Mailbox.put = _put  # type: ignore[method-assign]

    serve = worker.Worker.serve

    def _serve(self: Any, now: float, ready: set[int]) -> None:
        if self._mailbox.urgent:
            LINES_TID[0] = threading.get_native_id()
            t = _now()
            ev(
                (
                    "serve",
                    t,
                    self.cfg.rotator_id,
                    now,
                    id(self._mailbox),
                    *_sched(),
                    time.process_time(),
                )
            )
        serve(self, now, ready)

    worker.Worker.serve = _serve  # type: ignore[method-assign]

    write_frame = worker.write_frame

    def _write(port: Any, data: bytes) -> None:
        if data == b";":
            ev(("write", _now(), port.port))
        write_frame(port, data)

    worker.write_frame = _write

    starts: dict[int, float] = {}

    def _gc(phase: str, info: dict[str, Any]) -> None:
        if phase == "start":
            starts[info["generation"]] = _now()
        else:
            g = info["generation"]
            ev(("gc", starts.get(g, 0.0), _now(), g, info["collected"], counts["main"]))

    gc.callbacks.append(_gc)

    from bridge.interfaces.mqtt import express

    express_init = express.Express.__init__

    class _Wrote(deque[tuple[str, float]]):
        """The stop express's words "wrote" (its own clock: CLOCK_MONOTONIC, as ours)."""

        def append(self, x: tuple[str, float]) -> None:
            ev(("xwrite", x[1], x[0]))
            super().append(x)

    def _express_init(self: Any, *a: Any, **k: Any) -> None:
        express_init(self, *a, **k)
        self.wrote = _Wrote(maxlen=64)

    express.Express.__init__ = _express_init  # type: ignore[method-assign]

    def _dump() -> None:
        Path(path).write_text(json.dumps({"pid": os.getpid(), "events": EVENTS}))

    atexit.register(_dump)


def _first(events: list[Any], after: float, before: float, pred: Any) -> Any:
    for e in events:
        if after - 0.0005 <= e[1] <= before and pred(e):
            return e
    return None


def _written(by: dict[str, list[Any]], rid: str, t0: float, lat: float) -> float | None:
    """When the bridge wrote this stop's ``;`` to this rotor's port (None if not traced)."""
    w = _first(by["write"], t0, t0 + lat, lambda e: e[2].endswith(f"tty-{rid}"))
    return None if w is None else float(w[1])


def _hops(window: dict[str, Any], written: float | None) -> tuple[float, float] | None:
    """(the bridge's write -> the line read it, the line handed it on -> the frame) in ms: the
    bridge's pty hop and the controller's side (benchmarks/ptyhop.py)."""
    if written is None:
        return None
    relay = window["relay"]
    read = next((e for e in relay if e[0] == "in" and e[1] >= written - 0.0005), None)
    if read is None:
        return None
    handed = next((e for e in relay if e[0] == "out" and ";" in e[2] and e[1] >= read[1]), None)
    frame = next((f for f in window["frames"] if f[1] == ";"), None)
    if handed is None or frame is None:
        return None
    return (read[1] - written) * 1e3, (frame[0] - handed[1]) * 1e3


def _row(by: dict[str, list[Any]], rid: str, t0: float, lat: float) -> str:
    """One stop: its steps as ms from its publish, the waits the kernel saw, the collections and
    the Halts._lock waits inside it."""
    t1 = t0 + lat
    lane = by["lane"]
    m = _first(lane, t0, t1, lambda e: f"/{rid}/" in e[3])
    c = _first(by["carry"], m[1] if m else t0, t1, lambda e: e[2] == rid and "-stop" in e[4])
    s = _first(by["serve"], c[1] if c else t0, t1, lambda e: e[2] == rid)
    p = _first(by["put"], c[1] if c else t0, t1, lambda e: s is None or e[3] == s[4])
    w = _first(by["write"], s[1] if s else t0, t1, lambda e: e[2].endswith(f"tty-{rid}"))
    steps = [("lane", m, 1), ("carry", c, 1), ("put", p, 2), ("serve", s, 1), ("write", w, 1)]
    x = _first(by["xwrite"], t0, t1, lambda e: e[2] == rid)
    steps.insert(0, ("express wrote", x, 1))
    out = f"{rid} {lat * 1e3:6.1f} ms:"
    for name, e, k in steps:
        out += f" {name} {(e[k] - t0) * 1e3:.1f}" if e else f" {name} --"
    if m and len(m) > 9 and m[9]:
        out += f" | lane bytes in the kernel at {(m[9] - t0) * 1e3:.1f}"
    if m and lane.index(m):
        prev = lane[lane.index(m) - 1]
        out += f" | lane thread runq {(m[6] - prev[6]) / 1e6:.1f} since its last"
    if m and c and c[4] == m[4]:  # the lane's own carry: the main thread meanwhile
        out += f" | main thread lane->carry: cpu {(c[5] - m[7]) / 1e6:.1f}"
        out += f" runq {(c[6] - m[8]) / 1e6:.1f}"
        if len(c) > 8:  # the lane thread's own: its CPU, or a wait for one (else the GIL)
            out += f", lane thread cpu {(c[7] - m[5]) / 1e6:.1f} runq {(c[8] - m[6]) / 1e6:.1f}"
    if p and s:
        out += f" | lines thread runq {(s[6] - p[5]) / 1e6:.1f} cpu {(s[5] - p[4]) / 1e6:.1f}"
        out += f", process cpu {(s[7] - p[6]) * 1e3:.1f} (put->serve)"
    inside = [e for e in by["gc"] if e[2] >= t0 and e[1] <= t1 and e[2] - e[1] > 0.0005]
    out += "".join(f" | gc{e[3]} {(e[2] - e[1]) * 1e3:.1f}" for e in inside)
    waits = [e for e in by["lockwait"] if t0 <= e[1] <= t1]
    out += "".join(f" | lock {e[2] * 1e3:.1f} ({e[3][-5:]} {e[4]})" for e in waits)
    return out


def _firsts(by: dict[str, list[Any]], rows: list[Any]) -> str:
    """Every stop of a phase, not only the slow ones: how long after its publish the stop
    express wrote its frame and the bridge's serial-lines thread wrote its own (p50 / p99 /
    max, nearest rank), apart from what the host took to carry the frame on (the pty hop)."""

    def spread(name: str, ms: list[float]) -> str:
        if not ms:
            return f"{name}: none"
        ms.sort()
        p99 = ms[min(len(ms) - 1, math.ceil(0.99 * len(ms)) - 1)]
        return f"{name} ({len(ms)}): {ms[len(ms) // 2]:.1f} / {p99:.1f} / {ms[-1]:.1f}"

    express, lines = [], []
    for rid, t0, lat, *_taker in rows:
        x = _first(by["xwrite"], t0, t0 + lat, lambda e, rid=rid: e[2] == rid)
        w = _first(by["write"], t0, t0 + lat + 0.1, lambda e, rid=rid: e[2].endswith(f"tty-{rid}"))
        if x is not None:
            express.append((x[1] - t0) * 1e3)
        if w is not None:
            lines.append((w[1] - t0) * 1e3)
    return "every stop, ms after the publish, p50 / p99 / max: " + "; ".join(
        [spread("the express wrote", express), spread("the serial-lines thread wrote", lines)]
    )


def _line(window: dict[str, Any]) -> list[str]:
    """A stop's line (the benchmark's ``<trace>.lines.json``): the relay's reads of the bridge's
    bytes (``in``, with the due time of the last byte), its deliveries to the controller
    (``out``, how late against the due time of the first byte) and the controller's frames,
    in ms after the publish."""
    t0 = window["t0"]
    rows: list[tuple[float, str]] = []
    last: list[int] = []
    for kind, t, data, due, *sched in window["relay"]:
        waited = f", relay runq +{(sched[1] - last[1]) / 1e6:.1f}" if sched and last else ""
        last = sched
        if kind == "in":
            rows.append((t, f"relay read   {data!r} (due {(due - t0) * 1e3:.1f}{waited})"))
        else:
            rows.append((t, f"relay wrote  {data!r} ({(t - due) * 1e3:.1f} late{waited})"))
    last = []
    for t, data, outcome, *sched in window["frames"]:
        waited = f" (emulator runq +{(sched[1] - last[1]) / 1e6:.1f})" if sched and last else ""
        last = sched
        rows.append((t, f"frame        {data!r} {outcome}{waited}"))
    rows.sort(key=lambda row: row[0])  # stable: frames logged at one instant keep their order
    return [f"      {(t - t0) * 1e3:7.1f} {text}" for t, text in rows]


SLOWEST = 5  # the stops split step by step (_split), of each load
BYTE_S = 10 / 4800  # a byte on the measured lines (Rotor-EZ, 4800 baud)


def _split(by: dict[str, list[Any]], row: list[Any], window: dict[str, Any] | None) -> str:
    """One stop's time cut at its steps, in ms: the publish -> the broker's delivery (the
    probe's kernel stamp) -> the bridge's first write of ``;`` (the express's or the lines
    thread's; beside it, when the broker's copy to the bridge's stop lane reached the lane's
    socket, from the same moment: the broker's own order of sends) -> the line's relay read it
    (the pty's kernel worker, and the relay thread's own wake-up) -> the byte's due time on the
    line (its 2.1 ms, and any bytes ahead) -> the controller stamped the frame (the
    instrument's own wait: line.py rule 8)."""
    rid, t0, lat, *taker = row
    t1 = t0 + lat
    broker = taker[4] if len(taker) > 4 and taker[4] is not None else None
    x = _first(by["xwrite"], t0, t1, lambda e: e[2] == rid)
    w = _first(by["write"], t0, t1, lambda e: e[2].endswith(f"tty-{rid}"))
    wrote = min((e[1] for e in (x, w) if e is not None), default=None)
    who = "--" if wrote is None else ("express" if x is not None and x[1] == wrote else "lines")
    cells = [
        f"{rid} {lat * 1e3:5.1f}",
        "deliver " + ("--" if broker is None else f"{broker * 1e3:4.1f}"),
    ]
    since = broker if broker is not None else 0.0
    lane = _first(by["lane"], t0, t1 + 0.1, lambda e: f"/{rid}/" in e[3])
    if lane is not None and len(lane) > 9 and lane[9]:  # the broker's send to the bridge's lane
        cells.append(f"(lane's socket {(lane[9] - t0 - since) * 1e3:+.1f})")
    if wrote is not None:
        cells.append(f"bridge ({who}) {(wrote - t0 - since) * 1e3:4.1f}")
    read = None
    if window is not None and wrote is not None:
        read = next(
            (e for e in window["relay"] if e[0] == "in" and e[1] >= wrote - 0.0005 and ";" in e[2]),
            None,
        )
    if read is not None and wrote is not None:
        data, due_last = read[2], read[3]
        due = due_last - (len(data) - 1 - data.index(";")) * BYTE_S
        cells.append(f"pty hop {(read[1] - wrote) * 1e3:4.1f}")
        cells.append(f"line {(due - read[1]) * 1e3:4.1f}")
        cells.append(f"stamp {(t1 - due) * 1e3:4.1f}")
    elif len(taker) > 5 and taker[5] is not None:
        cells.append(f"stamp {taker[5] * 1e3:4.1f}")
    return " | ".join(cells)


def analyse(trace_path: str, samples_path: str, over_ms: float) -> None:
    trace = json.loads(Path(trace_path).read_text())["events"]
    samples = json.loads(Path(samples_path).read_text())
    lines_path = Path(trace_path + ".lines.json")
    windows = json.loads(lines_path.read_text()) if lines_path.exists() else {}
    kinds = ("msg", "carry", "put", "serve", "write", "gc", "lockwait", "xwrite")
    by = {k: [e for e in trace if e[0] == k] for k in kinds}
    by["lane"] = [e for e in by["msg"] if e[2] == "lane"]
    for phase, rows in samples.items():
        print(f"== {phase}: the stops over {over_ms:g} ms (ms after the publish)")
        shown = {(w["rid"], w["t0"]): w for w in windows.get(phase, [])}
        hops: list[tuple[float, float]] = []
        for rid, t0, lat, *taker in rows:
            if lat * 1e3 > over_ms:
                print("  " + _row(by, rid, t0, lat))
                if taker:  # the benchmark's own thread: its publish returned, it woke up
                    sent, seen = ((t - t0) * 1e3 for t in taker[:2])
                    print(f"      publish returned {sent:.1f}, the taker woke at {seen:.1f}")
                ahead_ms = taker[2] * 1e3 if len(taker) > 2 else 0.0
                broker_ms = taker[4] * 1e3 if len(taker) > 4 and taker[4] is not None else 0.0
                if ahead_ms > 0:  # the line's floor (line.py rule 7)
                    print(
                        f"      the line busy {ahead_ms:.1f} ms after the publish with "
                        f"{taker[3]!r} (written before it)"
                    )
                if ahead_ms > 0 or broker_ms > 0:  # the larger floor (stop_under_load.py)
                    floor_ms = max(ahead_ms, broker_ms)
                    print(f"      the bridge's part {lat * 1e3 - floor_ms:.1f} ms")
                if len(taker) > 4 and taker[4] is not None:  # the broker's delivery
                    print(
                        f"      the broker delivered it {taker[4] * 1e3:.1f} ms after the publish"
                    )
                if (rid, t0) in shown:
                    print("\n".join(_line(shown[rid, t0])))
                    hop = _hops(shown[rid, t0], _written(by, rid, t0, lat))
                    if hop is not None:
                        hops.append(hop)
        print("  " + _firsts(by, rows))
        print(
            f"  the {SLOWEST} slowest, ms from step to step (_split): the publish -> deliver -> "
            "the bridge wrote ';' -> pty hop -> line (due) -> the controller's stamp"
        )
        for row in sorted(rows, key=lambda r: -r[2])[:SLOWEST]:
            print("    " + _split(by, row, shown.get((row[0], row[1]))))
        if hops:
            one, two = (sorted(h[i] for h in hops) for i in (0, 1))
            print(
                f"  {len(hops)} of them: the bridge's write -> the line read it: median "
                f"{one[len(one) // 2]:.1f}, max {one[-1]:.1f} ms; the line handed it on -> "
                f"the frame: median {two[len(two) // 2]:.1f}, max {two[-1]:.1f} ms"
            )
    per: dict[int, list[float]] = {}
    for e in by["gc"]:
        per.setdefault(e[3], []).append(e[2] - e[1])
    for g, ds in sorted(per.items()):
        print(
            f"gc gen{g}: {len(ds)}, longest {max(ds) * 1e3:.1f} ms, in all {sum(ds) * 1e3:.0f} ms"
        )


if __name__ == "__main__":
    analyse(sys.argv[1], sys.argv[2], float(sys.argv[3]) if len(sys.argv) > 3 else 9.0)
