"""GS-232A/B codec: the commands byte for byte; both reply forms and their spacing variants
whole, bytewise and amid junk; ``?>`` and K3NG's blank lines never become readings."""

from __future__ import annotations

import re

import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from bridge.protocols import REGISTRY
from bridge.protocols.axes import Axis, axis_spec
from bridge.protocols.base import (
    LATE_LINES_MAX,
    HamlibRotType,
    JunkReason,
    JunkReply,
    PositionReply,
)
from bridge.protocols.gs232 import AXIS_STOPS, Gs232Codec
from tests.support import HOW, feed
from tests.support.codecs import STOPS, given_up


def positions(replies: list[object]) -> list[tuple[float, float | None]]:
    return [(r.az_deg, r.el_deg) for r in replies if isinstance(r, PositionReply)]


def junk(replies: list[object]) -> list[JunkReply]:
    return [r for r in replies if isinstance(r, JunkReply)]


def asked(variant: str = "b", elevation: bool = True) -> Gs232Codec:
    codec = Gs232Codec(variant, elevation=elevation)
    codec.encode_query()
    return codec


def test_commands_on_the_wire() -> None:
    azel, az = Gs232Codec("b"), Gs232Codec("a", elevation=False)
    assert azel.encode_target(123.4, 45.5) == [b"W123 046\r"]  # whole degrees, half up
    assert azel.encode_target(5, 0) == [b"W005 000\r"]
    assert az.encode_target(359.5) == [b"M360\r"]
    assert (azel.encode_query(), az.encode_query()) == (b"C2\r", b"C\r")
    assert azel.encode_stop() == b"S\r"
    assert AXIS_STOPS == {"az": b"A\r", "el": b"E\r"}
    assert (azel.encode_version(), azel.encode_connect(0.0), azel.encode_enable()) == (
        None,
        [],
        None,
    )


def test_targets_outside_what_the_box_takes_are_refused_before_sending() -> None:
    codec = Gs232Codec("b")
    for az, el in ((451, 0), (-1, 0), (10, 181)):
        with pytest.raises(ValueError, match="outside"):
            codec.encode_target(az, el)
    assert codec.wire_target(450, 180) == (450.0, 180.0)
    assert Gs232Codec("a", elevation=False).wire_target(12.5) == (13.0, None)


@pytest.mark.parametrize("how", HOW)
@pytest.mark.parametrize(
    ("variant", "elevation", "reply", "want"),
    [
        ("a", True, b"+0123+0045\r\n", (123.0, 45.0)),
        ("a", False, b"+0359\r\n", (359.0, None)),
        ("a", True, b"+0123 +0045\r", (123.0, 45.0)),
        ("a", False, b"+0005\r\n", (5.0, None)),
        ("b", True, b"AZ=123  EL=045\r\n", (123.0, 45.0)),  # Yaesu: two spaces
        ("b", True, b"AZ=123 EL=045\r\n", (123.0, 45.0)),  # some clones: one
        ("b", True, b"AZ=123EL=045\r", (123.0, 45.0)),  # or none, CR alone
        ("b", False, b"AZ=420\r\n", (420.0, None)),  # a 450-degree rotor in its overlap
        ("b", False, b"AZ=007  EL=000\r\n", (7.0, None)),  # an azimuth box that says EL too
    ],
)
def test_replies_of_both_forms(
    how: str, variant: str, elevation: bool, reply: bytes, want: tuple[float, float | None]
) -> None:
    codec = asked(variant, elevation)
    replies = feed(codec, reply, how)
    assert positions(replies) == [want]
    assert junk(replies) == []  # a CR LF's LF ends the line with its CR (rule 1)
    assert not codec.awaiting_reply()


@pytest.mark.parametrize("how", HOW)
def test_a_lf_ends_its_line_with_the_cr_before_it_and_is_no_blank_line_of_its_own(
    how: str,
) -> None:
    """Rule 1: the LF of a CR LF, in the read of its CR or in the next one, is no junk (no
    blank line the engine waits out after every reading); a LF that follows anything but a
    line's CR, and a CR that is a line of its own, are blank lines: chatter."""
    codec = asked("b", True)
    replies = feed(codec, b"AZ=123  EL=045\r", how) + feed(codec, b"\n", how)
    assert positions(replies) == [(123.0, 45.0)] and junk(replies) == []
    codec.encode_query()
    replies = feed(codec, b"\nAZ=124  EL=045\n\n", how)
    assert positions(replies) == [(124.0, 45.0)]
    assert [(j.data, j.reason) for j in junk(replies)] == [(b"\n", JunkReason.CHATTER)] * 2
    codec.encode_query()
    replies = feed(codec, b"AZ=125  EL=045\r\r\n", how)
    assert positions(replies) == [(125.0, 45.0)]
    assert [(j.data, j.reason) for j in junk(replies)] == [(b"\r", JunkReason.CHATTER)]


@pytest.mark.parametrize("how", HOW)
def test_k3ng_blank_lines_after_w_are_chatter(how: str) -> None:
    codec = Gs232Codec("b")
    codec.encode_target(100, 10)
    replies = feed(codec, b"\r\r\n\r\n", how)
    assert positions(replies) == []
    assert {j.reason for j in junk(replies)} == {JunkReason.CHATTER}
    assert all(codec.harmless(j.data) for j in junk(replies))
    codec.encode_query()
    assert positions(feed(codec, b"AZ=100  EL=010\r\n", how)) == [(100.0, 10.0)]


@pytest.mark.parametrize("how", HOW)
@pytest.mark.parametrize("tail", [b"", b"\r", b"\r\n"])
def test_a_refusal_is_junk_with_its_own_words_and_never_a_reading(how: str, tail: bytes) -> None:
    codec = asked("b")
    replies = feed(codec, b"?>" + tail, how)
    assert positions(replies) == []
    refusal = [j for j in junk(replies) if j.data == b"?>"]
    assert len(refusal) == 1 and "refused" in refusal[0].detail
    assert refusal[0].reason is JunkReason.REFUSED and not codec.harmless(b"?>")
    # the query stays open, but a reply after the refusal in the same exchange is not trusted
    assert codec.awaiting_reply()
    late = feed(codec, b"AZ=123  EL=045\r\n", how)
    assert positions(late) == [] and junk(late)[0].reason is JunkReason.UNTRUSTED


@pytest.mark.parametrize("how", HOW)
def test_junk_in_front_of_a_reply_on_its_line_makes_it_untrusted(how: str) -> None:
    codec = asked("a")
    replies = feed(codec, b"\x8f\x00+0123+0045\r\n", how)
    assert positions(replies) == []
    assert JunkReason.UNTRUSTED in {j.reason for j in junk(replies)}


@pytest.mark.parametrize("how", HOW)
def test_junk_lines_around_a_reply_leave_the_reading_alone_when_not_asked(how: str) -> None:
    codec = Gs232Codec("b")
    replies = feed(codec, b"garbage\r\nAZ=123  EL=045\r\n", how)
    assert positions(replies) == []  # nobody asked
    assert [j.reason for j in junk(replies) if j.data.strip()] == [
        JunkReason.NOISE,
        JunkReason.UNSOLICITED,
    ]


def test_the_other_forms_reply_names_the_likely_mistake() -> None:
    codec = asked("a")
    replies = codec.feed(b"AZ=123  EL=045\r\n")
    assert positions(replies) == []
    assert "GS-232B reply" in junk(replies)[0].detail
    codec = asked("b")
    assert "GS-232A reply" in junk(codec.feed(b"+0123+0045\r\n"))[0].detail


def test_out_of_range_and_half_replies_are_no_readings() -> None:
    for reply in (b"AZ=454  EL=000\r\n", b"AZ=100  EL=184\r\n", b"AZ=100\r\n"):
        codec = asked("b")
        replies = codec.feed(reply)
        assert positions(replies) == [], reply
        assert junk(replies)[0].reason is JunkReason.SPOILED


def test_a_line_without_end_is_given_up_once_too_long() -> None:
    codec = asked("b")
    replies = codec.feed(b"x" * 100)
    assert [j.reason for j in junk(replies)] == [JunkReason.NOISE]
    assert positions(codec.feed(b"\r")) == []


def test_an_expired_query_takes_no_late_reply() -> None:
    """Rule 5: no reading, and (its answer owed late) no notice either; a second is told."""
    codec = asked("b")
    codec.expire_query()
    replies = codec.feed(b"AZ=123  EL=045\r\n")
    assert positions(replies) == [] and junk(replies)[0].reason is JunkReason.UNSOLICITED
    assert codec.harmless(b"AZ=123  EL=045\r")
    assert not codec.harmless(b"AZ=123  EL=045\rAZ=124  EL=045\r")  # owed by no query


# -- a poll's answer after its reply time (rule 5) -------------------------------------------
B_LINES = (b"AZ=052  EL=000", b"AZ=053  EL=000", b"AZ=054  EL=000")
A_LINES = (b"+0052+0000", b"+0053+0000", b"+0054+0000")


@pytest.mark.parametrize(("variant", "lines"), [("b", B_LINES), ("a", A_LINES)])
@pytest.mark.parametrize("stop", STOPS)
def test_a_polls_answer_after_its_time_is_told_nowhere_and_is_no_reading(
    variant: str, lines: tuple[bytes, bytes, bytes], stop: str
) -> None:
    """A loaded host: the poll's answer came after its reply time, the next poll took it, and
    that poll's own answer, a line later, was told on R/error as bytes that are no reply. The
    stop's CR (a blank line) between them changes nothing."""
    codec = Gs232Codec(variant)
    given_up(codec, stop)
    first, second, third = lines
    assert positions(codec.feed(first + b"\r\n")) == [(52.0, 0.0)]  # (which: no line says)
    replies = codec.feed(b"\r" + second + b"\r\n")
    assert positions(replies) == [] and codec.harmless(b"\r" + second + b"\r")
    assert [j.reason for j in junk(replies)] == [JunkReason.CHATTER, JunkReason.UNSOLICITED]
    replies = codec.feed(third + b"\r\n")  # owed by no query: told
    assert positions(replies) == [] and not codec.harmless(third + b"\r")
    assert not codec.harmless(second + b"\r#\r")  # junk is still junk


def test_a_second_line_like_a_late_answer_that_no_poll_owes_is_told() -> None:
    """base.py rule 7: a late answer is discounted as often as it was owed, not wherever its
    text comes again (the box repeating the late line, owed by no query, was told nowhere)."""
    codec = asked("b")
    codec.expire_query()
    late = b"AZ=123  EL=045\r"
    replies = codec.feed(late + b"\n" + late + b"\n")
    assert [j.reason for j in junk(replies)] == [JunkReason.UNSOLICITED] * 2
    assert codec.harmless(late) and not codec.harmless(late + late)


def test_only_a_clean_line_of_the_boxs_own_form_is_a_late_answer() -> None:
    """Rule 5: junk in front of it, the other model's form, an azimuth alone from an az/el
    box, a bearing out of range: each told as before, and the late answer still owed."""
    codec = asked("b")
    codec.expire_query()
    for line in (b"#AZ=010  EL=005\r", b"+0010+0005\r", b"AZ=010\r", b"AZ=460  EL=005\r"):
        replies = codec.feed(line + b"\n")
        assert positions(replies) == [] and not codec.harmless(line), line
    assert codec.feed(b"AZ=010  EL=005\r\n") and codec.harmless(b"AZ=010  EL=005\r")


def test_late_answers_are_owed_for_a_few_polls_given_up_at_most() -> None:
    """Rule 5 (base.py rule 7): LATE_LINES_MAX given up in a row are owed (a 2-3 s stall's);
    a line more is told."""
    codec = Gs232Codec("a", elevation=False)
    for _ in range(LATE_LINES_MAX + 2):
        codec.encode_query()
        codec.expire_query()
    lines = [b"+0%03d\r" % az for az in range(10, 11 + LATE_LINES_MAX)]
    replies = codec.feed(b"\n".join(lines) + b"\n")
    assert positions(replies) == [] and codec.harmless(b"".join(lines[:LATE_LINES_MAX]))
    assert not codec.harmless(b"".join(lines))
    codec.encode_query()  # the next poll's answer is a reading as ever
    assert positions(codec.feed(b"+0099\r\n")) == [(99.0, None)]


@settings(max_examples=200, deadline=None)
@given(
    before=st.binary(max_size=40),
    variant=st.sampled_from(["a", "b"]),
    az=st.integers(0, 450),
    el=st.integers(0, 180),
)
def test_noise_before_a_reply_never_yields_another_bearing(
    before: bytes, variant: str, az: int, el: int
) -> None:
    codec = asked(variant)
    reply = b"+0%03d+0%03d\r\n" % (az, el) if variant == "a" else b"AZ=%03d  EL=%03d\r\n" % (az, el)
    # noise that is itself a whole reply line cannot be told from one (the engine's settle
    # rule catches the second reply of the exchange); anything else must not read
    assume(not re.search(rb"(^|[\r\n])(\+0\d{3}|AZ=\s*\d{3})", before))
    got = positions(codec.feed(before + reply))
    assert got in ([], [(float(az), float(el))])


def test_the_model_table() -> None:
    facts = {
        name: (spec.hamlib_model, spec.hamlib_rot_type, spec.has_elevation, spec.az_max_deg)
        for name, spec in REGISTRY.items()
        if name.startswith("gs232")
    }
    az, azel = HamlibRotType.AZ, HamlibRotType.AZEL
    assert facts == {
        "gs232a": (601, azel, True, 360.0),
        "gs232b": (603, azel, True, 360.0),
        "gs232a-az": (609, az, False, 360.0),
        "gs232b-az": (611, az, False, 360.0),
        "gs232a-450": (601, azel, True, 450.0),
        "gs232b-450": (603, azel, True, 450.0),
        "gs232a-az-450": (609, az, False, 450.0),
        "gs232b-az-450": (611, az, False, 450.0),
    }
    assert REGISTRY["gs232b-az-450"].az_wraps is False  # 10 and 370 are two cable wraps
    assert REGISTRY["gs232b"].el_max_deg == 180.0  # the G-5500 flips over


@pytest.mark.parametrize(
    ("el", "reading"),
    [(b"00-1", 0.0), (b"0-3", 0.0), (b"045", 45.0), (b"-9", None), (b"0-45", None), (b"-99", None)],
)
def test_k3ng_a_little_below_the_horizon_is_the_horizon_and_further_is_no_reading(
    el: bytes, reading: float | None
) -> None:
    codec = REGISTRY["gs232b"].codec_factory()
    codec.encode_query()
    replies = codec.feed(b"AZ=123EL=" + el + b"\r\n")
    positions = [r for r in replies if isinstance(r, PositionReply)]
    assert [p.el_deg for p in positions] == ([] if reading is None else [reading])


@pytest.mark.parametrize("how", HOW)
@pytest.mark.parametrize(
    ("model", "reply", "reading"),
    [
        ("gs232b-az", b"AZ=400\r\n", None),  # a 450-degree rotor's box at P45
        ("gs232a", b"+0400+0010\r\n", None),
        ("gs232b", b"AZ=364  EL=010\r\n", None),
        ("gs232b-az", b"AZ=360\r\n", 360.0),  # the end of the scale
        ("gs232b-az", b"AZ=363\r\n", 360.0),  # a pot calibrated a little short: the end
        ("gs232a-az", b"+0362\r\n", 360.0),
        ("gs232b-az-450", b"AZ=400\r\n", 400.0),  # the overlap, on the model set to P45
        ("gs232b-az-450", b"AZ=359\r\n", 359.0),  # a 450 box that says 0..360 (K3NG)
        ("gs232a-450", b"+0450+0010\r\n", 450.0),
    ],
)
def test_an_azimuth_past_the_models_scale_is_a_box_set_up_otherwise_and_says_what_to_configure(
    how: str, model: str, reply: bytes, reading: float | None
) -> None:
    codec = REGISTRY[model].codec_factory()
    codec.encode_query()
    replies = feed(codec, reply, how)
    assert [p[0] for p in positions(replies)] == ([] if reading is None else [reading])
    if reading is None:
        (misfit,) = junk(replies)
        assert misfit.reason is JunkReason.MISFIT
        assert f'model = "{model}-450"' in misfit.detail and "P36" in misfit.detail
    else:
        assert junk(replies) == []


@pytest.mark.parametrize("model", ["gs232a", "gs232b"])
def test_a_composite_elevation_boxs_own_azimuth_is_judged_by_no_models_scale(model: str) -> None:
    """Rule 2 (review 49): the elevation box's azimuth is never turned (axes.py rules 2 and 5):
    at 400 on a box at P45 configured as a 360 model it is read, and its elevation with it."""
    codec = axis_spec(REGISTRY[model], Axis.ELEVATION).codec_factory()
    codec.encode_query()
    reply = b"+0400+0045\r\n" if model == "gs232a" else b"AZ=400  EL=045\r\n"
    replies = codec.feed(reply)
    assert [r.el_deg for r in replies if isinstance(r, PositionReply)] == [45.0], replies
    assert not [r for r in replies if isinstance(r, JunkReply)], replies
