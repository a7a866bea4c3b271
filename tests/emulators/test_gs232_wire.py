"""The GS-232A/B emulator, sans-IO: what each command answers on the wire, the 450-degree range,
K3NG's blank lines, ``?>`` for anything it does not take, speeds and stops."""

from __future__ import annotations

import pytest

from bridge import emulators
from bridge.emulators.gs232 import Gs232, Outcome
from tests.emulators.conftest import ask


def test_the_replies_of_both_forms() -> None:
    a = Gs232("gs232a", start_az_deg=12.4, start_el_deg=34.6)
    b = Gs232("gs232b", start_az_deg=12.4, start_el_deg=34.6)
    assert ask(a, b"C\r", 0) == b"+0012\r\n"
    assert ask(a, b"C2\r", 0) == b"+0012+0035\r\n"
    assert ask(a, b"B\r", 0) == b"+0035\r\n"
    assert ask(b, b"C\r", 0) == b"AZ=012\r\n"
    assert ask(b, b"C2\r", 0) == b"AZ=012  EL=035\r\n"
    assert ask(b, b"B\r", 0) == b"EL=035\r\n"
    one_space = Gs232("gs232b", spacing=1, line_ending=b"\r")
    assert ask(one_space, b"C2\r", 0) == b"AZ=000 EL=000\r"


def test_commands_without_data_answer_a_cr_and_unknown_ones_a_refusal() -> None:
    device = Gs232("gs232b")
    for command in (b"S\r", b"A\r", b"E\r", b"X2\r", b"P45\r", b"M010\r", b"W010 010\r"):
        assert ask(device, command, 0) == b"\r", command
    for command in (b"Q\r", b"M10\r", b"W010\r", b"M1234\r", b"X5\r"):
        assert ask(device, command, 0) == b"?>\r\n", command
    assert [f.outcome for f in device.frames(Outcome.REFUSED)] == ["refused"] * 5


def test_a_move_runs_at_the_rotor_speed_and_stop_halts_it() -> None:
    device = Gs232("gs232b", az_speed_deg_s=10.0, el_speed_deg_s=5.0)
    ask(device, b"W100 050\r", 0.0)
    state = device.state(5.0)
    assert (state.az_deg, state.el_deg, state.is_moving) == (50.0, 25.0, True)
    ask(device, b"A\r", 5.0)  # azimuth only
    state = device.state(6.0)
    assert (state.az_deg, state.el_deg, state.is_moving) == (50.0, 30.0, True)
    ask(device, b"S\r", 6.0)
    assert not device.state(20.0).is_moving and device.state(20.0).el_deg == 30.0


def test_a_new_bearing_while_turning_retargets_at_once() -> None:
    device = Gs232("gs232b-az", az_speed_deg_s=10.0)
    ask(device, b"M200\r", 0.0)
    ask(device, b"M020\r", 5.0)  # at 50: turns back
    assert device.state(8.0).az_deg == 20.0 and not device.state(8.0).is_moving


def test_speed_levels() -> None:
    device = Gs232("gs232b-az", az_speed_deg_s=8.0)
    ask(device, b"X1\r", 0.0)
    t = device.state(0.0).time_s
    device.receive(b"M100\r", t)
    assert device.state(t + 10.0).az_deg == pytest.approx(20.0)  # a quarter of full speed
    device.receive(b"X4\r", t + 10.0)
    assert device.state(t + 12.0).az_deg == pytest.approx(36.0)


def test_the_450_degree_range() -> None:
    p36, p45 = Gs232("gs232b-az"), Gs232("gs232b-az-450", az_speed_deg_s=100.0)
    assert ask(p36, b"M400\r", 0) == b"?>\r\n" and not p36.state(1).is_moving
    assert ask(p45, b"M400\r", 0) == b"\r"
    assert ask(p45, b"C\r", 10) == b"AZ=400\r\n"
    assert ask(p45, b"M451\r", 10) == b"?>\r\n"
    assert ask(p36, b"P45\r", 1) == b"\r" and ask(p36, b"M400\r", 1) == b"\r"


def test_k3ng_blank_lines_after_w_only() -> None:
    device = Gs232("gs232b", blank_lines_after_w=2)
    assert ask(device, b"W010 010\r", 0) == b"\r\r\n\r\n"
    assert ask(device, b"S\r", 1) == b"\r"


def test_an_azimuth_box_has_no_elevation() -> None:
    device = Gs232("gs232a-az", az_speed_deg_s=100.0)
    assert ask(device, b"W010 045\r", 0) == b"\r"
    assert ask(device, b"C2\r", 5) == b"+0010+0000\r\n"
    assert ask(device, b"U\r", 5) == b"?>\r\n"
    with pytest.raises(ValueError, match="no elevation"):
        Gs232("gs232b-az", start_el_deg=10)


def test_power_cycle_forgets_range_and_speed() -> None:
    device = Gs232("gs232b-az", az_speed_deg_s=8.0)
    ask(device, b"P45\r", 0)
    ask(device, b"X1\r", 0)
    ask(device, b"M300\r", 0)
    device.power_cycle(1.0)
    state = device.state(2.0)
    assert (state.az_range_deg, state.speed_level, state.is_moving) == (360.0, 4, False)


def test_every_gs232_model_is_in_the_registry() -> None:
    names = {n for n in emulators.EMULATORS if n.startswith("gs232")}
    assert names == {
        "gs232a",
        "gs232b",
        "gs232a-450",
        "gs232b-450",
        "gs232a-az",
        "gs232b-az",
        "gs232a-az-450",
        "gs232b-az-450",
    }
    assert isinstance(emulators.create("gs232a-az-450", now=0.0), Gs232)
