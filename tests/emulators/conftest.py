"""Shared fixture: emulated controllers on ptys (links under tmp_path), closed after the test."""

from __future__ import annotations

import subprocess
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
import serial

from bridge.emulators import EmulatedPort, start
from tests.support.hamlib import Rotctl, rotctl_argv, run
from tests.support.waiting import slow

PortFactory = Callable[..., EmulatedPort[Any]]


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


@pytest.fixture
def rotctl_run(rotctl_path: str) -> Rotctl:
    """Hamlib's rotctl, the emulators' judge: ``rotctl_run(hamlib_model, port, baud, *commands)``
    runs it once on the port's link (tests/support/hamlib.py reads what it printed)."""

    def judged(
        hamlib_model: int, port: EmulatedPort[Any], baud: int, *commands: str
    ) -> subprocess.CompletedProcess[str]:
        assert port.link is not None
        return run([*rotctl_argv(rotctl_path, hamlib_model, port.link, baud), *commands])

    return judged
