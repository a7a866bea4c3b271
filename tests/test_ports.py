"""The tests' free ports (tests/support/ports.py): a port handed to a listener is one no sender
of another test can be given first. A PstRotator port the kernel had handed out was taken by
someone's unbound sendto before the bridge bound it, and fifteen tests failed to start."""

from __future__ import annotations

import socket

import pytest

from tests.support import ports
from tests.support.ports import _ephemeral_low, free_port, free_udp_pair, free_udp_port


def test_a_free_port_is_below_the_range_senders_are_given_and_never_handed_twice() -> None:
    low = _ephemeral_low()
    handed = [free_udp_port() for _ in range(20)] + [free_port() for _ in range(20)]
    assert all(port < low for port in handed), (handed, low)
    assert len(set(handed)) == len(handed)


def test_a_pst_pair_is_two_free_udp_ports_in_a_row() -> None:
    port = free_udp_pair()
    assert port + 1 < _ephemeral_low()
    with (
        socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as server,
        socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as replies,
    ):
        server.bind(("127.0.0.1", port))
        replies.bind(("127.0.0.1", port + 1))


class Highest:
    """A picker that takes the highest port it is offered (``_PICK.choice``)."""

    def choice(self, ports: range) -> int:
        return ports[-1]


def test_a_pst_pair_picked_at_the_top_of_the_range_stays_below_the_senders_range(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Run without parallel workers (a benchmark, one test file by hand), the range is every
    port below the kernel's range for senders, and a pair picked at its top had its reply
    port n + 1 in that range, where any test's sender may be given it first."""
    monkeypatch.delenv("PYTEST_XDIST_WORKER", raising=False)
    monkeypatch.setattr(ports, "_PICK", Highest())
    monkeypatch.setattr(ports, "_HANDED", set())
    port = free_udp_pair()
    assert port + 1 < _ephemeral_low(), port
