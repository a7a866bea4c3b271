"""One measured set-up: tests.support's Rig with the real timings, a private broker, emulated
controllers in this process (frames logged on our clock) behind paced lines, the bridge as its
own service process on them, and a recording MQTT client. Leaving the `with` block stops the
bridge, the emulators, the client and the broker. Also the emulator host (EmuHost), for
controllers in a process of their own.
"""

from __future__ import annotations

import contextlib
import json
import select
import subprocess
from collections import deque
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Any

from benchmarks.harness import PYTHON, BenchError, Mqtt, Scope, start_broker
from benchmarks.line import ByteCounter, FrameLog, PacedRelay, name_thread
from bridge import emulators
from bridge.emulators import EmulatedPort
from bridge.protocols import REGISTRY
from tests.support.process import Spawn
from tests.support.rig import REAL_TIMINGS, Line, OpenLine, Rig

__all__ = [
    "TOPIC",
    "EmuHost",
    "Line",
    "Rig",
    "baud_of",
    "many_rotators",
    "measured_rig",
    "open_line",
    "single_rotator",
]

TOPIC = "rotor"  # the base topic (a bridge with one rotator publishes right under it)


def baud_of(model: str, emu_opts: dict[str, Any] | None = None) -> int:
    if emu_opts and emu_opts.get("baud"):
        return int(emu_opts["baud"])
    return REGISTRY[model].baud


def open_line(
    scope: Scope,
    model: str,
    frames: FrameLog,
    emu_opts: dict[str, Any] | None = None,
    paced: bool = True,
    name: str = "tty",
    timeline: deque[tuple[Any, ...]] | None = None,
    direct: bool = False,
) -> tuple[EmulatedPort[Any], PacedRelay | None, Path]:
    """An in-process emulator and, if paced, the line relay in front of it (keeping its
    ``timeline``, if given: line.py rule 6; handing the client's bytes to the emulator in
    this process, not through its pty, if ``direct``: line.py rule 5); returns the path a
    client opens."""
    emu_link = scope.workdir / f"{name}-emulator"
    emu = emulators.start(model, link=str(emu_link), on_frame=frames, **(emu_opts or {}))
    scope.callback(emu.close)
    name_thread(emu._thread.native_id, f"emu-{name}")  # noqa: SLF001
    if not paced:
        return emu, None, emu_link
    link = scope.workdir / name
    deliver = partial(emu.inject, to="device") if direct else None
    relay = PacedRelay(emu.path, link, baud_of(model, emu_opts), timeline=timeline, deliver=deliver)
    scope.callback(relay.close)
    name_thread(relay.thread_id, f"line-{name}")
    return emu, relay, link


def measured_line(*, paced: bool = True, count_bytes: bool = True) -> OpenLine:
    """The rig's ``open_line`` for a measurement: the controller's frames logged, its bytes
    counted (if asked), behind a paced relay (if asked)."""

    def open_(rig: Rig, rid: str, model: str, options: dict[str, Any]) -> Line:
        assert isinstance(rig.scope, Scope)
        frames = FrameLog()
        emu, relay, path = open_line(rig.scope, model, frames, options, paced, name=f"tty-{rid}")
        counter = ByteCounter(emu) if count_bytes else None
        return Line(rid, model, emu, path, frames, counter, relay)

    return open_


@dataclass(frozen=True)
class _Broker:
    port: int


@contextlib.contextmanager
def measured_rig(
    parent: Scope,
    name: str,
    specs: list[tuple[str, str, dict[str, Any], dict[str, Any]]],
    *,
    homeassistant: bool = True,
    wait_online_s: float = 30.0,
    broker_conf: str = "",
    paced: bool = True,
    count_bytes: bool = True,
    spawn: Callable[[Scope], Spawn] | None = None,
) -> Iterator[Rig]:
    """specs: (id, model, emulator options, rotator settings) for each rotator of one bridge,
    which must be online within ``wait_online_s`` and still running at the end; ``spawn``
    starts the bridge (default: this checkout's, benchmarks/engines.py for another's)."""
    with Scope(parent.workdir / name) as scope:
        broker = _Broker(start_broker(scope, broker_conf))
        mqtt = Mqtt(broker.port, [f"{TOPIC}/#"], name=f"rec-{name}")
        scope.callback(mqtt.close)
        line = measured_line(paced=paced, count_bytes=count_bytes)
        rig = Rig(
            scope.workdir,
            broker,
            mqtt,
            timings=REAL_TIMINGS,
            open_line=line,
            scope=scope,
            spawn=scope.spawner if spawn is None else spawn(scope),
        )
        rig.base = TOPIC
        rig.express = None  # each engine as it ships (this one with its stop express)
        for rid, model, emu_opts, rot_opts in specs:
            rig.add(rid, model, emu_opts, **rot_opts)
        rig.sections["homeassistant"] = {"enabled": homeassistant}
        bridge = rig.start_process(log_level="INFO", error=BenchError)
        online = [rig.t(rid, "availability") for rid in rig.lines]
        try:
            mqtt.wait_all(online, "online", wait_online_s)
        except Exception:
            bridge.check()
            raise
        yield rig
        bridge.check()  # it must have survived the measurement


def single_rotator(
    parent: Scope,
    name: str,
    model: str,
    *,
    emu_opts: dict[str, Any] | None = None,
    rotator: dict[str, Any] | None = None,
    count_bytes: bool = False,
    homeassistant: bool = True,
    wait_online_s: float = 30.0,
    broker_conf: str = "",
    paced: bool = True,
) -> contextlib.AbstractContextManager[Rig]:
    """A rig with one rotator, id ``r``: ``rig.emu``, ``rig.frames``, ``rig.t(leaf)``."""
    return measured_rig(
        parent,
        name,
        [("r", model, emu_opts or {}, rotator or {})],
        homeassistant=homeassistant,
        wait_online_s=wait_online_s,
        broker_conf=broker_conf,
        paced=paced,
        count_bytes=count_bytes,
    )


def many_rotators(
    parent: Scope,
    name: str,
    specs: list[tuple[str, str, dict[str, Any], dict[str, Any]]],
    *,
    wait_online_s: float = 30.0,
    spawn: Callable[[Scope], Spawn] | None = None,
) -> contextlib.AbstractContextManager[Rig]:
    """A rig with several rotators, each line's bytes counted: ``rig.lines``, ``rig.t(rid, leaf)``
    (also ``rig.topic``); ``spawn(scope)``: how its bridge is started (measured_rig)."""
    return measured_rig(parent, name, specs, wait_online_s=wait_online_s, spawn=spawn)


class EmuHost:
    """The emulator host process (benchmarks/emuhost.py): `count` controllers behind paced lines."""

    def __init__(self, scope: Scope, model: str, count: int, name: str = "emuhost") -> None:
        self.dir = scope.workdir / name
        self.proc = scope.spawn(
            [
                PYTHON,
                "-m",
                "benchmarks.emuhost",
                "--model",
                model,
                "--count",
                str(count),
                "--dir",
                str(self.dir),
            ],
            log_name=f"{name}.log",
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            hardware=True,  # harness rule 5
        )
        scope.callback(self._quit)
        line = self._read_line(60)
        if line != "ready":
            raise BenchError(f"emulator host did not start: {line!r}")

    def link(self, i: int) -> Path:
        return self.dir / f"tty-{i}"

    def command(self, text: str, timeout_s: float = 30) -> str:
        assert self.proc.stdin is not None
        self.proc.stdin.write(text.encode() + b"\n")
        self.proc.stdin.flush()
        return self._read_line(timeout_s)

    def states(self) -> list[tuple[float, bool]]:
        return [(az, moving) for az, moving in json.loads(self.command("state"))]

    def _read_line(self, timeout_s: float) -> str:
        assert self.proc.stdout is not None
        ready, _, _ = select.select([self.proc.stdout], [], [], timeout_s)
        if not ready:
            raise BenchError("emulator host did not answer")
        line = self.proc.stdout.readline().decode().strip()
        if not line and self.proc.poll() is not None:
            raise BenchError(f"emulator host exited with status {self.proc.returncode}")
        return line

    def _quit(self) -> None:
        with contextlib.suppress(OSError, ValueError):
            assert self.proc.stdin is not None
            self.proc.stdin.write(b"quit\n")
            self.proc.stdin.close()
        with contextlib.suppress(subprocess.TimeoutExpired):
            self.proc.wait(10)
