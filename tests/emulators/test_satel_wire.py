"""SatEL emulator on the wire: bytes in -> bytes out with a fake clock (plain floats as `now`).

Covers identification, the exact status report, line endings, pacing, line parsing (whole,
byte by byte, with junk), the clock and the ephemeris memory. Motion rules: test_satel_motion.py.
"""

from __future__ import annotations

import re
from datetime import datetime
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bridge.emulators.satel import MEMORY_LIMIT, Outcome, SatEL, StoredPoint

BYTE_S = 10 / 9600  # 8N1 at 9600 baud
PROCESSING_S = 0.002


def make(**kwargs: Any) -> SatEL:
    return SatEL(**kwargs)


def exchange(device: SatEL, data: bytes, at: float) -> bytes:
    """Send `data` at `at` and collect everything that arrives within the next second."""
    device.receive(data, at)
    return device.due_output(at + 1.0)


def report(
    *,
    motion: str = "DISABLED",
    time: str = "2001/00/00 00:00:00",
    az: str = "000",
    el: str = "000",
    stored: str = "00",
    eol: str = "\r\n",
) -> bytes:
    lines = [
        f"Motion {motion}",
        "Mode 0 - azimuth break at NORTH",
        f"Time: {time}",
        f"Azimuth = {az}     Absolute = {az}",
        f"Elevation = {el}",
        "",
        f"Number of stored positions: {stored}",
        "",
        "",
    ]
    return "".join(line + eol for line in lines).encode("ascii")


# -- identification and status --


@pytest.mark.parametrize("ending", [b"\r\n", b"\n"])
def test_question_mark_identifies_the_controller(ending: bytes) -> None:
    assert exchange(make(line_ending=ending), b"?", 1.0) == b"SatEL" + ending


def test_status_report_is_exactly_the_fact_sheet_form() -> None:
    device = make(start_az_deg=7, start_el_deg=45)
    expected = (
        b"Motion DISABLED\r\n"
        b"Mode 0 - azimuth break at NORTH\r\n"
        b"Time: 2001/00/00 00:00:07\r\n"
        b"Azimuth = 007     Absolute = 007\r\n"
        b"Elevation = 045\r\n"
        b"\r\n"
        b"Number of stored positions: 00\r\n"
        b"\r\n"
        b"\r\n"
    )
    assert exchange(device, b"z", 7.0) == expected
    assert [(f.data, f.outcome) for f in device.log] == [(b"z", "status")]


def test_hamlib_reads_the_values_at_its_fixed_offsets() -> None:
    lines = exchange(make(start_az_deg=359.6, start_el_deg=9.5), b"z", 0.0).split(b"\n")
    assert lines[3][10:13] == b"360" and lines[4][12:15] == b"010"  # rounded half up


def test_status_with_lf_only_line_ending() -> None:
    device = make(line_ending=b"\n", start_az_deg=123, start_el_deg=67)
    expected = report(az="123", el="067", time="2001/00/00 00:00:01", eol="\n")
    assert exchange(device, b"Z", 1.5) == expected


def test_motion_line_follows_g_and_s_and_the_count_follows_the_memory() -> None:
    device = make()
    device.receive(b"g2002/03/14 19:45:30 40 60\r\n", 0.0)
    assert exchange(device, b"z", 0.0) == report(motion="ENABLED", stored="01")
    assert exchange(device, b"s", 2.0) == b""
    assert exchange(device, b"z", 3.0) == report(stored="01", time="2001/00/00 00:00:03")


def test_trailing_blank_lines_are_configurable() -> None:
    out = exchange(make(trailing_blank_lines=0), b"z", 0.0)
    assert out.endswith(b"Number of stored positions: 00\r\n") and out.count(b"\n") == 7


def test_unset_clock_counts_days_in_the_day_field() -> None:
    assert b"Time: 2001/00/01 01:00:05\r\n" in exchange(make(), b"z", 90005.9)


# -- pacing --


def test_reply_is_paced_at_9600_baud() -> None:
    device = make()
    device.receive(b"?", 10.0)
    first_due = 10.0 + PROCESSING_S + BYTE_S
    assert device.next_wakeup(10.0) == pytest.approx(first_due)
    assert device.due_output(first_due - 1e-6) == b""
    assert device.due_output(first_due + 1e-6) == b"S"
    last_due = 10.0 + PROCESSING_S + 7 * BYTE_S
    assert device.due_output(last_due - 1e-6) == b"atEL\r"
    assert device.due_output(last_due + 1e-6) == b"\n"
    assert device.next_wakeup(last_due + 1e-6) is None


def test_status_report_takes_its_line_time() -> None:
    device = make()
    device.receive(b"z", 0.0)
    size = len(report())
    assert size == 166  # ~173 ms at 9600 baud
    assert len(device.due_output(PROCESSING_S + 100 * BYTE_S + 1e-6)) == 100
    assert len(device.due_output(PROCESSING_S + size * BYTE_S + 1e-6)) == size - 100


def test_replies_queue_behind_each_other() -> None:
    device = make()
    device.receive(b"??", 0.0)
    assert device.due_output(PROCESSING_S + 13 * BYTE_S + 1e-6) == b"SatEL\r\nSatEL\r"


# -- parsing: whole, byte by byte, with junk --

HAMLIB_SET = b"*zgp100 45\r\n"  # after `?` has been answered (rot_open reads that line first)


def test_hamlib_set_sequence_whole_and_bytewise_give_the_same_result() -> None:
    whole = make(az_speed_deg_s=50.0, el_speed_deg_s=50.0)
    bytewise = make(az_speed_deg_s=50.0, el_speed_deg_s=50.0)
    for device in (whole, bytewise):
        assert exchange(device, b"?", 0.0) == b"SatEL\r\n"
    whole.receive(HAMLIB_SET, 1.0)
    for value in HAMLIB_SET:
        bytewise.receive(bytes([value]), 1.0)
    for device in (whole, bytewise):
        out = device.due_output(10.0)
        assert out == report(time="2001/00/00 00:00:00") + report(
            motion="ENABLED", time="2001/00/00 00:00:02", az="100", el="045"
        )
        assert [(f.data, f.outcome) for f in device.log] == [
            (b"?", "identify"),
            (b"*", "reset"),
            (b"z", "status"),
            (b"g", "motion enabled"),
            (b"p100 45\r", "slew"),
        ]
        assert not device.misuse_frames()


def test_commands_in_either_case() -> None:
    device = make(az_speed_deg_s=1000.0, el_speed_deg_s=1000.0)
    device.receive(b"GP20 40\r", 0.0)
    state = device.state(1.0)
    assert (state.az_deg, state.el_deg) == (20.0, 40.0)
    assert device.due_output(1.0).startswith(b"Motion ENABLED\r\n")  # the after-move report
    assert exchange(device, b"T\r", 2.0) == b"2001/00/00 00:00:02\r\n"


def test_reset_drops_a_reply_not_yet_sent() -> None:
    device = make()
    assert exchange(device, b"?*", 0.0) == b""
    assert [f.outcome for f in device.log] == ["identify", "reset"]


def test_junk_bytes_are_invalid_silent_and_do_not_derail_the_next_command() -> None:
    device = make()
    assert exchange(device, b"\x00\xffQ7?", 0.0) == b"SatEL\r\n"
    assert [f.outcome for f in device.log] == ["invalid"] * 4 + ["identify"]


def test_line_endings_between_commands_are_ignored() -> None:
    device = make()
    assert exchange(device, b"\r\n\r\n?\r\n", 0.0) == b"SatEL\r\n"
    assert [f.outcome for f in device.log] == ["identify"]


@pytest.mark.parametrize(
    "line",
    [
        b"p 100 45\r",  # the manual: no space after p
        b"p100  45\r",
        b"p100\r",
        b"p100,45\r",
        b"p-10 45\r",
        b"p10.5 45\r",
        b"p1000 45\r",
        b"p100 45 \r",
        b"tnow\r",
        b"t2002/13/01 00:00:00\r",
        b"t2002/02/14 12:20\r",
        b"2002/03/14 19:45:30 40\r",
        b"2002/02/30 19:45:30 40 60\r",
        b"p" + b"1" * 100 + b"\r",
    ],
)
def test_malformed_lines_are_invalid_and_silent(line: bytes) -> None:
    device = make(az_speed_deg_s=1000.0)
    device.receive(b"g", 0.0)
    assert exchange(device, line, 0.0) == b""
    assert device.log[-1].outcome == "invalid"
    state = device.state(5.0)
    assert (state.az_deg, state.el_deg, state.stored_points) == (0.0, 0.0, ())
    assert state.controller_time == "2001/00/00 00:00:05"


def test_a_line_may_end_in_lf_alone() -> None:
    assert exchange(make(), b"t\n", 3.0) == b"2001/00/00 00:00:03\r\n"


def test_c_is_a_no_op_and_lower_case_cx_is_not_the_clear_command() -> None:
    device = make()
    device.receive(b"2002/03/14 19:45:30 40 60\r", 0.0)
    device.receive(b"cx", 1.0)
    assert len(device.state(1.0).stored_points) == 1
    device.receive(b"Cx", 2.0)  # cx is lower case only: C (no-op), then x clears
    assert device.state(2.0).stored_points == ()
    assert [f.outcome for f in device.log[1:]] == [
        Outcome.CALIBRATE,
        Outcome.IGNORED_CX,
        Outcome.CALIBRATE,
        Outcome.MEMORY_CLEARED,
    ]


_LINE = (
    rb"(SatEL|Motion (EN|DIS)ABLED|Mode 0 - azimuth break at NORTH|Time: [\d/: ]{19}"
    rb"|Azimuth = \d{3}     Absolute = \d{3}|Elevation = \d{3}|Number of stored positions: \d{2}"
    rb"|\d{4}/\d{2}/\d{2} \d{2}:\d{2}:\d{2}|)\r\n"
)
_REPLY = re.compile(rb"(" + _LINE + rb")*")


@settings(max_examples=300, deadline=None)
@given(
    chunks=st.lists(
        st.one_of(st.binary(max_size=30), st.sampled_from([b"g", b"p100 45\r\n", b"z", b"s"])),
        max_size=10,
    ),
    corrupt=st.booleans(),
)
def test_garbage_never_crashes_and_only_whole_report_lines_come_out(
    chunks: list[bytes], corrupt: bool
) -> None:
    device = make(corrupt_on_misuse=corrupt)
    out = bytearray()
    for i, chunk in enumerate(chunks):
        device.receive(chunk, 1000.0 * i)  # long enough for any slew and reply to finish
        out += device.due_output(1000.0 * i + 999.0)
    assert _REPLY.fullmatch(bytes(out)), bytes(out)
    state = device.state(1e7)
    assert 0.0 <= state.az_deg <= 360.0 and 0.0 <= state.el_deg <= 90.0


# -- clock --


def test_t_enter_prints_the_controller_time() -> None:
    assert exchange(make(), b"t\r\n", 65.0) == b"2001/00/00 00:01:05\r\n"


def test_t_with_a_time_sets_the_clock_which_then_runs_from_there() -> None:
    device = make()
    assert exchange(device, b"T2002/02/14 12:20:30\r\n", 10.0) == b""
    assert device.log[-1].outcome == "time set"
    assert exchange(device, b"t\r", 75.4) == b"2002/02/14 12:21:35\r\n"
    assert b"Time: 2002/02/14 23:59:59\r\n" in exchange(device, b"z", 10.0 + 41969)
    assert device.state(10.0 + 41970).controller_time == "2002/02/15 00:00:00"


# -- ephemeris memory --


def test_store_a_point_and_clear_the_memory() -> None:
    device = make()
    assert exchange(device, b"2002/03/14 19:45:30 40 60\r\n", 0.0) == b""
    assert device.log[-1].outcome == "point stored"
    point = StoredPoint(datetime(2002, 3, 14, 19, 45, 30), 40, 60)
    assert device.state(0.0).stored_points == (point,)
    device.receive(b"X", 1.0)
    assert device.state(1.0).stored_points == ()
    assert device.log[-1].outcome == "memory cleared"


def test_memory_holds_fifty_points_and_loses_the_rest() -> None:
    device = make()
    for i in range(MEMORY_LIMIT + 2):
        device.receive(b"2002/03/14 19:%02d:00 %d 10\r" % (i, i), 0.0)
    assert MEMORY_LIMIT == 50
    assert len(device.state(0.0).stored_points) == 50
    assert [f.outcome for f in device.log[-3:]] == [
        "point stored",
        "ignored: memory full",
        "ignored: memory full",
    ]
    assert b"Number of stored positions: 50\r\n" in exchange(device, b"z", 1.0)


def test_points_are_kept_in_time_order() -> None:
    device = make(memory_limit=3)
    device.receive(b"2002/03/14 19:50:00 50 10\r2002/03/14 19:40:00 40 10\r", 0.0)
    assert [p.az_deg for p in device.state(0.0).stored_points] == [40, 50]


def test_invalid_configuration_is_refused() -> None:
    with pytest.raises(ValueError):
        make(line_ending=b"\r")
    with pytest.raises(ValueError):
        make(memory_limit=-1)
    with pytest.raises(ValueError):
        make(trailing_blank_lines=-1)
    with pytest.raises(ValueError):
        make(az_speed_deg_s=0.0)
    with pytest.raises(ValueError):
        make(start_el_deg=91.0)
