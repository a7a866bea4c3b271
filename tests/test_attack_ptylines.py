"""Attacks on the pty line server (interfaces/ptylines.py): what an unlucky client's terminal
settings do, on real pseudo-terminals with the GS-232B session onto a stand-in rotator."""

from __future__ import annotations

import errno
import os
import termios
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from bridge.core.haltwatch import HaltWatchers
from bridge.core.model import Target
from bridge.interfaces.gs232 import Gs232Session, gs232_pty
from bridge.interfaces.ptylines import PtyLineServer
from bridge.interfaces.tcplines import unread
from tests.support import wait_until
from tests.support.clock import FakeClock
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


def test_a_second_server_does_not_steal_a_link_another_one_serves(tmp_path: Path) -> None:
    """The remote (or the bridge) started twice with one pty path: a link already there was
    taken for a crash's leftover and replaced, so the second silently took the first one's
    clients, and on stopping removed the link while the first still served. A link a live
    server holds is refused, naming the path; once that server is gone it is taken."""
    path = str(tmp_path / "rotor-gs232")
    first, second = gs232_pty(StandIn(), path), gs232_pty(StandIn(), path)
    first.start()
    try:
        with pytest.raises(OSError, match=r"another program serves a pty there") as caught:
            second.listen()
        assert caught.value.errno == errno.EADDRINUSE
        assert os.readlink(path) == first.slave_name
    finally:
        first.stop()
    second.start()  # the path free again
    try:
        assert os.readlink(path) == second.slave_name
    finally:
        second.stop()


def test_a_leftover_link_of_a_server_that_died_is_still_replaced(tmp_path: Path) -> None:
    """The claim dies with its process: a crash's link (to a pty since closed, or one its
    number now names for someone else) is replaced as before."""
    path = tmp_path / "rotor-gs232"
    path.symlink_to("/dev/pts/0")
    server = gs232_pty(StandIn(), str(path))
    server.start()
    try:
        assert os.readlink(path) == server.slave_name
    finally:
        server.stop()


@dataclass
class Counted(StandIn):
    """A stand-in that counts halts (front.py ``HaltCounted.halts``) and hears refusals."""

    halts: int = 0
    refused: list[str] = field(default_factory=list)

    def report_refusal(self, message: str, command: str | None, **_: object) -> None:
        self.refused.append(message)


def test_moves_a_client_wrote_before_a_stop_are_not_carried_out_after_it(tmp_path: Path) -> None:
    """tcplines.py rule 9 on a pty (an attack pass): a program wrote its targets in one burst,
    the budget left most of them in the pty, a STOP from MQTT came (the halt count rose), and
    every target read after it turned the rotor again. Virtual time: the clock stands still
    until the STOP, so the rest is read only after it."""
    clock = FakeClock()
    rot = Counted()
    path = str(tmp_path / "rotor-gs232")
    server = PtyLineServer(
        rot.id, path, lambda: Gs232Session(rot), label="gs232", key="gs232", clock=clock
    )
    server.start()
    client = Client(path)
    burst = 400
    try:
        os.write(client.fd, b"M200\r" * burst)
        wait_until(lambda: server.paused > 0, 10, "the server paused")
        before = len(rot.submitted)
        assert 0 < before < burst
        rot.halts += 1  # an MQTT STOP, carried out while the rest waits in the pty

        def all_read() -> bool:
            clock.t += 1.0  # (a second's budget at each look)
            return len(rot.submitted) + len(rot.refused) == burst

        wait_until(all_read, 10, "every target read")
        assert len(rot.submitted) == before  # none of those sent before the STOP went out
    finally:
        client.close()
        server.stop()


def test_a_move_written_while_the_server_sleeps_over_its_budget_is_refused_after_a_stop(
    tmp_path: Path,
) -> None:
    """tcplines.py rule 9 on a pty (a cold review of the TCP fence): the thread sleeps over
    its budget, makes no look of its own, and the client writes ``M100`` then; an MQTT STOP
    comes. Without the look before the halt (the watchers) its bytes were first counted after
    the STOP, and the rotor turned to 100. Virtual time: the clock stands still until then."""
    clock = FakeClock()
    rot = Counted()
    watchers = HaltWatchers()
    path = str(tmp_path / "rotor-gs232")
    server = PtyLineServer(
        rot.id,
        path,
        lambda: Gs232Session(rot),
        label="gs232",
        key="gs232",
        clock=clock,
        halt_count=lambda: rot.halts,
        halt_watchers=watchers,
    )
    server.start()
    client = Client(path)
    burst = 400
    try:
        os.write(client.fd, b"M200\r" * burst)
        wait_until(lambda: server.paused > 0, 10, "the server paused")
        before = unread(server._master)
        os.write(client.fd, b"M100\r")  # while it sleeps: no look of its own
        # (a pty hands what its slave wrote to the master a moment later, off the writer's call)
        wait_until(lambda: unread(server._master) == before + 5, 10, "the M100 in the pty")
        watchers()  # an MQTT STOP: told first (mailbox.py rule 10), then counted
        rot.halts += 1

        def all_read() -> bool:
            clock.t += 1.0  # (a second's budget at each look)
            return len(rot.submitted) + len(rot.refused) == burst + 1

        wait_until(all_read, 10, "every target read")
        assert not [t for t in rot.submitted if isinstance(t, Target) and t.az_deg == 100.0]
    finally:
        client.close()
        server.stop()
