"""The benchmarks' own arithmetic, where a wrong figure would pass for a measurement: the paced
line's floor under a stop (benchmarks/line.py rule 7) and the stop rows' split of each latency
into the line's floor and the bridge's part (benchmarks/stop_under_load.py)."""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest

from benchmarks.line import PacedRelay, wire_ahead
from benchmarks.stop_under_load import Sample, floor_split, query_after
from tests.support.waiting import wait_until

BYTE_S = 10 / 4800  # a Rotor-EZ's line: 2.08 ms a byte
QUERY = b"AI1;"


def read_at(t: float, data: bytes, free_s: float = 0.0) -> tuple[float, float, bytes]:
    """A read as the relay keeps it: when, the due time of its last byte, the bytes."""
    return t, max(t, free_s) + len(data) * BYTE_S, data


def test_an_idle_line_puts_nothing_ahead() -> None:
    sent = read_at(10.0, QUERY)  # its last byte due at 10.0083
    ahead = wire_ahead([sent], 10.5)
    assert ahead.s == 0.0 and ahead.data == b""


def test_a_query_still_on_the_line_is_ahead_until_its_last_byte() -> None:
    t_read, due, _ = sent = read_at(10.0, QUERY)
    publish = t_read + 0.0003  # the STOP is published right after the query was handed over
    ahead = wire_ahead([sent], publish)
    assert ahead.data == QUERY
    assert ahead.s == pytest.approx(due - publish)
    assert ahead.s == pytest.approx(4 * BYTE_S - 0.0003)  # 8.0 ms of the query's 8.3


def test_a_query_sent_in_part_is_still_ahead() -> None:
    sent = read_at(10.0, QUERY)
    ahead = wire_ahead([sent], 10.0 + 2.5 * BYTE_S)  # its third byte on the wire
    assert ahead.data == QUERY
    assert ahead.s == pytest.approx(1.5 * BYTE_S)


def test_bytes_read_after_the_publish_are_not_the_lines_floor() -> None:
    """What the bridge wrote after the STOP (or what reached the line after it) is the
    bridge's part, not the line's."""
    publish = 10.0
    ahead = wire_ahead([read_at(publish + 0.001, QUERY)], publish)
    assert ahead.s == 0.0 and ahead.data == b""


def test_reads_queued_behind_each_other_are_ahead_together() -> None:
    first = read_at(10.0, QUERY)
    second = read_at(10.001, b"AP1180\r", free_s=first[1])  # waits behind the query
    done = read_at(9.0, QUERY)  # long delivered
    ahead = wire_ahead([done, first, second], 10.002)
    assert ahead.data == QUERY + b"AP1180\r"
    assert ahead.s == pytest.approx(second[1] - 10.002)
    assert ahead.s == pytest.approx(11 * BYTE_S - 0.002)


def stop(latency_ms: float, ahead_ms: float = 0.0, ahead: bytes = b"") -> Sample:
    return Sample("m0", "now", latency_ms / 1e3, 0.0, wire_ahead_s=ahead_ms / 1e3, ahead=ahead)


def test_the_bridges_part_is_the_latency_beyond_the_line_floor() -> None:
    assert stop(10.4, 8.0, QUERY).bridge_s * 1e3 == pytest.approx(2.4)


def test_a_row_judges_the_bridges_part_and_counts_the_stops_behind_bytes() -> None:
    """60 stops: one right behind a query (10.4 ms raw, 2.4 ms the bridge's), one behind a
    move frame, the others on an idle line: the bridge's p99 is the largest of its parts."""
    stops = [stop(3.0 + i * 0.01) for i in range(58)]
    stops += [stop(10.4, 8.0, QUERY), stop(9.0, 4.0, b"AP1180\r")]
    own99, behind, queries = floor_split(stops)
    assert own99 == pytest.approx(5.0)  # the move's stop: 9.0 - 4.0, over every idle one
    assert (behind, queries) == (2, 1)


def test_a_query_written_after_the_publish_stays_the_bridges_part() -> None:
    """A query that went out after the publish and before the stop: no floor (the bridge wrote
    it after the STOP was sent), counted on its own."""
    late = Sample("m0", "now", 0.0104, 0.0, after=QUERY + b";;")
    first = Sample("m0", "now", 0.003, 0.0, after=b";" + QUERY)  # the stop went first
    assert late.bridge_s == pytest.approx(0.0104)
    assert query_after([late, first]) == 1
    assert floor_split([late, first]) == (pytest.approx(10.4), 0, 0)


def test_the_relay_keeps_its_reads_on_the_publish_clock(tmp_path: Path) -> None:
    """The relay stamps what it reads with time.monotonic, the clock of the benchmark's
    publish stamps: a query written between two of our stamps is read between them, and is
    ahead of a publish right after it until its last byte is due."""
    master, slave = os.openpty()  # the controller's side: its bytes are not looked at here
    relay = PacedRelay(os.ttyname(slave), tmp_path / "line", 4800)
    try:
        fd = os.open(tmp_path / "line", os.O_RDWR | os.O_NOCTTY)
        try:
            before = time.monotonic()
            os.write(fd, QUERY)

            def got() -> bytes:
                return b"".join(data for *_, data in relay.received)

            wait_until(lambda: got() == QUERY, 5, "the relay read the query")
            after = time.monotonic()
        finally:
            os.close(fd)
        reads = list(relay.received)  # one read, or the query in parts as the pty passed it
        assert all(before <= t_read <= after for t_read, _, _ in reads)
        t_read, due, data = reads[0]
        assert due == pytest.approx(t_read + len(data) * BYTE_S)  # the line was idle
        ahead = relay.ahead_of(t_read + 1e-6)  # a publish right after that read
        assert ahead.data == data and ahead.s == pytest.approx(due - t_read - 1e-6)
        assert relay.read_between(before, after) == QUERY
    finally:
        relay.close()
        os.close(master)
        os.close(slave)
