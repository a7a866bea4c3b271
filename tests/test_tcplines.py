"""The shared line server's HTTP guard (tcplines.py rule 2), sans sockets: a GS-232 client's
CR-ended first line goes through at once, HTTP never does."""

from __future__ import annotations

from bridge.tcplines import HTTP_FIRST_LINE_MAX, HttpGuard


def test_a_first_line_ended_by_cr_alone_is_released_at_once() -> None:
    guard = HttpGuard()
    assert guard.feed(b"C2") == b""  # held: it might still become a request line
    assert guard.feed(b"\r") == b"C2\r" and guard.http is None
    assert guard.feed(b"W120 030\r\r") == b"W120 030\r\r"


def test_an_http_request_line_is_caught_however_it_is_cut() -> None:
    for cut in (b"POST / HTTP/1.1\r", b"POST / HTTP/1.1\r\n", b"GET /x HTTP/1.0\n"):
        guard = HttpGuard()
        assert guard.feed(cut) == b"" and guard.http == "an HTTP request line"


def test_a_header_line_is_caught_after_an_innocent_first_line() -> None:
    guard = HttpGuard()
    assert guard.feed(b"C2\r\n") == b"C2\r\n"
    assert guard.feed(b"Host: 127.0.0.1\r\n\r\nM120\r") == b""
    assert guard.http == "an HTTP header (Host)"


def test_a_first_line_with_no_end_is_released_at_the_limit() -> None:
    guard = HttpGuard()
    assert guard.feed(b"x" * (HTTP_FIRST_LINE_MAX - 1)) == b""
    assert len(guard.feed(b"x")) == HTTP_FIRST_LINE_MAX
