"""Hamlib's rotctl (models 901, 902, 903) as the independent judge of the SPID emulators.

Hamlib 4.5.4 pauses 300 ms after every write, so a `p` costs ~0.4 s and a `P` ~0.7 s (901/903
ask for the resolution first). rotctl must be installed (libhamlib-utils): a missing judge is a
failure, never a skip. Ports are built from Spid(...) directly (the registry is not used here).
"""

from __future__ import annotations

import subprocess
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from bridge.emulators.pty import EmulatedPort
from bridge.emulators.spid import Spid
from tests.support.hamlib import run_rotctl

pytestmark = pytest.mark.hamlib

STATUS = bytes.fromhex("57 00 00 00 00 00 00 00 00 00 00 1F 20")
STOP = bytes.fromhex("57 00 00 00 00 00 00 00 00 00 00 0F 20")
SpidPortFactory = Callable[..., EmulatedPort[Spid]]
Rotctl = Callable[..., subprocess.CompletedProcess[str]]


@pytest.fixture
def spid_port(tmp_path: Path) -> Iterator[SpidPortFactory]:
    ports: list[EmulatedPort[Spid]] = []

    def factory(model: str, **options: Any) -> EmulatedPort[Spid]:
        link = tmp_path / f"tty-{model}-{len(ports)}"
        port = EmulatedPort(Spid(model, now=time.monotonic(), **options), link=link, name=model)
        ports.append(port)
        return port

    yield factory
    for port in ports:
        port.close()


@pytest.fixture
def rotctl(rotctl_path: str) -> Rotctl:
    def run(
        hamlib_model: int, port: EmulatedPort[Spid], baud: int, *commands: str
    ) -> subprocess.CompletedProcess[str]:
        assert port.link is not None
        return run_rotctl(rotctl_path, hamlib_model, port.link, "-s", str(baud), *commands)

    return run


def values(result: subprocess.CompletedProcess[str]) -> list[str]:
    assert result.returncode == 0, f"rotctl failed: {result.stdout!r} {result.stderr!r}"
    return result.stdout.split()


def wire(port: EmulatedPort[Spid]) -> list[tuple[str, str]]:
    return [(f.data.hex(" "), f.outcome) for f in port.log()]


# -- 901 Rot2Prog --


def test_901_reads_the_fact_sheet_position(spid_port: SpidPortFactory, rotctl: Rotctl) -> None:
    port = spid_port("rot2prog", start_az_deg=12.5, start_el_deg=34.0)
    assert values(rotctl(901, port, 600, "p")) == ["12.50", "34.00"]
    assert [f.data for f in port.log()] == [STATUS]


def test_901_set_position_moves_the_rotor(spid_port: SpidPortFactory, rotctl: Rotctl) -> None:
    # fast enough to be there before rotctl's next frame even on a loaded machine: the set and
    # the read below go in one rotctl run, 134 degrees apart (27 ms at this speed, a 13-byte
    # frame at 600 baud takes 217 ms)
    port = spid_port("rot2prog", az_speed_deg_s=5000.0, el_speed_deg_s=5000.0)
    assert values(rotctl(901, port, 600, "P", "123.5", "45")) == []
    port.wait_for(lambda s: not s.is_moving and (s.az_deg, s.el_deg) == (123.5, 45.0))
    assert wire(port) == [  # auto-sensed resolution first, then the set (spid.md section 7)
        ("57 00 00 00 00 00 00 00 00 00 00 1f 20", "status"),
        ("57 30 39 36 37 02 30 38 31 30 02 2f 20", "set"),
    ]
    assert values(rotctl(901, port, 600, "P", "-10.3", "-5", "p")) == ["-10.50", "-5.00"]
    assert port.state().az_deg == -10.5


def test_901_stop_halts_a_move(spid_port: SpidPortFactory, rotctl: Rotctl) -> None:
    port = spid_port("rot2prog")  # 1 deg/s az, 0.5 deg/s el
    values(rotctl(901, port, 600, "P", "300", "60", "S"))
    state = port.state()
    assert not state.is_moving and 0.0 < state.az_deg < 10.0 and 0.0 < (state.el_deg or 0) < 5.0
    assert port.log()[-1].data == STOP and port.log()[-1].outcome == "stop"


def test_901_quarter_degree_resolution(spid_port: SpidPortFactory, rotctl: Rotctl) -> None:
    port = spid_port("rot2prog", resolution_ppd=4, az_speed_deg_s=500.0, el_speed_deg_s=500.0)
    values(rotctl(901, port, 600, "P", "123.3", "10"))
    assert port.wait_for(lambda s: not s.is_moving).az_deg == 123.25  # 1933 pulses
    assert values(rotctl(901, port, 600, "p")) == ["123.20", "10.00"]


# -- 902 Rot1Prog --


def test_902_reads_and_sets(spid_port: SpidPortFactory, rotctl: Rotctl) -> None:
    port = spid_port("rot1prog", start_az_deg=12.0, az_speed_deg_s=500.0)
    assert values(rotctl(902, port, 1200, "p", "P", "123", "0")) == ["12.00", "0.00"]
    port.wait_for(lambda s: not s.is_moving and s.az_deg == 123.0)
    assert wire(port)[-1] == ("57 34 38 33 30 00 00 00 00 00 00 2f 20", "set")
    assert values(rotctl(902, port, 1200, "p")) == ["123.00", "0.00"]


# -- 903 MD-01/02 --


def test_903_set_is_answered_so_hamlib_does_not_wait_out_its_retries(
    spid_port: SpidPortFactory, rotctl: Rotctl
) -> None:
    port = spid_port("md01", az_speed_deg_s=500.0, el_speed_deg_s=500.0)
    done = rotctl(903, port, 115200, "-vvvv", "P", "100", "20")  # Hamlib's own account
    assert done.returncode == 0 and done.stdout.startswith("Opened rot model 903"), done
    # unanswered, the set costs four waits of 400 ms, each logged "read_block_generic(): Timed
    # out 0.40 seconds after 0 chars"
    assert "Timed out" not in done.stderr, done.stderr[-600:]
    port.wait_for(lambda s: not s.is_moving)
    assert values(rotctl(903, port, 115200, "p")) == ["100.00", "20.00"]


def test_903_at_9600_baud_with_tenth_degrees(spid_port: SpidPortFactory, rotctl: Rotctl) -> None:
    port = spid_port(
        "md01", baud=9600, resolution_ppd=10, az_speed_deg_s=500.0, el_speed_deg_s=500.0
    )
    values(rotctl(903, port, 9600, "P", "12.3", "4.5"))
    port.wait_for(lambda s: not s.is_moving)
    assert values(rotctl(903, port, 9600, "p")) == ["12.30", "4.50"]


def test_903_move_runs_until_stop(spid_port: SpidPortFactory, rotctl: Rotctl) -> None:
    port = spid_port("md01", start_az_deg=100.0, az_speed_deg_s=10.0)
    values(rotctl(903, port, 115200, "M", "16", "50"))
    moving = port.wait_for(lambda s: s.is_moving)
    assert moving.target_az_deg == 540.0
    assert [outcome for _, outcome in wire(port)] == ["stop", "move"]  # Hamlib stops first
    values(rotctl(903, port, 115200, "S"))
    stopped = port.state()
    assert not stopped.is_moving and 100.0 < stopped.az_deg < 200.0
