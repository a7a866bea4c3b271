"""One measured set-up: a private broker, an emulated controller in this process (frames logged on
our clock), the bridge as its own service process on that emulator's pty, and a recording MQTT
client. Leaving the `with` block stops the bridge, the emulator, the client and the broker.
"""

from __future__ import annotations

import contextlib
import json
import select
import subprocess
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from benchmarks.harness import (
    PYTHON,
    BenchError,
    BridgeProcess,
    Mqtt,
    Scope,
    start_bridge,
    start_broker,
)
from benchmarks.line import ByteCounter, FrameLog, PacedRelay
from bridge import emulators
from bridge.emulators import EmulatedPort
from bridge.protocols import REGISTRY

TOPIC = "rotor"  # the topic of a bridge with one rotator


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
) -> tuple[EmulatedPort[Any], PacedRelay | None, Path]:
    """An in-process emulator and, if paced, the line relay in front of it; returns the path a
    client opens."""
    emu_link = scope.workdir / f"{name}-emulator"
    emu = emulators.start(model, link=str(emu_link), on_frame=frames, **(emu_opts or {}))
    scope.callback(emu.close)
    if not paced:
        return emu, None, emu_link
    link = scope.workdir / name
    relay = PacedRelay(emu.path, link, baud_of(model, emu_opts))
    scope.callback(relay.close)
    return emu, relay, link


@dataclass
class Rig:
    scope: Scope
    model: str
    emu: EmulatedPort[Any]
    frames: FrameLog
    mqtt: Mqtt
    bridge: BridgeProcess
    broker_port: int
    counter: ByteCounter | None
    relay: PacedRelay | None
    topic: str = TOPIC

    def t(self, leaf: str) -> str:
        return f"{self.topic}/{leaf}"


@contextlib.contextmanager
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
) -> Iterator[Rig]:
    with Scope(parent.workdir / name) as scope:
        broker_port = start_broker(scope, broker_conf)
        mqtt = Mqtt(broker_port, [f"{TOPIC}/#"], name=f"rec-{name}")
        scope.callback(mqtt.close)
        frames = FrameLog()
        emu, relay, link = open_line(scope, model, frames, emu_opts, paced)
        counter = ByteCounter(emu) if count_bytes else None
        rot = {"id": "r", "model": model, "port": str(link), **(rotator or {})}
        bridge = start_bridge(scope, broker_port, [rot], homeassistant=homeassistant)
        rig = Rig(scope, model, emu, frames, mqtt, bridge, broker_port, counter, relay)
        try:
            mqtt.wait_value(rig.t("availability"), "online", wait_online_s)
        except Exception:
            bridge.check()
            raise
        yield rig
        bridge.check()  # it must have survived the measurement


@dataclass
class Line:
    """One emulated controller behind its paced line, in this process."""

    id: str
    model: str
    emu: EmulatedPort[Any]
    frames: FrameLog
    counter: ByteCounter
    relay: PacedRelay | None
    path: Path


@dataclass
class MultiRig:
    scope: Scope
    lines: dict[str, Line]
    mqtt: Mqtt
    bridge: BridgeProcess
    broker_port: int

    def t(self, rid: str, leaf: str) -> str:
        return f"{TOPIC}/{rid}/{leaf}"


@contextlib.contextmanager
def many_rotators(
    parent: Scope,
    name: str,
    specs: list[tuple[str, str, dict[str, Any], dict[str, Any]]],
    *,
    wait_online_s: float = 30.0,
) -> Iterator[MultiRig]:
    """specs: (id, model, emulator options, rotator settings) for each rotator of one bridge."""
    with Scope(parent.workdir / name) as scope:
        broker_port = start_broker(scope)
        mqtt = Mqtt(broker_port, [f"{TOPIC}/#"], name=f"rec-{name}")
        scope.callback(mqtt.close)
        lines: dict[str, Line] = {}
        rotators = []
        for rid, model, emu_opts, rot_opts in specs:
            frames = FrameLog()
            emu, relay, path = open_line(scope, model, frames, emu_opts, name=f"tty-{rid}")
            lines[rid] = Line(rid, model, emu, frames, ByteCounter(emu), relay, path)
            rotators.append({"id": rid, "model": model, "port": str(path), **rot_opts})
        bridge = start_bridge(scope, broker_port, rotators)
        rig = MultiRig(scope, lines, mqtt, bridge, broker_port)
        try:
            mqtt.wait_all([rig.t(rid, "availability") for rid in lines], "online", wait_online_s)
        except Exception:
            bridge.check()
            raise
        yield rig
        bridge.check()


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
