"""WSJT-X's own reference server judges the tests' encoder (tests/support/wsjtx.py, written
from the fact sheet): ``udp_daemon`` from Debian's ``wsjtx`` package reads its datagrams with
WSJT-X's MessageServer and prints what it understood. Its Status handler prints only the dial
frequency and the mode (fields read before and after nothing else than the header); its QSO
Logged handler prints the DX call and grid, encoded the same way as in a Status. Its reply to
a heartbeat, built by WSJT-X's own code, is read back by the bridge's decoder. And the bridge's
listener shares a multicast group with it on one port, as it would with GridTracker."""

from __future__ import annotations

import shutil
import socket
import subprocess
import threading
from collections.abc import Iterator
from contextlib import contextmanager

import pytest

from bridge.interfaces.wsjtx import WsjtxListener
from bridge.interfaces.wsjtx.messages import Heartbeat, decode
from bridge.session.follow import Heard
from tests.support import wait_until
from tests.support import wsjtx as w
from tests.support.ports import free_udp_port
from tests.support.waiting import slow

GROUP = "239.255.0.1"


class Daemon:
    def __init__(self, process: subprocess.Popen[str]) -> None:
        self.process = process
        self.lines: list[str] = []
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        assert self.process.stdout is not None
        for line in self.process.stdout:
            self.lines.append(line.rstrip("\n"))

    def printed(self, text: str) -> bool:
        return any(text in line for line in list(self.lines))

    def wait_printed(self, text: str) -> None:
        wait_until(lambda: self.printed(text), 10, f"udp_daemon prints {text!r}: {self.lines}")


@contextmanager
def udp_daemon(port: int, group: str | None = None) -> Iterator[Daemon]:
    path = shutil.which("udp_daemon")
    if path is None:
        pytest.fail(
            "WSJT-X's udp_daemon is not installed (Debian: apt-get install wsjtx; ./tests/run "
            "installs it): it is the independent judge of the encoder, this cannot be skipped"
        )
    argv = [path, "--port", str(port)] + (["--multicast-group", group] if group else [])
    process = subprocess.Popen(
        argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, bufsize=1
    )
    try:
        yield Daemon(process)
    finally:
        process.terminate()
        try:
            process.wait(slow(5))
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait(slow(5))


def discovered(daemon: Daemon, send: socket.socket, to: tuple[str, int]) -> None:
    """Heartbeats until the daemon, listening by now, says it has seen WSJT-X."""

    def seen() -> bool:
        send.sendto(w.heartbeat(version="2.6.1", revision="r1"), to)
        return daemon.printed("Discovered WSJT-X instance: WSJT-X")

    wait_until(seen, 10, "udp_daemon discovers the instance", interval_s=0.2)


def test_udp_daemon_reads_the_tests_status_and_qso_messages() -> None:
    port = free_udp_port()
    to = ("127.0.0.1", port)
    with udp_daemon(port) as daemon, socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        discovered(daemon, sock, to)
        qso = w.StatusFields(dx_call="JA1ABC", dx_grid="PM95", dial_hz=7_074_000, mode="FT4")
        sock.sendto(w.status(qso), to)
        daemon.wait_printed("Dial frequency changed to 7074000")
        daemon.wait_printed("Mode changed to FT4")
        sock.sendto(w.qso_logged("JA1ABC", "PM95"), to)
        daemon.wait_printed("Logged JA1ABC grid: PM95")


def test_udp_daemons_own_heartbeat_is_read_by_the_bridges_decoder() -> None:
    port = free_udp_port()
    to = ("127.0.0.1", port)
    with udp_daemon(port) as daemon, socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.bind(("127.0.0.1", 0))
        discovered(daemon, sock, to)
        sock.settimeout(slow(10))
        reply, _ = sock.recvfrom(65536)  # the reply to the first heartbeat it read
    message = decode(reply)
    assert isinstance(message, Heartbeat)
    assert message.instance == "WSJT-X" and message.max_schema == 3


def test_the_bridges_listener_shares_a_multicast_group_with_udp_daemon() -> None:
    port = free_udp_port()
    got: list[Heard] = []

    class Rotator:
        id = "shared"
        followed = None  # following nothing, or the first heard

        def heard(self, heard: Heard) -> None:
            got.append(heard)

    listener = WsjtxListener(port, "127.0.0.1", GROUP, rotators=[Rotator()])  # type: ignore[list-item]
    with udp_daemon(port, GROUP) as daemon, socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        listener.start()  # bound after the daemon: the port is shared (SO_REUSEADDR both)
        try:
            s.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_IF, socket.inet_aton("127.0.0.1"))
            discovered(daemon, s, (GROUP, port))
            qso = w.StatusFields(dx_call="VK2XYZ", dx_grid="QF56", dial_hz=21_074_000)
            s.sendto(w.status(qso), (GROUP, port))
            daemon.wait_printed("Dial frequency changed to 21074000")
            heard = Heard("VK2XYZ", "QF56", False, "WSJT-X", 21_074_000)  # with its dial
            wait_until(lambda: heard in got, 10, "heard")
        finally:
            listener.stop()
