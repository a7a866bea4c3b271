"""M2 RC2800 codec: the commands byte for byte, split into each axis's frames in the order the
link paces them; the reply forms Hamlib reads (``A P=  98.1 S=9 MV``, ``E=43.7 S=9 M``) whole,
bytewise and split; an echo is never a reply; a line streamed unasked updates the bearing once
every axis has had a well-formed one; junk never becomes a reading."""

from __future__ import annotations

import re

import pytest
from hypothesis import given
from hypothesis import strategies as st

from bridge.protocols import REGISTRY
from bridge.protocols.base import JunkReason, JunkReply, PositionReply, RetargetPolicy
from bridge.protocols.rc2800 import Rc2800Codec
from tests.support import HOW, feed
from tests.support.codecs import given_up


def positions(replies: list[object]) -> list[tuple[float, float | None]]:
    return [(r.az_deg, r.el_deg) for r in replies if isinstance(r, PositionReply)]


def junk(replies: list[object]) -> list[JunkReply]:
    return [r for r in replies if isinstance(r, JunkReply)]


def test_commands_on_the_wire_one_frame_per_axis() -> None:
    azel, az = Rc2800Codec(), Rc2800Codec(elevation=False)
    assert azel.encode_target(123.45, 45) == [b"A123.5\r", b"E45.0\r"]  # tenths, half up
    assert az.encode_target(5) == [b"A5.0\r"]
    assert azel.encode_query() == [b"A\r", b"E\r"] and az.encode_query() == [b"A\r"]
    assert azel.encode_stop() == [b"A\rS\r", b"E\rS\r"]  # select the axis, stop it
    assert az.encode_stop() == [b"A\rS\r"]
    for codec in (azel, az):
        assert (codec.encode_version(), codec.encode_connect(0.0), codec.encode_enable()) == (
            None,
            [],
            None,
        )
    with pytest.raises(ValueError, match="no options"):
        azel.encode_option("jam", True)


def test_targets_outside_what_the_box_takes_are_refused_before_sending() -> None:
    for az, el in ((360.1, 0), (-0.1, 0), (10, 180.1), (10, -1)):
        with pytest.raises(ValueError, match="outside"):
            Rc2800Codec().encode_target(az, el)
    assert Rc2800Codec().wire_target(359.95, 0.04) == (360.0, 0.0)


def test_the_spec_paces_the_two_axes_and_not_the_lone_azimuth() -> None:
    azel, az = REGISTRY["rc2800"], REGISTRY["rc2800-az"]
    assert (azel.axis_gap_s, az.axis_gap_s) == (0.2, 0.0)
    assert (azel.baud, azel.has_elevation, az.has_elevation) == (9600, True, False)
    assert azel.retarget is RetargetPolicy.DIRECT and azel.reply_timeout_s >= 0.2 + 0.1


@pytest.mark.parametrize("how", HOW)
@pytest.mark.parametrize(
    ("az_line", "el_line", "want"),
    [
        (b"A P=  98.1 S=9 MV\r", b"E P=  12.5 S=9 MV\r", (98.1, 12.5)),
        (b"A P= 100.0 S=9 ST\r\n", b"E P=   0.0 S=4 ST\r\n", (100.0, 0.0)),  # CR LF
        (b"A=43.7 S=9 M\n", b"E=42.8 S=9 S\n", (43.7, 42.8)),  # the older form
        (b"A=359\r", b"E=-0.4\r", (359.0, -0.4)),  # a pot a little below the horizon
    ],
)
def test_a_query_reads_each_axis_line(
    az_line: bytes, el_line: bytes, want: tuple[float, float], how: str
) -> None:
    codec = Rc2800Codec()
    codec.encode_query()
    assert positions(feed(codec, az_line, how)) == []  # the elevation is still to come
    assert codec.awaiting_reply()
    assert positions(feed(codec, el_line, how)) == [want]
    assert not codec.awaiting_reply()


def test_an_echo_is_no_reply_and_harmless() -> None:
    codec = Rc2800Codec()
    codec.encode_query()
    out = feed(codec, b"A\rA P=  98.1 S=9 MV\rE\r")
    assert positions(out) == [] and codec.awaiting_reply()  # "E" echoed is not the elevation
    assert [j.reason for j in junk(out)] == [JunkReason.CHATTER, JunkReason.CHATTER]
    assert positions(feed(codec, b"E P=  10.0 S=9 ST\r")) == [(98.1, 10.0)]
    assert codec.harmless(b"A123.5\rA P= 123.5 S=9 MV\rE45.0\rS\r\r\n")


def test_the_stop_is_answered_by_both_axes_and_read_once() -> None:
    codec = Rc2800Codec()
    codec.encode_stop()
    out = feed(codec, b"A P=  50.0 S=9 MV\rA P=  50.2 S=9 ST\rE P=  10.0 S=9 MV\r")
    assert positions(out) == [] and codec.awaiting_reply()
    assert positions(feed(codec, b"E P=  10.1 S=9 ST\r")) == [(50.2, 10.1)]


@pytest.mark.parametrize("how", HOW)
def test_a_query_whose_elevation_came_in_the_exchange_before_is_read_at_its_azimuth(
    how: str,
) -> None:
    """Rule 2: a line lost from each of two polls in a row (the azimuth's of the first, the
    elevation's of the second: a line that drops a second in three) leaves both axes heard,
    whole, within two exchanges: that is a reading, made at the azimuth's line. An elevation
    older than the exchange before is not carried: a reading is never that stale."""
    codec = Rc2800Codec()
    codec.encode_query()  # its azimuth's answer lost
    assert positions(feed(codec, b"E P=  20.0 S=9 MV\r", how)) == []
    codec.expire_query()
    codec.encode_query()  # its elevation's answer lost
    assert positions(feed(codec, b"A P= 150.0 S=9 MV\r", how)) == [(150.0, 20.0)]
    assert not codec.awaiting_reply()  # that answered this poll; its E line, if it comes,
    assert positions(feed(codec, b"E P=  21.0 S=9 MV\r", how)) == [(150.0, 21.0)]  # is read

    stale = Rc2800Codec()
    stale.encode_query()
    feed(stale, b"E P=  20.0 S=9 MV\r", how)
    for _ in range(2):  # two exchanges that heard nothing
        stale.expire_query()
        stale.encode_query()
    assert positions(feed(stale, b"A P= 150.0 S=9 MV\r", how)) == []
    assert stale.awaiting_reply()  # the elevation of this poll is still owed
    assert positions(feed(stale, b"E P=  30.0 S=9 MV\r", how)) == [(150.0, 30.0)]


@pytest.mark.parametrize("how", HOW)
def test_after_a_query_read_at_its_azimuth_a_clean_line_reads_each_polls_own_elevation(
    how: str,
) -> None:
    """Rule 2, a review of 644adc4: once one azimuth line was lost, the elevation's answer to
    the poll read early at its azimuth was kept and carried into the next poll, which was read
    at its azimuth again: on a clean line from then on every reading's elevation was the poll
    before's (an elevation turning at 3 degrees a second shown a poll late, for good)."""
    codec = Rc2800Codec()
    codec.encode_query()  # its azimuth's answer lost
    feed(codec, b"E P=  20.0 S=9 MV\r", how)
    codec.expire_query()
    codec.encode_query()
    assert positions(feed(codec, b"A P= 150.0 S=9 MV\r", how)) == [(150.0, 20.0)]
    late = positions(feed(codec, b"E P=  21.0 S=9 MV\r", how))  # this poll's own, whole
    for az, el in ((151.0, 22.0), (152.0, 23.0)):  # the line clean again
        codec.encode_query()
        read = positions(feed(codec, b"A P= %.1f S=9 MV\r" % az, how))
        read += positions(feed(codec, b"E P=  %.1f S=9 MV\r" % el, how))
        assert read and read[-1] == (az, el), read
    assert late == [(150.0, 21.0)]


@pytest.mark.parametrize("how", HOW)
def test_an_elevation_from_an_exchange_with_line_noise_is_never_carried_into_a_reading(
    how: str,
) -> None:
    """Rules 1 and 2, a review of 644adc4: a reading of an exchange that had line noise is
    untrusted (a line after noise may be a mangled one). An elevation heard in such an exchange
    was carried into the next poll and read there, trusted, at its azimuth."""
    codec = Rc2800Codec()
    feed(codec, b"A\r")  # (not the connection's first line: that may be a cut one, rule 1)
    codec.encode_query()  # its azimuth's answer lost, and noise on the line
    out = feed(codec, b"P= 1 S=9\rE P=  20.0 S=9 MV\r", how)
    assert any(r.reason is JunkReason.NOISE for r in junk(out))
    codec.expire_query()
    codec.encode_query()
    assert positions(feed(codec, b"A P= 150.0 S=9 MV\r", how)) == []
    assert codec.awaiting_reply()  # this poll's own elevation is owed
    assert positions(feed(codec, b"E P=  30.0 S=9 MV\r", how)) == [(150.0, 30.0)]


@pytest.mark.parametrize("how", HOW)
def test_a_polls_answer_after_its_time_is_no_reading_nor_lets_the_older_stand(how: str) -> None:
    """Rule 6: a loaded host had a poll's answer and the next poll's come together; the older
    made the newer poll's reading, and the newer, kept as the box's stream, spoiled nothing
    (the bearing published 6 degrees behind). Now the newer is owed late: UNSOLICITED (it
    spoils the held reading), harmless, never a reading nor kept for one."""
    codec = Rc2800Codec()
    given_up(codec, "none")
    older = b"A P=  30.4 S=9 MV\rE P=   0.0 S=9 ST\r"
    newer = b"A P=  36.4 S=9 MV\rE P=   0.0 S=9 ST\r"
    out = feed(codec, older + newer, how)
    assert positions(out) == [(30.4, 0.0)]  # (which: no line says)
    assert [j.reason for j in junk(out)] == [JunkReason.UNSOLICITED] * 2
    assert codec.harmless(newer)
    out = feed(codec, b"A P=  37.0 S=9 MV\r", how)  # owed by none: the box's stream, kept
    assert positions(out) == [] and junk(out)[0].reason is JunkReason.CHATTER
    assert positions(feed(codec, b"E P=   0.0 S=9 ST\r", how)) == [(37.0, 0.0)]


@pytest.mark.parametrize("tail", [b"50.0 S=9 ST\r", b"P=  50.0 S=9 MV\r", b"=9 ST\r", b"T\r"])
def test_the_tail_of_a_line_the_ports_opening_cut_is_harmless_only_as_the_first_line(
    tail: bytes,
) -> None:
    """Rule 1: a streaming box was mid-line when the port opened: no reading, no error, but a
    query it came in is not trusted; later, the same bytes are noise."""
    codec = Rc2800Codec()
    stream = tail + b"E P=  10.0 S=9 ST\r"
    out = feed(codec, stream)
    assert positions(out) == [] and {j.reason for j in junk(out)} == {JunkReason.CHATTER}
    assert codec.harmless(stream)
    out = feed(codec, tail)
    assert [j.reason for j in junk(out)] == [JunkReason.NOISE] and not codec.harmless(tail)
    asked = Rc2800Codec(elevation=False)
    asked.encode_query()
    out = feed(asked, tail + b"A P=  50.0 S=9 ST\r")
    assert positions(out) == [] and junk(out)[-1].reason is JunkReason.UNTRUSTED
    for first in (b"\xff9 ST\r", b"garbage\r", b"9 ST X\r"):  # no tail of a position line
        assert [j.reason for j in junk(feed(Rc2800Codec(), first))] == [JunkReason.NOISE]


def test_a_position_out_of_range_is_never_harmless() -> None:
    """Rule 3: a position line is chatter only in its axis's range."""
    codec = Rc2800Codec()
    for line in (b"A P= 361.0 S=9 ST\r", b"A P= -0.6\r", b"E P= 180.6\r", b"E=-90.6\r"):
        assert not codec.harmless(line), line
    assert codec.harmless(b"A P= 360.0 S=9 ST\rE P= -90.0 S=9 ST\rE=180.0\r")


@pytest.mark.parametrize("how", HOW)
def test_a_polls_answer_after_its_time_with_no_exchange_since_is_the_newest_reading(
    how: str,
) -> None:
    """Rule 6: the lines of an exchange given up that come before any other is opened are the
    newest the box has said: kept as its stream (rule 2), a reading, and no longer owed. (A
    box always a little later than the reply time, polled every 2 s: each answer was owed
    late and dropped, no reading came, and the rotator went offline, its turn stopped.)"""
    codec = Rc2800Codec()
    codec.encode_query()
    codec.expire_query()
    out = feed(codec, b"A P=  30.4 S=9 MV\rE P=   0.0 S=9 ST\r", how)
    assert positions(out) == [(30.4, 0.0)] and codec.harmless(b"")
    assert all(j.reason is JunkReason.CHATTER for j in junk(out))
    codec.encode_query()  # the next poll's answer is its own
    assert positions(feed(codec, b"A P=  36.4 S=9 MV\rE P=   0.0 S=9 ST\r", how)) == [(36.4, 0.0)]


def test_lines_nobody_asked_for_update_the_bearing_once_every_axis_has_spoken() -> None:
    codec = Rc2800Codec()
    out = feed(codec, b"A P= 200.0 S=9 MV\r")
    assert positions(out) == [] and junk(out)[0].reason is JunkReason.CHATTER  # kept
    assert positions(feed(codec, b"E P=  30.0 S=9 MV\r")) == [(200.0, 30.0)]
    assert positions(feed(codec, b"E P=  31.0 S=9 MV\r")) == []  # the azimuth must speak again
    assert positions(feed(codec, b"A P= 201.0 S=9 MV\r")) == [(201.0, 31.0)]
    lone = Rc2800Codec(elevation=False)
    assert positions(feed(lone, b"A P=  77.7 S=9 ST\rA P=  77.8 S=9 ST\r")) == [
        (77.7, None),
        (77.8, None),
    ]


@pytest.mark.parametrize(
    "bad",
    [
        b"A P=  98",  # torn: no line end yet, then noise
        b"A P= 98.1 S=9 MVX\r",
        b"X P=  98.1 S=9 MV\r",
        b"A P= 1234.5 S=9 MV\r",
        b"\xffA P=  98.1 S=9 MV\r",  # noise in front of it on its line
    ],
)
def test_an_ill_formed_line_changes_nothing(bad: bytes) -> None:
    codec = Rc2800Codec(elevation=False)
    out = feed(codec, bad + b"\xfe\r")
    assert positions(out) == [] and not codec.harmless(bad + b"\xfe\r")
    assert any(j.reason is JunkReason.NOISE for j in junk(out))


@pytest.mark.parametrize("ask", [True, False])
@pytest.mark.parametrize("cut", [0, 65, 70])
def test_the_tail_of_a_line_too_long_is_no_reading_however_the_bytes_came(
    cut: int, ask: bool
) -> None:
    """Rule 1: noise without a line end past _MAX_LINE, then a position's bytes on the same
    line: one line, noise; read whole (cut 0) or with the noise given up first, no bearing,
    asked or streamed by the box (rule 2: unasked lines are read too). Asked, the exchange is
    spoiled, not ended: its answer may still come (and is then untrusted)."""
    stream = b"x" * 70 + b"A P=  98.1 S=9 MV\r"
    codec = Rc2800Codec(elevation=False)
    if ask:
        codec.encode_query()
    replies = codec.feed(stream[:cut]) + codec.feed(stream[cut:]) if cut else codec.feed(stream)
    assert positions(replies) == []
    assert {j.reason for j in junk(replies)} == {JunkReason.NOISE}
    assert b"".join(j.data for j in junk(replies)) == stream  # each byte said once
    assert codec.awaiting_reply() is ask
    if ask:
        late = codec.feed(b"A P=  98.2 S=9 MV\r")
        assert positions(late) == [] and junk(late)[0].reason is JunkReason.UNTRUSTED
    codec.encode_query()
    assert positions(codec.feed(b"A P=  98.2 S=9 MV\r")) == [(98.2, None)]  # the next line is


@pytest.mark.parametrize("how", HOW)
def test_a_line_is_read_up_to_64_bytes_and_one_longer_is_noise(how: str) -> None:
    """Rule 1's bound (_MAX_LINE, 64 bytes before the line's end): a position padded to 64 is
    read, padded to 65 it is noise, however the bytes come; so is one with blanks in front."""
    line = b"A P=  98.1 S=9 MV"
    for padded, read in (
        (line.ljust(64), [(98.1, None)]),
        (line.ljust(65), []),
        (line.rjust(65), []),
        (b"A P=  98.1" + b"0" * 60, []),
    ):
        codec = Rc2800Codec(elevation=False)
        codec.encode_query()
        assert positions(feed(codec, padded + b"\r", how)) == read, padded


def test_out_of_range_is_spoiled_an_error_is_reported_and_noise_spoils_the_exchange() -> None:
    codec = Rc2800Codec()
    out = feed(codec, b"A P= 361.0 S=9 MV\rE P= 181.0 S=9 MV\r")
    assert positions(out) == [] and {j.reason for j in junk(out)} == {JunkReason.SPOILED}
    (err,) = junk(feed(codec, b"A ERR=2\r"))
    # rule 1: the az/el box's error refuses one axis's frame, no target; the azimuth box's does
    assert err.reason is JunkReason.CHATTER and "error 2" in err.detail
    assert not codec.harmless(b"A ERR=2\r")
    (err,) = junk(feed(Rc2800Codec(elevation=False), b"A ERR=2\r"))
    assert err.reason is JunkReason.REFUSED and "error 2" in err.detail
    codec.encode_query()
    out = feed(codec, b"A P=  10.0 S=9 MV\rgarbage\rE P=  20.0 S=9 MV\r")
    assert positions(out) == [] and junk(out)[-1].reason is JunkReason.UNTRUSTED
    codec.encode_query()  # asked again: believed
    assert positions(feed(codec, b"A P=  10.0 S=9 MV\rE P=  20.0 S=9 MV\r")) == [(10.0, 20.0)]


_PIECES = st.one_of(
    st.binary(max_size=20),
    st.builds(
        lambda axis, deg, state: b"%c P=%6.1f S=9 %s\r" % (axis, deg, state),
        st.sampled_from(b"AE"),
        st.floats(-100, 400).map(lambda d: round(d, 1)),
        st.sampled_from([b"MV", b"ST"]),
    ),
    st.sampled_from([b"A\r", b"E\r", b"S\r", b"A123.4\r", b"\r\n", b"A ERR=5\r", b"A P= "]),
    st.builds(  # a run past rule 1's bound, or just inside it, ended or not
        lambda fill, n, end: fill * n + end,
        st.sampled_from([b"x", b" ", b"0"]),
        st.integers(55, 90),
        st.sampled_from([b"", b"\r", b"\n"]),
    ),
)


@given(pieces=st.lists(st.tuples(st.booleans(), _PIECES), max_size=20), el=st.booleans())
def test_any_stream_gives_the_same_readings_however_sliced_and_none_it_did_not_carry(
    pieces: list[tuple[bool, bytes]], el: bool
) -> None:
    def run(how: str) -> list[tuple[float, float | None]]:
        codec = Rc2800Codec(elevation=el)
        out: list[object] = []
        for ask, data in pieces:
            if ask:
                codec.encode_query()
            out += feed(codec, data, how)
        return positions(out)

    whole = run("whole")
    assert run("bytewise") == whole and run("split") == whole
    stream = b"".join(data for _, data in pieces)
    # a reading's value was on a whole line of its axis (from a line end to the next), in a
    # form rule 1 takes: ``A P=  98.1 S=9 MV``, ``E=43.7``, whole numbers too (``A P=0`` from
    # raw bytes is 0.0; more lenient than Hamlib's parser, which wants the decimals' columns)
    sp = rb"[ \t\f\v]"
    line = rb"(?:^|(?<=[\r\n]))%s*([AE])(?: P)?=%s*(-?\d{1,3}(?:\.\d+)?)" % (sp, sp)
    line += rb"(?:%s+S=\d+)?(?:%s+[A-Z]{1,2})?%s*[\r\n]" % (sp, sp, sp)
    lines = {
        (m.group(1), float(m.group(2)))
        for m in re.finditer(line, stream)
        if len(m.group()) <= 64 + 1  # rule 1: 64 bytes and the line's end, at most
    }
    for az, elev in whole:
        assert (b"A", az) in lines and 0 <= az <= 360
        assert (elev is None) is (not el) and (elev is None or (b"E", elev) in lines)
        assert elev is None or -90 <= elev <= 180


@pytest.mark.parametrize(
    ("elevation", "lines", "driving"),
    [
        (False, b"A P= 120.0 S=9 MV\r", True),
        (False, b"A P= 120.0 S=9 ST\r", False),
        (False, b"A=120.0 S=9 M\r", True),  # (Hamlib's examples: M and S)
        (False, b"A=120.0 S=9 S\r", False),
        (False, b"A P= 120.0\r", None),  # (no state word: it says nothing)
        (True, b"A P= 120.0 S=9 ST\rE P=  30.0 S=9 MV\r", True),  # (one axis's motor runs)
        (True, b"A P= 120.0 S=9 ST\rE P=  30.0 S=9 ST\r", False),
        (True, b"A P= 120.0 S=9 ST\rE P=  30.0 S=9\r", None),
    ],
)
def test_a_reading_says_whether_the_box_drives_a_motor(
    elevation: bool, lines: bytes, driving: bool | None
) -> None:
    """Rule 7: each axis's state word (base.py rule 8)."""
    codec = Rc2800Codec(elevation=elevation)
    codec.encode_query()
    [reading] = [r for r in codec.feed(lines) if isinstance(r, PositionReply)]
    assert reading.driving is driving
