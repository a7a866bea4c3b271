"""The RT-21 emulator, sans-IO: what each command answers on the wire (tenths, the paddings,
whole degrees for ``AI1;``), the CR that runs a heading and the ``;`` that closes it without
stopping, ``;`` alone to stop, re-targeting while turning, and silence for what it does not take."""

from __future__ import annotations

import pytest

from bridge import emulators
from bridge.emulators.rt21 import Outcome, Rt21
from tests.emulators.conftest import ask


def test_the_bearing_in_tenths_and_its_paddings() -> None:
    assert ask(Rt21(start_az_deg=20.0), b"BI1;", 0) == b"20.0;"
    assert ask(Rt21(start_az_deg=5.34), b"BI1;", 0) == b" 5.3;"
    assert ask(Rt21(start_az_deg=359.96), b"BI1;", 0) == b"360.0;"
    assert ask(Rt21(start_az_deg=5.3, reply_padding="none"), b"BI1;", 0) == b"5.3;"
    assert ask(Rt21(start_az_deg=5.3, reply_padding="zero"), b"BI1;", 0) == b"005.3;"
    assert ask(Rt21(start_az_deg=123.6), b"AI1;", 0) == b";124"  # the DCU-1's whole degrees


def test_a_heading_runs_at_its_cr_and_its_semicolon_is_no_stop() -> None:
    device = Rt21(az_speed_deg_s=10.0)
    assert ask(device, b"AP1100.5\r", 0.0) == b""
    assert device.state(0.1).is_moving and device.state(0.1).target_az_deg == 100.5
    assert ask(device, b";", 1.0) == b""  # closes the command
    assert device.state(5.0).is_moving and device.state(5.0).az_deg == pytest.approx(50.0)
    assert [(f.data, f.outcome) for f in device.log] == [(b"AP1100.5\r;", "move")]
    assert device.state(20.0).az_deg == 100.5 and not device.state(20.0).is_moving


def test_a_semicolon_alone_and_as1_stop() -> None:
    device = Rt21(az_speed_deg_s=10.0)
    ask(device, b"AP1200.0\r;", 0.0)
    ask(device, b";", 3.0)
    assert not device.state(4.0).is_moving and device.state(4.0).az_deg == pytest.approx(30.0)
    ask(device, b"AP1200.0\r;", 4.0)
    ask(device, b"AS1;", 5.0)
    assert not device.state(6.0).is_moving and device.state(6.0).az_deg == pytest.approx(40.0)
    assert [f.outcome for f in device.frames(Outcome.STOP)] == ["stop", "stop"]


def test_the_dcu1_two_step_form() -> None:
    device = Rt21(az_speed_deg_s=100.0)
    ask(device, b"AP1090;", 0.0)
    assert not device.state(1.0).is_moving and device.state(1.0).stored_target_az_deg == 90.0
    ask(device, b"AM1;", 1.0)
    assert device.state(3.0).az_deg == 90.0


def test_a_new_heading_while_turning_retargets_at_once() -> None:
    device = Rt21(az_speed_deg_s=10.0)
    ask(device, b"AP1200.0\r;", 0.0)
    ask(device, b"AP1020.0\r;", 5.0)  # at 50: turns back
    assert device.state(8.0).az_deg == 20.0 and not device.state(8.0).is_moving


def test_what_it_does_not_take_is_dropped_silently_and_moves_nothing() -> None:
    device = Rt21(start_az_deg=77.0)
    for command in (b"AP1400.0\r;", b"AP112.5\r;", b"XY1;", b"AP1abc;", b"AM1;", b"Q" * 20):
        assert ask(device, command, 0) == b"", command
    assert not device.state(1.0).is_moving and device.state(1.0).az_deg == 77.0
    assert len(device.frames(Outcome.REFUSED)) == 6


def test_power_cycle_forgets_the_half_command_and_the_stored_heading() -> None:
    device = Rt21(az_speed_deg_s=10.0)
    ask(device, b"AP1090;", 0.0)
    ask(device, b"AP1300", 0.5)
    device.power_cycle(1.0)
    assert ask(device, b"AM1;", 1.0) == b"" and not device.state(2.0).is_moving
    assert ask(device, b"BI1;", 2.0) == b" 0.0;"


def test_the_registry_builds_it() -> None:
    device = emulators.create("rt21", now=0.0, start_az_deg=42.0)
    assert isinstance(device, Rt21) and device.state(0.0).az_deg == 42.0


def test_a_heading_run_by_its_cr_without_a_semicolon_leaves_the_next_command_whole() -> None:
    device = Rt21(az_speed_deg_s=10.0, start_az_deg=10.0)
    assert ask(device, b"AP1100\rBI1;", 0.0) == b"10.0;"  # the Rotor-EZ's form, then a query
    assert [(f.data, f.outcome) for f in device.log] == [(b"AP1100\r", "move"), (b"BI1;", "query")]
    assert device.state(1.0).is_moving and device.state(1.0).target_az_deg == 100.0
