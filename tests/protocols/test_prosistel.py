"""Prosistel codec: the frames byte for byte (STX, unit, command, CR; whole degrees on a D,
tenths on the Combi-Track; the hard stop; the continuous output turned off at open); positions
whole, bytewise and amid junk; the Combi-Track's two lines in either order; the box's answers,
its unasked positions and its errors never read as a bearing."""

from __future__ import annotations

import re

import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from bridge.protocols import REGISTRY
from bridge.protocols.base import (
    HamlibRotType,
    JunkReason,
    JunkReply,
    PositionReply,
    RetargetPolicy,
)
from bridge.protocols.prosistel import (
    COMBI_TRACK,
    D_AZIMUTH,
    D_ELEVATION,
    D_ELEVATION_UNIT_A,
    Family,
    ProsistelCodec,
)
from tests.support import HOW, feed
from tests.support.codecs import STOPS, given_up

D, COMBI = D_AZIMUTH, COMBI_TRACK


def positions(replies: list[object]) -> list[tuple[float, float | None]]:
    return [(r.az_deg, r.el_deg) for r in replies if isinstance(r, PositionReply)]


def junk(replies: list[object]) -> list[JunkReply]:
    return [r for r in replies if isinstance(r, JunkReply)]


def asked(family: Family = D) -> ProsistelCodec:
    codec = ProsistelCodec(family)
    codec.encode_query()
    return codec


def test_frames_on_the_wire() -> None:
    d, combi = ProsistelCodec(D), ProsistelCodec(COMBI)
    assert d.encode_target(123.4) == [b"\x02AG123\r"]  # whole degrees, as Hamlib sends them
    assert d.encode_target(7.5) == [b"\x02AG8\r"]  # half up, no leading zeros
    assert combi.encode_target(100.25, 45.0) == [b"\x02AG1003\r", b"\x02BG450\r"]  # tenths
    assert combi.encode_target(0, None) == [b"\x02AG0\r", b"\x02BG0\r"]
    assert d.encode_query() == b"\x02A?\r"
    assert combi.encode_query() == b"\x02A?\r\x02B?\r"
    assert d.encode_stop() == b"\x02AG999\r"  # the hard stop
    assert combi.encode_stop() == b"\x02AG9999\r\x02BG9999\r"
    assert d.encode_connect(0.0) == [b"\x02AS\r"]  # no continuous position output
    assert combi.encode_connect(0.0) == [b"\x02AS\r\x02BS\r"]
    assert (d.encode_version(), d.encode_enable()) == (None, None)
    with pytest.raises(ValueError, match="no options"):
        d.encode_option("jam", True)


def test_a_d_on_an_elevation_rotor_speaks_as_unit_e_within_0_to_90() -> None:
    codec = ProsistelCodec(D_ELEVATION)
    assert codec.encode_target(45.4) == [b"\x02EG45\r"]
    assert (codec.encode_query(), codec.encode_stop()) == (b"\x02E?\r", b"\x02EG999\r")
    assert codec.encode_connect(0.0) == [b"\x02ES\r"]
    with pytest.raises(ValueError, match="bearing 90.6 outside 0..90"):
        codec.encode_target(90.6)
    got = codec.feed(b"\x02E,?,094,B\r")  # past its 90 by more than the slack (rule 1)
    assert positions(got) == [] and junk(got)[0].reason is JunkReason.SPOILED
    got = asked(D_ELEVATION).feed(b"\x02A,?,045,B\r")  # an azimuth box on the line
    assert positions(got) == [] and "is the model right?" in junk(got)[0].detail


def test_a_d_on_an_elevation_rotor_set_up_as_unit_a_speaks_as_unit_a_within_0_to_90() -> None:
    """Hamlib's 1704 (D elevation CBOX az): unit A's frames, an elevation rotor's range."""
    codec = ProsistelCodec(D_ELEVATION_UNIT_A)
    assert codec.encode_target(45.4) == [b"\x02AG45\r"]
    assert codec.encode_target(89.5) == [b"\x02AG90\r"]  # half up, within 0..90
    assert (codec.encode_query(), codec.encode_stop()) == (b"\x02A?\r", b"\x02AG999\r")
    assert codec.encode_connect(0.0) == [b"\x02AS\r"]
    for deg in (90.6, -0.6, 180.0):
        with pytest.raises(ValueError, match=f"bearing {deg:g} outside 0..90"):
            codec.encode_target(deg)
    assert codec.wire_target(12.5) == (13.0, None)
    got = asked(D_ELEVATION_UNIT_A).feed(b"\x02A,?,094,B\r")  # above an elevation's 93
    assert positions(got) == [] and junk(got)[0].reason is JunkReason.SPOILED
    got = asked(D_ELEVATION_UNIT_A).feed(b"\x02E,?,045,B\r")  # a unit-E box on the line
    assert positions(got) == [] and "is the model right?" in junk(got)[0].detail
    got = asked(D_ELEVATION_UNIT_A).feed(b"\x02A,?,0450,B\r")  # a Combi-Track's tenths
    assert positions(got) == [] and "is the model right?" in junk(got)[0].detail
    codec = asked(D_ELEVATION_UNIT_A)
    got = codec.feed(b"\x02A,S,B\r\x02A,G,R\r\x02A,?,090,B\r")  # answers, then the position
    assert positions(got) == [(90.0, None)]
    assert {j.reason for j in junk(got)} == {JunkReason.CHATTER}


def test_targets_outside_what_the_box_takes_are_refused_before_sending() -> None:
    d, combi = ProsistelCodec(D), ProsistelCodec(COMBI)
    for az in (360.5, -0.6, 997, 999):
        with pytest.raises(ValueError, match="outside"):
            d.encode_target(az)
    with pytest.raises(ValueError, match="elevation 90.1 outside 0..90"):
        combi.encode_target(10, 90.1)
    assert d.wire_target(359.6) == (360.0, None)
    assert combi.wire_target(12.34, 5.06) == (12.3, 5.1)


@pytest.mark.parametrize("how", HOW)
@pytest.mark.parametrize(
    ("family", "reply", "want"),
    [
        (D, b"\x02A,?,290,R\r", (290.0, None)),
        (D, b"\x02A,?,7,B\r", (7.0, None)),
        (D_ELEVATION, b"\x02E,?,045,R\r", (45.0, None)),  # the elevation is the bearing
        (D_ELEVATION_UNIT_A, b"\x02A,?,45,R\r", (45.0, None)),  # ... on unit A too
        (COMBI, b"\x02A,?,1000,R\r\x02B,?,0900,B\r", (100.0, 90.0)),
        (COMBI, b"\x02B,?,0455,R\r\x02A,?,3600,R\r", (360.0, 45.5)),  # either order
    ],
)
def test_positions_in_their_forms(how: str, family: Family, reply: bytes, want: object) -> None:
    codec = asked(family)
    got = feed(codec, reply, how)
    assert positions(got) == [want] and not codec.awaiting_reply()
    assert [j.reason for j in junk(got)] == []


def test_the_answers_to_commands_are_harmless_chatter() -> None:
    codec = asked()
    got = codec.feed(b"\x02A,S,B\r\x02A,G,R\r\x02A,G,123,R\r\x02A,?,045,R\r")
    assert positions(got) == [(45.0, None)]
    assert {j.reason for j in junk(got)} == {JunkReason.CHATTER}
    assert codec.harmless(b"\x02A,S,B\r\x02A,G,R\r\r\n")


def test_positions_nobody_asked_for_are_harmless_and_never_read() -> None:
    codec = ProsistelCodec(D)
    stream = b"\x02A,?,200,B\r" * 3  # a box sending its position unasked
    got = codec.feed(stream)
    assert positions(got) == [] and {j.reason for j in junk(got)} == {JunkReason.CHATTER}
    assert codec.harmless(stream)
    codec.encode_query()
    got = codec.feed(b"\x02A,?,201,B\r\x02A,?,201,B\r")  # the answer, then the stream's line
    assert positions(got) == [(201.0, None)] and junk(got)[0].reason is JunkReason.CHATTER


def test_a_position_the_box_cannot_say_is_never_harmless() -> None:
    """Rule 2: only the box's own positions are chatter (its unit, its width, in range)."""
    for family, line in (
        (D, b"\x02A,?,364,B\r"),
        (D, b"\x02A,?,0200,B\r"),
        (D, b"\x02B,?,045,B\r"),
        (COMBI, b"\x02B,?,0906,B\r"),
        (COMBI, b"\x02A,?,200,B\r"),
        (D_ELEVATION, b"\x02E,?,094,B\r"),
    ):
        codec = ProsistelCodec(family)
        assert not codec.harmless(line) and positions(codec.feed(line)) == [], line
    assert ProsistelCodec(COMBI).harmless(b"\x02B,?,0900,B\r\x02A,?,3600,R\r")


def test_the_combi_tracks_second_line_of_one_unit_waits_for_the_other() -> None:
    codec = asked(COMBI)
    assert positions(codec.feed(b"\x02A,?,0100,R\r\x02A,?,0101,R\r")) == []
    assert codec.awaiting_reply()
    assert positions(codec.feed(b"\x02B,?,0200,R\r")) == [(10.0, 20.0)]


@pytest.mark.parametrize("how", HOW)
def test_junk_before_a_reply_makes_it_untrusted(how: str) -> None:
    got = feed(asked(), b"#~\x02A,?,123,B\r", how)
    assert positions(got) == []
    assert [j.reason for j in junk(got)] == [JunkReason.NOISE, JunkReason.UNTRUSTED]
    got = feed(asked(), b"garbage\r\x02A,?,123,B\r", how)
    assert positions(got) == [] and junk(got)[-1].reason is JunkReason.UNTRUSTED


def test_errors_are_reported_and_not_harmless() -> None:
    codec = asked(COMBI)
    got = codec.feed(b"\x02B,?,E,00003\r")
    assert positions(got) == [] and junk(got)[0].reason is JunkReason.SPOILED
    assert "unit B answered ? with error 00003" in junk(got)[0].detail
    assert not codec.harmless(b"\x02A,G,E,00001\r")
    assert positions(codec.feed(b"\x02A,?,0100,R\r")) == []  # the exchange is spoiled
    d = asked()
    got = d.feed(b"\x02B,?,045,B\r")  # a unit this model has not got
    assert positions(got) == [] and "is the model right?" in junk(got)[0].detail


def test_an_error_to_a_ds_g_is_its_refusal_and_to_a_combi_tracks_unit_is_not() -> None:
    """Rule 3: a D's target is its one G; a Combi-Track's a G per unit, the other may turn."""
    got = ProsistelCodec(D_AZIMUTH).feed(b"\x02A,G,E,00001\r")
    assert [j.reason for j in junk(got)] == [JunkReason.REFUSED]
    assert "unit A answered G with error 00001" in junk(got)[0].detail
    got = ProsistelCodec(COMBI_TRACK).feed(b"\x02B,G,E,00001\r")
    assert [j.reason for j in junk(got)] == [JunkReason.SPOILED]
    got = ProsistelCodec(D_AZIMUTH).feed(b"\x02A,?,E,00003\r")  # a query's error: no refusal
    assert [j.reason for j in junk(got)] == [JunkReason.SPOILED]


def test_out_of_range_and_torn_replies_are_no_readings() -> None:
    for reply in (b"\x02A,?,364,B\r", b"\x02A,?,12345,B\r", b"\x02A,?,12,\r", b"\x02A?\r"):
        got = asked().feed(reply)
        assert positions(got) == [] and junk(got), reply
    got = asked(COMBI).feed(b"\x02A,?,0100,R\r\x02B,?,0906,R\r")  # elevation above 90.5
    assert positions(got) == [] and junk(got)[-1].reason is JunkReason.SPOILED


@pytest.mark.parametrize(("family", "tail"), [(D, b"?,050,B\r"), (COMBI, b"0,B\r")])
def test_the_tail_of_a_line_the_ports_opening_cut_is_harmless_only_as_the_first_line(
    family: Family, tail: bytes
) -> None:
    """Rule 1: a streaming box was mid-line when the port opened; its first line has no STX."""
    codec = ProsistelCodec(family)
    stream = tail + b"\x02A,S,B\r"
    got = codec.feed(stream)
    assert positions(got) == [] and {j.reason for j in junk(got)} == {JunkReason.CHATTER}
    assert codec.harmless(stream)
    got = codec.feed(tail)  # later, a line without its STX is noise, as ever
    assert [j.reason for j in junk(got)] == [JunkReason.NOISE] and not codec.harmless(tail)
    for first in (b"\xff0,B\r", b"garbage\r", b"A,?,12345,B\r"):  # no tail of a position
        got = ProsistelCodec(family).feed(first)
        assert [j.reason for j in junk(got)] == [JunkReason.NOISE], first
    codec = asked(family)  # a query it came in is not trusted
    width = 4 if family is COMBI else 3
    lines = [b"\x02%s,?,%0*d,B\r" % (u.encode(), width, 50) for u in family.units]
    got = codec.feed(tail + b"".join(lines))
    assert positions(got) == [] and junk(got)[-1].reason is JunkReason.UNTRUSTED


def test_an_expired_query_takes_no_late_reply() -> None:
    """Rule 7: its answer, owed late, is no reading (and spoils one held with it); the box's
    stream after it is chatter again (rule 2)."""
    codec = asked()
    codec.expire_query()
    got = codec.feed(b"\x02A,?,123,B\r")
    assert positions(got) == [] and junk(got)[0].reason is JunkReason.UNSOLICITED
    assert codec.harmless(b"\x02A,?,123,B\r")
    got = codec.feed(b"\x02A,?,124,B\r")
    assert positions(got) == [] and junk(got)[0].reason is JunkReason.CHATTER


@pytest.mark.parametrize("stop", STOPS)
@pytest.mark.parametrize("how", HOW)
def test_a_polls_answer_after_its_time_is_no_reading_nor_lets_the_older_stand(
    stop: str, how: str
) -> None:
    """Rule 7: a loaded host had a poll's answer and the next poll's come together; the older
    was taken as the newer poll's reading and the newer, chatter, spoiled nothing. Now the
    newer is owed late: UNSOLICITED (it spoils the held reading), harmless, no reading."""
    codec = ProsistelCodec(COMBI)
    given_up(codec, stop)
    older, newer = b"\x02A,?,0301,R\r\x02B,?,0000,B\r", b"\x02A,?,0331,R\r\x02B,?,0000,B\r"
    got = feed(codec, older + newer, how)
    assert positions(got) == [(30.1, 0.0)]  # (which: no line says)
    assert [j.reason for j in junk(got)] == [JunkReason.UNSOLICITED] * 2
    assert codec.harmless(newer)
    got = feed(codec, b"\x02A,?,0340,R\r", how)  # owed by no query: the box's own chatter
    assert positions(got) == [] and junk(got)[0].reason is JunkReason.CHATTER
    codec.encode_query()
    assert positions(feed(codec, b"\x02B,?,0000,B\r\x02A,?,0350,R\r", how)) == [(35.0, 0.0)]


def test_a_line_without_end_is_given_up_once_too_long() -> None:
    codec = asked()
    got = codec.feed(b"\x02A,?," + b"1" * 40)
    assert positions(got) == [] and junk(got)[0].reason is JunkReason.NOISE
    assert positions(asked().feed(b"\x02A,?,008,B\r")) == [(8.0, None)]


@given(before=st.binary(max_size=40), value=st.integers(0, 360), chunk=st.integers(1, 8))
def test_noise_before_a_reply_never_yields_another_bearing(
    before: bytes, value: int, chunk: int
) -> None:
    # noise that is itself a whole position line cannot be told from one (the engine's settle
    # rule catches the second reply of the exchange); anything else must not read
    assume(not re.search(rb"\x02A,\?,\d{1,4},[A-Z]\r", before))
    data = before + b"\x02A,?,%03d,B\r" % value
    codec = asked()
    got = [r for i in range(0, len(data), chunk) for r in codec.feed(data[i : i + chunk])]
    assert positions(got) in ([], [(float(value), None)])


def test_the_model_table() -> None:
    d, el, combi = REGISTRY["prosistel"], REGISTRY["prosistel-el"], REGISTRY["prosistel-combi"]
    assert (el.display_name, el.hamlib_model, el.hamlib_rot_type) == (
        "D elevation",
        1702,
        HamlibRotType.AZ,  # the rotctld port answers its elevation as its bearing
    )
    assert (el.az_max_deg, el.az_wraps, el.has_elevation, el.nominal_speed_deg_s) == (
        90.0,
        False,
        False,
        3.0,
    )
    el_a = REGISTRY["prosistel-el-a"]
    assert (el_a.display_name, el_a.hamlib_model, el_a.hamlib_rot_type) == (
        "D elevation (unit A)",
        1704,  # Hamlib's "D elevation CBOX az", an El rotator answered as an azimuth, as 1702
        HamlibRotType.AZ,
    )
    codec = el_a.codec_factory()
    assert isinstance(codec, ProsistelCodec) and codec.family is D_ELEVATION_UNIT_A
    for name in ("az_max_deg", "az_wraps", "has_elevation", "nominal_speed_deg_s", "whole_degrees"):
        assert getattr(el_a, name) == getattr(el, name), name
    assert (el_a.query_bytes, el_a.reply_bytes) == (el.query_bytes, el.reply_bytes)
    assert d.az_wraps and (d.az_max_deg, combi.az_max_deg) == (360.0, 360.0)
    assert (d.manufacturer, d.display_name, d.baud) == ("Prosistel", "D azimuth", 9600)
    assert (combi.display_name, combi.baud) == ("Combi-Track az/el", 9600)
    assert (d.hamlib_model, d.hamlib_rot_type) == (1701, HamlibRotType.AZ)
    assert (combi.hamlib_model, combi.hamlib_rot_type) == (1703, HamlibRotType.AZEL)
    assert not d.has_elevation and combi.has_elevation and combi.el_max_deg == 90.0
    assert d.whole_degrees and not combi.whole_degrees
    assert d.retarget is RetargetPolicy.DIRECT and d.brake_delay_s == 0.0
    assert (d.query_bytes, d.reply_bytes) == (len(b"\x02A?\r"), len(b"\x02A,?,123,B\r"))
    assert (combi.query_bytes, combi.reply_bytes) == (8, 2 * len(b"\x02A,?,1234,B\r"))


@pytest.mark.parametrize(
    ("family", "answer", "driving"),
    [
        (D, b"\x02A,?,120,R\r", True),
        (D, b"\x02A,?,120,B\r", False),
        (D, b"\x02A,?,120,X\r", None),  # (a letter the sheet does not name says nothing)
        (COMBI, b"\x02A,?,1200,B\r\x02B,?,0300,R\r", True),  # (one unit's motor runs)
        (COMBI, b"\x02B,?,0300,B\r\x02A,?,1200,B\r", False),
        (COMBI, b"\x02A,?,1200,B\r\x02B,?,0300,X\r", None),
    ],
)
def test_a_reading_says_whether_the_box_drives_a_motor(
    family: Family, answer: bytes, driving: bool | None
) -> None:
    """Rule 8: the position's last letter, running or braked (base.py rule 8)."""
    codec = ProsistelCodec(family)
    codec.encode_query()
    [reading] = [r for r in codec.feed(answer) if isinstance(r, PositionReply)]
    assert reading.driving is driving
