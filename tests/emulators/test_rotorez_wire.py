"""Rotor-EZ family on the wire: bytes in -> bytes out, with a fake clock (plain floats)."""

from __future__ import annotations

import re
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bridge.emulators.rotorez import DEFAULT_JUMPERS, Outcome, RotorEZ

BANNER = b"C2000 IDIOM V1.4S "
BYTE_S = 10 / 4800  # 8N1 at 4800 baud
PROCESSING_S = 0.002


def make(model: str = "rotorez", **kwargs: Any) -> RotorEZ:
    options: dict[str, Any] = {"power_on_junk": False, "jitter_deg": 0}
    options.update(kwargs)
    return RotorEZ(model, **options)


def exchange(device: RotorEZ, data: bytes, at: float) -> bytes:
    """Send `data` at `at` and collect everything that arrives within the next 100 ms."""
    device.receive(data, at)
    return device.due_output(at + 0.1)


# -- queries --


@pytest.mark.parametrize("query", [b"AI1;", b"AI1\r"])
def test_bearing_query_answers_four_bytes_without_terminator(query: bytes) -> None:
    device = make(start_az_deg=123)
    assert exchange(device, query, 1.0) == b";123"
    assert [(f.data, f.outcome) for f in device.log] == [(query, "query")]


@pytest.mark.parametrize(
    ("az_deg", "reply"),
    [
        (0.0, b";000"),
        (9.0, b";009"),
        (0.5, b";001"),
        (359.4, b";359"),
        (359.6, b";000"),
        (360.0, b";000"),
    ],
)
def test_reading_is_rounded_half_up_and_360_reads_000(az_deg: float, reply: bytes) -> None:
    assert exchange(make(start_az_deg=az_deg), b"AI1;", 1.0) == reply


def test_reply_is_paced_at_the_line_rate() -> None:
    device = make(start_az_deg=123)
    device.receive(b"AI1;", 10.0)
    first_due = 10.0 + PROCESSING_S + BYTE_S
    assert device.next_wakeup(10.0) == pytest.approx(first_due)
    assert device.due_output(first_due - 1e-6) == b""
    assert device.due_output(first_due + 1e-6) == b";"
    last_due = 10.0 + PROCESSING_S + 4 * BYTE_S  # ~10.3 ms after the command
    assert device.due_output(last_due - 1e-6) == b"12"
    assert device.due_output(last_due + 1e-6) == b"3"
    assert device.next_wakeup(last_due + 1e-6) is None


def test_back_to_back_replies_queue_behind_each_other() -> None:
    device = make(start_az_deg=7)
    device.receive(b"AI1;AI1;", 0.0)
    end_s = PROCESSING_S + 8 * BYTE_S
    assert device.due_output(end_s - 1e-6) == b";007;00"
    assert device.due_output(end_s + 1e-6) == b"7"


def test_slower_baud_means_slower_replies() -> None:
    device = make(baud=1200, start_az_deg=5)
    device.receive(b"AI1;", 0.0)
    assert device.due_output(PROCESSING_S + 3 * (10 / 1200) + 1e-6) == b";00"


def test_frames_may_arrive_in_pieces() -> None:
    device = make(start_az_deg=42)
    out = bytearray()
    for i, value in enumerate(b"AI1;AI1;"):
        device.receive(bytes([value]), float(i))
        out += device.due_output(float(i) + 0.5)
    assert bytes(out) == b";042;042"


# -- the banner, the version, invalid input --


def test_semicolon_while_idle_is_invalid_and_prints_the_banner() -> None:
    device = make()
    out = exchange(device, b";", 1.0)
    assert out == BANNER and len(out) == 18
    assert device.frames(Outcome.INVALID)[0].data == b";"


def test_banner_carries_the_configured_firmware_version() -> None:
    assert exchange(make(version="2.0X"), b";", 0.0) == b"C2000 IDIOM V2.0X "


@pytest.mark.parametrize("model", ["rotorez", "rotorcard"])
def test_version_letter_reports_idiom_version_ending_in_a_space(model: str) -> None:
    device = make(model)
    out = exchange(device, b"V", 0.0)
    assert b"IDIOM V1.4S" in out and out.endswith(b" ")
    assert device.log[-1].outcome == "version"


@pytest.mark.parametrize(
    "frame",
    [
        b"AP19;",
        b"AP1361;",
        b"AP1abc;",
        b"AP1-10;",
        b"AP1 90;",
        b"AM2;",
        b"AI1",
        b"A;",
        b"AX;",
        b"AS1;",
        b"AM1\r",
        b"X",
        b"\xe0",
        b"v",
        b"K",
    ],
)
def test_invalid_commands_print_the_banner_and_move_nothing(frame: bytes) -> None:
    device = make(start_az_deg=100)
    device.receive(b"AP1200;", 0.0)
    out = exchange(device, frame + (b"\r" if frame == b"AI1" else b""), 1.0)
    if frame == b"AI1":  # AI1<CR> is a valid query
        assert out == b";100"
        return
    assert out == BANNER
    assert device.log[-1] == device.frames(Outcome.INVALID)[-1]
    state = device.state(2.0)
    assert not state.is_moving and state.az_deg == 100 and state.stored_target_az_deg == 200


def test_overlong_frame_is_invalid_after_its_seventh_byte() -> None:
    device = make()
    assert exchange(device, b"AP10900", 0.0) == BANNER
    assert device.log[-1].data == b"AP10900"
    # the parser is back in step for the next command
    assert exchange(device, b"AI1;", 1.0) == b";000"


def test_line_endings_between_commands_are_ignored() -> None:
    device = make(speed_deg_s=10.0)
    assert exchange(device, b"AP1080\r\n\r\n", 0.0) == b""
    assert [f.outcome for f in device.log] == ["executed"]


def test_each_stray_byte_is_its_own_invalid_command() -> None:
    device = make()
    device.receive(b"xyz", 0.0)
    # 54 bytes at 4800 baud take ~113 ms: after 100 ms only the first 47 have arrived
    arrived = int((0.1 - PROCESSING_S) / BYTE_S)
    assert arrived == 47
    assert device.due_output(0.1) == (BANNER * 3)[:arrived]
    assert device.due_output(0.2) == (BANNER * 3)[arrived:]


def test_garbage_then_a_clean_query_still_gets_its_answer() -> None:
    device = make(start_az_deg=270)
    out = exchange(device, b"\xe0\x00AI1;", 0.0)
    assert out == BANNER * 2 + b";270"


_REPLY = re.compile(rb"(C2000 IDIOM V1\.4S |;\d{3})*")


@settings(max_examples=300, deadline=None)
@given(chunks=st.lists(st.binary(max_size=40), max_size=8), start=st.integers(0, 360))
def test_garbage_never_crashes_and_only_well_formed_replies_come_out(
    chunks: list[bytes], start: int
) -> None:
    device = make(start_az_deg=start, jitter_deg=1, power_on_junk=False)
    out = bytearray()
    for i, chunk in enumerate(chunks):
        device.receive(chunk, float(i))
        out += device.due_output(float(i) + 0.9)
    out += device.due_output(1e6)
    assert _REPLY.fullmatch(bytes(out))
    assert 0.0 <= device.true_az_deg(1e6) <= 360.0


# -- options --


def test_option_letters_switch_options_silently_and_at_once() -> None:
    device = make(jumpers={"endpoint": True, "jam": False})
    assert device.options == {"endpoint": True, "jam": False, "overshoot": False, "unstick": False}
    assert exchange(device, b"eJOS", 0.0) == b""
    assert device.options == {"endpoint": False, "jam": True, "overshoot": True, "unstick": True}
    assert exchange(device, b"Eos", 1.0) == b""
    assert device.options == {"endpoint": True, "jam": True, "overshoot": False, "unstick": False}
    assert [f.outcome for f in device.log] == ["option"] * 7


def test_capital_s_is_unstick_not_stop() -> None:
    device = make(speed_deg_s=1.0)
    device.receive(b"AP1100\rS", 0.0)
    assert device.options["unstick"] is True
    assert device.is_moving(5.0)


def test_power_cycle_puts_options_back_to_the_jumpers() -> None:
    device = make()
    device.receive(b"ejO", 0.0)
    device.power_cycle(1.0)
    assert device.options == dict(DEFAULT_JUMPERS)


def test_default_jumpers_have_jam_protection_on() -> None:
    assert make().options == {"endpoint": False, "jam": True, "overshoot": False, "unstick": False}


def test_unknown_jumper_is_refused() -> None:
    with pytest.raises(ValueError, match="jumpers"):
        make(jumpers={"turbo": True})


# -- RotorCard --


def test_rotorcard_has_no_option_letters() -> None:
    device = make("rotorcard")
    assert exchange(device, b"E", 0.0) == BANNER
    assert device.options == {}


def test_rotorcard_calibration_letters_are_logged_and_move_nothing() -> None:
    device = make("rotorcard", start_az_deg=30)
    assert exchange(device, b"K", 0.0) == b""
    assert device.calibrating
    assert exchange(device, b"k", 1.0) == b""
    assert not device.calibrating
    assert [f.outcome for f in device.log] == ["calibration", "calibration"]
    assert device.state(2.0).az_deg == 30 and not device.is_moving(2.0)


# -- DCU-1 --


def test_dcu1_obeys_set_and_execute_but_never_says_a_word() -> None:
    device = make("dcu1", speed_deg_s=10.0, power_on_junk=True)
    assert device.due_output(0.1) == b""  # no power-on byte either
    assert exchange(device, b"AP1100;", 0.0) == b""
    assert exchange(device, b"AM1;", 0.5) == b""
    assert device.is_moving(1.0)
    for noise in (b"AI1;", b"V", b";", b"xyz", b"E", b"AP1050\r"):
        assert exchange(device, noise, 2.0) == b""
    assert device.state(2.0).target_az_deg == 100  # AP1050<CR> is not DCU-1: no re-target
    assert exchange(device, b"AS1;", 3.0) == b""
    assert not device.is_moving(3.0)
    assert device.true_az_deg(3.0) == pytest.approx(25.0)  # executed at 0.5 s, 10 deg/s
    assert device.log[-1].outcome == "stop"
    assert [f.data for f in device.frames(Outcome.INVALID)] == [
        b"AI1;",
        b"V",
        b";",
        b"x",
        b"y",
        b"z",
        b"E",
        b"AP1050\r",
    ]


def test_dcu1_has_the_hy_gain_brake_delay() -> None:
    device = make("dcu1", speed_deg_s=100.0)
    device.receive(b"AP1010;AM1;", 0.0)  # arrives at 0.1 s
    device.receive(b"AP1020;", 5.0)
    assert device.log[-1].outcome == "ignored: brake delay"


# -- power-on junk --


def test_power_on_emits_one_e0_byte() -> None:
    device = make(power_on_junk=True, now=100.0)
    assert device.due_output(100.1) == b"\xe0"
    assert device.due_output(200.0) == b""
    device.power_cycle(300.0)
    assert device.due_output(300.1) == b"\xe0"


def test_power_cycle_drops_a_half_received_command() -> None:
    device = make(start_az_deg=50)
    device.receive(b"AI", 0.0)
    device.power_cycle(1.0)
    assert exchange(device, b"AI1;", 2.0) == b";050"
