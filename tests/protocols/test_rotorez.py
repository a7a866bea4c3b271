"""The Rotor-EZ codec: bytes on the wire, and replies fed whole, byte by byte and amid junk."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from bridge.protocols import REGISTRY
from bridge.protocols.base import UNTRUSTED, JunkReason, JunkReply, PositionReply, VersionReply
from bridge.protocols.rotorez import RotorEzCodec
from tests.support import HOW, feed
from tests.support.codecs import STOPS, given_up


def positions(replies: list) -> list[float]:
    return [r.az_deg for r in replies if isinstance(r, PositionReply)]


@pytest.mark.parametrize(
    ("az", "frame"),
    [
        (0, b"AP1000\r"),
        (9, b"AP1009\r"),
        (120, b"AP1120\r"),
        (180.5, b"AP1181\r"),
        (180.4, b"AP1180\r"),
        (359.6, b"AP1360\r"),
        (360, b"AP1360\r"),
    ],
)
def test_rotorez_target_is_set_and_execute_with_three_digits(az: float, frame: bytes) -> None:
    assert RotorEzCodec().encode_target(az) == [frame]


@pytest.mark.parametrize(
    ("az", "frames"), [(80, [b"AP1080;", b"AM1;"]), (360, [b"AP1000;", b"AM1;"])]
)
def test_dcu1_target_is_set_then_execute(az: float, frames: list[bytes]) -> None:
    assert REGISTRY["dcu1"].codec_factory().encode_target(az) == frames


@pytest.mark.parametrize("az", [-0.6, 360.5, 1000])
def test_target_outside_the_wire_range_is_refused(az: float) -> None:
    with pytest.raises(ValueError):
        RotorEzCodec().encode_target(az)


def test_stop_query_version_and_option_frames() -> None:
    ez = REGISTRY["rotorez"].codec_factory()
    assert ez.encode_stop() == b";"
    assert ez.encode_query() == b"AI1;"
    assert ez.encode_version() == b"V"
    assert [ez.encode_option(n, True) for n in ("endpoint", "jam", "overshoot", "unstick")] == [
        b"E",
        b"J",
        b"O",
        b"S",
    ]
    assert [ez.encode_option(n, False) for n in ("endpoint", "jam", "overshoot", "unstick")] == [
        b"e",
        b"j",
        b"o",
        b"s",
    ]
    dcu = REGISTRY["dcu1"].codec_factory()
    assert dcu.encode_stop() == b"AS1;"
    assert dcu.encode_query() is None and dcu.encode_version() is None
    with pytest.raises(ValueError):
        dcu.encode_option("jam", True)
    card = REGISTRY["rotorcard"].codec_factory()
    with pytest.raises(ValueError):
        card.encode_option("jam", True)


def test_capabilities_are_data() -> None:
    assert REGISTRY["rotorez"].options == ("endpoint", "jam", "overshoot", "unstick")
    assert REGISTRY["rotorcard"].options == ()
    assert REGISTRY["dcu1"].can_report_position is False
    assert REGISTRY["rotorez"].brake_delay_s == 5 and REGISTRY["rotorcard"].brake_delay_s == 0
    assert REGISTRY["dcu1"].brake_delay_s == 5
    assert REGISTRY["rotorez"].baud == 4800


@pytest.mark.parametrize("how", HOW)
def test_position_reply(how: str) -> None:
    c = RotorEzCodec()
    c.encode_query()
    assert positions(feed(c, b";123", how)) == [123.0]


@pytest.mark.parametrize("how", HOW)
def test_power_on_byte_and_banner_are_junk_and_banner_gives_version(how: str) -> None:
    c = RotorEzCodec()
    c.encode_query()
    replies = feed(c, b"\xe0C2000 IDIOM V1.4S ;045", how)
    assert positions(replies) == [45.0]
    assert VersionReply("1.4S") in replies
    junk = b"".join(r.data for r in replies if isinstance(r, JunkReply))
    assert junk == b"\xe0C2000 IDIOM V1.4S "


def power_ons(replies: list) -> list[bytes]:
    return [r.data for r in replies if isinstance(r, JunkReply) and r.reason is JunkReason.POWER_ON]


@pytest.mark.parametrize("how", HOW)
def test_the_codec_says_when_the_board_was_switched_on(how: str) -> None:
    """The power-on byte is POWER_ON junk of its own (the engine re-sends the options on it);
    the banner, line noise and readings around it are not, and it taints no reading."""
    c = RotorEzCodec()
    c.encode_query()
    replies = feed(c, b"\x13\xe0C2000 IDIOM V1.4S ;045", how)
    assert power_ons(replies) == [b"\xe0"]
    assert positions(replies) == []  # the \x13 before it is noise the board never sends
    c.encode_query()
    replies = feed(c, b"\xe0;046C2000 IDIOM V1.4S ", how)
    assert power_ons(replies) == [b"\xe0"] and positions(replies) == [46.0]
    c.encode_query()
    assert power_ons(feed(c, b"C2000 IDIOM V1.4S \x13;047\r", how)) == []


def test_a_run_of_power_on_bytes_is_one_power_on() -> None:
    assert power_ons(RotorEzCodec().feed(b"\xe0\xe0\xe0")) == [b"\xe0\xe0\xe0"]


@pytest.mark.parametrize("how", HOW)
def test_360_is_a_bearing_but_361_is_junk(how: str) -> None:
    c = RotorEzCodec()
    c.encode_query()
    assert positions(feed(c, b";360", how)) == [360.0]
    c.encode_query()
    assert positions(feed(c, b";361", how)) == []


def test_unsolicited_bearing_frame_is_not_a_reading() -> None:
    c = RotorEzCodec()
    replies = c.feed(b";123")
    assert positions(replies) == []
    assert any(isinstance(r, JunkReply) for r in replies)


def test_expired_query_does_not_accept_a_late_frame() -> None:
    c = RotorEzCodec()
    c.encode_query()
    c.expire_query()
    assert positions(c.feed(b";200")) == []


def test_torn_frame_waits_for_the_rest() -> None:
    c = RotorEzCodec()
    c.encode_query()
    assert c.feed(b";1") == []
    assert positions(c.feed(b"2")) == []
    assert positions(c.feed(b"7")) == [127.0]


def test_a_frame_after_line_noise_is_not_trusted_and_the_next_query_is() -> None:
    c = RotorEzCodec()
    c.encode_query()
    replies = c.feed(b"\x13\x7f;193")
    assert positions(replies) == []
    assert JunkReply(b";193", UNTRUSTED) in replies
    c.encode_query()
    assert positions(c.feed(b";150")) == [150.0]
    c.encode_query()
    assert positions(c.feed(b";1x;090")) == []  # a torn frame is noise too


def test_the_boards_own_junk_does_not_taint_a_reading() -> None:
    c = RotorEzCodec()
    c.encode_query()
    assert positions(c.feed(b"\xe0C2000 IDIOM V1.4S ;045")) == [45.0]


@given(st.binary(max_size=200))
def test_junk_never_becomes_a_bearing_without_a_frame(data: bytes) -> None:
    c = RotorEzCodec()
    c.encode_query()
    for r in c.feed(data):
        if isinstance(r, PositionReply):
            # a reading can only come from a ';ddd' frame somewhere in the input
            assert b";%03d" % int(r.az_deg) in data
            assert 0 <= r.az_deg <= 360


@given(st.binary(max_size=60), st.integers(0, 360), st.binary(max_size=60))
def test_reply_amid_junk_is_read_only_when_the_junk_is_the_boards_own(
    prefix: bytes, az: int, suffix: bytes
) -> None:
    c = RotorEzCodec()
    c.encode_query()
    prefix = prefix.replace(b";", b"")  # keep the prefix frame-free
    got = positions(c.feed(prefix + b";%03d" % az + suffix))
    clean = all(b in b"\xe0 .0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZ" for b in prefix)
    assert got[:1] == ([float(az)] if clean else [])


BANNER = b"C2000 IDIOM V1.4S "


def junk_of(codec: RotorEzCodec, data: bytes) -> bytes:
    """The junk of one read, as the line gathers it (session/link.py) and asks about it."""
    return b"".join(r.data for r in codec.feed(data) if isinstance(r, JunkReply))


@pytest.mark.parametrize("cut", range(1, len(BANNER)))
def test_a_banner_torn_across_reads_is_harmless_at_every_cut(cut: int) -> None:
    """Rule 5: a second stop reaching an idle board (the stop express's and the session's) is
    answered with the banner, which a busy host reads in pieces, judged as they come (the line
    went quiet between them) or together: no piece is reported."""
    codec = RotorEzCodec()
    first = junk_of(codec, BANNER[:cut])
    assert first == BANNER[:cut] and codec.harmless(first)
    second = junk_of(codec, BANNER[cut:])
    assert second == BANNER[cut:] and codec.harmless(second)
    assert codec.harmless(first + second)


def test_a_banner_begun_in_the_read_of_a_power_on_byte_is_harmless() -> None:
    """Rule 5 beside the power-on byte: the line gathers the junk of one quiet spell, a
    power-on byte and the first piece of a banner (the stop express's stop and the session's
    reached an idle RotorCard), as ``\\xe0C20``: it was reported on R/error as "controller sent
    4 bytes that are no valid reply" (seen in CI)."""
    codec = RotorEzCodec()
    first = junk_of(codec, b"\xe0" + BANNER[:3])
    assert first == b"\xe0C20" and codec.harmless(first)
    assert codec.harmless(junk_of(codec, BANNER[3:]))
    assert not codec.harmless(junk_of(codec, b"\xe0XYZ"))


def test_a_banner_fed_byte_by_byte_is_harmless_and_what_goes_on_otherwise_is_not() -> None:
    codec = RotorEzCodec()
    assert all(codec.harmless(junk_of(codec, bytes([b]))) for b in BANNER * 2)
    assert not codec.harmless(junk_of(codec, b"XYZ"))
    pieces = [junk_of(codec, bytes([b])) for b in b"C2000 IDX"]
    assert not codec.harmless(pieces[-1])  # no banner goes on like that
    assert not codec.harmless(b"1.4S ")  # the end of a banner whose beginning never came


def test_a_reply_begun_before_the_query_is_no_answer_to_it() -> None:
    """Rule 1: ``;18`` of a reply the engine gave up on, then the next query, then its ``0``:
    not the new query's answer (a reading one reply timeout old), and the reply that follows
    is not trusted (asked again)."""
    c = RotorEzCodec()
    c.encode_query()
    assert c.feed(b";18") == []
    c.expire_query()
    c.encode_query()
    got = c.feed(b"0;123")
    assert not [r for r in got if isinstance(r, PositionReply)]
    assert JunkReply(b";18", JunkReason.NOISE, "a frame begun before the query") in got
    c.encode_query()
    assert c.feed(b";123") == [PositionReply(123.0)]


def test_a_power_on_byte_after_a_frame_begun_before_the_query_is_still_one() -> None:
    """Rule 1 beside the power-on byte: the board power-cycled while its reply was half sent
    (``;0``, then 0xE0): the byte still says the board forgot its options."""
    c = RotorEzCodec()
    c.encode_query()
    assert c.feed(b";0\xe0") == []
    c.expire_query()
    c.encode_query()
    got = c.feed(b";123")
    assert JunkReply(b"\xe0", JunkReason.POWER_ON, "power-on byte") in got
    assert not [r for r in got if isinstance(r, PositionReply)]


@pytest.mark.parametrize("cut", range(1, len(BANNER)))
def test_a_banner_torn_after_a_whole_one_in_the_same_read_is_harmless_at_every_cut(
    cut: int,
) -> None:
    """Rule 5: the two stops' banners read in one quiet spell, the second torn by the read
    (``C2000 IDIOM V1.4S C2000 IDIOM ``): seen in CI on R/error as "controller sent 30 bytes
    that are no valid reply" when a lock ON reached an idle board (the session's stop and the
    express's). Whole banners before the piece (a power-on byte too), and the rest after it."""
    codec = RotorEzCodec()
    first = junk_of(codec, b"\xe0" + BANNER * 2 + BANNER[:cut])
    assert first == b"\xe0" + BANNER * 2 + BANNER[:cut] and codec.harmless(first)
    assert codec.harmless(junk_of(codec, BANNER[cut:]))
    assert not codec.harmless(junk_of(codec, BANNER + b"C2000 IDX"))


@pytest.mark.parametrize("stop", STOPS)
@pytest.mark.parametrize("how", HOW)
def test_a_polls_answer_after_its_time_is_told_nowhere_and_is_no_reading(
    stop: str, how: str
) -> None:
    """Rule 7: a bearing frame after its query was given up is its late answer, said so (the
    engine learns from it how late the board answers; before, an RT-21's was, a Rotor-EZ's
    not, and a board that answered every poll late was 'not answering'): never a reading."""
    codec = RotorEzCodec()
    given_up(codec, stop)
    assert [r.az_deg for r in feed(codec, b";052", how) if isinstance(r, PositionReply)] == [52]
    replies = feed(codec, b";053", how)
    assert [(type(r), r.late) for r in replies if isinstance(r, JunkReply)] == [(JunkReply, True)]
    assert len(replies) == 1 and codec.harmless(b";053")
    replies = feed(codec, b";054", how)  # owed by no query: no late answer
    assert len(replies) == 1 and isinstance(replies[0], JunkReply) and not replies[0].late
    codec.encode_query()
    assert [r.az_deg for r in feed(codec, b";055", how) if isinstance(r, PositionReply)] == [55]
