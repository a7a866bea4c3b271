"""Opening a port (runtime/port.py): what another program on the same tty meets, and what the
bridge says when one is there (issue 14, item 8: Hamlib's rotctld takes no flock, so the bridge
opened a port rotctld held and the two stole each other's replies, 27 reopen cycles in 20 s)."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest
import serial

from bridge.protocols import REGISTRY
from bridge.runtime.port import close_in_background, open_port, read_available, watched
from tests.support.waiting import slow


@pytest.fixture
def tty() -> str:
    """A pty's slave, as a USB adapter's tty: openable by anyone, as /dev/ttyUSB0 by dialout."""
    master, slave = os.openpty()
    path = os.ttyname(slave)
    os.chmod(path, 0o666)
    os.close(slave)
    yield path
    os.close(master)


def test_while_the_bridge_has_the_port_no_other_program_can_open_it(tty: str) -> None:
    port = open_port(tty, REGISTRY["rotorez"])
    try:
        code = (
            "import errno, os, sys\n"
            "try:\n    os.open(sys.argv[1], os.O_RDWR | os.O_NOCTTY)\n"
            "except OSError as e:\n    print(errno.errorcode[e.errno])\nelse:\n    print('opened')"
        )
        # root passes TIOCEXCL by: the other program runs as nobody, with the system's python
        as_user = {"user": 65534} if os.geteuid() == 0 else {}
        python = "/usr/bin/python3" if os.path.exists("/usr/bin/python3") else sys.executable
        out = subprocess.run(
            [python, "-c", code, tty], capture_output=True, text=True, timeout=slow(10), **as_user
        )
        assert out.stdout.strip() == "EBUSY", (out.stdout, out.stderr)
    finally:
        port.close()


def test_a_port_whose_bytes_another_reader_took_is_busy_not_unplugged(tty: str) -> None:
    port = open_port(tty, REGISTRY["rotorez"])
    try:
        # poll said readable, the read found nothing: another reader got there first
        with pytest.raises(serial.SerialException, match="another program reads from this port"):
            read_available(port.fileno(), True, tty)
        with pytest.raises(serial.SerialException, match="adapter unplugged"):
            read_available(port.fileno(), True, tty + "-gone")
        assert read_available(port.fileno(), False, tty) == b""  # not readable: nothing to say
    finally:
        port.close()


class Watch:
    """What the stop express is told (port.py rule 7), and whether the port was open then."""

    def __init__(self) -> None:
        self.told: list[tuple[str, int, bool]] = []
        self.fd = -1

    def opened(self, fd: int) -> None:
        self.fd = fd
        self.told.append(("opened", fd, _is_open(fd)))

    def closing(self, fd: int) -> None:
        self.told.append(("closing", fd, _is_open(fd)))


def _is_open(fd: int) -> bool:
    try:
        os.fstat(fd)
    except OSError:
        return False
    return True


def test_a_watch_gets_each_port_open_and_is_told_before_it_is_closed(tty: str) -> None:
    watch = Watch()
    port = watched(open_port, watch)(tty, REGISTRY["rotorez"], None)
    close_in_background(port, watch).join(slow(10))
    fd = watch.fd
    assert watch.told == [("opened", fd, True), ("closing", fd, True)]  # still open when told
    assert not port.is_open


def test_a_watch_that_fails_costs_the_port_nothing(tty: str) -> None:
    class Broken:
        def opened(self, fd: int) -> None:
            raise RuntimeError("the express is gone")

        def closing(self, fd: int) -> None:
            raise RuntimeError("the express is gone")

    port = watched(open_port, Broken())(tty, REGISTRY["rotorez"], None)
    assert port.is_open
    close_in_background(port, Broken()).join(slow(10))
    assert not port.is_open
