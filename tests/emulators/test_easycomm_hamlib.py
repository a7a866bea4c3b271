"""Hamlib's rotctl as the independent judge of the Easycomm II/III controller emulator: models 202
(Easycomm II) and 204 (Easycomm III) set, read and stop it on a pty.

Hamlib 4.5.4's easycomm back end asks ``AZ EL`` on one line and reads one line to its LF,
``AZ%f EL%f``; it sends ``AZ%.1f EL%.1f`` and ``SA SE`` and waits for no answer to them. Newer
Hamlib asks ``AZ`` and ``EL`` separately, for controllers that answer only so: Hamlib 4.5.4 gets
no answer from those (``-separate`` here) but still sets and stops them. rotctl must be installed
(libhamlib-utils): a missing judge is a failure, never a skip.
"""

from __future__ import annotations

import subprocess
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from bridge.emulators.easycomm import EasycommController, Outcome
from bridge.emulators.pty import EmulatedPort
from tests.emulators.conftest import served
from tests.support.hamlib import run_rotctl

pytestmark = pytest.mark.hamlib

PortFactory = Callable[..., EmulatedPort[EasycommController]]
Rotctl = Callable[..., subprocess.CompletedProcess[str]]


@pytest.fixture
def easycomm_port(tmp_path: Path) -> Iterator[PortFactory]:
    ports: list[EmulatedPort[EasycommController]] = []

    def factory(model: str, **options: Any) -> EmulatedPort[EasycommController]:
        link = tmp_path / f"tty-{model}-{len(ports)}"
        device = EasycommController(model, now=time.monotonic(), **options)
        port = EmulatedPort(device, link=link, name=model)
        ports.append(port)
        return port

    yield factory
    for port in ports:
        port.close()


@pytest.fixture
def rotctl(rotctl_path: str) -> Rotctl:
    def run(hamlib_model: int, port: EmulatedPort[EasycommController], *commands: str) -> Any:
        assert port.link is not None
        return run_rotctl(rotctl_path, hamlib_model, port.link, "-s", "19200", *commands)

    return run


def values(result: subprocess.CompletedProcess[str]) -> list[str]:
    assert result.returncode == 0, f"rotctl failed: {result.stdout!r} {result.stderr[-800:]!r}"
    return result.stdout.split()


def commands(port: EmulatedPort[EasycommController]) -> list[tuple[bytes, str]]:
    return [(f.data, f.outcome) for f in port.log()]


@pytest.mark.parametrize(("model", "hamlib"), [("easycomm2", 202), ("easycomm3", 204)])
def test_reads_sets_and_stops_an_az_el_controller(
    easycomm_port: PortFactory, rotctl: Rotctl, model: str, hamlib: int
) -> None:
    port = easycomm_port(model, start_az_deg=12.3, start_el_deg=34.5)
    assert values(rotctl(hamlib, port, "p")) == ["12.30", "34.50"]
    assert commands(port) == [(b"AZ", "query"), (b"EL", "query")]

    values(rotctl(hamlib, port, "P", "123.4", "45"))
    moving = port.wait_for(lambda s: s.is_moving)
    assert (moving.target_az_deg, moving.target_el_deg) == (123.4, 45.0)
    assert commands(port)[-2:] == [(b"AZ123.4", "move"), (b"EL45.0", "move")]

    values(rotctl(hamlib, port, "S"))
    stopped = port.wait_for(lambda s: not s.is_moving)
    assert 12.3 <= stopped.az_deg < 123.4 and stopped.el_deg is not None
    assert commands(port)[-2:] == [(b"SA", "stop"), (b"SE", "stop")]
    az, el = values(rotctl(hamlib, port, "p"))  # where it stopped, as the controller reads it
    assert float(az) == round(stopped.az_deg, 1) and float(el) == round(stopped.el_deg, 1)
    assert not [f for f in port.log() if f.outcome in (Outcome.REFUSED, Outcome.IGNORED)]


@pytest.mark.parametrize(("model", "hamlib"), [("easycomm2", 202), ("easycomm3", 204)])
def test_a_set_move_arrives(
    easycomm_port: PortFactory, rotctl: Rotctl, model: str, hamlib: int
) -> None:
    port = easycomm_port(model, az_speed_deg_s=500.0, el_speed_deg_s=500.0)
    values(rotctl(hamlib, port, "P", "271.5", "12.5"))
    port.wait_for(lambda s: not s.is_moving and (s.az_deg, s.el_deg) == (271.5, 12.5))
    assert values(rotctl(hamlib, port, "p")) == ["271.50", "12.50"]


def test_whole_degree_answers_and_the_version(easycomm_port: PortFactory, rotctl: Rotctl) -> None:
    port = easycomm_port("easycomm3", decimals=0, version="K3NG 2024", start_az_deg=200)
    assert values(rotctl(204, port, "p")) == ["200.00", "0.00"]
    assert values(rotctl(204, port, "_")) == ["EasycommIII"]  # Hamlib's own words for get_info


def test_easycomm3_moves_at_a_velocity_and_stops(
    easycomm_port: PortFactory, rotctl: Rotctl
) -> None:
    """rotctl's M (move) is Easycomm III's VR/VL/VU/VD with a speed in millidegrees a second."""
    port = easycomm_port("easycomm3", start_az_deg=100)
    values(rotctl(204, port, "M", "16", "2"))  # 16: right; speed 2 of 100 -> VR0100 (0.1 deg/s)
    state = port.wait_for(lambda s: s.is_moving)
    assert state.target_az_deg == 360.0 and commands(port)[-1] == (b"VR0100", "jog")
    values(rotctl(204, port, "S"))
    assert port.wait_for(lambda s: not s.is_moving).az_deg < 101


def test_hamlib_454_gets_no_answer_from_a_separate_controller_but_sets_and_stops_it(
    easycomm_port: PortFactory, rotctl: Rotctl
) -> None:
    port = easycomm_port("easycomm2-separate", start_az_deg=50, start_el_deg=5)
    assert rotctl(202, port, "p").returncode != 0  # AZ EL on one line: no answer at all
    assert commands(port) == [(b"AZ", "unanswered"), (b"EL", "unanswered")]
    values(rotctl(202, port, "P", "60", "10"))
    port.wait_for(lambda s: s.is_moving)
    values(rotctl(202, port, "S"))
    port.wait_for(lambda s: not s.is_moving)


def test_rotor_bridge_emulate_serves_an_easycomm_controller_that_hamlib_drives(
    tmp_path: Path, rotctl_path: str
) -> None:
    """``rotor-bridge emulate easycomm2`` (here ``python -m bridge.emulators``), answering in
    whole degrees as some firmware does."""
    link = tmp_path / "easycomm"
    with served(
        "easycomm2", link, "--start-az-deg", "30.3", "--start-el-deg", "10", "--decimals", "0"
    ):
        done = run_rotctl(rotctl_path, 202, str(link), "-s", "19200", "p", "P", "40", "20", "S")
        assert done.returncode == 0 and done.stdout.split()[:2] == ["30.00", "10.00"], done


@pytest.mark.parametrize(("model", "hamlib"), [("easycomm2-az", 202), ("easycomm3-az", 204)])
def test_an_azimuth_controller_turns_and_reads_elevation_zero(
    easycomm_port: PortFactory, rotctl: Rotctl, model: str, hamlib: int
) -> None:
    port = easycomm_port(model, az_speed_deg_s=500.0, start_az_deg=5)
    values(rotctl(hamlib, port, "P", "181.5", "30"))  # the elevation moves nothing
    port.wait_for(lambda s: not s.is_moving and s.az_deg == 181.5)
    assert port.state().el_deg is None
    assert values(rotctl(hamlib, port, "p")) == ["181.50", "0.00"]
