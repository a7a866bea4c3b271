"""Attack 29: an N1MM report address given by name (``n1mm_report_to = "n1mm-pc.lan:13010"``) is
looked up on the loggers' one thread at every position report, and while the name server does not
answer (the shack's router forwarding to an internet that is down, a resolver that is slow) the
thread waits in the lookup: a STOP sent to the PstRotator (or N1MM) port meanwhile is read only
when the lookup gives up, and the rotor turns on for that long.

The setting takes a host name (settings/loggers.py checks only ``host:port``, and reads any name
as another machine); interfaces/loggers/server.py ``_report_one`` hands ``(host, port)`` to
``sendto`` each time, which resolves the name right there, on the thread that reads every
logger port (rule 3: "the serial line ... never waits for this one"; rule 8: "the thread never
sleeps while a datagram waits"). While the rotor turns, a report is due every REPORT_MOVING_S,
so with the name server silent the thread spends nearly all of a turn in lookups.

Measured here (glibc with ``options timeout:5 attempts:1``, its name server silent; a Rotor-EZ at
10 degrees a second; the STOP sent right after the lookup of a report began): the STOP reached
the rotor some 5 s late, 50 degrees past where it was sent. With glibc's defaults (5 s, two
attempts) a lookup holds the thread 10 s. The control, the same bridge reporting to an address
given as digits, stops at once.

Real parts: mosquitto, the bridge as its own process (``python -m bridge run``) in a mount
namespace of its own whose /etc/resolv.conf names a name server on 127.0.0.N that takes queries
and never answers (``unshare -m``, root: the test machine's own resolver untouched), the
emulated Rotor-EZ on a pty, UDP sockets on loopback.

Fixed: the name is looked up on a thread of its own (interfaces/loggers/resolver.py), the reports
go to the last address it found (none while it has found none), and the STOP is carried out at
once while a lookup hangs."""

from __future__ import annotations

import contextlib
import shutil
import socket
import subprocess
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from bridge.interfaces.loggers.resolver import RETRY_S
from tests.support.ports import free_udp_port
from tests.support.process import ROOT, Spawn, bridge_env
from tests.support.rig import Rig
from tests.support.udp_logger import PstClient, reserve_pst_ports, tag
from tests.support.waiting import slow, wait_until

LOOKUP_S = 5  # glibc's wait for it (resolv.conf ``options timeout:5 attempts:1``)
SPEED_DEG_S = 10.0
START_DEG, GOAL_DEG = 10, 350
PROMPT_S = 1.0  # a STOP carried out within this (scaled) leaves the rotor this near


class SilentNameServer:
    """A UDP port 53 that takes every query and answers none; when each came (monotonic)."""

    def __init__(self) -> None:
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        for last in range(2, 255):  # (tests run side by side: each its own loopback address)
            try:
                self._sock.bind((f"127.0.0.{last}", 53))
                break
            except OSError:
                continue
        else:
            self._sock.close()
            pytest.fail("no loopback address 127.0.0.2..254 has port 53 free")
        self.host: str = self._sock.getsockname()[0]
        self.queries: list[float] = []
        self._lock = threading.Lock()
        threading.Thread(target=self._take, daemon=True).start()

    def _take(self) -> None:
        while True:
            try:
                self._sock.recv(4096)
            except OSError:
                return
            with self._lock:
                self.queries.append(time.monotonic())

    def asked_since(self, t: float) -> bool:
        with self._lock:
            return any(q > t for q in self.queries)

    def close(self) -> None:
        with contextlib.suppress(OSError):  # (wakes the blocked recv: the port is let go)
            self._sock.shutdown(socket.SHUT_RDWR)
        self._sock.close()


def _in_namespace(resolv_conf: Path) -> Spawn:
    """A Rig ``Spawn``: the bridge in a mount namespace whose /etc/resolv.conf is
    ``resolv_conf``."""

    def spawn(argv: list[str], log_path: Path) -> subprocess.Popen[bytes]:
        wrapped = [
            "unshare",
            "-m",
            "sh",
            "-c",
            'mount --bind "$0" /etc/resolv.conf && exec "$@"',
            str(resolv_conf),
            *argv,
        ]
        with open(log_path, "ab") as log:
            return subprocess.Popen(
                wrapped, stdout=log, stderr=subprocess.STDOUT, env=bridge_env(), cwd=str(ROOT)
            )

    return spawn


@pytest.fixture
def name_server(tmp_path: Path) -> Iterator[tuple[SilentNameServer, Path]]:
    if shutil.which("unshare") is None:
        pytest.fail("unshare (util-linux) is needed: the bridge's own resolver is the point")
    server = SilentNameServer()
    conf = tmp_path / "resolv.conf"
    conf.write_text(f"nameserver {server.host}\noptions timeout:{LOOKUP_S} attempts:1\n")
    yield server, conf
    server.close()


def _station(rig: Rig, conf: Path, report_to: str) -> tuple[int, socket.socket]:
    """The bridge (its own process, resolving through ``conf``) with ``tower`` on a PstRotator
    port and an N1MM port whose position reports go to ``report_to``; the PST port and the
    socket reserved for its replies."""
    pst_port, replies = reserve_pst_ports()
    rig.add(
        "tower",
        "rotorez",
        emu={"start_az_deg": START_DEG, "speed_deg_s": SPEED_DEG_S, "jitter_deg": 0},
        pst_udp_port=pst_port,
        n1mm_rotor_name="Yagi",
        n1mm_udp_port=free_udp_port(),
        n1mm_udp_bind="0.0.0.0",  # (a report to another machine leaves from a LAN address)
        n1mm_report_to=report_to,
    )
    rig.spawn = _in_namespace(conf)
    rig.start_process()
    rig.ready("tower", timeout_s=slow(30))
    return pst_port, replies


def _stop_in_a_turn(
    rig: Rig, pst_port: int, replies: socket.socket, dns: SilentNameServer, by_name: bool
) -> tuple[float, float]:
    """The operator's PstRotator turns the rotor toward GOAL_DEG; once it turns (and, reporting
    by name, once a report's lookup began after that) it sends STOP. Where the rotor was when
    the STOP was sent, and where it came to rest."""
    emu = rig.emus["tower"]
    with PstClient(pst_port, replies=replies) as operator:
        operator.command(tag("AZIMUTH", GOAL_DEG))
        emu.wait_for(lambda s: s.is_moving, slow(3 * LOOKUP_S))
        turning = time.monotonic()
        if by_name:
            # (the name is looked up again RETRY_S after a lookup gave up: resolver.py rule 2)
            wait_until(lambda: dns.asked_since(turning), slow(3 * LOOKUP_S + RETRY_S), "a lookup")
        at_stop = emu.state().az_deg
        operator.command(tag("STOP", 1))
        rest = emu.wait_for(lambda s: not s.is_moving, slow(60)).az_deg
    return at_stop, rest


def test_control_reports_to_an_address_in_digits_leave_the_stop_prompt(
    rig: Rig, name_server: tuple[SilentNameServer, Path]
) -> None:
    dns, conf = name_server
    pst_port, replies = _station(rig, conf, "127.0.0.1:13010")
    at_stop, rest = _stop_in_a_turn(rig, pst_port, replies, dns, by_name=False)
    assert rest - at_stop <= SPEED_DEG_S * slow(PROMPT_S), (at_stop, rest)


def test_a_report_address_by_name_never_holds_a_pst_stop(
    rig: Rig, name_server: tuple[SilentNameServer, Path]
) -> None:
    dns, conf = name_server
    pst_port, replies = _station(rig, conf, "n1mm-pc.lan:13010")
    at_stop, rest = _stop_in_a_turn(rig, pst_port, replies, dns, by_name=True)
    assert rest - at_stop <= SPEED_DEG_S * slow(PROMPT_S), (
        f"the STOP was sent at {at_stop:.1f} degrees and the rotor came to rest at {rest:.1f}: "
        f"it turned on {(rest - at_stop) / SPEED_DEG_S:.1f} s after the STOP"
    )
