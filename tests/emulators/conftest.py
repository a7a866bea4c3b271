"""Shared fixtures: emulated controllers on ptys (links under tmp_path), closed after the test;
real pyserial clients on them; Hamlib's rotctl as their judge."""

from __future__ import annotations

import contextlib
import signal
import subprocess
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
import serial

from bridge.emulators import EmulatedPort, Responder, start
from tests.support import ROOT
from tests.support.hamlib import run_rotctl
from tests.support.waiting import slow

PortFactory = Callable[..., EmulatedPort[Any]]


def ask(device: Responder, data: bytes, now: float) -> bytes:
    """A sans-IO emulator's whole answer to ``data`` sent at ``now`` (or at the device's
    latest instant, if later: time never goes back)."""
    now = device.state(now).time_s
    device.receive(data, now)
    return device.due_output(now + 0.1)


@pytest.fixture
def make_port(tmp_path: Path) -> Iterator[PortFactory]:
    """Start a model with a quiet line by default (no power-on byte, no jitter)."""
    ports: list[EmulatedPort[Any]] = []

    def factory(model: str = "rotorez", **options: Any) -> EmulatedPort[Any]:
        options.setdefault("link", str(tmp_path / "by-id" / f"usb-emulated-{model}-{len(ports)}"))
        if model in ("rotorez", "rotorcard", "dcu1"):
            options.setdefault("power_on_junk", False)
            options.setdefault("jitter_deg", 0)
        port = start(model, **options)
        ports.append(port)
        return port

    yield factory
    for port in ports:
        port.close()


@pytest.fixture
def clients() -> Iterator[Callable[..., serial.Serial]]:
    """Real pyserial clients on emulated ports (the baud rate only labels a pty), closed after."""
    opened: list[serial.Serial] = []

    def open_client(path: str, baud: int = 4800, timeout_s: float = 3.0) -> serial.Serial:
        client = serial.Serial(path, baud, timeout=slow(timeout_s))
        opened.append(client)
        return client

    yield open_client
    for client in opened:
        try:
            client.close()
        except (serial.SerialException, OSError):
            pass


Hamlib = Callable[..., list[str]]


@pytest.fixture
def hamlib(rotctl_path: str) -> Hamlib:
    """``hamlib(1701, port, "p")``: Hamlib's rotctl as that model on the emulator's link, at the
    baud rate given (9600 unless told); what it printed, word by word (it must succeed)."""

    def run(model: int, port: EmulatedPort[Any], *commands: str, baud: int = 9600) -> list[str]:
        assert port.link is not None
        done = run_rotctl(rotctl_path, model, port.link, "-s", str(baud), *commands)
        assert done.returncode == 0, f"rotctl failed: {done.stdout!r} {done.stderr[-800:]!r}"
        return done.stdout.split()

    return run


@contextlib.contextmanager
def served(model: str, link: Path, *options: str) -> Iterator[None]:
    """``rotor-bridge emulate MODEL --link LINK OPTIONS`` (here ``python -m bridge.emulators``)
    as a process of its own, once it has printed its device and its link; at the end it must
    take SIGTERM and exit with status 0."""
    argv = [sys.executable, "-m", "bridge.emulators", model, "--link", str(link), *options]
    proc = subprocess.Popen(argv, cwd=ROOT, stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout is not None
        assert proc.stdout.readline().startswith("/dev/pts/")
        assert proc.stdout.readline().strip() == str(link)
        yield
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=slow(10)) == 0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
