"""The Prosistel emulator, sans-IO: what each frame answers on the wire (whole degrees on a D,
tenths on the Combi-Track, R while running and B braked), the stops (hard at once, soft with the
PWM ramp running on), the errors for a unit the box has not got and a command it cannot carry
out, the position sent unasked until ``S``, and frames cut short by a new STX."""

from __future__ import annotations

import pytest

from bridge import emulators
from bridge.emulators.prosistel import Outcome, Prosistel
from tests.emulators.conftest import ask


def test_positions_in_whole_degrees_and_in_tenths() -> None:
    assert ask(Prosistel(start_az_deg=290.4), b"\x02A?\r", 0) == b"\x02A,?,290,B\r"
    assert ask(Prosistel(start_az_deg=7.0), b"\x02A?\r", 0) == b"\x02A,?,007,B\r"
    combi = Prosistel("prosistel-combi", start_az_deg=100.0, start_el_deg=90.0)
    assert ask(combi, b"\x02A?\r\x02B?\r", 0) == b"\x02A,?,1000,B\r\x02B,?,0900,B\r"
    assert ask(Prosistel("prosistel-el", start_el_deg=45.0), b"\x02E?\r", 0) == (b"\x02E,?,045,B\r")


def test_a_d_on_an_elevation_rotor_set_up_as_an_azimuth_box_answers_as_unit_a() -> None:
    """Hamlib's 1704 (D elevation CBOX az): the elevation rotor is unit A, 0..90; unit E is
    not there."""
    device = Prosistel("prosistel-el-a", start_el_deg=45.0, el_speed_deg_s=5.0)
    assert ask(device, b"\x02A?\r", 0) == b"\x02A,?,045,B\r"
    assert ask(device, b"\x02E?\r", 0) == b"\x02E,?,E,00003\r"  # no unit E
    assert ask(device, b"\x02AS\r", 0) == b"\x02A,S,B\r"
    assert ask(device, b"\x02AG91\r", 0) == b"\x02A,G,E,00001\r"  # above an elevation's 90
    assert ask(device, b"\x02AG90\r", 0.0) == b"\x02A,G,R\r"
    running = ask(device, b"\x02A?\r", 2.0)
    assert running.startswith(b"\x02A,?,0") and running.endswith(b",R\r")  # on its way up
    assert ask(device, b"\x02AG997\r", 2.0) == b"\x02A,G,B\r"  # Hamlib's stop
    state = device.state(5.0)
    assert state.el_deg is not None and 45.0 < state.el_deg < 90.0 and not state.is_moving
    assert abs(int(running[5:8]) - state.el_deg) <= 1 and state.az_deg == 0.0
    assert [f.outcome for f in device.log] == [
        "query",
        "refused",
        "output off",
        "refused",
        "move",
        "query",
        "stop",
    ]
    with pytest.raises(ValueError, match="no rotor"):
        Prosistel("prosistel-el-a", start_az_deg=10.0)


def test_a_bearing_runs_at_once_and_reads_r_while_running() -> None:
    device = Prosistel(az_speed_deg_s=10.0)
    assert ask(device, b"\x02AG100\r", 0.0) == b"\x02A,G,R\r"
    assert ask(device, b"\x02A?\r", 5.0) == b"\x02A,?,050,R\r"
    assert ask(device, b"\x02AG020\r", 5.0) == b"\x02A,G,R\r"  # leading zeros, while turning
    assert ask(device, b"\x02A?\r", 10.0) == b"\x02A,?,020,B\r"
    assert [f.outcome for f in device.log] == ["move", "query", "move", "query"]


def test_the_hard_stop_stops_at_once_and_the_soft_one_runs_the_ramp_out() -> None:
    device = Prosistel(az_speed_deg_s=10.0)
    ask(device, b"\x02AG300\r", 0.0)
    assert ask(device, b"\x02AG999\r", 3.0) == b"\x02A,G,B\r"
    assert device.state(4.0).az_deg == pytest.approx(30.0)
    ramped = Prosistel(az_speed_deg_s=10.0, soft_stop_s=1.5)
    ask(ramped, b"\x02AG300\r", 0.0)
    assert ask(ramped, b"\x02AG997\r", 3.0) == b"\x02A,G,R\r"  # still running
    assert ramped.state(10.0).az_deg == pytest.approx(45.0) and not ramped.state(10).is_moving
    combi = Prosistel("prosistel-combi", az_speed_deg_s=10.0, el_speed_deg_s=5.0)
    ask(combi, b"\x02AG3000\r\x02BG900\r", 0.0)
    ask(combi, b"\x02AG9999\r\x02BG9777\r", 2.0)  # Combi-Track: hard and soft, per unit
    assert (combi.state(5.0).az_deg, combi.state(5.0).el_deg) == pytest.approx((20.0, 10.0))
    assert [f.outcome for f in combi.frames(Outcome.STOP)] == ["stop", "stop"]


def test_errors_for_a_missing_unit_and_what_the_box_cannot_do() -> None:
    device = Prosistel()
    assert ask(device, b"\x02B?\r", 0) == b"\x02B,?,E,00003\r"  # a D has unit A only
    assert ask(device, b"\x02AG361\r", 0) == b"\x02A,G,E,00001\r"
    assert ask(device, b"\x02AG99x\r", 0) == b"\x02A,G,E,00001\r"
    assert ask(device, b"\x02AX\r", 0) == b"\x02A,X,E,00001\r"
    combi = Prosistel("prosistel-combi")
    assert ask(combi, b"\x02BG901\r", 0) == b"\x02B,G,E,00001\r"  # above 90.0 degrees
    assert ask(combi, b"\x02BG999\r", 0) == b"\x02B,G,E,00001\r"  # no stop here: 99.9
    assert device.frames(Outcome.MOVE) == [] and combi.frames(Outcome.MOVE) == []
    assert not device.state(1).is_moving and not combi.state(1).is_moving


def test_a_streaming_box_sends_its_position_unasked_until_s() -> None:
    device = Prosistel("prosistel-combi", start_az_deg=12.3, streaming=True)
    assert device.next_wakeup(0.0) == pytest.approx(0.25)
    out = device.due_output(0.6)
    line = b"\x02A,?,0123,B\r\x02B,?,0000,B\r"
    assert out == line * 2
    assert ask(device, b"\x02AS\r", 0.6) == b"\x02A,S,B\r"
    assert device.due_output(1.3) == b"\x02B,?,0000,B\r" * 3  # unit B still streams
    ask(device, b"\x02BS\r", 1.3)
    assert device.due_output(5.0) == b"" and device.next_wakeup(5.0) is None
    device.power_cycle(6.0)  # streams again from power-on
    assert device.state(6.0).streaming == ("A", "B")
    assert device.due_output(6.3) == line


def test_a_new_stx_starts_the_frame_afresh_and_bytes_outside_one_are_ignored() -> None:
    device = Prosistel(az_speed_deg_s=10.0)
    assert ask(device, b"junk\r\x02AG1\x02A?\r", 0) == b"\x02A,?,000,B\r"
    assert ask(device, b"\x02" + b"9" * 20 + b"\r", 0) == b""  # too long: dropped
    assert [f.outcome for f in device.log] == ["query", "refused"]


def test_the_registry_builds_each_model() -> None:
    for model in ("prosistel", "prosistel-el", "prosistel-el-a", "prosistel-combi"):
        device = emulators.create(model, now=0.0)
        assert isinstance(device, Prosistel) and device.spec.name == model
    with pytest.raises(ValueError, match="no rotor"):
        Prosistel("prosistel", start_el_deg=10.0)
