"""EmulatedPort on a real pseudo-terminal, driven by real pyserial clients.

Waits are conditions with deadlines (port.wait_for / serial read timeouts), never bare sleeps,
except the one idle-cost measurement, which needs a stretch of idle time to measure.
"""

from __future__ import annotations

import os
import resource
import select
import time
from collections.abc import Callable
from pathlib import Path

import pytest
import serial

from tests.emulators.conftest import PortFactory
from tests.support.waiting import slow

BANNER = b"C2000 IDIOM V1.4S "


def test_bearing_query_round_trip_through_the_link(
    make_port: PortFactory, clients: Callable[[str], serial.Serial]
) -> None:
    port = make_port(start_az_deg=123)
    assert port.link is not None and os.path.realpath(port.link) == port.path
    client = clients(port.link)
    client.write(b"AI1;")
    assert client.read(4) == b";123"
    assert port.wait_for_frame(b"AI1;", "query").outcome == "query"


def test_reply_takes_line_time_to_arrive(
    make_port: PortFactory, clients: Callable[[str], serial.Serial]
) -> None:
    port = make_port()
    client = clients(port.path)
    started = time.monotonic()
    client.write(b";")  # idle: the 18-byte banner
    assert client.read(18) == BANNER
    assert time.monotonic() - started >= 18 * 10 / 4800  # 37.5 ms at 4800 baud


def test_first_client_after_power_on_sees_the_e0_byte(
    make_port: PortFactory, clients: Callable[[str], serial.Serial]
) -> None:
    port = make_port(power_on_junk=True, start_az_deg=10)
    client = clients(port.link)
    assert client.read(1) == b"\xe0"
    client.write(b"AI1;")
    assert client.read(4) == b";010"
    assert port.flush_count >= 1


def test_serial_command_turns_the_emulated_rotor(
    make_port: PortFactory, clients: Callable[[str], serial.Serial]
) -> None:
    port = make_port(speed_deg_s=300.0, brake_delay_s=0.0)
    client = clients(port.link)
    client.write(b"AP1090\r")
    state = port.wait_for(lambda s: not s.is_moving and s.az_deg == 90.0, timeout_s=5.0)
    assert state.az_deg == 90.0
    client.write(b"AI1;")
    assert client.read(4) == b";090"


def test_garbage_from_the_host_gets_banners(
    make_port: PortFactory, clients: Callable[[str], serial.Serial]
) -> None:
    port = make_port()
    client = clients(port.path)
    client.write(b"\xe0x")
    assert client.read(36) == BANNER * 2
    assert [f.outcome for f in port.log()] == ["invalid", "invalid"]


def test_inject_puts_noise_on_the_line_in_either_direction(
    make_port: PortFactory, clients: Callable[[str], serial.Serial]
) -> None:
    port = make_port(start_az_deg=77)
    client = clients(port.path)
    port.inject(b"\x00\xff", to="host")
    assert client.read(2) == b"\x00\xff"
    port.inject(b"A", to="device")  # a stray 'A' corrupts the next command
    client.write(b"AI1;")
    assert client.read(18) == BANNER
    assert port.log()[-1].data == b"AAI1;"
    with pytest.raises(ValueError):
        port.inject(b"x", to="sideways")  # type: ignore[arg-type]


def test_silent_controller_obeys_but_never_answers(
    make_port: PortFactory, clients: Callable[[str], serial.Serial]
) -> None:
    port = make_port(start_az_deg=5)
    client = clients(port.path)
    client.timeout = 0.3
    port.set_silent(True)
    client.write(b"AI1;")
    port.wait_for_frame(b"AI1;", "query")
    assert client.read(4) == b""
    port.set_silent(False)
    client.timeout = 10  # (the answer ends the read: 0.3 s was too short once, in a suite run)
    client.write(b"AI1;")
    assert client.read(4) == b";005"


def test_front_panel_brake_stops_a_serial_rotation(
    make_port: PortFactory, clients: Callable[[str], serial.Serial]
) -> None:
    port = make_port(speed_deg_s=1.0)
    client = clients(port.path)
    client.write(b"AP1300\r")
    port.wait_for(lambda s: s.is_moving)
    assert port.press_brake()
    state = port.state()
    assert not state.is_moving and state.in_brake_delay and state.az_deg < 300


def test_unplug_fails_the_client_and_removes_the_link(
    make_port: PortFactory, clients: Callable[[str], serial.Serial]
) -> None:
    port = make_port(speed_deg_s=200.0)
    assert port.link is not None
    client = clients(port.link)
    client.write(b"AP1100\r")
    port.wait_for(lambda s: s.is_moving or s.az_deg == 100.0)
    port.unplug()
    assert not port.is_plugged and port.path == ""
    assert not os.path.lexists(port.link)
    with pytest.raises(serial.SerialException):
        client.read(1)
    with pytest.raises(serial.SerialException):
        client.write(b"AI1;")
    with pytest.raises(serial.SerialException):
        serial.Serial(port.link, 4800, timeout=0.1)  # refused at once: not a deadline
    # the rotor did not care about the USB plug
    assert port.wait_for(lambda s: s.az_deg == 100.0).az_deg == 100.0


def test_replug_repoints_the_link_and_powers_up_with_junk(
    make_port: PortFactory, clients: Callable[[str], serial.Serial]
) -> None:
    port = make_port(
        start_az_deg=0,
        speed_deg_s=1000.0,
        brake_delay_s=0.0,
        jumpers={"jam": True},
        power_on_junk=True,
    )
    assert port.link is not None
    first = clients(port.link)
    assert first.read(1) == b"\xe0"
    first.write(b"AP1150\rj")
    port.wait_for(lambda s: s.az_deg == 150.0 and s.options["jam"] is False)
    port.unplug()
    port.replug()
    assert os.path.realpath(port.link) == port.path
    second = clients(port.link)
    assert second.read(1) == b"\xe0"  # what a power-up looks like on the line
    second.write(b"AI1;")
    assert second.read(4) == b";150"  # mechanical position kept
    assert port.state().options["jam"] is True  # options back to the jumpers


def test_replug_without_power_cycle_is_just_a_cable(
    make_port: PortFactory, clients: Callable[[str], serial.Serial]
) -> None:
    port = make_port(start_az_deg=33, power_on_junk=True)
    assert port.link is not None
    client = clients(port.link)
    assert client.read(1) == b"\xe0"
    client.write(b"o")
    port.wait_for(lambda s: s.options["overshoot"] is False)
    client.close()
    port.unplug()
    port.replug(power_cycle=False)
    client = clients(port.link)
    client.timeout = 10  # (the answer ends the read)
    client.write(b"AI1;")
    assert client.read(4) == b";033"
    client.timeout = 0.3
    assert client.read(1) == b""  # (and nothing after it)
    assert port.state().options["overshoot"] is False


def test_power_cycle_while_connected_sends_e0_to_the_open_port(
    make_port: PortFactory, clients: Callable[[str], serial.Serial]
) -> None:
    port = make_port(power_on_junk=True)
    client = clients(port.path)
    assert client.read(1) == b"\xe0"
    port.power_cycle()
    assert client.read(1) == b"\xe0"


def test_link_replaces_whatever_was_at_that_path(tmp_path: Path, make_port: PortFactory) -> None:
    link = tmp_path / "ttyROTOR"
    link.symlink_to("/dev/null")
    port = make_port(link=str(link))
    assert os.readlink(link) == port.path


def test_close_removes_the_link_and_is_idempotent(make_port: PortFactory) -> None:
    port = make_port()
    assert port.link is not None and os.path.lexists(port.link)
    port.close()
    port.close()
    assert not os.path.lexists(port.link)
    with pytest.raises(RuntimeError):
        port.unplug()


def test_client_closing_does_not_disturb_the_port(
    make_port: PortFactory, clients: Callable[[str], serial.Serial]
) -> None:
    port = make_port(start_az_deg=222)
    for _ in range(3):
        client = clients(port.path)
        client.write(b"AI1;")
        assert client.read(4) == b";222"
        client.close()
    assert len(port.frames("query")) == 3


def test_idle_port_sleeps(make_port: PortFactory, clients: Callable[[str], serial.Serial]) -> None:
    port = make_port(speed_deg_s=1000.0, brake_delay_s=0.0)
    client = clients(port.path)
    client.write(b"AP1010\rAI1;")
    assert len(client.read(4)) == 4
    port.wait_for(lambda s: not s.is_moving)
    before = port.loop_iterations
    time.sleep(0.3)  # measuring idle cost, not waiting for anything
    assert port.loop_iterations - before <= 2


def test_a_port_whose_descriptors_pass_1023_still_answers(make_port: PortFactory) -> None:
    """select() refuses a descriptor above 1023: the device thread ended at its first wait and
    the controller never answered (a test worker late in a busy run holds that many: a bridge
    there never came online). However high its descriptors, the port answers."""
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if soft < 1100:
        resource.setrlimit(resource.RLIMIT_NOFILE, (min(hard, 2048), hard))
    fillers: list[int] = []
    try:
        while not fillers or fillers[-1] < 1030:  # the port's descriptors come after these
            fillers.append(os.open(os.devnull, os.O_RDONLY))
        port = make_port(start_az_deg=123)
    finally:
        for fd in fillers:
            os.close(fd)
        resource.setrlimit(resource.RLIMIT_NOFILE, (soft, hard))
    assert port.link is not None
    client = os.open(port.link, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
    try:
        os.write(client, b"AI1;")
        got, deadline = b"", time.monotonic() + slow(5)
        waiting = select.poll()
        waiting.register(client, select.POLLIN)
        while len(got) < 4 and time.monotonic() < deadline:
            if waiting.poll(100):
                got += os.read(client, 16)
        assert got == b";123"
    finally:
        os.close(client)
