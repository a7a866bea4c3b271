"""SPID family on the wire: bytes in -> bytes out, with a fake clock (plain floats).

Every literal frame below is taken from Hamlib 4.5.4's spid traffic or the rot2prog PyPI page;
the decoder here is their formula, written out again on purpose.
"""

from __future__ import annotations

from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bridge.emulators.spid import Outcome, Spid

STATUS = bytes.fromhex("57 00 00 00 00 00 00 00 00 00 00 1F 20")
STOP = bytes.fromhex("57 00 00 00 00 00 00 00 00 00 00 0F 20")
PROCESSING_S = 0.002


def make(model: str = "rot2prog", **kwargs: Any) -> Spid:
    return Spid(model, **kwargs)


def exchange(device: Spid, data: bytes, at: float, within_s: float = 1.0) -> bytes:
    """Send `data` at `at` and collect everything that arrives within `within_s`."""
    device.receive(data, at)
    return device.due_output(at + within_s)


def decode12(reply: bytes) -> tuple[float, float, int, int]:
    """spid.md section 2: az = 100*H1 + 10*H2 + H3 + H4/10 - 360 (raw digits), same for el."""
    assert len(reply) == 12 and reply[0] == 0x57 and reply[11] == 0x20
    h1, h2, h3, h4, ph, v1, v2, v3, v4, pv = reply[1:11]
    az = 100 * h1 + 10 * h2 + h3 + h4 / 10 - 360
    el = 100 * v1 + 10 * v2 + v3 + v4 / 10 - 360
    return round(az, 1), round(el, 1), ph, pv


# -- status and the reply format --


def test_status_reply_is_the_fact_sheet_example() -> None:
    device = make(start_az_deg=12.5, start_el_deg=34.0)
    reply = exchange(device, STATUS, 0.0)
    assert reply == bytes.fromhex("57 03 07 02 05 02 03 09 04 00 02 20")
    assert decode12(reply) == (12.5, 34.0, 2, 2)
    assert [(f.data, f.outcome) for f in device.log] == [(STATUS, "status")]


def test_power_on_position_reads_like_the_rot2prog_simulator() -> None:
    assert exchange(make(), STATUS, 0.0) == bytes.fromhex("57 03 06 00 00 02 03 06 00 00 02 20")


@pytest.mark.parametrize("ppd", [1, 2, 4])
def test_reply_carries_the_configured_resolution_never_zero(ppd: int) -> None:
    reply = exchange(make(resolution_ppd=ppd), STATUS, 0.0)
    assert reply[5] == reply[10] == ppd


def test_stop_answers_the_position_too() -> None:
    device = make(start_az_deg=-180.0, start_el_deg=-20.0)
    assert decode12(exchange(device, STOP, 0.0)) == (-180.0, -20.0, 2, 2)
    assert device.log[-1].outcome == "stop"


def test_rot1prog_reply_is_five_bytes_of_whole_degrees() -> None:
    device = make("rot1prog", start_az_deg=12.0)
    assert exchange(device, STATUS, 0.0) == bytes.fromhex("57 03 07 02 20")
    assert exchange(device, STOP, 1.0) == bytes.fromhex("57 03 07 02 20")
    assert [f.outcome for f in device.log] == ["status", "stop"]


# -- set: the fact sheet's encodings, decoded by the controller --


@pytest.mark.parametrize(
    ("frame", "target", "reply"),
    [
        # spid.txt example (also on the PyPI page): az 123.5, el 77, PH = PV = 2
        ("57 30 39 36 37 02 30 38 37 34 02 2F 20", (123.5, 77.0), None),
        # spid.md section 7, Hamlib 4.5.4 on the wire, with the simulator's answers
        ("57 30 39 36 37 02 30 38 31 30 02 2F 20", (123.5, 45.0),
         "57 04 08 03 05 02 04 00 05 00 02 20"),
        ("57 30 36 39 39 02 30 37 31 30 02 2F 20", (-10.5, -5.0),
         "57 03 04 09 05 02 03 05 05 00 02 20"),
        # P 10 20 with the resolution pinned (section 4)
        ("57 30 37 34 30 02 30 37 36 30 02 2F 20", (10.0, 20.0), None),
    ],
)  # fmt: skip
def test_set_frames_from_the_fact_sheet(
    frame: str, target: tuple[float, float], reply: str | None
) -> None:
    device = make(az_speed_deg_s=1000.0, el_speed_deg_s=1000.0)
    device.receive(bytes.fromhex(frame), 0.0)
    state = device.state(0.0)
    assert device.due_output(5.0) == b""  # a Rot2Prog says nothing
    assert (state.target_az_deg, state.target_el_deg) == target
    assert device.log[-1].outcome == "set"
    answer = exchange(device, STATUS, 10.0)
    assert decode12(answer)[:2] == target
    if reply is not None:
        assert answer == bytes.fromhex(reply)


def test_negative_target_minus_10_3_arrives_as_0699_and_means_minus_10_5() -> None:
    device = make(az_speed_deg_s=100.0)
    device.receive(b"W0699\x020720\x02\x2f ", 0.0)  # el "0720" = 0 deg
    assert device.state(1.0).az_deg == -10.5
    assert device.reported_position(1.0) == (-10.5, 0.0)


def test_quarter_degree_resolution_reads_back_in_tenths_rounded_down() -> None:
    device = make(resolution_ppd=4, az_speed_deg_s=1000.0)
    device.receive(b"W1933\x041440\x04\x2f ", 0.0)  # 1933/4 - 360 = 123.25, 1440/4 - 360 = 0
    assert device.state(1.0).az_deg == 123.25
    assert device.reported_position(1.0) == (123.2, 0.0)
    assert exchange(device, STATUS, 1.0) == bytes.fromhex("57 04 08 03 02 04 03 06 00 00 04 20")


def test_whole_degree_resolution() -> None:
    device = make(resolution_ppd=1, az_speed_deg_s=1000.0, el_speed_deg_s=1000.0)
    device.receive(b"W0483\x010405\x01\x2f ", 0.0)
    assert decode12(exchange(device, STATUS, 1.0)) == (123.0, 45.0, 1, 1)


def test_command_ph_pv_bytes_are_ignored_the_controller_uses_its_own() -> None:
    device = make(resolution_ppd=2, az_speed_deg_s=1000.0, el_speed_deg_s=1000.0)
    device.receive(bytes.fromhex("57 30 39 36 37 04 30 38 37 34 7E 2F 20"), 0.0)
    assert (device.state(0.0).target_az_deg, device.state(0.0).target_el_deg) == (123.5, 77.0)


def test_rot1prog_set_frames_from_the_fact_sheet() -> None:
    device = make("rot1prog", az_speed_deg_s=1000.0)
    device.receive(bytes.fromhex("57 34 38 33 30 00 00 00 00 00 00 2F 20"), 0.0)
    assert device.state(0.0).target_az_deg == 123.0
    assert device.due_output(1.0) == b""
    assert exchange(device, STATUS, 1.0) == bytes.fromhex("57 04 08 03 20")
    device.receive(bytes.fromhex("57 33 34 39 30 00 00 00 00 00 00 2F 20"), 2.0)  # -10.5 -> 349
    assert device.state(3.0).az_deg == -11.0
    assert exchange(device, STATUS, 3.0) == bytes.fromhex("57 03 04 09 20")
    assert device.state(3.0).el_deg is None


def test_rot1prog_refuses_a_rot2prog_style_four_digit_set() -> None:
    device = make("rot1prog", start_az_deg=5.0)
    device.receive(b"W0483\x01\x00\x00\x00\x00\x00\x2f ", 0.0)  # byte 4 is '3', not '0'
    assert device.log[-1].outcome == "invalid"
    assert not device.state(1.0).is_moving


def test_md01_answers_a_set_with_the_position_before_the_move() -> None:
    device = make("md01", start_az_deg=12.5, start_el_deg=34.0)
    reply = exchange(device, bytes.fromhex("57 30 39 36 37 02 30 38 37 34 02 2F 20"), 0.0)
    assert reply == bytes.fromhex("57 03 07 02 05 02 03 09 04 00 02 20")
    assert device.state(0.0).target_az_deg == 123.5
    assert device.log[-1].outcome == "set"


def test_md01_tenth_degree_resolution() -> None:
    device = make("md01", resolution_ppd=10, az_speed_deg_s=1000.0, el_speed_deg_s=1000.0)
    device.receive(b"W4835\x0a3645\x0a\x2f ", 0.0)  # 483.5 - 360, 364.5 - 360
    assert decode12(device.due_output(1.0)) == (0.0, 0.0, 10, 10)  # the answer to the set
    reply = exchange(device, STATUS, 1.0)
    assert reply == bytes.fromhex("57 04 08 03 05 0A 03 06 04 05 0A 20")
    assert decode12(reply) == (123.5, 4.5, 10, 10)


def test_only_the_md01_may_be_set_to_tenth_degrees() -> None:
    with pytest.raises(ValueError, match="resolution_ppd"):
        make("rot2prog", resolution_ppd=10)
    with pytest.raises(ValueError, match="resolution_ppd"):
        make("md01", resolution_ppd=0)


# -- pacing --


def test_a_12_byte_reply_takes_0_2_s_at_600_baud() -> None:
    device = make()
    byte_s = 10 / 600
    device.receive(STATUS, 10.0)
    first_due = 10.0 + PROCESSING_S + byte_s
    assert device.next_wakeup(10.0) == pytest.approx(first_due)
    assert device.due_output(first_due - 1e-6) == b""
    assert len(device.due_output(first_due + 1e-6)) == 1
    last_due = 10.0 + PROCESSING_S + 12 * byte_s
    assert last_due - 10.0 == pytest.approx(0.202)
    assert len(device.due_output(last_due - 1e-6)) == 10
    assert len(device.due_output(last_due + 1e-6)) == 1
    assert device.next_wakeup(last_due + 1e-6) is None


def test_back_to_back_replies_queue_behind_each_other() -> None:
    device = make()
    device.receive(STATUS + STATUS, 0.0)
    assert len(device.due_output(0.4)) == 23
    assert len(device.due_output(0.41)) == 1


@pytest.mark.parametrize(
    ("model", "baud", "reply_bytes"), [("rot1prog", 1200, 5), ("md01", 115200, 12)]
)
def test_each_model_has_its_own_line_rate(model: str, baud: int, reply_bytes: int) -> None:
    device = make(model)
    assert device.baud == baud
    device.receive(STATUS, 0.0)
    done_s = PROCESSING_S + reply_bytes * 10 / baud
    assert len(device.due_output(done_s - 1e-6)) == reply_bytes - 1
    assert len(device.due_output(done_s + 1e-6)) == 1


def test_md01_line_rate_is_configurable() -> None:
    device = make("md01", baud=9600)
    device.receive(STATUS, 0.0)
    assert len(device.due_output(PROCESSING_S + 6 * 10 / 9600 + 1e-6)) == 6


# -- framing: pieces, junk, resynchronisation --

_SESSION = (
    STATUS
    + bytes.fromhex("57 30 39 36 37 02 30 38 37 34 02 2F 20")
    + b"\x00\xffjunk"
    + STOP
    + b"W"  # a stray start byte
    + STATUS
)


def _feed(device: Spid, data: bytes, chunk: int) -> bytes:
    out = bytearray()
    for i in range(0, len(data), chunk):
        device.receive(data[i : i + chunk], 0.0)
    out += device.due_output(10.0)
    return bytes(out)


@pytest.mark.parametrize("chunk", [1, 2, 5, 12, 13, 14, len(_SESSION)])
def test_same_result_whole_byte_by_byte_and_in_odd_pieces(chunk: int) -> None:
    device = make()
    out = _feed(device, _SESSION, chunk)
    assert len(out) == 36  # status, stop, status; the set answers nothing
    assert [(f.data, f.outcome) for f in device.log] == [
        (STATUS, "status"),
        (bytes.fromhex("57 30 39 36 37 02 30 38 37 34 02 2F 20"), "set"),
        (b"\x00\xffjunk", "invalid"),
        (STOP, "stop"),
        (b"W", "invalid"),
        (STATUS, "status"),
    ]


def test_a_frame_with_a_bad_end_byte_costs_only_its_start_byte() -> None:
    device = make()
    # a truncated command (7 bytes), then a good one: the 13-byte window ends on a 0x00
    out = exchange(device, STATUS[:7] + STATUS, 0.0)
    assert len(out) == 12
    assert [(f.data, f.outcome) for f in device.log] == [
        (STATUS[:7], "invalid"),
        (STATUS, "status"),
    ]


def test_long_junk_is_logged_in_frame_sized_runs() -> None:
    device = make()
    device.receive(bytes(30), 0.0)
    assert [len(f.data) for f in device.frames(Outcome.INVALID)] == [13, 13]
    device.receive(STATUS, 1.0)
    assert [len(f.data) for f in device.log] == [13, 13, 4, 13]


@pytest.mark.parametrize(
    ("model", "frame"),
    [
        ("rot2prog", "57 02 00 00 00 7F 00 00 00 00 6E 14 20"),  # MD-01 move on a Rot2Prog
        ("rot1prog", "57 02 00 00 00 7F 00 00 00 00 6E 14 20"),
        ("md01", "57 00 00 00 00 00 00 00 00 00 00 3F 20"),  # unknown K
        ("rot2prog", "57 30 39 36 41 02 30 38 37 34 02 2F 20"),  # 'A' in the azimuth digits
        ("rot2prog", "57 30 39 36 37 02 30 38 37 00 02 2F 20"),  # raw 0 in the elevation
        ("rot1prog", "57 34 38 33 31 00 00 00 00 00 00 2F 20"),  # byte 4 not '0'
    ],
)
def test_invalid_frames_get_no_answer_and_move_nothing(model: str, frame: str) -> None:
    device = make(model, start_az_deg=7.0)
    assert exchange(device, bytes.fromhex(frame), 0.0) == b""
    assert device.log[-1].outcome == "invalid"
    state = device.state(5.0)
    assert not state.is_moving and state.az_deg == 7.0


def test_status_ignores_whatever_the_client_put_in_the_digit_bytes() -> None:
    device = make(start_az_deg=12.5, start_el_deg=34.0)
    frame = bytes.fromhex("57 30 39 36 37 02 30 38 37 34 02 1F 20")
    assert decode12(exchange(device, frame, 0.0)) == (12.5, 34.0, 2, 2)
    assert not device.state(1.0).is_moving


_JUNK_WITHOUT_START = st.binary(max_size=30).map(lambda b: b.replace(b"W", b""))


@settings(max_examples=200, deadline=None)
@given(
    pieces=st.lists(st.tuples(_JUNK_WITHOUT_START, st.sampled_from([STATUS, STOP])), max_size=6),
    chunk=st.integers(1, 20),
    model=st.sampled_from(["rot2prog", "md01"]),
)
def test_junk_between_frames_never_costs_a_frame(
    pieces: list[tuple[bytes, bytes]], chunk: int, model: str
) -> None:
    device = make(model, start_az_deg=33.3, start_el_deg=4.4)
    stream = b"".join(junk + frame for junk, frame in pieces)
    out = _feed(device, stream, chunk)
    assert out == bytes.fromhex("57 03 09 03 05 02 03 06 04 05 02 20") * len(pieces)
    assert [f.data for f in device.frames("status", "stop")] == [frame for _, frame in pieces]


@settings(max_examples=300, deadline=None)
@given(chunks=st.lists(st.binary(max_size=40), max_size=8), ppd=st.sampled_from([1, 2, 4]))
def test_any_garbage_only_ever_yields_well_formed_replies(chunks: list[bytes], ppd: int) -> None:
    device = make(resolution_ppd=ppd, az_speed_deg_s=50.0, el_speed_deg_s=50.0)
    out = bytearray()
    for i, data in enumerate(chunks):
        device.receive(data + STATUS, float(i))
        out += device.due_output(float(i) + 0.9)
    out += device.due_output(1e6)
    assert len(out) % 12 == 0 and len(out) >= 12 * len(chunks)
    for i in range(0, len(out), 12):
        reply = out[i : i + 12]
        assert reply[0] == 0x57 and reply[11] == 0x20 and reply[5] == reply[10] == ppd
        assert all(d <= 9 for d in reply[1:5] + reply[6:10])
        az, el, _, _ = decode12(bytes(reply))
        assert -180.0 <= az <= 540.0 and -20.0 <= el <= 210.0
