"""SPID codec: the fact sheet's examples byte for byte; replies whole, bytewise and amid junk."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from bridge.core.model import Target
from bridge.pointing import Pointing
from bridge.protocols import REGISTRY
from bridge.protocols.base import JunkReason, JunkReply, NotReady, PositionReply, Reply
from bridge.protocols.spid import SpidCodec
from tests.support import HOW, feed
from tests.support.codecs import STOPS, given_up

REPLY_12_5_34 = bytes.fromhex("57 03 07 02 05 02 03 09 04 00 02 20")


def taken(c: SpidCodec, replies: list[Reply]) -> list[Reply]:
    """``replies``, each reading taken as the engine takes it (link.py rule 9, rule 5)."""
    for r in replies:
        if isinstance(r, PositionReply):
            c.taken(r)
    return replies


def known(ph: int = 2, variant: str = "rot2prog") -> SpidCodec:
    """A codec that took two readings saying ``ph`` (rule 5: a connection's first resolution
    is confirmed by a second)."""
    c = SpidCodec(variant)
    for _ in range(2):
        c.encode_query()
        taken(c, c.feed(bytes([0x57, 3, 6, 0, 0, ph, 3, 6, 0, 0, ph, 0x20])))
    assert c.resolution == ph
    return c


def test_status_and_stop_frames() -> None:
    c = SpidCodec()
    assert c.encode_query() == bytes.fromhex("57 00 00 00 00 00 00 00 00 00 00 1F 20")
    assert c.encode_stop() == bytes.fromhex("57 00 00 00 00 00 00 00 00 00 00 0F 20")


@pytest.mark.parametrize(
    ("ph", "az", "el", "frame"),
    [
        (2, 123.5, 77, "57 30 39 36 37 02 30 38 37 34 02 2F 20"),
        (2, 123.5, 45, "57 30 39 36 37 02 30 38 31 30 02 2F 20"),
        (2, -10.3, -5, "57 30 36 39 39 02 30 37 31 30 02 2F 20"),
        (2, 10, 20, "57 30 37 34 30 02 30 37 36 30 02 2F 20"),
    ],
)
def test_rot2prog_set_frames_from_the_fact_sheet(ph: int, az: float, el: float, frame: str) -> None:
    assert known(ph).encode_target(az, el) == [bytes.fromhex(frame)]


def test_targets_snap_down_to_the_resolution_grid() -> None:
    assert known(2).wire_target(-10.3, 12.25) == (-10.5, 12.0)
    assert known(4).wire_target(123.3, 0) == (123.25, 0.0)
    assert known(1).wire_target(200.9, 45.5) == (200.0, 45.0)


def test_a_bearing_on_the_grid_after_the_offset_goes_out_at_its_own_step() -> None:
    """Rule 1: an MD-01 at 10 pulses per degree whose rotor's north lies 4.9 degrees west of
    true is asked for true 251.2: the controller's 256.1 (in binary 256.09999999999997, the
    subtraction's rounding) goes out as 2561 tenths and reads 256.1, not a tenth below."""
    aim = Pointing.of(REGISTRY["md01"], offset_deg=-4.9)
    c = known(10, "md01")
    for true in (251.2, 251.7, 300.3):
        raw = aim.judge(Target(az_deg=true, el_deg=10.0), None).az_deg
        assert raw is not None
        frame = c.encode_target(raw, 10.0)[0]
        want = round((360 + true + 4.9) * 10)
        assert frame[1:5] == b"%04d" % want, (true, raw, frame)
        assert c.wire_target(raw, 10.0)[0] == pytest.approx(true + 4.9)


@pytest.mark.parametrize("ph", [1, 2, 4, 10])
def test_an_axis_held_where_it_reads_is_asked_for_at_its_own_step(ph: int) -> None:
    """Rule 6: every step of the grid, read in tenths rounded down (44.25 reads 44.2) or to
    the nearest (44.3), is asked for as that step, never the one below it."""
    c = known(ph)
    for pulses in range(0, 5400):  # -360..180 at 10 pulses per degree: both ends of each axis
        for tenths in (pulses * 10 // ph, round(pulses * 10 / ph)):  # (of 360 + the angle)
            read = tenths / 10 - 360
            frame = c.encode_target(c.held(read, "azimuth"), c.held(read, "elevation"))[0]
            assert frame[1:5] == frame[6:10] == b"%04d" % pulses, (pulses, read)


def test_no_set_without_a_known_resolution() -> None:
    with pytest.raises(ValueError, match="resolution"):
        SpidCodec().encode_target(10, 10)


def test_rot1prog_frames() -> None:
    c = SpidCodec("rot1prog")
    assert c.encode_target(123) == [bytes.fromhex("57 34 38 33 30 00 00 00 00 00 00 2F 20")]
    assert c.encode_target(123.7) == c.encode_target(123)
    assert c.wire_target(-10.5) == (-11.0, None)
    c.encode_query()
    assert c.feed(bytes.fromhex("57 03 07 02 20")) == [PositionReply(12.0, None)]


@pytest.mark.parametrize("how", HOW)
def test_reply_decodes_with_resolution(how: str) -> None:
    c = SpidCodec()
    for _ in range(2):  # (rule 5: the first resolution once a second reading says it too)
        c.encode_query()
        assert taken(c, feed(c, REPLY_12_5_34, how)) == [PositionReply(12.5, 34.0)]
    assert c.resolution == 2 and not c.awaiting_reply()


@pytest.mark.parametrize("how", HOW)
def test_md01_debug_lines_are_skipped_never_read(how: str) -> None:
    c = SpidCodec("md01")
    c.encode_query()
    out = feed(c, b"123: motor on\r\n" + REPLY_12_5_34 + b"7: W \x02\r\n", how)
    assert [r for r in out if isinstance(r, PositionReply)] == [PositionReply(12.5, 34.0)]
    junk = [r for r in out if isinstance(r, JunkReply)]
    assert junk and all(r.reason is JunkReason.CHATTER for r in junk)
    assert all(r.detail == "controller debug line" for r in junk)


def test_md01_answers_a_set_rot2prog_does_not() -> None:
    md = known(2, "md01")
    md.encode_target(10, 10)
    assert md.awaiting_reply()
    r2 = known(2, "rot2prog")
    r2.encode_target(10, 10)
    assert not r2.awaiting_reply()


def test_stop_is_answered_with_a_position() -> None:
    c = known(2)
    c.encode_stop()
    assert c.awaiting_reply()
    assert c.feed(REPLY_12_5_34) == [PositionReply(12.5, 34.0)]


def test_unasked_frame_is_not_a_reading() -> None:
    c = SpidCodec()
    out = c.feed(REPLY_12_5_34)
    assert out and all(isinstance(r, JunkReply) for r in out)


@pytest.mark.parametrize(
    "bad",
    [
        bytes.fromhex("57 03 07 02 05 02 03 09 04 00 02 21"),  # wrong end byte
        bytes.fromhex("57 03 07 32 05 02 03 09 04 00 02 20"),  # ASCII digit where raw belongs
        bytes.fromhex("57 03 07 02 05 00 03 09 04 00 00 20"),
    ],  # resolution 0
)
def test_malformed_frames_are_junk(bad: bytes) -> None:
    c = SpidCodec()
    c.encode_query()
    assert not [r for r in c.feed(bad) if isinstance(r, PositionReply)]


@given(st.binary(max_size=40), st.binary(max_size=40))
def test_junk_around_a_reply_never_gives_a_wrong_reading(prefix: bytes, suffix: bytes) -> None:
    c = SpidCodec()
    c.encode_query()
    got = [r for r in c.feed(prefix + REPLY_12_5_34 + suffix) if isinstance(r, PositionReply)]
    # noise in the exchange makes the reply untrusted (asked again); it never makes up a value
    assert got in ([], [PositionReply(12.5, 34.0)])
    if not prefix:
        assert got == [PositionReply(12.5, 34.0)]


def test_spid_specs() -> None:
    r2 = REGISTRY["rot2prog"]
    assert (r2.baud, r2.has_elevation, r2.full_duplex, r2.az_min_deg, r2.az_max_deg) == (
        600,
        True,
        False,
        -180,
        540,
    )
    assert (r2.el_min_deg, r2.el_max_deg, r2.brake_delay_s) == (-20, 210, 0)
    assert REGISTRY["rot1prog"].has_elevation is False and REGISTRY["rot1prog"].baud == 1200
    assert r2.reply_timeout_s > 25 * 10 / 600


def status_frame(az_digits: list[int], el_digits: list[int], ph: int, pv: int) -> bytes:
    return bytes([0x57, *az_digits, ph, *el_digits, pv, 0x20])


AT_10_5 = ([3, 7, 0, 0], [3, 6, 5, 0])  # az 10.0, el 5.0


def test_a_resolution_flipped_once_is_never_what_targets_are_counted_in() -> None:
    """Rule 5: PH 2 flipped to 10 in one reply (one bit) made the next target 3800 pulses:
    azimuth 540, the end stop. A reply that says another resolution for either axis than the
    one known is believed only when the next says it too."""
    c = SpidCodec("rot2prog")
    for _ in range(2):
        c.encode_query()
        assert taken(c, c.feed(status_frame(*AT_10_5, 2, 2))) == [PositionReply(10.0, 5.0)]
    flips = (status_frame(*AT_10_5, 10, 2), status_frame(*AT_10_5, 2, 10))
    for flipped in (*flips, status_frame(*AT_10_5, 10, 10)):
        c.encode_query()
        (junk,) = c.feed(flipped)
        assert isinstance(junk, JunkReply) and junk.reason is JunkReason.UNTRUSTED
        c.encode_query()
        assert taken(c, c.feed(status_frame(*AT_10_5, 2, 2))) == [PositionReply(10.0, 5.0)]
        assert c.encode_target(20.0, 5.0)[0][1:5] == b"0760"
    c.encode_query()  # the resolution changed at the controller's panel: said twice
    assert isinstance(taken(c, c.feed(status_frame(*AT_10_5, 4, 4)))[0], JunkReply)
    c.encode_query()
    assert taken(c, c.feed(status_frame(*AT_10_5, 4, 4))) == [PositionReply(10.0, 5.0)]
    assert c.encode_target(20.0, 5.0)[0][1:5] == b"1520"


def test_a_connections_first_resolution_is_confirmed_by_a_second_reading() -> None:
    """Rule 5 at connect: the first reading's PH flipped 2 to 10 counted every target in 10
    (the end stops again); until two readings taken agree, no target is counted (NotReady:
    the engine asks first)."""
    c = SpidCodec("rot2prog")
    for ph in (10, 2):  # the first flipped, the second right: they do not agree
        c.encode_query()
        assert taken(c, c.feed(status_frame(*AT_10_5, ph, ph))) == [PositionReply(10.0, 5.0)]
        with pytest.raises(NotReady):
            c.encode_target(20.0, 5.0)
        with pytest.raises(NotReady):
            c.wire_target(20.0, 5.0)
    c.encode_query()
    taken(c, c.feed(status_frame(*AT_10_5, 2, 2)))
    assert c.encode_target(20.0, 5.0)[0][1:5] == b"0760"


def test_each_axis_is_counted_in_its_own_resolution() -> None:
    """Rule 5: Hamlib's az_resolution and el_resolution: PH for the azimuth, PV for the
    elevation (PV 4, PH 2: 5 degrees up is 1460 pulses, not 730, which that controller reads
    as -177.5)."""
    c = SpidCodec("rot2prog")
    for _ in range(2):
        c.encode_query()
        assert taken(c, c.feed(status_frame(*AT_10_5, 2, 4))) == [PositionReply(10.0, 5.0)]
    frame = c.encode_target(20.0, 5.0)[0]
    assert (frame[1:5], frame[5], frame[6:10], frame[10]) == (b"0760", 2, b"1460", 4)
    assert c.wire_target(20.3, 5.3) == (20.0, 5.25)


def test_a_frame_that_is_no_reading_teaches_no_resolution() -> None:
    c = known(2)
    taken(c, c.feed(status_frame(*AT_10_5, 10, 10)))  # nobody asked
    c.encode_query()
    c.feed(b"\x99" + status_frame(*AT_10_5, 10, 10))  # noise before it
    c.encode_query()
    taken(c, c.feed(status_frame(*AT_10_5, 10, 10)))  # the first to say 10 as a reading
    assert c.resolution == 2
    c.encode_query()
    c.feed(status_frame(*AT_10_5, 10, 10))  # said again, but not taken (a second reply
    assert c.resolution == 2  # spoiled the exchange: link.py rule 9)


def test_a_position_the_controller_cannot_turn_to_is_no_reading() -> None:
    c = SpidCodec("rot2prog")
    c.encode_query()
    (junk,) = taken(c, c.feed(status_frame([9, 9, 9, 9], [0, 0, 0, 0], 2, 2)))  # az 639.9, el -360
    assert isinstance(junk, JunkReply) and junk.reason is JunkReason.SPOILED


AT = [([3, 7, az, 0], [3, 6, 5, 0]) for az in range(5)]  # az 10.0 .. 14.0, el 5.0


@pytest.mark.parametrize("stop", STOPS)
@pytest.mark.parametrize("how", HOW)
def test_a_status_answered_after_its_time_is_told_nowhere_and_is_no_reading(
    stop: str, how: str
) -> None:
    """Rule 7: a loaded host had a status's answer come after its reply time; the next status
    took it, and its own answer was told on R/error as no reply. A stop written with the
    status given up owes its frame late too."""
    c = known()
    given_up(c, stop)
    frames = [status_frame(*at, 2, 2) for at in AT]
    assert taken(c, feed(c, frames[0], how)) == [PositionReply(10.0, 5.0)]  # (which: none says)
    owed = 1 if stop == "none" else 2
    for late in frames[1 : 1 + owed]:
        replies = feed(c, late, how)
        assert [r.reason for r in replies if isinstance(r, JunkReply)] == [JunkReason.UNSOLICITED]
        assert not [r for r in replies if isinstance(r, PositionReply)] and c.harmless(late)
    told = frames[1 + owed]
    replies = feed(c, told, how)  # owed by nothing: told
    assert not [r for r in replies if isinstance(r, PositionReply)] and not c.harmless(told)
    assert not c.harmless(frames[1] * (owed + 1)) and not c.harmless(frames[1] + b"#")
    c.encode_query()
    assert taken(c, feed(c, frames[4], how)) == [PositionReply(14.0, 5.0)]
