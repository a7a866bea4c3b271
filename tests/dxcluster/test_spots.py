"""DX cluster lines: spots parsed, everything else dropped (never an exception), whole, byte by
byte and surrounded by garbage (house rule 1)."""

from __future__ import annotations

import random

from bridge.dxcluster.spots import MAX_LINE_BYTES, Lines, Spot, parse_spot

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
    b"DX de EA5WU:     abc  JA1ABC       cq   1829Z",
    b"DX de EA5WU:     14025.0  ABCDEF       cq   1829Z",  # no digit: no call
    b"DX de EA5WU:     0.0  JA1ABC       cq   1829Z",
    b"DX de EA5WU:     14025.0  JA1\xffABC  cq   1829Z",  # not UTF-8 (Latin-1: no call)
    b"DX de EA5WU:     14025.0  JA1ABC  c\x00q   1829Z",  # not printable
    "DX de EA5WU:  14025.0  JA1ÄBC  cq  1829Z".encode(),
    bytes(range(256)),
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
