"""Easycomm II/III codec (the controller side): the commands byte for byte; the reply forms on one
line or two, with and without spaces and decimals, whole, bytewise and amid junk; alarms, blank
lines and radio words never become readings; III's version at connect."""

from __future__ import annotations

import re

import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from bridge.protocols import REGISTRY
from bridge.protocols.base import (
    HamlibRotType,
    JunkReason,
    JunkReply,
    PositionReply,
    VersionReply,
)
from bridge.protocols.easycomm import UNASKED_POLLS, EasycommCodec
from tests.support import HOW, feed
from tests.support.codecs import STOPS, given_up


def positions(replies: list[object]) -> list[tuple[float, float | None]]:
    return [(r.az_deg, r.el_deg) for r in replies if isinstance(r, PositionReply)]


def junk(replies: list[object]) -> list[JunkReply]:
    return [r for r in replies if isinstance(r, JunkReply)]


def asked(version: int = 2, *, elevation: bool = True, separate: bool = False) -> EasycommCodec:
    codec = EasycommCodec(version, elevation=elevation, separate=separate)
    codec.encode_query()
    return codec


def test_commands_on_the_wire() -> None:
    azel, az = EasycommCodec(2), EasycommCodec(3, elevation=False)
    separate = EasycommCodec(2, separate=True)
    assert azel.encode_target(123.44, 45.05) == [b"AZ123.4 EL45.1\n"]  # tenths, half up
    assert azel.encode_target(5, 0) == [b"AZ5.0 EL0.0\n"]
    assert az.encode_target(359.96) == [b"AZ360.0\n"]
    assert (azel.encode_query(), az.encode_query()) == (b"AZ EL\n", b"AZ EL\n")  # rule 8
    assert separate.encode_query() == b"AZ\nEL\n"
    assert azel.encode_stop() == az.encode_stop() == b"SA SE\n"
    assert (azel.encode_version(), azel.encode_connect(0.0), azel.encode_enable()) == (
        None,
        [],
        None,
    )
    assert (az.encode_version(), az.encode_connect(0.0)) == (b"VE\n", [b"VE\n"])


def test_targets_outside_what_the_controller_takes_are_refused_before_sending() -> None:
    codec = EasycommCodec(2)
    for az, el in ((360.1, 0), (-0.1, 0), (10, 180.06), (10, -1)):
        with pytest.raises(ValueError, match="outside"):
            codec.encode_target(az, el)
    assert codec.wire_target(360, 180) == (360.0, 180.0)
    assert EasycommCodec(2, elevation=False).wire_target(12.25) == (12.3, None)


@pytest.mark.parametrize("how", HOW)
@pytest.mark.parametrize(
    ("elevation", "reply", "want"),
    [
        (True, b"AZ123.4 EL45.0\n", (123.4, 45.0)),  # SatNOGS
        (True, b"AZ123.4 EL45.0\r\n", (123.4, 45.0)),
        (True, b"AZ123.4EL45.0\r", (123.4, 45.0)),  # no space, CR alone
        (True, b"AZ123 EL45\n", (123.0, 45.0)),  # whole degrees
        (True, b"AZ 123.4  EL 45.0 \n", (123.4, 45.0)),  # spaces after the letters
        (True, b"AZ0.0 EL-0.5\n", (0.0, -0.5)),  # parked a little below the horizon
        (True, b"AZ10.0 EL20.0 UP000 XXX DN000 XXX\n", (10.0, 20.0)),  # radio words ignored
        (False, b"AZ359.9\n", (359.9, None)),
        (False, b"AZ7.5 EL0.0\n", (7.5, None)),  # an azimuth controller that says EL too
    ],
)
def test_replies_on_one_line(
    how: str, elevation: bool, reply: bytes, want: tuple[float, float | None]
) -> None:
    codec = asked(2, elevation=elevation)
    replies = feed(codec, reply, how)
    assert positions(replies) == [want]
    assert all(j.reason is JunkReason.CHATTER for j in junk(replies))  # the LF of a CR LF
    assert not codec.awaiting_reply()


@pytest.mark.parametrize("how", HOW)
@pytest.mark.parametrize("reply", [b"AZ123.4\nEL45.0\n", b"EL45.0\r\nAZ123.4\r\n"])
def test_replies_on_two_lines_make_one_reading(how: str, reply: bytes) -> None:
    codec = asked(2, separate=True)
    replies = feed(codec, reply, how)
    assert positions(replies) == [(123.4, 45.0)]
    assert not codec.awaiting_reply()


def test_half_an_answer_is_no_reading_and_keeps_the_query_open() -> None:
    codec = asked(2, separate=True)
    assert codec.feed(b"AZ123.4\n") == [] and codec.awaiting_reply()
    codec.expire_query()
    assert junk(codec.feed(b"EL45.0\n"))[0].reason is JunkReason.UNSOLICITED
    codec.encode_query()  # a new exchange starts from nothing: the old azimuth is gone
    assert codec.feed(b"EL45.0\n") == [] and codec.awaiting_reply()


@pytest.mark.parametrize("how", HOW)
def test_an_alarm_and_blank_lines_are_chatter_never_a_reading(how: str) -> None:
    codec = asked(2)
    replies = feed(codec, b"\r\nALJAM AZ\n\n", how)
    assert positions(replies) == []
    assert {j.reason for j in junk(replies)} == {JunkReason.CHATTER}
    (alarm,) = [j for j in junk(replies) if "alarm: JAM AZ" in j.detail]
    assert not codec.harmless(alarm.data)  # the user is told
    assert all(codec.harmless(j.data) for j in junk(replies) if j is not alarm)
    assert positions(feed(codec, b"AZ1.0 EL2.0\n", how)) == [(1.0, 2.0)]  # still trusted


@pytest.mark.parametrize("how", HOW)
def test_the_version_answer(how: str) -> None:
    codec = EasycommCodec(3)
    replies = feed(codec, b"VESatNOGS v2.1\n", how)
    assert [r for r in replies if isinstance(r, VersionReply)] == [VersionReply("SatNOGS v2.1")]


@pytest.mark.parametrize("end", [b"\n", b"\r\n", b"\r"])
@pytest.mark.parametrize("how", [*HOW, "all but its end"])
def test_a_version_line_fills_80_bytes_at_most_however_it_is_read(how: str, end: bytes) -> None:
    """Rule 6: 80 bytes before the line end are a version; 81 are noise, whole or not (an
    81-byte line was read when whole and noise when a read stopped before its end)."""
    for text, want in (("v" * 78, [VersionReply("v" * 78)]), ("v" * 79, [])):
        line = b"VE" + text.encode() + end
        codec = EasycommCodec(3)
        if how == "all but its end":
            replies = [*codec.feed(line[: -len(end)]), *codec.feed(end)]
        else:
            replies = feed(codec, line, how)
        assert [r for r in replies if isinstance(r, VersionReply)] == want, len(line)
        if not want:
            assert [j.detail for j in junk(replies)][:1] == ["line too long"]


@pytest.mark.parametrize("how", HOW)
def test_junk_in_front_of_a_reply_on_its_line_makes_it_untrusted(how: str) -> None:
    codec = asked(2)
    replies = feed(codec, b"\x8f\x00AZ123.4 EL45.0\n", how)
    assert positions(replies) == []
    assert JunkReason.UNTRUSTED in {j.reason for j in junk(replies)}


@pytest.mark.parametrize("how", HOW)
def test_a_junk_line_between_the_two_answers_makes_the_reading_untrusted(how: str) -> None:
    codec = asked(2, separate=True)
    replies = feed(codec, b"AZ123.4\ngarbage\nEL45.0\n", how)
    assert positions(replies) == []
    assert [j.reason for j in junk(replies)] == [JunkReason.NOISE, JunkReason.UNTRUSTED]


@pytest.mark.parametrize("how", HOW)
def test_junk_lines_around_a_reply_leave_the_reading_alone_when_not_asked(how: str) -> None:
    codec = EasycommCodec(2)
    replies = feed(codec, b"garbage\nAZ123.4 EL45.0\n", how)
    assert positions(replies) == []  # nobody asked
    assert [j.reason for j in junk(replies)] == [JunkReason.NOISE, JunkReason.UNSOLICITED]


def test_out_of_range_and_empty_replies_are_no_readings() -> None:
    for reply, reason in (
        (b"AZ360.6 EL0.0\n", JunkReason.SPOILED),
        (b"AZ-0.6 EL0.0\n", JunkReason.SPOILED),
        (b"AZ100.0 EL180.6\n", JunkReason.SPOILED),
        (b"AZ-1.0 EL10.0\n", JunkReason.SPOILED),
        (b"AZ EL\n", JunkReason.NOISE),  # an echo of the question is no answer
        (b"AZ=123\n", JunkReason.NOISE),  # a GS-232B answer
    ):
        codec = asked(2)
        replies = codec.feed(reply)
        assert positions(replies) == [], reply
        assert junk(replies)[0].reason is reason, reply


def test_a_line_without_end_is_given_up_once_too_long() -> None:
    codec = asked(2)
    replies = codec.feed(b"x" * 100)
    assert [j.reason for j in junk(replies)] == [JunkReason.NOISE]
    assert positions(codec.feed(b"\n")) == []


def test_a_whole_line_too_long_is_noise_and_never_matched() -> None:
    """Rule 6, an attack pass: ``AZ1`` and 32 ``UP`` words in one read (a whole line, so the
    cap on a line without end never saw it) held the serial-lines thread 3 s in the pattern."""
    codec = asked(2)
    replies = codec.feed(b"AZ1" + b" UP" * 32 + b" !\n")
    assert [(j.reason, j.detail) for j in junk(replies)] == [(JunkReason.NOISE, "line too long")]
    replies = codec.feed(b"AZ1" + b" UP" * 24 + b" !\n")  # 80 bytes: judged, read one way
    assert positions(replies) == [] and junk(replies)[0].reason is JunkReason.NOISE
    assert positions(asked(2).feed(b"AZ10.0 EL5.0 UP UP DN FM\n")) == [(10.0, 5.0)]


def test_an_expired_query_takes_no_late_reply() -> None:
    codec = asked(2)
    codec.expire_query()
    replies = codec.feed(b"AZ123.4 EL45.0\n")
    assert positions(replies) == [] and junk(replies)[0].reason is JunkReason.UNSOLICITED


@settings(max_examples=200, deadline=None)
@given(
    before=st.binary(max_size=40),
    az_tenths=st.integers(0, 3600),
    el_tenths=st.integers(0, 1800),
)
def test_noise_before_a_reply_never_yields_another_bearing(
    before: bytes, az_tenths: int, el_tenths: int
) -> None:
    codec = asked(2)
    az, el = az_tenths / 10, el_tenths / 10
    # noise that is itself a whole reply line cannot be told from one (the engine's settle
    # rule catches the second reply of the exchange); anything else must not read
    assume(not re.search(rb"(AZ|EL)\s*[-+]?\d", before))
    got = positions(codec.feed(before + b"AZ%.1f EL%.1f\n" % (az, el)))
    assert got in ([], [(az, el)])


@pytest.mark.parametrize("ws", [b"\t", b"\x0b", b"\x0c"])
@pytest.mark.parametrize(
    "reply",
    [
        b"AZ123.4 EL%s5.0\n",  # the 4 of EL45.0 a control byte: never read as EL5.0
        b"AZ123.4%sEL45.0\n",
        b"AZ%s123.4 EL45.0\n",
        b"%sAZ123.4 EL45.0\n",
        b"+123.4%s\n",
    ],
)
def test_a_tab_or_form_feed_in_a_reply_is_noise_not_a_space(reply: bytes, ws: bytes) -> None:
    """Rule 3: only a space parts a reply's words; a tab, a vertical tab or a form feed (a
    digit or a space the line corrupted) is junk in the exchange (an attack pass: a form feed
    in place of the 4 of ``EL45.0`` was read as elevation 5.0)."""
    codec = asked(2)
    replies = codec.feed(reply % ws)
    if not replies:  # an axis read after the junk: the exchange waits for the other one
        replies = codec.feed(b"AZ123.4 EL45.0\n")
    assert positions(replies) == []
    assert [j.reason for j in junk(replies)] in (
        [JunkReason.NOISE],
        [JunkReason.UNTRUSTED],
    )


def test_the_model_table() -> None:
    facts = {
        name: (spec.hamlib_model, spec.has_elevation, spec.has_version, spec.baud)
        for name, spec in REGISTRY.items()
        if name.startswith("easycomm")
    }
    assert facts == {
        "easycomm2": (202, True, False, 19200),
        "easycomm2-az": (202, False, False, 19200),
        "easycomm2-separate": (202, True, False, 19200),
        "easycomm3": (204, True, True, 19200),
        "easycomm3-az": (204, False, True, 19200),
        "easycomm3-separate": (204, True, True, 19200),
    }
    assert {s.hamlib_rot_type for n, s in REGISTRY.items() if n.startswith("easycomm")} == {
        HamlibRotType.OTHER
    }
    assert REGISTRY["easycomm2"].whole_degrees is False  # tenths on the wire


# -- K3NG's default build (rule 7) ------------------------------------------------------------
@pytest.mark.parametrize(
    ("reply", "elevation", "separate", "want"),
    [
        (b"+123.4 +45.0\n", True, False, (123.4, 45.0)),
        (b"+123.4 -1.5\n", True, False, (123.4, -1.5)),
        (b"+123.4\n+45.0\n", True, True, (123.4, 45.0)),
        (b"+123.4 ?\n", False, False, (123.4, None)),
        (b"+123.4 +45.0\n", False, False, (123.4, None)),
    ],
)
def test_k3ngs_signed_values_answer_the_query_azimuth_first(
    reply: bytes, elevation: bool, separate: bool, want: tuple[float, float | None]
) -> None:
    codec = asked(2, elevation=elevation, separate=separate)
    replies = codec.feed(reply)
    assert positions(replies) == [want] and junk(replies) == []


@pytest.mark.parametrize("reply", [b"123.4 45.0\n", b"+123.4 ?\n", b"+123.4 +45.0 +1.0\n"])
def test_a_number_without_its_sign_or_a_missing_elevation_is_no_reading(reply: bytes) -> None:
    codec = asked(2)
    replies = codec.feed(reply)
    assert positions(replies) == [] and junk(replies)[0].reason is JunkReason.NOISE


def test_k3ngs_refused_se_is_harmless_to_an_azimuth_model_alone() -> None:
    az, azel = asked(2, elevation=False), asked(2)
    assert az.harmless(b" ?\n") and not azel.harmless(b" ?\n")
    assert [j.reason for j in junk(az.feed(b" ?\n"))] == [JunkReason.CHATTER]
    assert positions(az.feed(b"+10.0 ?\n")) == [(10.0, None)]


def test_a_stops_refusals_judged_together_are_harmless_up_to_a_stops_frames() -> None:
    """Rule 7 (attack 9): a STOP reaches the box two or three times (the express's SA SE, the
    stop lane's, the main connection's copy), a K3NG azimuth build refuses each SE with ' ?',
    and two in one quiet spell were told on R/error. More are refusals of something else."""
    az, azel = EasycommCodec(2, elevation=False), EasycommCodec(2)
    for _ in range(3):
        az.encode_stop()
        assert [j.reason for j in junk(az.feed(b" ?\n"))] == [JunkReason.CHATTER]
    assert az.harmless(b" ?\n ?\n") and az.harmless(b" ?\n ?\n ?\n") and az.harmless(b"?\r\n?\r\n")
    assert not az.harmless(b" ?\n ?\n ?\n ?\n")  # a fourth: no STOP's
    assert not az.harmless(b" ?\n#\n") and not az.harmless(b" ?\nAZ10.0\n")  # junk is junk
    assert not az.harmless(b" ??\n") and not az.harmless(b" ? ?\n")  # one to a line
    assert not azel.harmless(b" ?\n ?\n")  # an az/el box has an SE to take


# -- a SatNOGS's answer to a stop (rule 9) ----------------------------------------------------
def test_a_position_after_a_stop_is_its_answer_not_a_reading_nor_junk_told() -> None:
    codec = EasycommCodec(2)
    codec.encode_stop()
    replies = codec.feed(b"AZ220.0 EL40.0\n")
    assert positions(replies) == [] and [j.reason for j in junk(replies)] == [JunkReason.CHATTER]
    assert codec.harmless(b"AZ220.0 EL40.0\n") and not codec.harmless(b"AZ221.0 EL40.0\n")
    codec.encode_stop()  # once seen to answer, its answer is awaited ahead of the next poll's
    codec.encode_query()
    assert positions(codec.feed(b"AZ219.0 EL40.0\nAZ218.0 EL40.0\n")) == [(218.0, 40.0)]


def test_a_controller_that_answers_no_stop_keeps_its_poll_answer() -> None:
    codec = EasycommCodec(2)
    codec.encode_stop()
    codec.encode_query()
    assert positions(codec.feed(b"+219.0 +40.0\n")) == [(219.0, 40.0)]
    codec.encode_stop()
    assert positions(codec.feed(b"AZ1.0 EL40.0\n")) == []  # no query open: never a reading


@pytest.mark.parametrize("answer", [b"AZ219.0 EL40.0\n", b"+219.0 +40.0\n"])
def test_a_stop_written_behind_an_open_poll_leaves_the_polls_answer_to_it(answer: bytes) -> None:
    """Rule 9: the controller answers in the order it was asked; the poll's answer was taken
    for the stop's and the codec, taking this controller for one that answers stops, then ate
    the first poll's answer after every stop."""
    codec = EasycommCodec(2)
    codec.encode_query()
    codec.encode_stop()  # (full duplex: the poll's answer still on its way)
    assert positions(codec.feed(answer)) == [(219.0, 40.0)]
    codec.encode_stop()
    codec.encode_query()
    assert positions(codec.feed(b"AZ218.0 EL40.0\n")) == [(218.0, 40.0)]
    codec.encode_query()  # a SatNOGS: the stop's answer after the poll's
    codec.encode_stop()
    replies = codec.feed(b"AZ217.0 EL40.0\nAZ217.0 EL40.0\n")
    assert positions(replies) == [(217.0, 40.0)]
    assert [j.reason for j in junk(replies)] == [JunkReason.CHATTER]


def test_a_poll_answered_after_its_time_with_a_stop_behind_it_teaches_nothing() -> None:
    """Rule 9 (a review): the poll's time ran out with a stop written behind it, and its
    answer came after all: taken for the stop's, it taught the codec that this controller (a
    K3NG, answering no stop) answers stops, and every later stop ate the next poll's answer."""
    codec = EasycommCodec(2)
    codec.encode_query()
    codec.encode_stop()
    codec.expire_query()
    replies = codec.feed(b"AZ219.0 EL40.0\n")  # (late: no reading, and no notice either)
    assert positions(replies) == [] and codec.harmless(b"AZ219.0 EL40.0\n")
    codec.encode_stop()  # a later stop, nothing answers it
    codec.encode_query()
    assert positions(codec.feed(b"AZ218.0 EL40.0\n")) == [(218.0, 40.0)]


# -- a poll's answer after its reply time (rule 10) ------------------------------------------
@pytest.mark.parametrize("stop", STOPS)
def test_a_polls_answer_after_its_time_is_told_nowhere_and_is_no_reading(stop: str) -> None:
    """A CI run at load 23: the poll's answer came after its reply time, the next poll took it,
    and that poll's own answer, a line later, was told on R/error as bytes that are no reply."""
    codec = EasycommCodec(3)
    given_up(codec, stop)
    assert positions(codec.feed(b"AZ52.4 EL0.0\n")) == [(52.4, 0.0)]  # (which it is: no line says)
    replies = codec.feed(b"AZ52.5 EL0.0\n")
    assert positions(replies) == [] and codec.harmless(b"AZ52.5 EL0.0\n")
    assert [j.reason for j in junk(replies)] == [JunkReason.UNSOLICITED]  # (spoils: link rule 9)
    replies = codec.feed(b"AZ52.6 EL0.0\n")  # owed by no query: told
    assert positions(replies) == [] and not codec.harmless(b"AZ52.6 EL0.0\n")
    assert not codec.harmless(b"AZ52.5 EL0.0\n#\n")  # junk is still junk


def test_a_late_answer_with_no_poll_open_and_the_late_halves_of_a_separate_one() -> None:
    codec = asked(2)
    codec.expire_query()
    assert positions(codec.feed(b"AZ10.0 EL5.0\n")) == [] and codec.harmless(b"AZ10.0 EL5.0\n")
    assert not codec.harmless(b"AZ10.0\n")
    two = asked(2, separate=True)
    two.expire_query()
    replies = two.feed(b"AZ10.0\nEL5.0\nAZ11.0\n")
    assert positions(replies) == [] and two.harmless(b"AZ10.0\nEL5.0\n")
    assert not two.harmless(b"AZ10.0\nEL5.0\nAZ11.0\n")  # a third line: owed by none
    half = asked(2, separate=True)
    assert half.feed(b"AZ10.0\n") == []  # the azimuth in time, the elevation late
    half.expire_query()
    assert half.feed(b"EL5.0\n") and half.harmless(b"EL5.0\n")
    assert not half.harmless(b"EL5.0\nAZ10.0\n")


@pytest.mark.parametrize("again", [False, True])
def test_a_poll_given_up_before_a_stop_teaches_nothing_by_its_late_answer(again: bool) -> None:
    """Rule 10: the poll's time ran out, a stop went (and, ``again``, its repeat), and the
    poll's answer came: taken for the stop's, it taught the codec that this controller (one
    that answers no stop) answers stops, and the next poll's answer after a stop was eaten."""
    codec = EasycommCodec(2)
    codec.encode_query()
    if again:  # the stop behind the poll, the poll given up, the stop's repeat
        codec.encode_stop()
    codec.expire_query()
    codec.encode_stop()
    replies = codec.feed(b"AZ219.0 EL40.0\n")
    assert positions(replies) == [] and codec.harmless(b"AZ219.0 EL40.0\n")
    codec.encode_stop()  # a later stop, nothing answers it
    codec.encode_query()
    assert positions(codec.feed(b"AZ218.0 EL40.0\n")) == [(218.0, 40.0)]


def test_a_satnogs_answers_a_stop_after_a_late_poll_answer_and_is_learned() -> None:
    """Rule 10: the late answer first (asked first), then the stop's: that one teaches."""
    codec = EasycommCodec(2)
    codec.encode_query()
    codec.expire_query()
    codec.encode_stop()
    replies = codec.feed(b"AZ10.0 EL5.0\nAZ10.0 EL5.0\n")
    assert positions(replies) == [] and codec.harmless(b"AZ10.0 EL5.0\nAZ10.0 EL5.0\n")
    replies = codec.feed(b"AZ10.0 EL5.0\n")  # the stop express's copy, answered
    assert [j.reason for j in junk(replies)] == [JunkReason.CHATTER]


def test_an_azimuth_model_ignores_the_elevation_on_its_line_in_range_or_not() -> None:
    """Rule 2, since rule 8 asks it AZ EL: a SatNOGS's unused channel may say anything."""
    out = asked(2, elevation=False).feed(b"AZ100.0 EL-120.0\n")
    assert positions(out) == [(100.0, None)] and junk(out) == []


@pytest.mark.parametrize("late", [b"+12.0 ?\n", b"AZ12.0 EL0.0\n"])
def test_an_answer_nobody_asked_for_is_unsolicited_in_either_form(late: bytes) -> None:
    """A second answer in one exchange spoils the held reading (link.py rule 9): a K3NG's was
    taken for an elevation, harmless, and a late answer stood."""
    codec = asked(2, elevation=False)
    assert positions(codec.feed(b"+10.0 ?\n")) == [(10.0, None)]
    assert [j.reason for j in junk(codec.feed(late))] == [JunkReason.UNSOLICITED]


def test_once_it_answered_a_stop_a_whole_line_unasked_is_a_stop_express_copys_answer() -> None:
    """The stop express writes its own SA SE (rule 9): a SatNOGS's answer to it came with no
    stop of this codec's, a reply nobody asked for, told at every stop."""
    codec = EasycommCodec(2)
    codec.encode_query()
    codec.feed(b"AZ10.0 EL5.0\n")
    assert [j.reason for j in junk(codec.feed(b"AZ11.0 EL5.0\n"))] == [JunkReason.UNSOLICITED]
    codec.encode_stop()
    codec.feed(b"AZ12.0 EL5.0\n")  # seen to answer a stop
    replies = codec.feed(b"AZ13.0 EL5.0\n")  # the express's, unasked
    assert [j.reason for j in junk(replies)] == [JunkReason.CHATTER]
    assert codec.harmless(b"AZ12.0 EL5.0\nAZ13.0 EL5.0\n")
    half = junk(codec.feed(b"AZ13.0\n"))  # not a whole answer: no stop's
    assert [j.reason for j in half] == [JunkReason.UNSOLICITED]


@pytest.mark.parametrize("first", ["express", "poll"])
def test_the_express_stops_answer_before_the_codecs_own_stop_is_told_nowhere(first: str) -> None:
    """Rule 9 (attack 9): the express's SA SE goes ahead of the codec's own, at the first STOP
    of a connection, before this SatNOGS was seen to answer a stop: its answer (after the
    poll's, or ahead of it) came with no query open and was told on R/error. It still spoils
    the reading held (nothing tells it from a second reply then); once the codec's own stop is
    answered, it is that STOP's answer, told nowhere."""
    codec = EasycommCodec(2)
    codec.encode_query()
    assert positions(codec.feed(b"AZ10.0 EL5.0\n")) == [(10.0, 5.0)]
    unasked = b"AZ10.1 EL5.0\n" if first == "poll" else b"AZ10.0 EL5.0\n"
    assert [j.reason for j in junk(codec.feed(unasked))] == [JunkReason.UNSOLICITED]
    assert not codec.harmless(unasked)  # (no stop seen answered yet)
    codec.encode_query()  # the re-poll the spoiled reading asked
    assert positions(codec.feed(b"AZ10.2 EL5.0\n")) == [(10.2, 5.0)]
    codec.encode_stop()  # the session's own stop
    assert [j.reason for j in junk(codec.feed(b"AZ10.2 EL5.0\n"))] == [JunkReason.CHATTER]
    assert codec.harmless(unasked + b"AZ10.2 EL5.0\n")
    assert not codec.harmless(unasked * 2 + b"AZ10.2 EL5.0\n")  # (as often as it came)


def test_a_position_nobody_asked_for_long_before_a_stop_or_never_answered_is_still_told() -> None:
    """Rule 9: only the lines of the last UNASKED_POLLS polls before the first stop answered
    are the express's; a controller that answers no stop learns nothing."""
    old = EasycommCodec(2)
    old.encode_query()
    old.feed(b"AZ10.0 EL5.0\nAZ11.0 EL5.0\n")  # the second: nobody asked for it
    for _ in range(UNASKED_POLLS + 1):
        old.encode_query()
        assert positions(old.feed(b"AZ12.0 EL5.0\n")) == [(12.0, 5.0)]
    old.encode_stop()
    assert [j.reason for j in junk(old.feed(b"AZ12.0 EL5.0\n"))] == [JunkReason.CHATTER]
    assert old.harmless(b"AZ12.0 EL5.0\n") and not old.harmless(b"AZ11.0 EL5.0\n")
    k3ng = EasycommCodec(2)
    k3ng.encode_query()
    k3ng.feed(b"+10.0 +5.0\n+11.0 +5.0\n")
    k3ng.encode_stop()  # answered by nothing
    k3ng.encode_query()
    assert positions(k3ng.feed(b"+12.0 +5.0\n")) == [(12.0, 5.0)]
    assert not k3ng.harmless(b"+11.0 +5.0\n")
