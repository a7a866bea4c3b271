"""Attack 29: a burst of targets on the remote's PstRotator port holds a STOP sent to the same
port for seconds, until the rotor has turned on far past where the STOP caught it.

The remote's PstRotator ports are served by one thread (interfaces/loggers/server.py), and each
datagram that moves is handed to the station's broker through the remote's link, whose ``send``
returns only once the broker acknowledged it (interfaces/mqtt/remote.py rule 7): every target
costs that thread a round trip to the station's broker. A program on the remote's computer that
sends targets faster than the link's round trips take them (a tracking script, a logger resending
its bearing; here one burst of 190, within one sender's budget of 200 a second, loggers/server.py
rule 8) leaves them queued in the system's buffer, and the operator's ``<STOP>1</STOP>`` from
PstRotator, on its own socket, is read after all of them: rule 8's "a stop is carried out at
once" holds from its read, and the read waits for every round trip ahead of it. The station's
own PstRotator port takes the same burst and STOP (same rotor, speed and turn) in 0.06 s, the
rotor at rest 0.6 degrees past where the STOP was sent (no round trip per datagram).

Measured here (Rotor-EZ at 40 degrees a second from 10 to 300, one burst of 190 targets, the
STOP right after it): the STOP reached the rotor 3.9 s after it was sent with the station's
broker on loopback, and with a link of 25 ms each way (a modest internet link, the remote's
reason to be) never: the rotor arrived at 300, 7.3 s later. The test below uses a slower rotor
(10 degrees a second, 10 to 350) and the 25 ms link, and asserts where the rotor rests: within
two seconds' turn of where it was when the STOP was sent (the control, without the burst,
passes); with the burst the STOP sent at 10 degrees left the rotor at rest at 114, 10.4 s of
turn after it. Each target held up so goes out stamped when it came, and the station refuses
it as older than its 5 s expiry: the round trips spent on them move nothing, and hold the STOP.

Real parts: mosquitto, the station's bridge (App) and its emulated Rotor-EZ on a pty, the remote
(bridge/remote), UDP sockets on loopback; a TCP relay that holds each segment 25 ms stands for the
internet between the remote and the station's broker."""

from __future__ import annotations

import contextlib
import queue
import socket
import threading
import time
from collections.abc import Iterator

import pytest

from tests.remote.test_remote import OPERATOR
from tests.support.remote import running_remote
from tests.support.rig import Rig
from tests.support.udp_logger import PstClient, pst, reserve_pst_ports, tag, udp_socket
from tests.support.waiting import slow

ONE_WAY_S = 0.025  # the link's delay each way: 50 ms round trips to the station's broker
SPEED_DEG_S = 10.0
START_DEG, GOAL_DEG = 10, 350
BURST = 190  # targets sent at once by another program (its budget: 200 a second)
PROMPT_S = 2.0  # a STOP carried out within this (scaled) leaves the rotor this near


class DelayingLink:
    """A TCP relay on loopback to ``target`` that delivers each segment ``one_way_s`` after it
    came, in order, both ways: a link with a round trip of twice that."""

    def __init__(self, target: int, one_way_s: float) -> None:
        self.target, self.one_way_s = target, one_way_s
        self._server = socket.create_server(("127.0.0.1", 0))
        self.port = int(self._server.getsockname()[1])
        self._socks: list[socket.socket] = []
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self) -> None:
        while True:
            try:
                conn, _ = self._server.accept()
            except OSError:
                return
            upstream = socket.create_connection(("127.0.0.1", self.target))
            self._socks += [conn, upstream]
            for src, dst in ((conn, upstream), (upstream, conn)):
                held: queue.Queue[tuple[float, bytes]] = queue.Queue()
                threading.Thread(target=self._take, args=(src, held), daemon=True).start()
                threading.Thread(target=self._deliver, args=(dst, held), daemon=True).start()

    def _take(self, src: socket.socket, held: queue.Queue[tuple[float, bytes]]) -> None:
        with contextlib.suppress(OSError):
            while data := src.recv(65536):
                held.put((time.monotonic() + self.one_way_s, data))
        held.put((0.0, b""))

    def _deliver(self, dst: socket.socket, held: queue.Queue[tuple[float, bytes]]) -> None:
        pause = threading.Event()  # (never set: the link's delay, not a wait for anything)
        with contextlib.suppress(OSError):
            while True:
                due, data = held.get()
                if not data:
                    dst.shutdown(socket.SHUT_WR)
                    return
                pause.wait(max(0.0, due - time.monotonic()))
                dst.sendall(data)

    def close(self) -> None:
        self._server.close()
        for s in self._socks:
            with contextlib.suppress(OSError):
                s.close()


@pytest.fixture
def remote_pst(rig: Rig) -> Iterator[tuple[Rig, PstClient, int]]:
    """The station (``tower``, a Rotor-EZ at START_DEG), the remote's PstRotator port onto it
    across a DelayingLink, and the operator's PstRotator client; and the port."""
    rig.add("tower", emu={"start_az_deg": START_DEG, "speed_deg_s": SPEED_DEG_S, "jitter_deg": 0})
    rig.start()
    rig.ready("tower")
    link = DelayingLink(rig.broker.port, ONE_WAY_S)
    port, replies = reserve_pst_ports()
    try:
        with (
            running_remote(link.port, OPERATOR, {"rotator": "tower", "pst_udp_port": port}),
            PstClient(port, replies=replies) as operator,
        ):
            yield rig, operator, port
    finally:
        replies.close()
        link.close()


def _stop_in_a_turn(rig: Rig, operator: PstClient, port: int, burst: int) -> tuple[float, float]:
    """The operator turns the rotor toward GOAL_DEG; once it turns, another program on the
    remote's computer sends ``burst`` targets (the same goal) to the same port from its own
    socket, and the operator's PstRotator sends its STOP right after. Where the rotor was when
    the STOP was sent, and where it came to rest."""
    emu = rig.emus["tower"]
    operator.command(tag("AZIMUTH", GOAL_DEG))
    emu.wait_for(lambda s: s.is_moving, slow(10))
    other = udp_socket()
    try:
        target = pst(tag("AZIMUTH", GOAL_DEG))
        for _ in range(burst):
            other.sendto(target, ("127.0.0.1", port))
        at_stop = emu.state().az_deg
        operator.command(tag("STOP", 1))
        rest = emu.wait_for(lambda s: not s.is_moving, slow(60)).az_deg
    finally:
        other.close()
    return at_stop, rest


def test_control_a_stop_on_the_remotes_pst_port_is_prompt(
    remote_pst: tuple[Rig, PstClient, int],
) -> None:
    rig, operator, port = remote_pst
    at_stop, rest = _stop_in_a_turn(rig, operator, port, burst=0)
    assert rest - at_stop <= SPEED_DEG_S * slow(PROMPT_S), (at_stop, rest)


def test_a_burst_of_targets_on_the_remotes_pst_port_does_not_hold_the_stop(
    remote_pst: tuple[Rig, PstClient, int],
) -> None:
    rig, operator, port = remote_pst
    at_stop, rest = _stop_in_a_turn(rig, operator, port, burst=BURST)
    assert rest - at_stop <= SPEED_DEG_S * slow(PROMPT_S), (
        f"the STOP was sent at {at_stop:.1f} degrees and the rotor came to rest at {rest:.1f}: "
        f"it turned on {(rest - at_stop) / SPEED_DEG_S:.1f} s after the STOP"
    )


def test_the_newest_target_of_a_burst_on_the_remotes_pst_port_is_the_one_that_counts(
    remote_pst: tuple[Rig, PstClient, int],
) -> None:
    """A newer target replaces one not yet sent (remote/courier.py rule 2): the rotor ends at
    the burst's last target, never at one replaced on the way, nor short of it."""
    rig, _operator, port = remote_pst
    emu = rig.emus["tower"]
    last = START_DEG + 40
    other = udp_socket()
    try:
        for az in range(START_DEG + 1, last + 1):
            other.sendto(pst(tag("AZIMUTH", az)), ("127.0.0.1", port))
        rest = emu.wait_for(lambda s: abs(s.az_deg - last) < 1 and not s.is_moving, slow(30))
    finally:
        other.close()
    assert abs(rest.az_deg - last) < 1, rest
