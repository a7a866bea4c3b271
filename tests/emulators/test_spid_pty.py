"""SPID emulators on a real pseudo-terminal (EmulatedPort), driven by real pyserial clients.

Waits are conditions with deadlines (port.wait_for / serial read timeouts), never bare sleeps.
The registry is not touched here: ports are built from Spid(...) directly.
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
from bridge.emulators.spid import Spid

STATUS = bytes.fromhex("57 00 00 00 00 00 00 00 00 00 00 1F 20")
STOP = bytes.fromhex("57 00 00 00 00 00 00 00 00 00 00 0F 20")
SpidPortFactory = Callable[..., EmulatedPort[Spid]]


@pytest.fixture
def spid_port(tmp_path: Path) -> Iterator[SpidPortFactory]:
    ports: list[EmulatedPort[Spid]] = []

    def factory(model: str = "rot2prog", **options: Any) -> EmulatedPort[Spid]:
        link = tmp_path / "by-id" / f"usb-emulated-{model}-{len(ports)}"
        port = EmulatedPort(Spid(model, now=time.monotonic(), **options), link=link, name=model)
        ports.append(port)
        return port

    yield factory
    for port in ports:
        port.close()


def test_status_round_trip_takes_line_time_at_600_baud(
    spid_port: SpidPortFactory, clients: Callable[..., serial.Serial]
) -> None:
    port = spid_port(start_az_deg=12.5, start_el_deg=34.0)
    assert port.link is not None and os.path.realpath(port.link) == port.path
    client = clients(port.link)
    started = time.monotonic()
    client.write(STATUS)
    assert client.read(12) == bytes.fromhex("57 03 07 02 05 02 03 09 04 00 02 20")
    assert time.monotonic() - started >= 0.2  # 12 bytes x 10 bits at 600 baud
    assert port.wait_for_frame(STATUS, "status").outcome == "status"


def test_set_turns_the_rotor_and_status_reads_it_back(
    spid_port: SpidPortFactory, clients: Callable[..., serial.Serial]
) -> None:
    port = spid_port(az_speed_deg_s=500.0, el_speed_deg_s=500.0)
    client = clients(port.path)
    client.write(bytes.fromhex("57 30 39 36 37 02 30 38 37 34 02 2F 20"))  # 123.5 / 77
    state = port.wait_for(lambda s: not s.is_moving and s.az_deg == 123.5)
    assert state.el_deg == 77.0
    client.write(STATUS)
    assert client.read(12) == bytes.fromhex("57 04 08 03 05 02 04 03 07 00 02 20")
    assert client.in_waiting == 0  # the set itself was answered with nothing


def test_frames_in_pieces_with_junk_around_them(
    spid_port: SpidPortFactory, clients: Callable[..., serial.Serial]
) -> None:
    port = spid_port("rot1prog", start_az_deg=200.0)
    client = clients(port.path, 1200)
    client.write(b"\x00\xffW")  # junk and a stray start byte
    client.write(STATUS[:6])
    port.wait_until(lambda device, _now: len(device.log), lambda n: n >= 1)
    client.write(STATUS[6:])
    assert client.read(5) == bytes.fromhex("57 05 06 00 20")
    assert [(f.data, f.outcome) for f in port.log()] == [
        (b"\x00\xff", "invalid"),
        (b"W", "invalid"),  # its 13-byte window ended on 0x1F, not 0x20: resynchronised
        (STATUS, "status"),
    ]


def test_md01_set_answer_and_debug_lines_through_the_pty(
    spid_port: SpidPortFactory, clients: Callable[..., serial.Serial]
) -> None:
    port = spid_port("md01", debug_lines="before", resolution_ppd=10)
    client = clients(port.path, 115200)
    client.write(bytes.fromhex("57 34 38 33 35 0A 33 36 34 35 0A 2F 20"))  # 123.5 / 4.5
    line = client.read_until(b"\r\n")
    assert line.endswith(b": cmd set\r\n") and line.split(b":")[0].isdigit()
    assert client.read(12) == bytes.fromhex("57 03 06 00 00 0A 03 06 00 00 0A 20")
    port.call(lambda device, now: device.emit_debug_line(now, "on request"))
    assert client.read_until(b"\r\n").endswith(b": on request\r\n")


def test_silent_controller_obeys_but_never_answers(
    spid_port: SpidPortFactory, clients: Callable[..., serial.Serial]
) -> None:
    port = spid_port(az_speed_deg_s=200.0)
    client = clients(port.path)
    client.timeout = 0.5
    port.set_silent(True)
    client.write(bytes.fromhex("57 30 37 34 30 02 30 37 32 30 02 2F 20") + STATUS)  # az 10
    port.wait_for_frame(STATUS, "status")
    assert port.wait_for(lambda s: s.az_deg == 10.0).az_deg == 10.0
    assert client.read(12) == b""
    port.set_silent(False)
    client.timeout = 10  # (the answer ends the read)
    client.write(STATUS)
    assert client.read(12)[1:5] == bytes([3, 7, 0, 0])


def test_injected_noise_towards_the_device_costs_no_frame(
    spid_port: SpidPortFactory, clients: Callable[..., serial.Serial]
) -> None:
    port = spid_port(start_az_deg=-5.0)
    client = clients(port.path)
    port.inject(b"W\x00", to="device")  # a stray start byte before the client's frame
    client.write(STATUS)
    assert client.read(12)[1:5] == bytes([3, 5, 5, 0])
    assert [f.outcome for f in port.log()] == ["invalid", "status"]


def test_unplug_keeps_the_rotor_turning_and_replug_powers_it_off_and_on(
    spid_port: SpidPortFactory, clients: Callable[..., serial.Serial]
) -> None:
    port = spid_port(az_speed_deg_s=20.0)
    assert port.link is not None
    client = clients(port.link)
    client.write(bytes.fromhex("57 30 39 32 30 02 30 37 32 30 02 2F 20"))  # az 100
    port.wait_for(lambda s: s.is_moving)
    port.unplug()
    assert not os.path.lexists(port.link)
    with pytest.raises(serial.SerialException):
        client.read(1)
    port.wait_for(lambda s: s.az_deg > 1.0)  # the rotor did not care about the plug
    port.replug()  # power_cycle: the motors stop
    stopped = port.wait_for(lambda s: not s.is_moving)
    assert 0.0 < stopped.az_deg < 100.0
    second = clients(port.link)
    second.write(STATUS)
    az_deg = (lambda r: 100 * r[1] + 10 * r[2] + r[3] + r[4] / 10 - 360)(second.read(12))
    assert abs(az_deg - stopped.az_deg) <= 0.5
