"""SatEL codec: the report read by labels (whole, bytewise, CR LF or LF), what is owed, frames."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from bridge.protocols import REGISTRY
from bridge.protocols.base import UNTRUSTED, JunkReply, PositionReply, VersionReply
from bridge.protocols.satel import SatelCodec
from tests.support import feed

REPORT = (
    b"Motion ENABLED\r\nMode 0 - azimuth break at NORTH\r\nTime: 2026/11/22 04:10:00\r\n"
    b"Azimuth = 123     Absolute = 123\r\nElevation = 045\r\n\r\n"
    b"Number of stored positions: 00\r\n\r\n\r\n"
)
READING = PositionReply(123.0, 45.0, motion_enabled=True, controller_time="2026/11/22 04:10:00")


def positions(replies: list) -> list:
    return [r for r in replies if isinstance(r, PositionReply)]


@pytest.mark.parametrize("ending", [b"\r\n", b"\n"])
@pytest.mark.parametrize("how", ["whole", "bytewise"])
def test_report_is_read_by_labels(ending: bytes, how: str) -> None:
    data = REPORT.replace(b"\r\n", ending)
    c = SatelCodec()
    c.encode_query()
    out = feed(c, data, how)
    assert positions(out) == [READING]
    assert not c.awaiting_reply()
    assert all(c.harmless(r.data) for r in out if isinstance(r, JunkReply))


def test_disabled_motion_is_understood() -> None:
    c = SatelCodec()
    c.encode_query()
    text = REPORT.replace(b"ENABLED", b"DISABLED").replace(b"Azimuth = 123", b"Azimuth = 007")
    (reading,) = positions(c.feed(text))
    assert reading.motion_enabled is False and reading.az_deg == 7.0


@pytest.mark.parametrize(
    ("line", "text"),
    [
        (b"Azimuth = 123", b"Azimuth = 12"),  # its 3 lost on the line
        (b"Azimuth = 123", b"Azimuth = 12 "),  # ... or turned into a space (one bit of 0x33)
        (b"Azimuth = 123", b"Azimuth =  7"),
        (b"Elevation = 045", b"Elevation = 04"),
    ],
)
def test_a_value_of_fewer_than_three_digits_lost_a_byte_and_is_no_reading(
    line: bytes, text: bytes
) -> None:
    """Rule 3: the controller pads every value to three digits; ``Azimuth = 12`` is 123 that
    lost its last byte on the line (read as 12, it was published and acted on)."""
    c = SatelCodec()
    c.encode_query()
    assert positions(c.feed(REPORT.replace(line, text))) == []


@pytest.mark.parametrize(
    "spoiled",
    [
        REPORT.replace(b"Azimuth = 123", b"Azimuth = 1x3"),
        REPORT.replace(b"Elevation = 045", b"Elevation = 999"),
        REPORT.replace(b"Azimuth = 123     Absolute = 123\r\n", b""),
        REPORT.replace(b"Elevation = 045\r\n", b"Elevation = 045\r\ngarbage line\r\n"),
        REPORT.replace(b"Motion", b"M\xffotion"),  # its first line lost
        REPORT.replace(b"Motion ENABLED\r\n", b""),
    ],
)
def test_a_spoiled_report_is_junk_not_a_reading(spoiled: bytes) -> None:
    c = SatelCodec()
    c.encode_query()
    assert positions(c.feed(spoiled)) == []


def test_identify_and_connect_sequence() -> None:
    c = SatelCodec()
    frames = c.encode_connect(0.0)
    assert frames == [b"s", b"x", b"?", b"t1970/01/01 00:00:00\r\n", b"g", b"z"]
    assert not c.awaiting_reply()  # owed as each is written (session/link.py rule 14)
    for frame in frames[:3]:
        c.connect_written(frame)
    assert c.awaiting_reply()  # the identification
    assert c.feed(b"SatEL\r\n") == [VersionReply("SatEL")]
    assert not c.awaiting_reply()  # the rest may go
    for frame in frames[3:]:
        c.connect_written(frame)
    assert c.awaiting_reply()  # the report
    assert positions(c.feed(REPORT)) == [READING]
    assert not c.awaiting_reply()


def test_point_is_preceded_by_enable_and_owes_the_after_move_report() -> None:
    c = SatelCodec()
    assert c.encode_target(100.4, 45.6) == [b"g", b"p100 50\r\n"]  # rule 7: its steps
    assert c.encode_target(10, 20)[1] == b"p10 20\r\n"  # not zero-padded, as Hamlib sends
    c.encode_stop()  # the first slew is cut short: its report may show any position
    assert positions(c.feed(REPORT)) == [READING]
    assert c.awaiting_reply()  # two points were owed
    at_point = REPORT.replace(b"Azimuth = 123", b"Azimuth = 012").replace(b"= 045", b"= 020")
    assert [(r.az_deg, r.el_deg) for r in positions(c.feed(at_point))] == [(12.0, 20.0)]
    assert not c.awaiting_reply()
    with pytest.raises(ValueError):
        c.encode_target(10, 95)


def test_a_report_that_does_not_show_the_point_does_not_end_its_slew() -> None:
    """A report that was on its way before the point (the answer to a poll the engine gave up
    on) must not pass for the after-move report: the engine would poll into the slew."""
    c = SatelCodec()
    c.encode_target(300, 60)
    out = c.feed(REPORT)  # 123/45: not where the point goes
    assert positions(out) == [] and isinstance(out[-1], JunkReply)
    assert c.awaiting_reply()
    at_point = REPORT.replace(b"Azimuth = 123", b"Azimuth = 302").replace(b"= 045", b"= 059")
    assert len(positions(c.feed(at_point))) == 1  # coasting a little past is the end
    assert not c.awaiting_reply()


@pytest.mark.parametrize(
    "lost_first_line",
    [REPORT.replace(b"Motion", b"M\xffotion"), REPORT.replace(b"Motion ENABLED\r\n", b"")],
)
def test_an_after_move_report_without_its_first_line_still_ends_the_slew(
    lost_first_line: bytes,
) -> None:
    """Noise in the `Motion` line must not hide the end of a slew: the report is recognised by
    its other lines, spoiled (no reading from it), and the slew is over (UNTRUSTED: ask again)."""
    c = SatelCodec()
    c.encode_target(123, 45)
    out = c.feed(lost_first_line)
    assert positions(out) == []
    assert [r.reason for r in out if isinstance(r, JunkReply)].count(UNTRUSTED) == 1
    assert not c.awaiting_reply()


def test_a_headless_report_that_does_not_show_the_point_does_not_end_its_slew() -> None:
    """The same check for a report whose first line was lost: its position can still be read,
    and a stale one must not end the slew either."""
    c = SatelCodec()
    c.encode_target(300, 60)
    out = c.feed(REPORT.replace(b"Motion", b"M\xffotion"))  # 123/45
    assert positions(out) == [] and UNTRUSTED not in [r.reason for r in out]
    assert c.awaiting_reply()


@pytest.mark.parametrize(
    ("point", "shown", "ends"),
    [
        ((360, 10), b"000", True),  # the north stop, either way round
        ((0, 10), b"360", True),
        ((359, 10), b"000", True),  # sent as 360 (rule 7), coasted onto the stop
        ((350, 10), b"354", True),  # short of the point, within the tolerance
        ((350, 10), b"002", False),  # 12 degrees across north: an old report
        ((10, 10), b"358", False),
    ],
)
def test_000_and_360_are_one_place_and_nothing_else_wraps(
    point: tuple[int, int], shown: bytes, ends: bool
) -> None:
    c = SatelCodec()
    c.encode_target(*point)
    report = REPORT.replace(b"Azimuth = 123", b"Azimuth = " + shown).replace(b"= 045", b"= 010")
    assert len(positions(c.feed(report))) == (1 if ends else 0)
    assert c.awaiting_reply() is not ends


@pytest.mark.parametrize(
    ("asked", "sent"),
    [((126, 36), b"p130 40"), ((124.9, 34.9), b"p120 30"), ((125, 35), b"p130 40"),
     ((356, 86), b"p360 90"), ((4.9, 0.4), b"p0 0")],
)  # fmt: skip
def test_a_point_goes_out_as_the_nearest_of_the_rotors_ten_degree_steps(
    asked: tuple[float, float], sent: bytes
) -> None:
    """Rule 7: the rotors stop only at ten-degree steps, so each axis is sent the nearest one
    (half up): the place it reaches, which the slew's end and the arrival are judged by."""
    c = SatelCodec()
    assert c.encode_target(*asked) == [b"g", sent + b"\r\n"]
    az, el = (float(v) for v in sent[1:].split())
    assert c.wire_target(*asked) == (az, el)


def test_other_frames() -> None:
    c = SatelCodec()
    assert (c.encode_stop(), c.encode_enable()) == (b"s", b"g")


@given(st.binary(max_size=300))
def test_garbage_never_becomes_a_reading(data: bytes) -> None:
    c = SatelCodec()
    c.encode_query()
    for r in positions(c.feed(data)):
        assert b"Azimuth" in data and b"Number of stored positions" in data
        assert 0 <= r.az_deg <= 360 and 0 <= r.el_deg <= 90


def test_satel_spec() -> None:
    s = REGISTRY["satel"]
    assert (s.baud, s.has_elevation, s.full_duplex, s.stop_interrupts, s.reports_while_moving) == (
        9600,
        True,
        False,
        True,
        False,
    )
    assert (s.az_min_deg, s.az_max_deg, s.el_min_deg, s.el_max_deg) == (0, 360, 0, 90)
