"""Hamlib's rotctl as the independent judge of the RT-21 emulator: model 405 (Green Heron RT-21)
sets, reads and stops it on a pty.

Hamlib 4.5.4 sends ``AP1ddd.d`` CR ``;`` for a heading, ``BI1;`` for the bearing (it reads up
to the ``;``, at most seven bytes, and takes a leading digit or space) and ``;`` to stop; it
waits half a second after every write. rotctl must be installed (libhamlib-utils): a missing
judge is a failure, never a skip.
"""

from __future__ import annotations

import subprocess
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from bridge.emulators.pty import EmulatedPort
from bridge.emulators.rt21 import Outcome, Rt21
from tests.emulators.conftest import served
from tests.support.hamlib import run_rotctl

pytestmark = pytest.mark.hamlib

PortFactory = Callable[..., EmulatedPort[Rt21]]
Rotctl = Callable[..., subprocess.CompletedProcess[str]]


@pytest.fixture
def rt21_port(tmp_path: Path) -> Iterator[PortFactory]:
    ports: list[EmulatedPort[Rt21]] = []

    def factory(**options: Any) -> EmulatedPort[Rt21]:
        link = tmp_path / f"tty-rt21-{len(ports)}"
        port = EmulatedPort(Rt21(now=time.monotonic(), **options), link=link, name="rt21")
        ports.append(port)
        return port

    yield factory
    for port in ports:
        port.close()


@pytest.fixture
def rotctl(rotctl_path: str) -> Rotctl:
    def run(port: EmulatedPort[Rt21], *commands: str) -> Any:
        assert port.link is not None
        return run_rotctl(rotctl_path, 405, port.link, "-s", "4800", *commands)

    return run


def values(result: subprocess.CompletedProcess[str]) -> list[str]:
    assert result.returncode == 0, f"rotctl failed: {result.stdout!r} {result.stderr[-800:]!r}"
    return result.stdout.split()


def commands(port: EmulatedPort[Rt21]) -> list[tuple[bytes, str]]:
    return [(f.data, f.outcome) for f in port.log()]


def test_reads_sets_and_stops_the_box(rt21_port: PortFactory, rotctl: Rotctl) -> None:
    port = rt21_port(start_az_deg=12.3)
    assert values(rotctl(port, "p")) == ["12.30", "0.00"]
    assert commands(port) == [(b"BI1;", "query")]

    values(rotctl(port, "P", "123.4", "0"))
    moving = port.wait_for(lambda s: s.is_moving)
    assert moving.target_az_deg == 123.4
    assert commands(port)[-1] == (b"AP1123.4\r;", "move")

    values(rotctl(port, "S"))
    stopped = port.wait_for(lambda s: not s.is_moving)
    assert 12.3 <= stopped.az_deg < 123.4
    assert commands(port)[-1] == (b";", "stop")
    (az, _el) = values(rotctl(port, "p"))  # where it stopped, to the tenth
    assert float(az) == round(port.state().az_deg, 1)
    assert port.log()[-1].outcome == "query"
    assert not [f for f in port.log() if f.outcome == Outcome.REFUSED]


def test_a_set_move_arrives_to_the_tenth(rt21_port: PortFactory, rotctl: Rotctl) -> None:
    port = rt21_port(az_speed_deg_s=500.0)
    values(rotctl(port, "P", "271.6", "0"))
    port.wait_for(lambda s: not s.is_moving and s.az_deg == 271.6)
    assert values(rotctl(port, "p")) == ["271.60", "0.00"]


@pytest.mark.parametrize("padding", ["none", "zero"])
def test_hamlib_reads_the_padded_replies(
    rt21_port: PortFactory, rotctl: Rotctl, padding: str
) -> None:
    port = rt21_port(start_az_deg=7.5, reply_padding=padding)
    assert values(rotctl(port, "p")) == ["7.50", "0.00"]


def test_rotor_bridge_emulate_serves_an_rt21_that_hamlib_drives(
    tmp_path: Path, rotctl_path: str
) -> None:
    """``rotor-bridge emulate rt21`` (here ``python -m bridge.emulators``)."""
    link = tmp_path / "rt21"
    with served("rt21", link, "--start-az-deg", "3.5", "--reply-padding", "none"):
        done = run_rotctl(rotctl_path, 405, str(link), "-s", "4800", "p", "P", "40", "0", "S")
        assert done.returncode == 0 and done.stdout.split()[:2] == ["3.50", "0.00"], done
