"""Green Heron RT-21 codec: the commands byte for byte (tenths, the CR that runs a heading, ``;``
to stop); the bearing reply unpadded, space- and zero-padded, whole, bytewise and amid junk; junk
never becomes a reading, and a reading after noise is not trusted."""

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
from bridge.protocols.rt21 import Rt21Codec
from tests.support import HOW, feed
from tests.support.codecs import STOPS, given_up


def positions(replies: list[object]) -> list[float]:
    return [r.az_deg for r in replies if isinstance(r, PositionReply)]


def junk(replies: list[object]) -> list[JunkReply]:
    return [r for r in replies if isinstance(r, JunkReply)]


def asked() -> Rt21Codec:
    codec = Rt21Codec()
    assert codec.encode_query() == b"BI1;"
    return codec


def test_commands_on_the_wire() -> None:
    codec = Rt21Codec()
    assert codec.encode_target(123.4) == [b"AP1123.4\r;"]  # one frame: the CR runs it
    assert codec.encode_target(5) == [b"AP1005.0\r;"]  # zero-padded, as Hamlib sends it
    assert codec.encode_target(12.35) == [b"AP1012.4\r;"]  # tenths, half up
    # north as the box takes it (rule 4: 0..359.9, Hamlib's caps), never 360.0
    assert codec.encode_target(359.96) == codec.encode_target(360) == [b"AP1000.0\r;"]
    assert codec.encode_stop() == b";"
    assert (codec.encode_version(), codec.encode_connect(0.0), codec.encode_enable()) == (
        None,
        [],
        None,
    )
    with pytest.raises(ValueError, match="no options"):
        codec.encode_option("jam", True)


def test_targets_outside_what_the_box_takes_are_refused_before_sending() -> None:
    codec = Rt21Codec()
    for az in (360.1, -0.1, 400):
        with pytest.raises(ValueError, match="outside"):
            codec.encode_target(az)
    assert codec.wire_target(359.95) == (0.0, None)  # rule 4: north is 000.0
    assert codec.wire_target(-0.04) == (0.0, None)
    assert codec.wire_target(77.77, 30) == (77.8, None)  # one axis: an elevation is not its


@pytest.mark.parametrize("how", HOW)
@pytest.mark.parametrize(
    ("reply", "want"),
    [
        (b"20.0;", 20.0),  # as a box answered Hamlib on the wire
        (b" 20.0;", 20.0),  # padded to five characters
        (b"  5.3;", 5.3),
        (b"005.3;", 5.3),  # zero-padded, as the protocol sheet writes it
        (b"359.9;", 359.9),
        (b"360.0;", 360.0),
        (b"0.0;", 0.0),
    ],
)
def test_the_bearing_reply_in_its_forms(how: str, reply: bytes, want: float) -> None:
    codec = asked()
    got = feed(codec, reply, how)
    assert positions(got) == [want] and junk(got) == []
    assert not codec.awaiting_reply()


@pytest.mark.parametrize("how", HOW)
def test_junk_before_a_reply_makes_it_untrusted(how: str) -> None:
    codec = asked()
    got = feed(codec, b"\xffx" + b"123.4;", how)
    assert positions(got) == []
    reasons = [j.reason for j in junk(got)]
    assert reasons[-1] is JunkReason.UNTRUSTED and JunkReason.NOISE in reasons
    assert not codec.awaiting_reply()  # the exchange is over: the engine asks again


@pytest.mark.parametrize("how", HOW)
def test_junk_is_reported_at_once_without_waiting_for_a_semicolon(how: str) -> None:
    codec = asked()
    got = feed(codec, b"garbage", how)
    assert positions(got) == [] and got
    assert all(j.reason is JunkReason.NOISE for j in junk(got))
    assert b"".join(j.data for j in junk(got)) == b"garbage"
    assert codec.awaiting_reply()


def test_a_reply_nobody_asked_for_is_no_reading() -> None:
    codec = Rt21Codec()
    (got,) = codec.feed(b"123.4;")
    assert isinstance(got, JunkReply) and got.reason is JunkReason.UNSOLICITED


def test_an_expired_query_takes_no_late_reply() -> None:
    codec = asked()
    codec.expire_query()
    assert positions(codec.feed(b"42.0;")) == []
    codec.encode_query()
    assert positions(codec.feed(b"43.0;")) == [43.0]


@pytest.mark.parametrize("stop", STOPS)
@pytest.mark.parametrize("how", HOW)
def test_a_polls_answer_after_its_time_is_told_nowhere_and_is_no_reading(
    stop: str, how: str
) -> None:
    """Rule 5: a loaded host had a poll's answer come after its reply time; the next poll took
    it, and that poll's own answer, right behind it, was told on R/error as no reply."""
    codec = Rt21Codec()
    given_up(codec, stop)
    assert positions(feed(codec, b"52.0;", how)) == [52.0]  # (which: no bearing says)
    replies = feed(codec, b" 53.0;", how)
    assert positions(replies) == [] and codec.harmless(b"53.0;")
    assert [j.reason for j in junk(replies)] == [JunkReason.UNSOLICITED]
    replies = feed(codec, b"54.0;", how)  # owed by no query: told
    assert positions(replies) == [] and not codec.harmless(b"54.0;")
    assert not codec.harmless(b"53.0;53.0;")  # the same again, owed by none: told
    assert not codec.harmless(b"53.0;#")  # junk is still junk
    codec.encode_query()
    assert positions(feed(codec, b"55.0;", how)) == [55.0]


def test_out_of_range_and_torn_replies_are_no_readings() -> None:
    codec = asked()
    got = codec.feed(b"360.1;")
    assert positions(got) == [] and junk(got)[0].reason is JunkReason.SPOILED
    for torn in (b"12;", b"12.;", b".5;", b"AZ;"):
        codec = asked()
        got = codec.feed(torn)
        assert positions(got) == [] and junk(got)[0].reason is JunkReason.NOISE, torn


def test_a_lone_semicolon_is_chatter_and_harmless() -> None:
    codec = asked()
    (got,) = codec.feed(b";")
    assert isinstance(got, JunkReply) and got.reason is JunkReason.CHATTER
    assert codec.harmless(b";") and codec.harmless(b" ;")
    assert not codec.harmless(b"garbage")
    assert positions(codec.feed(b"7.0;")) == [7.0]  # chatter spoils nothing


def test_a_reply_without_end_is_given_up_once_too_long() -> None:
    codec = asked()
    got = codec.feed(b"1" * 3 + b" " * 40)
    assert positions(got) == [] and junk(got)
    assert positions(asked().feed(b"8.5;")) == [8.5]


@given(
    before=st.binary(max_size=40),
    tenths=st.integers(0, 3600),
    chunk=st.integers(1, 8),
)
def test_noise_before_a_reply_never_yields_another_bearing(
    before: bytes, tenths: int, chunk: int
) -> None:
    reply = b"%d.%d;" % divmod(tenths, 10)
    # noise that is itself a whole reply cannot be told from one (the engine's settle rule
    # catches the second reply of the exchange), nor can digits that join the reply's own
    # ("1" before "0.0;" is the bytes of "10.0;"); anything else must not read
    assume(not re.search(rb"\d\.\d;", before) and not before[-1:].isdigit())
    data = before + reply
    codec = asked()
    got = [r for i in range(0, len(data), chunk) for r in codec.feed(data[i : i + chunk])]
    assert positions(got) in ([], [tenths / 10])


def test_what_is_left_before_a_query_begins_no_reply_of_it() -> None:
    """Rule 3: a digit left by noise before the query, or by a flipped ``;`` of the query
    before, is no first digit of this query's reply: it is noise, and the reply is asked
    again (not trusted)."""
    codec = Rt21Codec()
    codec.feed(b"\xfe3")  # idle line noise; the 3 could begin a bearing
    codec.encode_query()
    got = codec.feed(b"45.6;")
    assert positions(got) == []
    assert [(j.data, j.reason) for j in got if isinstance(j, JunkReply)] == [
        (b"3", JunkReason.NOISE),
        (b"45.6;", JunkReason.UNTRUSTED),
    ]
    codec.encode_query()
    assert positions(codec.feed(b"5.03")) == []  # "5.0;" with its ";" flipped to "3"
    codec.expire_query()
    codec.encode_query()
    assert positions(codec.feed(b"5.0;")) == []  # untrusted, never 35.0
    codec.encode_query()
    assert positions(codec.feed(b" ")) == []  # padding of a reply cut short: no noise
    codec.expire_query()
    codec.encode_query()
    assert positions(codec.feed(b" 20.0;")) == [20.0]


def test_the_model_table() -> None:
    spec = REGISTRY["rt21"]
    assert (spec.manufacturer, spec.display_name, spec.baud) == ("Green Heron", "RT-21", 4800)
    assert (spec.hamlib_model, spec.hamlib_rot_type, spec.hamlib_info) == (
        405,
        HamlibRotType.OTHER,
        None,
    )
    assert spec.has_elevation is False and spec.can_report_position
    assert (spec.az_min_deg, spec.az_max_deg, spec.az_wraps) == (0.0, 360.0, True)
    assert spec.retarget is RetargetPolicy.DIRECT and spec.brake_delay_s == 0.0
    assert spec.whole_degrees is False  # tenths both ways
    assert (spec.query_bytes, spec.reply_bytes) == (len(b"BI1;"), len(b"123.4;"))
