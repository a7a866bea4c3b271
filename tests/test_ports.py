"""The tests' free ports (tests/support/ports.py): a port handed to a listener is one no sender
of another test can be given first. A PstRotator port the kernel had handed out was taken by
someone's unbound sendto before the bridge bound it, and fifteen tests failed to start."""

from __future__ import annotations

import socket

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
