"""The loggers' datagrams (bridge/interfaces/loggers/datagrams.py), from the fact sheet's examples
(../shared/protocols/logger-udp.md): what each client sends, and what must be refused."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from bridge.interfaces.loggers.datagrams import (
    MAX_DATAGRAM,
    Malformed,
    N1mmRequest,
    PstRequest,
    may_stop_n1mm,
    may_stop_pst,
    n1mm_report,
    parse_n1mm,
    parse_pst,
    pst_reply,
)


@pytest.mark.parametrize(
    ("datagram", "request_"),
    [
        (b"<PST><AZIMUTH>85</AZIMUTH></PST>", PstRequest(azimuth=85.0)),  # manual, Minos, KST
        (b"<PST><ELEVATION>45.0</ELEVATION></PST>", PstRequest(elevation=45.0)),
        (b"<PST><AZIMUTH>120.000000.2</AZIMUTH></PST>", PstRequest(azimuth=120.0)),  # Hamlib 4.6
        (b"<PST><AZIMUTH>123.400002.2</AZIMUTH></PST>", PstRequest(azimuth=123.400002)),
        (
            b"<PST><TRACK>0</TRACK><AZIMUTH>123.4</AZIMUTH><ELEVATION>45.6</ELEVATION></PST>",
            PstRequest(azimuth=123.4, elevation=45.6, ignored=("TRACK",)),  # QLog, horus-gui
        ),
        (b"<PST><STOP>1</STOP></PST>", PstRequest(stop=True)),
        (b"<PST><PARK>1</PARK></PST>", PstRequest(park=True)),
        (b"<PST><PARK>0</PARK></PST>", PstRequest()),  # no park: nothing to do
        (b"<PST><PARK>0</PARK><STOP>1</STOP><PARK>x</PARK></PST>", PstRequest(stop=True)),
        (b"<PST><QRA>KN34BJ</QRA></PST>", PstRequest(locator="KN34BJ")),
        (b"<PST>AZ?</PST>", PstRequest(queries=("AZ",))),
        (b"<PST>EL?</PST>", PstRequest(queries=("EL",))),
        (b"<PST>MODE?</PST>", PstRequest(ignored=("MODE",))),
        (b"<pst><azimuth>-20</azimuth></pst>\r\n", PstRequest(azimuth=-20.0)),  # any case, CRLF
        (b"<PST> <AZIMUTH>10</AZIMUTH> AZ? </PST>", PstRequest(azimuth=10.0, queries=("AZ",))),
        (
            b"<PST><AZIMUTH>10</AZIMUTH><STOP>1</STOP></PST>",  # the stop wins (the server)
            PstRequest(stop=True, azimuth=10.0),
        ),
        (b"<PST><ON>1</ON></PST>", PstRequest(ignored=("ON",))),  # undocumented tags
        (  # the same target twice says one thing
            b"<PST><AZIMUTH>10</AZIMUTH><AZIMUTH>10.0</AZIMUTH></PST>",
            PstRequest(azimuth=10.0),
        ),
        (  # a stop is never refused: ambiguous targets beside it are dropped
            b"<PST><AZIMUTH>10</AZIMUTH><STOP>1</STOP><AZIMUTH>200</AZIMUTH></PST>",
            PstRequest(stop=True),
        ),
        (b"<PST>" + b"AZ?" * 677 + b"EL?AZ?</PST>", PstRequest(queries=("AZ", "EL"))),  # one each
    ],
)
def test_what_the_pst_clients_send_is_read(datagram: bytes, request_: PstRequest) -> None:
    assert parse_pst(datagram) == request_


@pytest.mark.parametrize(
    "datagram",
    [
        b"<PST><AZIMUTH>nan</AZIMUTH></PST>",
        b"<PST><AZIMUTH>inf</AZIMUTH></PST>",
        b"<PST><AZIMUTH></AZIMUTH></PST>",
        b"<PST><AZIMUTH>12x</AZIMUTH></PST>",
        b"<PST><AZIMUTH>1e3</AZIMUTH></PST>",
        b"<PST><AZIMUTH>1.2.3.4</AZIMUTH></PST>",
        b"<PST><AZIMUTH>85</PST>",  # not closed
        b"<PST><AZIMUTH>85</ELEVATION></PST>",
        b"<PST>hello</PST>",
        b"AZ?",
        b"<PST>AZ?",
        b"<N1MMRotor><rotor>T</rotor><goazi>1</goazi></N1MMRotor>",  # the other protocol
        "<PST><AZIMUTH>85</AZIMUTH></PST>°".encode(),  # not ASCII
        b"<PST>" + b" " * MAX_DATAGRAM + b"</PST>",
        b"",
        # a park that is neither 1 nor 0 (an attack pass: each of these parked the rotor)
        b"<PST><PARK>0.0</PARK></PST>",
        b"<PST><PARK>false</PARK></PST>",
        b"<PST><PARK>no</PARK></PST>",
        b"<PST><PARK></PARK></PST>",
        b"<PST><PARK> 00 </PARK></PST>",
        b"<PST><QRA>JO</QRA></PST>",  # a field: a continent, no place to turn to
        b"<PST><QRA>JO62QM1</QRA></PST>",
    ],
)
def test_anything_else_is_malformed(datagram: bytes) -> None:
    with pytest.raises(Malformed):
        parse_pst(datagram)


def test_replies_are_integer_degrees_with_one_cr_as_minos_needs() -> None:
    assert pst_reply("AZ", 123.4) == b"AZ:123\r"
    assert pst_reply("AZ", 122.5) == b"AZ:123\r"
    assert pst_reply("EL", 45.0) == b"EL:45\r"


N1MM_SAMPLE = (  # n1kdo's capture, one line, no XML declaration
    b"<N1MMRotor><rotor>*</rotor><goazi>66.0</goazi><offset>0.0</offset>"
    b"<bidirectional>0</bidirectional><freqband>28.0</freqband></N1MMRotor>"
)


@pytest.mark.parametrize(
    ("datagram", "request_"),
    [
        (N1MM_SAMPLE, N1mmRequest("*", azimuth=66.0, freqband_mhz=28.0)),
        (
            b"<N1MMRotor>\r\n  <rotor>Tower</rotor>\r\n  <goazi>123.4</goazi>\r\n"
            b"  <offset>0</offset>\r\n  <bidirectional>1</bidirectional>\r\n"
            b"  <freqband>14</freqband>\r\n</N1MMRotor>",
            N1mmRequest("Tower", azimuth=123.4, bidirectional=True, freqband_mhz=14.0),
        ),
        (
            b"<N1MMRotor><stop><rotor>YaesuCom9</rotor><freqband>21.0</freqband></stop></N1MMRotor>",
            N1mmRequest("YaesuCom9", stop=True),
        ),
        (b"<N1MMRotor><stop>Tower</stop></N1MMRotor>", N1mmRequest("Tower", stop=True)),
        (b"<N1MMRotor><rotor>Tower</rotor><stop/></N1MMRotor>", N1mmRequest("Tower", stop=True)),
        (
            b"<N1MMRotor><rotor>Tower</rotor><stop></stop></N1MMRotor>",
            N1mmRequest("Tower", stop=True),
        ),
        (
            b"<N1MMRotor><goazi>5</goazi><rotor>Tower</rotor><offset>2.5</offset></N1MMRotor>",
            N1mmRequest("Tower", azimuth=5.0, offset=2.5),
        ),
    ],
)
def test_what_n1mm_sends_is_read(datagram: bytes, request_: N1mmRequest) -> None:
    assert parse_n1mm(datagram) == request_


@pytest.mark.parametrize(
    "datagram",
    [
        b"<N1MMRotor><rotor>T</rotor><goazi>361</goazi></N1MMRotor>",
        b"<N1MMRotor><rotor>T</rotor><goazi>-1</goazi></N1MMRotor>",
        b"<N1MMRotor><rotor>T</rotor><goazi>nan</goazi></N1MMRotor>",
        b"<N1MMRotor><rotor>T</rotor></N1MMRotor>",  # neither goazi nor stop
        b"<N1MMRotor><goazi>10</goazi></N1MMRotor>",  # no name
        b"<N1MMRotor><rotor>T</rotor><goazi>10</goazi><x></N1MMRotor>",
        b"<N1MMRotor><rotor>T</rotor><goazi>10</goazi>",
        b"<PST><AZIMUTH>85</AZIMUTH></PST>",
    ],
)
def test_n1mm_datagrams_not_understood_are_malformed(datagram: bytes) -> None:
    with pytest.raises(Malformed):
        parse_n1mm(datagram)


def test_the_n1mm_position_report_is_the_heading_times_ten() -> None:
    assert n1mm_report("rotor on com1", 65.0) == b"rotor on com1 @ 650"
    assert n1mm_report("Tower", 0.04) == b"Tower @ 0"
    assert n1mm_report("Tower", 359.96) == b"Tower @ 0"  # 360.0 is north, as 0


@given(st.binary(max_size=300))
def test_random_bytes_are_read_or_malformed_never_anything_else(data: bytes) -> None:
    for parse in (parse_pst, parse_n1mm):
        try:
            parse(data)
        except Malformed:
            pass


@given(st.text(alphabet="<>/PSTAZIMUTHELVONQRK?0123456789.-+ \r\n", max_size=80))
def test_tag_soup_is_read_or_malformed_and_numbers_are_finite(text: str) -> None:
    try:
        req = parse_pst(f"<PST>{text}</PST>".encode())
    except Malformed:
        return
    for value in (req.azimuth, req.elevation):
        assert value is None or value == value and abs(value) != float("inf")


@pytest.mark.parametrize("flag", [b"abc", b"2", b"yes", b"-1", b"1.0"])
def test_a_bidirectional_flag_other_than_0_or_1_is_malformed(flag: bytes) -> None:
    """Rule 1, an attack pass: ``<bidirectional>abc</bidirectional>`` was taken as a yes, and
    the rotor turned to the reciprocal bearing."""
    datagram = (
        b"<N1MMRotor><rotor>Tower</rotor><goazi>260</goazi><offset>0.0</offset>"
        b"<bidirectional>" + flag + b"</bidirectional><freqband>14</freqband></N1MMRotor>"
    )
    with pytest.raises(Malformed, match="bidirectional"):
        parse_n1mm(datagram)


@pytest.mark.parametrize(
    "datagram",
    [
        b"<PST><AZIMUTH>10</AZIMUTH><AZIMUTH>200</AZIMUTH></PST>",  # two azimuths
        b"<PST><ELEVATION>10</ELEVATION><ELEVATION>80</ELEVATION></PST>",
        b"<PST><AZIMUTH>10</AZIMUTH><QRA>JO62</QRA></PST>",  # a bearing and a locator
        b"<PST><QRA>JO62</QRA><QRA>KN34</QRA></PST>",
        b"<PST><AZIMUTH>10</AZIMUTH>AZ?<AZIMUTH>200</AZIMUTH></PST>",  # no answer either
        # an N1MM turn naming two rotors, or giving one of its tags twice
        b"<N1MMRotor><rotor>Tower</rotor><rotor>Yagi</rotor><goazi>90</goazi></N1MMRotor>",
        b"<N1MMRotor><rotor>Tower</rotor><goazi>10</goazi><goazi>200</goazi></N1MMRotor>",
        b"<N1MMRotor><rotor>Tower</rotor><goazi>10</goazi><goazi>10</goazi></N1MMRotor>",
        b"<N1MMRotor><rotor>T</rotor><goazi>1</goazi><offset>0</offset><offset>5</offset></N1MMRotor>",
        b"<N1MMRotor><rotor>T</rotor><goazi>1</goazi><bidirectional>0</bidirectional>"
        b"<bidirectional>1</bidirectional></N1MMRotor>",
    ],
)
def test_a_datagram_saying_two_things_is_ambiguous(datagram: bytes) -> None:
    parse = parse_pst if datagram.startswith(b"<PST>") else parse_n1mm
    with pytest.raises(Malformed, match="ambiguous"):
        parse(datagram)


@pytest.mark.parametrize(
    "datagram",
    [
        b"<N1MMRotor><rotor>Tower</rotor><stop>Yagi</stop></N1MMRotor>",
        b"<N1MMRotor><stop><rotor>Tower</rotor><rotor>Yagi</rotor></stop></N1MMRotor>",
    ],
)
def test_an_n1mm_stop_naming_two_rotors_is_a_stop_for_both(datagram: bytes) -> None:
    assert parse_n1mm(datagram) == N1mmRequest("Tower", stop=True, also=("Yagi",))


def test_an_n1mm_stop_naming_one_rotor_twice_is_that_rotors() -> None:
    datagram = b"<N1MMRotor><rotor>Tower</rotor><stop>Tower</stop></N1MMRotor>"
    assert parse_n1mm(datagram) == N1mmRequest("Tower", stop=True)


@pytest.mark.parametrize(
    ("datagram", "wanted"),
    [
        (b"<PST><STOP>1</STOP><AZIMUTH>12x</AZIMUTH></PST>", PstRequest(stop=True)),
        (b"<PST><STOP>1</STOP>junk<AZIMUTH>5</PST>", PstRequest(stop=True)),
    ],
)
def test_a_pst_stop_beside_what_cannot_be_read_is_still_a_stop(
    datagram: bytes, wanted: PstRequest
) -> None:
    """A stop is never refused (the bridge's last word): the rest of the datagram is moot."""
    assert parse_pst(datagram) == wanted


def test_an_n1mm_stop_beside_a_name_too_long_or_junk_stops_the_rotor_it_names() -> None:
    long = b"x" * 80
    datagram = b"<N1MMRotor><stop><rotor>Tower</rotor><rotor>" + long + b"</rotor></stop>?"
    assert parse_n1mm(datagram + b"</N1MMRotor>") == N1mmRequest("Tower", stop=True)


# -- rule 6: the byte search that finds a stop before any budget -----------------------------------
_PIECES = [
    "<STOP>1</STOP>",
    "<stop></stop>",
    "<Stop>0</Stop>",
    "<AZIMUTH>5</AZIMUTH>",
    "AZ?",
    " ",
    "<rotor>Tower</rotor>",
    "<stop>Tower</stop>",
    "<stop/>",
    "<stop >",
    "<goazi>9</goazi>",
    "<STOP>",
    "junk",
    "<PARK>1</PARK>",
    "\r\n",
]


def _mixed_case(draw: st.DrawFn, text: str) -> str:
    flips = draw(st.lists(st.booleans(), min_size=len(text), max_size=len(text)))
    return "".join(c.swapcase() if f else c for c, f in zip(text, flips, strict=True))


@st.composite
def _datagrams(draw: st.DrawFn, frame: str) -> bytes:
    body = "".join(draw(st.lists(st.sampled_from(_PIECES), max_size=6)))
    return _mixed_case(draw, f"<{frame}>{body}</{frame}>").encode("ascii")


@given(_datagrams("PST"))
def test_every_pst_stop_is_found_by_the_byte_search(datagram: bytes) -> None:
    try:
        stop = parse_pst(datagram).stop
    except Malformed:
        stop = False
    assert may_stop_pst(datagram) or not stop


@given(_datagrams("N1MMRotor"))
def test_every_n1mm_stop_is_found_by_the_byte_search(datagram: bytes) -> None:
    try:
        stop = parse_n1mm(datagram).stop
    except Malformed:
        stop = False
    assert may_stop_n1mm(datagram) or not stop


def test_the_byte_search_passes_over_what_is_no_stop() -> None:
    assert not may_stop_pst(b"<PST><AZIMUTH>x</AZIMUTH></PST>")
    assert not may_stop_n1mm(b"<N1MMRotor><rotor>T</rotor><goazi>9</goazi></N1MMRotor>")


# -- rule 8: what an XML writer puts in front of the root element ------------------------------
_DECLARATION = b'<?xml version="1.0" encoding="utf-8"?>'
_BOM = b"\xef\xbb\xbf"


@pytest.mark.parametrize(
    "head",
    [
        _DECLARATION,
        _DECLARATION + b"\r\n",
        _BOM,
        _BOM + _DECLARATION + b"\n",
        b" <?xml version='1.0' standalone='yes' ?> ",
    ],
)
def test_a_bom_and_an_xml_declaration_in_front_are_passed_over_as_an_xml_parser_would(
    head: bytes,
) -> None:
    """An attack pass: a datagram headed as N1MM heads its other broadcasts was Malformed, its
    stop included, and the rotor turned on."""
    assert parse_pst(head + b"<PST><STOP>1</STOP></PST>") == PstRequest(stop=True)
    assert parse_pst(head + b"<PST><AZIMUTH>85</AZIMUTH></PST>") == PstRequest(azimuth=85.0)
    assert parse_n1mm(head + b"<N1MMRotor><stop>Tower</stop></N1MMRotor>") == N1mmRequest(
        "Tower", stop=True
    )
    assert parse_n1mm(head + N1MM_SAMPLE) == N1mmRequest("*", azimuth=66.0, freqband_mhz=28.0)
    padded = head + b"<PST><STOP>1</STOP>" + b" " * MAX_DATAGRAM  # rule 7, the socket's cut
    assert parse_pst(padded[: MAX_DATAGRAM + 1]) == PstRequest(stop=True)


@pytest.mark.parametrize(
    "datagram",
    [
        _DECLARATION + _DECLARATION + b"<PST><AZIMUTH>85</AZIMUTH></PST>",  # one declaration
        b"<!-- x --><PST><AZIMUTH>85</AZIMUTH></PST>",  # no comment
        b"<?xml-stylesheet href='a'?><PST><AZIMUTH>85</AZIMUTH></PST>",  # no other instruction
        _BOM + _BOM + b"<PST><AZIMUTH>85</AZIMUTH></PST>",
        b"<PST><AZIMUTH>85</AZIMUTH></PST>" + _DECLARATION,  # only in front
        _DECLARATION,
        b"<?XML version='1.0'?><PST><AZIMUTH>85</AZIMUTH></PST>",  # 'xml' is lower case
    ],
)
def test_nothing_else_in_front_is_passed_over(datagram: bytes) -> None:
    with pytest.raises(Malformed):
        parse_pst(datagram)
