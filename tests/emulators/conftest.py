"""Shared fixture: emulated controllers on ptys (links under tmp_path), closed after the test."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from bridge.emulators import EmulatedPort, start

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
