"""Opening a port (engine/port.py): what another program on the same tty meets, and what the
bridge says when one is there (issue 14, item 8: Hamlib's rotctld takes no flock, so the bridge
opened a port rotctld held and the two stole each other's replies, 27 reopen cycles in 20 s)."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest
import serial

from bridge.engine.port import open_port, read_available
from bridge.protocols import REGISTRY
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
