"""GS-232B and Easycomm II input, sans-IO: the line splitter fed whole, byte by byte and split,
and each protocol's reading of a line (junk, partial lines, NaN, huge numbers)."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from bridge.interfaces.gs232.parser import (
    MAX_LINE,
    EasycommRequest,
    Gs232Kind,
    Gs232Request,
    LineSplitter,
    dcu1_holds_stop,
    easycomm_holds_stop,
    gs232_holds_stop,
    parse_easycomm,
    parse_gs232,
)
from tests.support import feed
from tests.support.codecs import HOW


@pytest.mark.parametrize("how", HOW)
def test_lines_end_at_cr_or_lf_and_empty_lines_are_nothing(how: str) -> None:
    data = b"W120 030\r\rC2\r\nAZ EL \n\n  S  \r"
    assert feed(LineSplitter(), data, how) == ["W120 030", "C2", "AZ EL", "S"]


def test_a_partial_line_is_held_until_it_ends() -> None:
    lines = LineSplitter()
    assert lines.feed(b"W120 0") == [] and not lines.idle
    assert lines.feed(b"30\r") == ["W120 030"] and lines.idle


def test_an_overlong_line_is_junk_once_it_ends_and_the_stream_goes_on() -> None:
    lines = LineSplitter()
    assert lines.feed(b"M" + b"9" * (MAX_LINE * 3)) == [] and not lines.idle
    assert lines.feed(b"\rC\r") == [None, "C"]
    assert lines.idle


def test_any_bytes_keep_the_stream_usable() -> None:
    lines = LineSplitter()
    lines.feed(bytes(range(256)) * 3)
    assert lines.feed(b"\rC2\r")[-1:] == ["C2"]  # what the junk read as comes before it


@pytest.mark.parametrize(
    ("line", "request_"),
    [
        ("C", Gs232Request(Gs232Kind.READ_AZ)),
        ("B", Gs232Request(Gs232Kind.READ_EL)),
        ("C2", Gs232Request(Gs232Kind.READ_AZEL)),
        ("M120", Gs232Request(Gs232Kind.GOTO_AZ, 120)),
        ("M007", Gs232Request(Gs232Kind.GOTO_AZ, 7)),
        ("W120 030", Gs232Request(Gs232Kind.GOTO_AZEL, 120, 30)),
        ("W450 180", Gs232Request(Gs232Kind.GOTO_AZEL, 450, 180)),  # the protocol's range
        ("W5  9", Gs232Request(Gs232Kind.GOTO_AZEL, 5, 9)),
        ("S", Gs232Request(Gs232Kind.STOP)),
        ("A", Gs232Request(Gs232Kind.STOP_AZ)),
        ("E", Gs232Request(Gs232Kind.STOP_EL)),
    ],
)
def test_gs232_commands_are_read(line: str, request_: Gs232Request) -> None:
    assert parse_gs232(line) == request_


@pytest.mark.parametrize(
    "line",
    [
        None,  # an overlong line
        "M1200",  # huge: four digits are no GS-232 bearing
        "W99999 0",
        "Mnan",
        "WNaN 000",
        "M-10",
        "M12.5",
        "W120",  # elevation missing
        "W120 030 7",
        "c2",
        "X4",  # speed: not carried out
        "L",
        "R",
        "U",
        "D",
        "H",
        "S1",
        "\x00\xff",
    ],
)
def test_gs232_junk_is_unknown(line: str | None) -> None:
    assert parse_gs232(line) == Gs232Request(Gs232Kind.UNKNOWN)


@pytest.mark.parametrize(
    ("line", "request_"),
    [
        ("AZ EL", EasycommRequest(queries=("AZ", "EL"))),
        ("EL AZ", EasycommRequest(queries=("EL", "AZ"))),
        ("VE", EasycommRequest(queries=("VE",))),
        ("AZ120.0 EL30.5", EasycommRequest(az_deg=120.0, el_deg=30.5)),
        # Hamlib's -m 204 after a configuration command (``GS\n;``): its ``;`` starts the line
        (";AZ120.0 EL30.5", EasycommRequest(az_deg=120.0, el_deg=30.5)),
        (";AZ EL", EasycommRequest(queries=("AZ", "EL"))),
        ("AZ120", EasycommRequest(az_deg=120.0)),
        ("EL.5", EasycommRequest(el_deg=0.5)),
        ("az10 el5", EasycommRequest(az_deg=10.0, el_deg=5.0)),
        ("SA SE", EasycommRequest(stop=True)),
        ("SA", EasycommRequest(stop=True)),
        ("PARK", EasycommRequest(park=True)),
        ("RESET", EasycommRequest(unsupported=("RESET",))),
        ("ML", EasycommRequest(unsupported=("ML",))),
        ("VL0050", EasycommRequest(unsupported=("VL",))),  # Easycomm III's jog (-m 204's M)
        ("VU0010", EasycommRequest(unsupported=("VU",))),
        # Easycomm I's line: the radio's words are ignored, the bearing taken
        (
            "AZ10.0 EL5.0 UP000 XXX DN000 XXX",
            EasycommRequest(az_deg=10.0, el_deg=5.0, ignored=("UP000", "XXX", "DN000", "XXX")),
        ),
    ],
)
def test_easycomm_lines_are_read(line: str, request_: EasycommRequest) -> None:
    assert parse_easycomm(line) == request_


@pytest.mark.parametrize(
    "line",
    [
        *("AZnan EL0", "AZinf", "AZ1e9", "AZ99999.0", "EL--5", "AZ10 ELx", "AZ1,5", "AZ+"),
        *("AZ190 AZ200", "AZ10 EL5 EL50", "EL5 AZ10 el50"),  # which is meant? (not the last)
        # an axis word behind junk is none, and the line is not half of it (package rule 3)
        *(";;AZ200.0 EL30.0", "\x1fAZ200.0 EL30.0", "AZ200.0\x1cEL30.0", "EL30 UP000 X;Z"),
        *(" ;AZ200.0 EL30.0", "AZ200.0 ;EL30.0"),  # (only a line's first byte is Hamlib's)
    ],
)
def test_an_easycomm_line_with_a_malformed_number_does_nothing(line: str) -> None:
    request_ = parse_easycomm(line)
    assert request_.invalid is not None
    assert request_.az_deg is None and request_.el_deg is None and not request_.stop


@pytest.mark.parametrize(
    "line", ["SA SE AZ1x", "AZ1x SA SE", "SA SE EL--", "AZnan SA", "AZ190 SA AZ200"]
)
def test_a_stop_beside_a_malformed_easycomm_word_still_stops(line: str) -> None:
    """Package rule 6: the line does nothing else (rule 3), but stops."""
    request_ = parse_easycomm(line)
    assert request_.invalid is not None and request_.stop
    assert request_.az_deg is None and request_.el_deg is None and not request_.queries


def test_an_overlong_easycomm_line_is_invalid() -> None:
    assert parse_easycomm(None).invalid == "an overlong line"


@pytest.mark.parametrize(
    ("holds", "data", "stop"),
    [
        (gs232_holds_stop, b"S\r", True),
        (gs232_holds_stop, b"C\rA\r", True),
        (gs232_holds_stop, b"E\n", True),
        (gs232_holds_stop, b"C\rM120\r", False),
        (gs232_holds_stop, b"S", False),  # no end yet: no command
        (easycomm_holds_stop, b"AZ EL\nSA SE\n", True),
        (easycomm_holds_stop, b"AZ120.0 SA\n", True),
        (easycomm_holds_stop, b"AZ EL\n", False),
        (dcu1_holds_stop, b";", True),
        (dcu1_holds_stop, b"AI1;AS1;", True),
        (dcu1_holds_stop, b"AI1;", False),
        (dcu1_holds_stop, b"AP1120;AM1;", False),
    ],
)
def test_a_stop_among_complete_commands_is_told_for_the_accept_loop(
    holds: Callable[[bytes], bool], data: bytes, stop: bool
) -> None:
    """interfaces/tcplines.py rule 5: a connection whose first commands hold a stop goes
    ahead of its address's budget; the front end's own parser says which."""
    assert holds(data) is stop
