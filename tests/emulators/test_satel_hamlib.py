"""Hamlib's rotctl (model 2101) as the independent judge of the SatEL emulator.

Every rotctl run opens the port with `?` then `*` (a reset), reads positions with `z` and sets
them with `z`, `g`, `p<az> <el>\\r\\n` and a 7-line read of the after-move report (satel.md
sections 4-5). rotctl must be installed (libhamlib-utils): a missing judge is a failure, never
a skip.

One session running `P` then `p` races against the report's two trailing empty lines, which are
still on the wire when Hamlib flushes after its 7th line (satel.py rule 9): that combination
runs with trailing_blank_lines=0; the default report is judged across separate sessions.
"""

from __future__ import annotations

import subprocess
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from bridge.emulators.pty import EmulatedPort
from bridge.emulators.satel import SatEL
from tests.support.hamlib import run_rotctl

pytestmark = pytest.mark.hamlib

SatelPort = Callable[..., EmulatedPort[SatEL]]
Rotctl = Callable[..., subprocess.CompletedProcess[str]]
FAST = {"az_speed_deg_s": 200.0, "el_speed_deg_s": 100.0}


@pytest.fixture
def satel_port(tmp_path: Path) -> Iterator[SatelPort]:
    ports: list[EmulatedPort[SatEL]] = []

    def factory(**options: Any) -> EmulatedPort[SatEL]:
        link = tmp_path / "by-id" / f"usb-emulated-satel-{len(ports)}"
        port = EmulatedPort(SatEL(now=time.monotonic(), **options), link=link, name="satel")
        ports.append(port)
        return port

    yield factory
    for port in ports:
        port.close()


@pytest.fixture
def rotctl(rotctl_path: str) -> Rotctl:
    def run(port: EmulatedPort[SatEL], *commands: str) -> subprocess.CompletedProcess[str]:
        assert port.link is not None
        return run_rotctl(rotctl_path, 2101, port.link, "-s", "9600", *commands)

    return run


def values(result: subprocess.CompletedProcess[str]) -> list[str]:
    assert result.returncode == 0, f"rotctl failed: {result.stdout!r} {result.stderr!r}"
    return result.stdout.split()


def outcomes(port: EmulatedPort[SatEL]) -> list[str]:
    return [f.outcome for f in port.log()]


def test_2101_sets_and_reads_in_one_session(satel_port: SatelPort, rotctl: Rotctl) -> None:
    port = satel_port(trailing_blank_lines=0, **FAST)
    assert values(rotctl(port, "P", "100", "45", "p")) == ["100.00", "45.00"]
    assert [(f.data, f.outcome) for f in port.log()] == [
        (b"?", "identify"),
        (b"*", "reset"),
        (b"z", "status"),
        (b"g", "motion enabled"),
        (b"p100 45\r", "slew"),
        (b"z", "status"),
    ]
    state = port.state()
    assert (state.az_deg, state.el_deg, state.motion_enabled) == (100.0, 45.0, True)
    assert state.misuse_count == 0


def test_2101_waits_out_the_slew_for_the_after_move_report(
    satel_port: SatelPort, rotctl: Rotctl
) -> None:
    port = satel_port(az_speed_deg_s=100.0, el_speed_deg_s=100.0)
    started = time.monotonic()
    assert values(rotctl(port, "P", "100", "45")) == []
    assert time.monotonic() - started >= 1.0  # 100 deg at 100 deg/s
    assert port.state().az_deg == 100.0 and not port.frames("misuse: input while slewing")


def test_2101_default_report_is_read_across_sessions(satel_port: SatelPort, rotctl: Rotctl) -> None:
    port = satel_port(**FAST)
    assert values(rotctl(port, "P", "200", "30")) == []
    assert values(rotctl(port, "p")) == ["200.00", "30.00"]
    assert outcomes(port)[-3:] == ["identify", "reset", "status"]


@pytest.mark.parametrize("ending", [b"\r\n", b"\n"])
def test_2101_reads_a_position(satel_port: SatelPort, rotctl: Rotctl, ending: bytes) -> None:
    port = satel_port(start_az_deg=123, start_el_deg=67, line_ending=ending)
    assert values(rotctl(port, "p")) == ["123.00", "67.00"]
    assert outcomes(port) == ["identify", "reset", "status"]
    assert not port.state().motion_enabled  # every open resets the controller


def test_2101_sends_g_before_every_set_and_stops_with_a_reset(
    satel_port: SatelPort, rotctl: Rotctl
) -> None:
    port = satel_port(trailing_blank_lines=0, **FAST)
    values(rotctl(port, "P", "10", "20", "P", "30", "40", "S"))
    assert [f.data for f in port.frames("motion enabled")] == [b"g", b"g"]  # its motion-flag bug
    # rotctl exits right after writing its `*`; the byte may still be on its way
    port.wait_until(lambda d, now: d.frames()[-1].outcome, lambda o: o == "reset", 5)
    state = port.state()
    assert (state.az_deg, state.el_deg) == pytest.approx((30.0, 40.0), abs=1e-6)
    assert state.motion_enabled is False
    assert state.misuse_count == 0
