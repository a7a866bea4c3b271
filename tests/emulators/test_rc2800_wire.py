"""The RC2800 emulator, sans-IO: the axis line each command answers (the fixed-width position
Hamlib reads, MV or ST), the axis a command selects and ``S`` stops, errors for what it does not
take, the echo and the unasked stream as options, and the count of commands that came within
200 ms of a command to the other axis."""

from __future__ import annotations

import pytest

from bridge import emulators
from bridge.emulators.rc2800 import Outcome, Rc2800
from tests.emulators.conftest import ask


def test_each_command_is_answered_by_its_axis_line() -> None:
    device = Rc2800(start_az_deg=98.1, start_el_deg=5.0, az_speed_deg_s=10.0)
    assert ask(device, b"A\r", 0.0) == b"A P=  98.1 S=9 ST\r"
    assert ask(device, b"E\r", 0.5) == b"E P=   5.0 S=9 ST\r"
    assert ask(device, b"A200\r", 1.0) == b"A P=  98.1 S=9 MV\r"  # the move begins
    assert device.state(2.0).az_deg == pytest.approx(108.1)
    assert ask(device, b"E\r", 2.0) == b"E P=   5.0 S=9 ST\r"
    assert ask(device, b"S\r", 2.5) == b"E P=   5.0 S=9 ST\r"  # stops the elevation: none
    assert device.state(3.0).is_moving
    assert ask(device, b"A\rS\r", 3.0) == b"A P= 118.1 S=9 MV\rA P= 118.1 S=9 ST\r"
    assert not device.state(4.0).is_moving and device.state(4.0).az_deg == pytest.approx(118.1)
    outcomes = [f.outcome for f in device.log]
    assert outcomes == ["query", "query", "move", "query", "stop", "query", "stop"]


def test_what_it_does_not_take_is_answered_with_an_error_and_moves_nothing() -> None:
    device = Rc2800()
    assert ask(device, b"A361\r", 0.0) == b"A ERR=2\r"
    assert ask(device, b"XYZ\r", 1.0) == b"A ERR=1\r"
    assert ask(device, b"E181\r", 2.0) == b"E ERR=2\r"
    azimuth = Rc2800("rc2800-az")
    assert ask(azimuth, b"E\r", 0.0) == b"E P=   0.0 S=9 ST\r"  # nothing on the elevation
    assert ask(azimuth, b"E10\r", 1.0) == b"E ERR=2\r"
    assert ask(azimuth, b"S\r", 2.0) == b"E ERR=2\r"
    for box in (device, azimuth):
        assert not box.state(3.0).is_moving and box.frames(Outcome.MOVE) == []
    with pytest.raises(ValueError, match="no elevation"):
        Rc2800("rc2800-az", start_el_deg=10.0)


def test_the_echo_comes_before_the_answer() -> None:
    device = Rc2800(echo=True, start_az_deg=10.0)
    assert ask(device, b"A45.5\r", 0.0) == b"A45.5\rA P=  10.0 S=9 MV\r"


def test_the_stream_comes_after_a_quiet_stretch_and_not_amid_a_conversation() -> None:
    device = Rc2800(stream_s=1.0, start_az_deg=10.0, start_el_deg=20.0)
    assert device.next_wakeup(0.0) == 1.0
    assert device.due_output(1.1) == b"A P=  10.0 S=9 ST\rE P=  20.0 S=9 ST\r"
    assert ask(device, b"A\r", 1.5) == b"A P=  10.0 S=9 ST\r"  # nothing streamed at 2.0
    assert device.due_output(2.4) == b""
    assert device.due_output(2.6).startswith(b"A P=  10.0")  # a second after the answer


def test_a_command_to_the_other_axis_within_200_ms_is_counted() -> None:
    device = Rc2800()
    ask(device, b"A\r", 0.0)
    ask(device, b"E\r", 0.1)  # too soon
    ask(device, b"E10\r", 0.15)  # the same axis: no gap needed
    ask(device, b"A\r", 0.4)
    assert device.state(1.0).too_soon == 1


def test_the_registry_and_the_command_line_offer_both_models() -> None:
    for model in ("rc2800", "rc2800-az"):
        assert isinstance(emulators.create(model, echo=True, stream_s=2.0), Rc2800)
