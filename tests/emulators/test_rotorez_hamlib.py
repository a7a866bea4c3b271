"""Hamlib's rotctl (models 401, 402, 403) as the independent judge of the Rotor-EZ emulator.

Hamlib 4.5.4 sleeps 500 ms after every write, so each `p` costs ~0.55 s and each `P` ~1.05 s;
the file keeps to a handful of sessions. rotctl must be installed (libhamlib-utils): a missing
judge is a failure, never a skip.
"""

from __future__ import annotations

import subprocess
from collections.abc import Callable
from typing import Any

import pytest

from bridge.emulators import EmulatedPort
from tests.emulators.conftest import PortFactory
from tests.support.hamlib import run_rotctl

pytestmark = pytest.mark.hamlib


Rotctl = Callable[..., subprocess.CompletedProcess[str]]


@pytest.fixture
def rotctl(rotctl_path: str) -> Rotctl:
    def run(
        hamlib_model: int, port: EmulatedPort[Any], *commands: str
    ) -> subprocess.CompletedProcess[str]:
        assert port.link is not None
        return run_rotctl(rotctl_path, hamlib_model, port.link, "-s", "4800", *commands)

    return run


def values(result: subprocess.CompletedProcess[str]) -> list[str]:
    assert result.returncode == 0, f"rotctl failed: {result.stdout!r} {result.stderr!r}"
    return result.stdout.split()


def test_401_reads_the_emulated_bearing(make_port: PortFactory, rotctl: Rotctl) -> None:
    port = make_port("rotorez", start_az_deg=123)
    assert values(rotctl(401, port, "p")) == ["123.00", "0.00"]
    assert [(f.data, f.outcome) for f in port.log()] == [(b"AI1;", "query")]


def test_401_stationary_jitter_shows_two_neighbouring_values(
    make_port: PortFactory, rotctl: Rotctl
) -> None:
    port = make_port("rotorez", start_az_deg=45, jitter_deg=1)
    assert values(rotctl(401, port, "p", "p")) == ["45.00", "0.00", "46.00", "0.00"]


def test_401_set_position_turns_the_emulated_rotor(make_port: PortFactory, rotctl: Rotctl) -> None:
    port = make_port("rotorez", start_az_deg=150, speed_deg_s=60.0)
    assert values(rotctl(401, port, "P", "200", "0")) == []
    state = port.wait_for(lambda s: not s.is_moving and s.az_deg == 200.0, timeout_s=5.0)
    assert state.in_brake_delay
    assert [(f.data, f.outcome) for f in port.log()] == [
        (b"AP1200;", "stored"),
        (b"AM1;", "executed"),
    ]


def test_401_stop_halts_a_move(make_port: PortFactory, rotctl: Rotctl) -> None:
    port = make_port("rotorez", start_az_deg=0, speed_deg_s=6.0)
    values(rotctl(401, port, "P", "300", "0", "S"))
    state = port.state()
    assert not state.is_moving and 0.0 < state.az_deg < 10.0
    assert port.log()[-1].data == b";" and port.log()[-1].outcome == "stop"


def test_401_second_set_position_while_turning_stops_the_rotor(
    make_port: PortFactory, rotctl: Rotctl
) -> None:
    port = make_port("rotorez", start_az_deg=0, speed_deg_s=6.0)
    values(rotctl(401, port, "P", "300", "0", "P", "100", "0"))
    assert [f.outcome for f in port.log()] == [
        "stored",
        "executed",
        "ignored: re-target while turning (stopped)",
        "ignored: brake delay",
    ]
    state = port.state()
    assert not state.is_moving and state.az_deg < 10.0


def test_401_set_conf_switches_the_emulated_options(make_port: PortFactory, rotctl: Rotctl) -> None:
    jumpers = {"endpoint": True, "jam": False, "overshoot": False, "unstick": True}
    port = make_port("rotorez", jumpers=jumpers)
    commands = ["C", "endpt", "0", "C", "jam", "1", "C", "oversht", "1", "C", "unstick", "0"]
    values(rotctl(401, port, *commands))
    assert port.state().options == {
        "endpoint": False,
        "jam": True,
        "overshoot": True,
        "unstick": False,
    }
    assert [f.data for f in port.frames("option")] == [b"e", b"J", b"O", b"s"]


def test_401_idle_stop_banner_is_flushed_and_the_next_read_is_right(
    make_port: PortFactory, rotctl: Rotctl
) -> None:
    port = make_port("rotorez", start_az_deg=77)
    assert values(rotctl(401, port, "S", "p")) == ["77.00", "0.00"]
    outcomes = [f.outcome for f in port.log()]
    assert outcomes[0] == "invalid" and outcomes[1:] == ["query"] * (len(outcomes) - 1)
    assert len(outcomes) == 3  # the banner spoiled one answer; Hamlib flushed and asked again


def test_401_copes_with_the_power_on_byte(make_port: PortFactory, rotctl: Rotctl) -> None:
    port = make_port("rotorez", start_az_deg=200, power_on_junk=True)
    assert values(rotctl(401, port, "p")) == ["200.00", "0.00"]


def test_402_rotorcard_sets_and_reads(make_port: PortFactory, rotctl: Rotctl) -> None:
    port = make_port("rotorcard", start_az_deg=10, speed_deg_s=1000.0)
    assert values(rotctl(402, port, "P", "90", "0", "p")) == ["90.00", "0.00"]
    assert not port.state().in_brake_delay  # Yaesu rotors have no brake


def test_403_dcu1_set_position_works_and_there_is_no_readback(
    make_port: PortFactory, rotctl: Rotctl
) -> None:
    port = make_port("dcu1", start_az_deg=150, speed_deg_s=60.0)
    values(rotctl(403, port, "P", "200", "0"))
    assert port.wait_for(lambda s: s.az_deg == 200.0, timeout_s=5.0).az_deg == 200.0
    result = rotctl(403, port, "p")
    assert result.returncode != 0
    assert "Feature not available" in result.stdout + result.stderr
    assert [f.data for f in port.log()] == [b"AP1200;", b"AM1;"]
