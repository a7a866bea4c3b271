"""The SatEL emulator on a real pseudo-terminal (pty.EmulatedPort), driven by real pyserial.

Waits are conditions with deadlines (serial read timeouts, port.wait_for), never bare sleeps.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
import serial

from bridge.emulators.pty import EmulatedPort
from bridge.emulators.satel import SatEL

SatelPort = Callable[..., EmulatedPort[SatEL]]
MISUSE = "misuse: input while slewing"


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


def read_report(client: serial.Serial) -> list[bytes]:
    """The 7 lines Hamlib reads, plus the two trailing empty lines."""
    lines = [client.readline() for _ in range(9)]
    assert all(line.endswith(b"\r\n") for line in lines), lines
    return [line[:-2] for line in lines]


def test_identify_and_status_through_the_link(
    satel_port: SatelPort, clients: Callable[[str], serial.Serial]
) -> None:
    port = satel_port(start_az_deg=123, start_el_deg=67)
    assert port.link is not None and os.path.realpath(port.link) == port.path
    client = clients(port.link)
    client.write(b"?")
    assert client.readline() == b"SatEL\r\n"
    client.write(b"z")
    report = read_report(client)
    assert report[0] == b"Motion DISABLED"
    assert report[3] == b"Azimuth = 123     Absolute = 123" and report[4] == b"Elevation = 067"
    assert report[6] == b"Number of stored positions: 00" and report[7:] == [b"", b""]


def test_slew_then_the_after_move_report(
    satel_port: SatelPort, clients: Callable[[str], serial.Serial]
) -> None:
    port = satel_port(az_speed_deg_s=100.0, el_speed_deg_s=50.0)
    client = clients(port.path)
    client.write(b"g")
    port.wait_for_frame(b"g", "motion enabled")
    started = time.monotonic()
    client.write(b"p50 20\r\n")
    report = read_report(client)
    assert time.monotonic() - started >= 0.5  # the az slew takes 0.5 s, the report comes after
    assert report[0] == b"Motion ENABLED" and report[3] == b"Azimuth = 050     Absolute = 050"
    assert report[4] == b"Elevation = 020"
    state = port.state()
    assert (state.az_deg, state.el_deg, state.is_moving) == (50.0, 20.0, False)
    assert not port.frames(MISUSE)


def test_input_during_a_slew_is_recorded_as_misuse(
    satel_port: SatelPort, clients: Callable[[str], serial.Serial]
) -> None:
    port = satel_port(az_speed_deg_s=100.0, el_speed_deg_s=50.0)
    client = clients(port.path)
    client.write(b"gp50 20\r\n")
    port.wait_for(lambda s: s.slewing)
    client.write(b"z")
    port.wait_for_frame(b"z", MISUSE)
    report = read_report(client)  # the z got no answer: the first report is the after-move one
    assert report[3] == b"Azimuth = 050     Absolute = 050"
    client.timeout = 0.3
    assert client.read(1) == b""


def test_misuse_with_corruption_leaves_the_client_hanging_until_reset(
    satel_port: SatelPort, clients: Callable[[str], serial.Serial]
) -> None:
    port = satel_port(az_speed_deg_s=50.0, el_speed_deg_s=50.0, corrupt_on_misuse=True)
    client = clients(port.path)
    client.write(b"gp100 0\r\n")
    port.wait_for(lambda s: s.slewing)
    client.write(b"?")
    state = port.wait_for(lambda s: s.corrupted)
    assert not state.is_moving and state.az_deg < 100.0
    client.timeout = 0.5
    assert client.read(1) == b""  # no after-move report ever comes
    client.timeout = 3.0
    client.write(b"*gp0 0\r")
    assert read_report(client)[3] == b"Azimuth = 000     Absolute = 000"


def test_s_stops_a_slew_and_the_report_shows_where(
    satel_port: SatelPort, clients: Callable[[str], serial.Serial]
) -> None:
    port = satel_port(az_speed_deg_s=10.0, el_speed_deg_s=10.0)
    client = clients(port.path)
    client.write(b"gp300 80\r\n")
    port.wait_for(lambda s: s.az_deg >= 1.0)
    client.write(b"s")
    report = read_report(client)
    state = port.state()
    assert report[0] == b"Motion DISABLED" and not state.is_moving and state.az_deg < 10.0
    assert report[3] == b"Azimuth = %03d     Absolute = %03d" % ((round(state.az_deg),) * 2)


def test_replug_power_cycles_but_the_position_stays(
    satel_port: SatelPort, clients: Callable[[str], serial.Serial]
) -> None:
    port = satel_port(start_az_deg=200, start_el_deg=30)
    assert port.link is not None
    client = clients(port.link)
    client.write(b"g")
    port.wait_for(lambda s: s.motion_enabled)
    port.unplug()
    with pytest.raises((serial.SerialException, OSError)):
        client.write(b"z")
        client.read(1)
    assert not os.path.exists(port.link)
    port.replug()
    state = port.state()
    assert not state.motion_enabled and (state.az_deg, state.el_deg) == (200.0, 30.0)
    again = clients(port.link)
    again.write(b"z")
    assert read_report(again)[3] == b"Azimuth = 200     Absolute = 200"


def test_silent_line_and_injected_junk(
    satel_port: SatelPort, clients: Callable[[str], serial.Serial]
) -> None:
    port = satel_port()
    client = clients(port.path)
    client.timeout = 0.3
    port.set_silent(True)
    client.write(b"?")
    port.wait_for_frame(b"?", "identify")
    assert client.read(1) == b""
    # the identify's reply wholly sent into the silence (a loaded machine: its tail, "tEL", went
    # out after the line spoke again, and was read as the second line)
    port.wait_until(lambda device, now: device.next_wakeup(now), lambda due: due is None)
    port.set_silent(False)
    client.timeout = 3.0
    port.inject(b"\x00junk\r\n", to="host")
    client.write(b"?")
    assert client.readline() == b"\x00junk\r\n" and client.readline() == b"SatEL\r\n"
