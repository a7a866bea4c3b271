"""Attacks on the pty line server (ptylines.py): what an unlucky client's terminal settings do,
on real pseudo-terminals with the GS-232B session onto a stand-in rotator."""

from __future__ import annotations

import termios
from collections.abc import Iterator
from pathlib import Path

import pytest

from bridge.gs232 import gs232_pty
from bridge.ptylines import PtyLineServer
from tests.test_ptylines import Client, StandIn


@pytest.fixture
def served(tmp_path: Path) -> Iterator[tuple[PtyLineServer, str]]:
    path = str(tmp_path / "rotor-gs232")
    server = gs232_pty(StandIn(), path)
    server.start()
    yield server, path
    server.stop()


def test_a_client_that_turns_echo_on_does_not_start_a_loop_of_replies(
    served: tuple[PtyLineServer, str],
) -> None:
    """A program that opens the port in cooked mode (or ``stty -F /tmp/rotor-gs232 sane``) turns
    the tty's ECHO on. A pty echoes what its master writes back to the master: the server read
    its own reply "AZ=042" as a command, answered "?>", read that, ... tens of thousands of
    replies a second, for ever while anyone reads, and the client's next answer lost in them.
    A serial line has no echo towards the computer: the server keeps it off."""
    _, path = served
    client = Client(path)
    try:
        attrs = termios.tcgetattr(client.fd)
        attrs[3] |= termios.ECHO | termios.ICANON  # what `stty sane` sets among the rest
        termios.tcsetattr(client.fd, termios.TCSANOW, attrs)
        assert client.ask(b"C\r") == b"AZ=042\r\n"
        assert client.ask(b"C\r", reply_ends=b"AZ=042\r\n") == b"AZ=042\r\n"
    finally:
        client.close()
