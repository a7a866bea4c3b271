"""SatEL codec: the report read by labels (whole, bytewise, CR LF or LF), what is owed, frames."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from bridge.protocols import REGISTRY
from bridge.protocols.base import JunkReply, PositionReply, VersionReply
from bridge.protocols.satel import SLEW_TIMEOUT_S, SatelCodec

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
    if how == "whole":
        out = c.feed(data)
    else:
        out = [r for i in range(len(data)) for r in c.feed(data[i : i + 1])]
    assert positions(out) == [READING]
    assert not c.awaiting_reply()
    assert all(c.harmless(r.data) for r in out if isinstance(r, JunkReply))


def test_disabled_motion_and_other_widths_are_understood() -> None:
    c = SatelCodec()
    c.encode_query()
    text = REPORT.replace(b"ENABLED", b"DISABLED").replace(b"Azimuth = 123", b"Azimuth =  7")
    (reading,) = positions(c.feed(text))
    assert reading.motion_enabled is False and reading.az_deg == 7.0


@pytest.mark.parametrize(
    "spoiled",
    [
        REPORT.replace(b"Azimuth = 123", b"Azimuth = 1x3"),
        REPORT.replace(b"Elevation = 045", b"Elevation = 999"),
        REPORT.replace(b"Azimuth = 123     Absolute = 123\r\n", b""),
        REPORT.replace(b"Elevation = 045\r\n", b"Elevation = 045\r\ngarbage line\r\n"),
    ],
)
def test_a_spoiled_report_is_junk_not_a_reading(spoiled: bytes) -> None:
    c = SatelCodec()
    c.encode_query()
    assert positions(c.feed(spoiled)) == []


def test_identify_and_connect_sequence() -> None:
    c = SatelCodec()
    frames = c.encode_connect(0.0)
    assert frames == [b"s", b"?", b"t1970/01/01 00:00:00\r\n", b"g", b"z"]
    out = c.feed(b"SatEL\r\n" + REPORT)
    assert VersionReply("SatEL") in out and positions(out) == [READING]
    assert not c.awaiting_reply()


def test_point_is_preceded_by_enable_and_owes_a_long_report() -> None:
    c = SatelCodec()
    assert c.encode_target(100.4, 45.6) == [b"g", b"p100 46\r\n"]
    assert c.encode_target(10, 20)[1] == b"p10 20\r\n"  # not zero-padded, as Hamlib sends
    assert c.slewing() and c.reply_timeout_s(2.0) == SLEW_TIMEOUT_S
    c.feed(REPORT)
    assert c.slewing()  # two points were owed
    c.feed(REPORT)
    assert not c.slewing() and c.reply_timeout_s(2.0) == 2.0
    with pytest.raises(ValueError):
        c.encode_target(10, 95)


def test_other_frames() -> None:
    c = SatelCodec()
    assert (c.encode_stop(), c.encode_enable(), c.encode_reset(), c.encode_clear_memory()) == (
        b"s",
        b"g",
        b"*",
        b"x",
    )
    assert c.encode_store_point(0.0, 40, 60) == b"21970/01/01 00:00:00 40 60\r\n"


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
