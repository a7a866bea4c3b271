"""The DX cluster client alone (no broker, no rotator), against the fake node on loopback: a
node that never prompts is left after LOGIN_WAIT_S (its clock is the test's) and tried again; a
node that cannot be reached is tried again; stop() ends both threads."""

from __future__ import annotations

import json
import socket
from collections.abc import Iterator

import pytest

from bridge.dxcluster.book import Book
from bridge.dxcluster.client import LOGIN_WAIT_S, DxCluster
from bridge.dxcluster.cty import parse_dat
from tests.dxcluster.cty_sample import CTY_DAT
from tests.support import wait_until
from tests.support.cluster import FakeCluster, Session

SPOT = b"DX de EA5WU:     14025.0  JA1ABC       cq up 2                        1829Z\r\n"


class JumpingClock:
    """Each reading LOGIN_WAIT_S later than the one before: the first quiet read is already
    past the prompt's deadline (virtual time for the wait; the socket's read is real)."""

    def __init__(self) -> None:
        self.t = 0.0

    def __call__(self) -> float:
        self.t += LOGIN_WAIT_S
        return self.t


@pytest.fixture
def published() -> Iterator[list[str]]:
    yield []


def client(port: int, published: list[str], clock: JumpingClock | None = None) -> DxCluster:
    book = Book(parse_dat(CTY_DAT), (52.5, 13.4))
    dx = DxCluster("127.0.0.1", port, "G4ABC", book, published.append, backoff_s=0.01)
    if clock is not None:
        dx.clock = clock
    return dx


def test_no_prompt_in_time_is_a_failure_and_the_client_tries_again(
    published: list[str],
) -> None:
    def silent(s: Session) -> None:  # never prompts; waits until the client hangs up
        s.conn.settimeout(30)
        while s.conn.recv(1024):
            pass

    def prompt(s: Session) -> None:
        s.send(b"login: ")
        cluster.logins.append(s.read_line())
        s.send(SPOT)
        cluster.done.wait(30)

    cluster = FakeCluster([silent, prompt])
    dx = client(cluster.port, published, JumpingClock())
    dx.start()
    try:
        wait_until(lambda: any("JA1ABC" in p for p in published), 20, "the spot published")
        assert cluster.logins == [b"G4ABC"]
        assert (dx.counts.failures, dx.counts.connects) == (1, 1)
        assert json.loads(published[0]) == {"spots": []}  # the run before's spots cleared
    finally:
        dx.stop()
        cluster.close()
    assert not cluster.errors, cluster.errors


def test_a_node_that_cannot_be_reached_is_tried_again_and_stop_ends_it(
    published: list[str],
) -> None:
    with socket.socket() as probe:  # a port with nothing listening on it
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    dx = client(port, published)
    dx.start()
    wait_until(lambda: dx.counts.failures >= 3, 20, "three refused connections")
    threads = list(dx._threads)
    assert len(threads) == 2
    dx.stop()
    assert not any(t.is_alive() for t in threads)
    assert dx.counts.connects == 0
