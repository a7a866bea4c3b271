"""Hamlib's rotctld, the peer a user would pick instead: started on a device, spoken to over TCP,
and its command latency measured the same way as the bridge's (item 1)."""

from __future__ import annotations

import contextlib
import random
import socket
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from benchmarks.harness import BenchError, Scope, check_abort, check_alive, free_port, wait_until
from benchmarks.line import FrameLog
from benchmarks.rig import baud_of, open_line


def _spid_set(f: Any) -> bool:
    return f.outcome.startswith("set")


class RotctlConnection:
    def __init__(self, port: int) -> None:
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=30)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.file = self.sock.makefile("rwb")

    def send(self, line: str) -> None:
        self.file.write(line.encode() + b"\n")
        self.file.flush()

    def read_lines(self, n: int) -> list[str]:
        return [self.file.readline().decode().strip() for _ in range(n)]

    def close(self) -> None:
        with contextlib.suppress(OSError):
            self.file.close()
            self.sock.close()


def start_rotctld(scope: Scope, hamlib_model: int, device: str, baud: int, name: str) -> int:
    """One rotctld on `device`; returns its TCP port once it accepts connections."""
    port = free_port()
    argv = ["rotctld", "-m", str(hamlib_model), "-r", device, "-s", str(baud)]
    argv += ["-T", "127.0.0.1", "-t", str(port)]
    proc = scope.spawn(argv, log_name=f"{name}.log")

    def listening() -> bool:
        check_alive(proc, f"rotctld ({name})", scope.workdir / f"{name}.log")
        with contextlib.suppress(OSError), socket.create_connection(("127.0.0.1", port), 0.2):
            return True
        return False

    wait_until(listening, 10, f"rotctld {name} to listen", 0.02)
    return port


@dataclass(frozen=True)
class RotctldCase:
    model: str  # emulator
    hamlib: int
    command: Callable[[int], str]
    label: str
    match: Callable[[Any], bool]  # the complete command (the frame that acts)
    first: Callable[[Any], bool] | None  # the first frame of a multi-frame command
    conditions: tuple[str, ...]
    emu_opts: dict[str, Any] = field(default_factory=dict)
    # turn the rotor from the front panel before each command: a stop then stops something
    # (a Rotor-EZ answers a stop while idle with a banner, which sends Hamlib's next read into
    # its 1.5 s flush; the bridge's rows are unaffected by that)
    turn_first: bool = False


def rotctld_cases() -> list[RotctldCase]:
    return [
        RotctldCase(
            "rotorez",
            401,
            lambda i: "S",
            "S -> ;",
            lambda f: f.data == b";",
            None,
            ("idle", "polling"),
            turn_first=True,
        ),
        RotctldCase(
            "rotorcard",
            402,
            lambda i: f"P {110 if i % 2 else 100} 0",
            "P -> AP1xxx; ... AM1;",
            lambda f: f.data == b"AM1;",
            lambda f: f.data.startswith(b"AP1"),
            ("idle", "polling"),
            emu_opts={"speed_deg_s": 1000.0},
        ),
        RotctldCase(
            "rot2prog",
            901,
            lambda i: f"P {10 + i} 10",
            "P -> set (13 B)",
            _spid_set,
            None,
            ("idle", "polling"),
        ),
        RotctldCase(
            "gs232b",
            603,
            lambda i: f"P {10 + i} 10",
            "P -> Wxxx yyy<CR>",
            lambda f: f.outcome == "move",
            None,
            ("idle", "polling"),
        ),
        RotctldCase(
            "easycomm2",
            202,
            lambda i: f"P {10 + i} 10",
            "P -> AZxx.x ELyy.y<LF>",
            lambda f: f.outcome == "move",
            None,
            ("idle", "polling"),
        ),
        RotctldCase(
            "rt21",
            405,
            lambda i: f"P {10 + i}.5 0",
            "P -> AP1ddd.d<CR>;",
            lambda f: f.outcome == "move",
            None,
            ("idle", "polling"),
        ),
        RotctldCase(
            "prosistel",
            1701,
            lambda i: f"P {10 + i} 0",
            "P -> STX AGddd<CR>",
            lambda f: f.outcome == "move",
            None,
            ("idle", "polling"),
        ),
        RotctldCase(
            "rc2800",
            1001,
            lambda i: f"P {10 + i}.5 10",
            "P -> Addd<CR> (200 ms) Eee<CR>",
            lambda f: f.outcome == "move" and f.data.startswith(b"A"),
            None,
            ("idle", "polling"),
        ),
    ]


def run_rotctld_case(
    scope: Scope, case: RotctldCase, condition: str, n: int, rng: random.Random
) -> dict[str, Any]:
    name = f"rotctld-{case.model}-{condition}"
    with Scope(scope.workdir / name) as sc:
        frames = FrameLog()
        emu, _relay, link = open_line(sc, case.model, frames, case.emu_opts)
        port = start_rotctld(sc, case.hamlib, str(link), baud_of(case.model), "rotctld")
        conn = RotctlConnection(port)
        sc.callback(conn.close)
        if case.model != "dcu1":  # one read first: Hamlib flushes the power-on byte (1.5 s)
            conn.send("p")
            conn.read_lines(2)
        stop = threading.Event()
        if condition == "polling":  # the glue asks for the bearing as fast as rotctld answers

            def poll() -> None:
                c = RotctlConnection(port)
                try:
                    while not stop.is_set():
                        c.send("p")
                        c.read_lines(2)
                except OSError:
                    pass
                finally:
                    c.close()

            poller = threading.Thread(target=poll, daemon=True)
            poller.start()
            sc.callback(poller.join, 5)
            sc.callback(stop.set)
            time.sleep(0.3)
        complete: list[float] = []
        first: list[float] = []
        replies: list[float] = []
        for i in range(n):
            check_abort()
            if case.turn_first:  # always towards the far end, so that it surely turns
                emu.manual_rotate(350.0 if emu.state().az_deg < 180 else 10.0)
            time.sleep(rng.uniform(0.0, 0.05))
            mark = frames.mark()
            t0 = time.monotonic()
            conn.send(case.command(i))
            answer = conn.read_lines(1)[0]
            t_reply = time.monotonic()
            if not answer.startswith("RPRT 0"):
                raise BenchError(f"rotctld {case.hamlib}: {case.command(i)!r} -> {answer!r}")
            frame = frames.wait(case.match, mark, 5.0)
            if frame is None:
                raise BenchError(f"rotctld {case.hamlib}: no frame for {case.command(i)!r}")
            complete.append(frame.time_s - t0)
            replies.append(t_reply - t0)
            if case.first is not None:
                f1 = frames.wait(case.first, mark, 1.0)
                if f1 is not None:
                    first.append(f1.time_s - t0)
        return {"latencies_s": complete, "first_frame_s": first, "rprt_s": replies}
