"""DX cluster lines: spots parsed, everything else dropped (never an exception), whole, byte by
byte and surrounded by garbage (house rule 1)."""

from __future__ import annotations

import random
import re

from hypothesis import given, settings
from hypothesis import strategies as st

from bridge.interfaces.dxcluster.spots import MAX_LINE_BYTES, Lines, Spot, parse_spot

SPOTS = [
    (
        b"DX de EA5WU:     14025.0  JA1ABC       cq up 2                        1829Z",
        Spot("JA1ABC", 14025.0, "EA5WU", "1829", "cq up 2"),
    ),
    (
        b"DX de W3LPL-#:    7012.5  VK2XYZ/P     CW 21 dB 28 WPM CQ             0102Z FN20",
        Spot("VK2XYZ/P", 7012.5, "W3LPL-#", "0102", "CW 21 dB 28 WPM CQ"),
    ),
    (
        b"DX de g4abc:   50313.0  w1xyz   FT8 JO01<>FN31pr  2359Z\x07\x07",
        Spot("W1XYZ", 50313.0, "G4ABC", "2359", "FT8 JO01<>FN31pr"),
    ),
    (b"DX de DL1XX:  3510  F5ABC  1200Z", Spot("F5ABC", 3510.0, "DL1XX", "1200", "")),
    # rule 6: a time in the comment is the comment's; after the spot's time, a zone, a state
    (
        b"DX de EA5WU:     14025.0  JA1ABC       PM95 QRV til 2300Z            1829Z",
        Spot("JA1ABC", 14025.0, "EA5WU", "1829", "PM95 QRV til 2300Z"),
    ),
    (
        b"DX de EA5WU:     14025.0  JA1ABC       QSX 1835Z                    1829Z JO01",
        Spot("JA1ABC", 14025.0, "EA5WU", "1829", "QSX 1835Z"),
    ),
    (
        b"DX de K1TTT:     14025.0  JA1ABC       cq                      25  1829Z  5",
        Spot("JA1ABC", 14025.0, "K1TTT", "1829", "cq                      25"),
    ),
    (
        b"DX de K1TTT:     14025.0  JA1ABC       cq                             1829Z MA",
        Spot("JA1ABC", 14025.0, "K1TTT", "1829", "cq"),
    ),
]
JUNK = [
    b"",
    b"login: ",
    b"Hello G4ABC, this is GB7DJK in Dorking",
    b"To ALL de G4ABC: hello",
    b"WWV de W0MU <18>:   SFI=70, A=5, K=1, No Storms -> No Storms",
    b"DX de EA5WU:     14025.0  JA1ABC       cq                             2561Z",  # 25:61
    b"DX de EA5WU:     14025.0  JA1ABC       cq                             2459Z",  # hour 24
    b"DX de EA5WU:     14025.0  JA1ABC       cq                             1860Z",  # minute 60
    b"DX de EA5WU:     14025.0  JA1ABC       cq",  # no time
    b"DX de EA5WU:     14025.0  JA1ABC       cq 1829Z  QRV",  # rule 6: no field a node adds
    b"DX de EA5WU:     14025.0  JA1ABC       cq 1829Z  1830",
    b"DX de EA5WU:     abc  JA1ABC       cq   1829Z",
    b"DX de EA5WU:     14025.0  ABCDEF       cq   1829Z",  # no digit: no call
    b"DX de EA5WU:     0.0  JA1ABC       cq   1829Z",
    b"DX de EA5WU:     14025.0  JA1\xffABC  cq   1829Z",  # not UTF-8 (Latin-1: no call)
    b"DX de EA5WU:     14025.0  JA1ABC  c\x00q   1829Z",  # not printable
    "DX de EA5WU:  14025.0  JA1ÄBC  cq  1829Z".encode(),
    bytes(range(256)),
    # rule 3 (an attack pass): what a user said, not a spot, whatever it holds
    b"To ALL de M0BAD: DX de EA5WU: 14026.0 JA1ABC cq FN30as 1830Z",
    b"To ALL de M0BAD-2: look DX de EA5WU: 14026.0 JA1ABC cq FN30as 1830Z",
    b"WWV de VE7CC <18>: DX de EA5WU: 14026.0 JA1ABC cq FN30as 1830Z",
    b"G4XYZ de M0BAD: DX de EA5WU: 14026.0 JA1ABC cq FN30as 1830Z",
]


def test_spots_are_parsed() -> None:
    for line, spot in SPOTS:
        assert parse_spot(line) == spot, line
        assert parse_spot(line.decode("utf-8")) == spot


def test_what_is_no_spot_is_none() -> None:
    for line in JUNK:
        assert parse_spot(line) is None, line
    rng = random.Random(28)
    for _ in range(2000):  # random bytes, and spots with bytes flipped: never an exception
        parse_spot(bytes(rng.randrange(256) for _ in range(rng.randrange(120))))
        line = bytearray(SPOTS[0][0])
        line[rng.randrange(len(line))] = rng.randrange(256)
        parse_spot(bytes(line))


def _stream() -> bytes:
    parts = [b"Hello\r\nlogin: "]
    for (line, _), junk in zip(SPOTS, JUNK, strict=False):
        parts += [line + b"\r\n", junk + b"\r\n"]
    return b"".join(parts)


def _spots_of(lines: list[bytes]) -> list[Spot]:
    return [s for s in map(parse_spot, lines) if s is not None]


def test_lines_whole_and_byte_by_byte_give_the_same_spots() -> None:
    want = [spot for _, spot in SPOTS]
    whole = Lines()
    assert _spots_of(whole.feed(_stream())) == want
    assert whole.pending == b""
    single = Lines()
    got: list[bytes] = []
    for i in range(len(_stream())):
        got += single.feed(_stream()[i : i + 1])
    assert _spots_of(got) == want
    assert got == Lines().feed(_stream())


def test_a_spot_after_a_prompt_left_without_a_line_end_is_a_spot() -> None:
    """Rule 3: a node's prompt ("G4ABC de GB7DJK 4-Dec-2026 1830Z dxspider >") is no header
    of something said."""
    line, spot = SPOTS[0]
    for prompt in (b"G4ABC de GB7DJK 4-Dec-2026 1830Z dxspider >", b"login: ", b"\x07"):
        assert parse_spot(prompt + line) == spot, prompt


def test_a_prompt_without_a_line_end_is_pending() -> None:
    lines = Lines()
    assert lines.feed(b"Welcome\r\nlog") == [b"Welcome"]
    assert lines.feed(b"in: ") == []
    assert lines.pending == b"login: "


def test_a_long_line_is_dropped_whole_and_counted() -> None:
    lines = Lines()
    spot = SPOTS[0][0]
    flood = b"DX de X" + b"9" * (3 * MAX_LINE_BYTES)
    out: list[bytes] = []
    for i in range(0, len(flood), 100):
        out += lines.feed(flood[i : i + 100])
    assert out == [] and len(lines.pending) <= MAX_LINE_BYTES
    out = lines.feed(b"tail of it " + spot + b"\r\n" + spot + b"\r\n")
    assert _spots_of(out) == [SPOTS[0][1]]  # the long line's tail is gone, the next one kept
    assert lines.long_lines == 1
    exact = Lines()
    assert exact.feed(b"a" * MAX_LINE_BYTES + b"\n") == [b"a" * MAX_LINE_BYTES]
    assert exact.long_lines == 0


def test_reset_forgets_half_a_line() -> None:
    lines = Lines()
    lines.feed(b"DX de half")
    lines.reset()
    assert lines.feed(SPOTS[0][0] + b"\n") == [SPOTS[0][0]]


def test_a_spot_whose_comment_is_latin_1_is_kept() -> None:
    """Nodes relay their users' comments as typed: a Spanish or German operator's ``ñ`` or
    ``ä`` arrives as one Latin-1 byte, not UTF-8. The spot (call, frequency, time) is sound and
    must not be lost for one letter of its comment."""
    line = "DX de EA5WU:     14025.0  JA1ABC       señor grüß                     1829Z"
    spot = parse_spot(line.encode("latin-1"))
    assert spot is not None
    assert (spot.call, spot.freq_khz, spot.comment) == ("JA1ABC", 14025.0, "señor grüß")


# -- hostile lines (rule 5): whatever a node sends, parsing is linear in the line -------------

_HOSTILE_HEADS = [
    "DX de ",
    "DX de K1ABC: ",
    "DX de K1ABC: 14000 ",
    "DX de K1ABC: 14000 DL1ABC ",
]


def _hostile(head: str, filler: str, length: int) -> str:
    body = (filler * length)[: length - len(head) - 1]
    return head + body + "x"


def test_a_line_of_spaces_with_no_time_is_no_spot_at_the_longest_line() -> None:
    """A line the node may send (under the longest line), made to make a backtracking pattern
    try every split of its spaces between the comment and the time: cubic in the line, 0.2 s
    for one such line, several seconds for a stream of them, all of it holding the GIL beside
    a stop. Each shape below is parsed (and is no spot), a thousand of them in this test."""
    for head in _HOSTILE_HEADS:
        for filler in (" ", " 1", " 1234", "1 ", " Z", " 1829"):
            line = _hostile(head, filler, MAX_LINE_BYTES - 1)
            for _ in range(40):
                assert parse_spot(line) is None, line
                assert parse_spot(line.encode()) is None
    spot = _hostile("DX de K1ABC: 14000 DL1ABC 1829Z", " ", MAX_LINE_BYTES - 1)[:-4] + "JO01"
    assert parse_spot(spot) == Spot("DL1ABC", 14000.0, "K1ABC", "1829", "")


def test_a_line_longer_than_the_longest_is_no_spot_whatever_it_holds() -> None:
    """The parser takes str too (not only what Lines cut): a line past MAX_LINE_BYTES is no
    spot, however it is made; a spot line is under 100 characters."""
    spot = SPOTS[0][0].decode()
    long_comment = spot.replace("cq up 2", "cq " + "a" * MAX_LINE_BYTES)
    assert parse_spot(long_comment) is None
    assert parse_spot(_hostile(_HOSTILE_HEADS[3], " ", 10 * (MAX_LINE_BYTES - 1))) is None
    fits = spot.replace("cq up 2", "cq " + "a" * (MAX_LINE_BYTES - len(spot) + 4))
    assert len(fits) == MAX_LINE_BYTES
    assert parse_spot(fits) == Spot("JA1ABC", 14025.0, "EA5WU", "1829", fits[33:-5].strip())


# the pattern the parser had: right, but cubic on hostile lines; after the time, only what a
# node puts there (spots.py rule 6: a locator, a zone, a state)
_ORACLE = re.compile(
    r"DX de (?P<spotter>[A-Z0-9/#-]{3,24}):?\s+(?P<freq>\d{1,9}(?:\.\d{1,3})?)\s+"
    r"(?P<call>[A-Z0-9/]{3,20})\s+(?P<comment>.*?)\s*(?P<time>\d{4})Z"
    r"(?:\s+(?:[A-R]{2}\d{2}(?:[A-X]{2})?|\d{1,2}|[A-Z]{2}))?\s*",
    re.ASCII | re.IGNORECASE,
)


def _oracle(text: str) -> Spot | None:
    start = text.find("DX de ")
    if start < 0:
        return None
    text = text[start:].strip("\r\n\x07 ")
    m = _ORACLE.fullmatch(text) if text.isprintable() else None
    if m is None:
        return None
    call, hhmm, freq_khz = m["call"].upper(), m["time"], float(m["freq"])
    if not re.search("[0-9]", call) or not re.search("[A-Z]", call):
        return None
    if int(hhmm[:2]) > 23 or int(hhmm[2:]) > 59 or not 1.0 <= freq_khz <= 300e6:
        return None
    return Spot(call, freq_khz, m["spotter"].upper(), hhmm, m["comment"].strip())


_PIECES = [" ", "  ", "1", "0", "9", "Z", "z", "A", "k", "/", ":", ".", "-", "#", "\t", "\x07"]
_WORDS = ["1829Z", "2359z", "14025.0", "JA1ABC", "ea5wu", "FN20", "DX de "]


@settings(max_examples=500, deadline=None)
@given(
    head=st.sampled_from(["", "DX de ", "DX de EA5WU: ", "DX de EA5WU:  14025.0  "]),
    body=st.lists(st.sampled_from(_PIECES + _WORDS), max_size=16),
)
def test_the_parser_reads_what_the_pattern_read(head: str, body: list[str]) -> None:
    """On short lines (where the old pattern's backtracking costs nothing) the parser finds
    the same spot as the pattern did, or no spot where it found none."""
    line = head + "".join(body)
    assert parse_spot(line) == _oracle(line), line
