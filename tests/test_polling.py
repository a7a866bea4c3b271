"""core/polling.py: the poller the remote waits with on Windows (select() alone) says what
poll() says, run here over the same sockets."""

from __future__ import annotations

import socket
from collections.abc import Iterator

import pytest

from bridge.core.polling import POLLIN, POLLNVAL, POLLOUT, Poller, SelectPoller, new_poller


@pytest.fixture
def pair() -> Iterator[tuple[socket.socket, socket.socket]]:
    a, b = socket.socketpair()
    yield a, b
    a.close()
    b.close()


def test_it_says_readable_and_writable_as_poll_does(
    pair: tuple[socket.socket, socket.socket],
) -> None:
    a, b = pair
    for poller in (SelectPoller(), new_poller()):
        poller.register(a, POLLIN)
        assert poller.poll(0) == []  # nothing to read yet
        b.send(b"x")
        assert poller.poll(1000) == [(a.fileno(), POLLIN)]
        poller.modify(a, POLLOUT)
        assert poller.poll(0) == [(a.fileno(), POLLOUT)]
        poller.unregister(a)
        with pytest.raises(KeyError):
            poller.unregister(a)
        a.recv(1)


def test_a_descriptor_closed_under_it_is_said_gone(
    pair: tuple[socket.socket, socket.socket],
) -> None:
    a, _b = pair
    poller: Poller = SelectPoller()
    poller.register(a.fileno(), POLLIN)
    number = a.fileno()
    a.close()
    assert poller.poll(0) == [(number, POLLNVAL)]


def test_with_nothing_registered_it_waits_its_timeout_and_says_nothing() -> None:
    assert SelectPoller().poll(1) == []


def test_modify_of_a_descriptor_never_registered_is_refused(
    pair: tuple[socket.socket, socket.socket],
) -> None:
    with pytest.raises(FileNotFoundError):
        SelectPoller().modify(pair[0], POLLIN)
