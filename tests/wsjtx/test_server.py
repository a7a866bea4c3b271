"""The WSJT-X listener (bridge/interfaces/wsjtx/server.py) on real UDP sockets: statuses reach every
rotator, junk is counted and logged rarely, a fault behind a datagram is contained, a port
in use is an error naming it."""

from __future__ import annotations

import contextlib
import logging
import socket
import struct

import pytest

from bridge.interfaces.wsjtx import WsjtxListener
from bridge.interfaces.wsjtx.server import JUNK_LOG_S
from bridge.session.follow import Heard
from tests.support import wait_until
from tests.support import wsjtx as w
from tests.support.clock import FakeClock
from tests.support.ports import free_udp_port
from tests.support.waiting import slow


class Ears:
    def __init__(self, rid: str, fail: bool = False) -> None:
        self.id = rid
        self.got: list[Heard] = []
        self.fail = fail
        self.followed: str | None = None  # following nothing, or the first heard

    def heard(self, heard: Heard) -> None:
        if self.fail:
            raise RuntimeError("a bug behind the datagram")
        self.got.append(heard)


def test_statuses_reach_every_rotator_and_junk_is_counted_and_logged_rarely(
    caplog: pytest.LogCaptureFixture,
) -> None:
    clock = FakeClock()
    broken, a, b = Ears("broken", fail=True), Ears("a"), Ears("b")
    listener = WsjtxListener(0, "127.0.0.1", clock=clock, rotators=[broken, a, b])  # type: ignore[list-item]
    listener.start()
    caplog.set_level(logging.INFO, "bridge.interfaces.wsjtx.server")
    try:
        to = listener.address
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            for _ in range(5):
                sock.sendto(b"junk", to)
            sock.sendto(w.heartbeat(), to)
            sock.sendto(w.status(w.StatusFields(dx_call="JA1ABC", dx_grid="PM95")), to)
            wait_until(lambda: a.got and b.got, 10, "both rotators hear the status")
            assert a.got == b.got == [Heard("JA1ABC", "PM95", False, "WSJT-X", 14_074_000)]
            counts = listener.counts
            assert (counts.malformed, counts.ignored, counts.statuses) == (5, 1, 1)
            assert counts.faults == 1  # the broken rotator's, and the others heard it all the same
            junk_lines = [r for r in caplog.records if "malformed" in r.getMessage()]
            assert len(junk_lines) == 1  # once per JUNK_LOG_S, with the count since
            clock.t += JUNK_LOG_S + 1
            sock.sendto(b"more junk", to)
            wait_until(lambda: listener.counts.malformed == 6, 10, "the sixth counted")
            junk_lines = [r for r in caplog.records if "malformed" in r.getMessage()]
            assert len(junk_lines) == 2 and "5 malformed" in junk_lines[-1].getMessage()
    finally:
        listener.stop()


def test_a_port_in_use_is_an_error_naming_it() -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as taken:
        taken.bind(("127.0.0.1", 0))
        port = taken.getsockname()[1]
        with pytest.raises(OSError, match=f"WSJT-X UDP port 127.0.0.1:{port}"):
            WsjtxListener(port, "127.0.0.1").listen()


def lan_address() -> str | None:
    """This computer's address on a network interface (not loopback), if it has one."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        try:
            probe.connect(("192.0.2.1", 9))  # no packet is sent: the route's source address
        except OSError:
            return None
        address: str = probe.getsockname()[0]
    return None if address.startswith(("127.", "0.")) else address


def test_a_loopback_listener_never_hears_the_group_from_the_lan(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """The bridge joins the group on loopback; another program on the same computer joins it on
    the network interface (as GridTracker does). A Status sent to the group from that
    interface (a hostile neighbour's, forged) reaches that program, and never a rotator; one
    sent on loopback (WSJT-X on this computer) does."""
    lan = lan_address()
    if lan is None:
        pytest.skip("no network interface besides loopback")
    group, port = "239.255.77.41", free_udp_port()
    ears = Ears("tower")
    listener = WsjtxListener(port, "127.0.0.1", group, rotators=[ears])  # type: ignore[list-item]
    listener.start()
    caplog.set_level(logging.WARNING, "bridge.interfaces.wsjtx.server")
    try:
        with contextlib.ExitStack() as stack:
            other = stack.enter_context(socket.socket(socket.AF_INET, socket.SOCK_DGRAM))
            other.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            other.bind((group, port))
            join = struct.pack("4s4s", socket.inet_aton(group), socket.inet_aton(lan))
            other.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP, join)
            other.settimeout(slow(10))
            forger = stack.enter_context(socket.socket(socket.AF_INET, socket.SOCK_DGRAM))
            forger.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_IF, socket.inet_aton(lan))
            forger.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_LOOP, 1)
            forged = w.status(w.StatusFields(dx_call="FORGED", dx_grid="AA00"))
            forger.sendto(forged, (group, port))
            assert other.recvfrom(65536)[0] == forged  # on this computer, from the LAN side
            genuine = stack.enter_context(socket.socket(socket.AF_INET, socket.SOCK_DGRAM))
            genuine.setsockopt(
                socket.IPPROTO_IP, socket.IP_MULTICAST_IF, socket.inet_aton("127.0.0.1")
            )
            genuine.sendto(
                w.status(w.StatusFields(dx_call="JA1ABC", dx_grid="PM95")), (group, port)
            )
            wait_until(lambda: ears.got, 10, "the status sent on loopback")
        assert ears.got == [Heard("JA1ABC", "PM95", False, "WSJT-X", 14_074_000)]
        assert listener.counts.foreign == 0  # the system never handed it over (IP_MULTICAST_ALL)
    finally:
        listener.stop()


def test_a_loopback_listener_drops_a_datagram_from_elsewhere_counts_and_says_it(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """Rule 1's second guard, whatever the system delivers: the source address is checked."""
    ears = Ears("tower")
    listener = WsjtxListener(0, "127.0.0.1", rotators=[ears])  # type: ignore[list-item]
    caplog.set_level(logging.WARNING, "bridge.interfaces.wsjtx.server")
    status = w.status(w.StatusFields(dx_call="FORGED", dx_grid="AA00"))
    for _ in range(3):
        listener.datagram(status, "192.168.1.66")
    assert ears.got == [] and listener.counts.foreign == 3 and listener.counts.statuses == 0
    said = [r.getMessage() for r in caplog.records if "192.168.1.66" in r.getMessage()]
    assert len(said) == 1
    listener.datagram(status, "127.0.0.1")
    assert [h.call for h in ears.got] == ["FORGED"]


def test_a_flood_over_its_senders_budget_is_dropped_said_once_and_others_are_heard(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """Rule 5, in virtual time (the clock stands still): a program flooding the port with
    statuses is heard up to a second's budget and the rest dropped undecoded, said once;
    WSJT-X on another port is heard all the while, and each of them is read to the end (the
    reader slept over its budget, and the system's buffer filled with the flood); when time
    passes the flooding program is heard again."""
    clock = FakeClock()
    ears = Ears("a")
    listener = WsjtxListener(0, "127.0.0.1", clock=clock, rotators=[ears])  # type: ignore[list-item]
    listener.start()
    try:
        flood = w.status(w.StatusFields(dx_call="JA1ABC", dx_grid="PM95"))
        with (
            socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s,
            socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as wsjtx,
        ):
            for sent in range(40, 161, 40):  # in batches the reader keeps up with
                for _ in range(40):
                    s.sendto(flood, listener.address)
                wait_until(lambda n=sent: len(ears.got) >= n, 10, "heard")
            for _ in range(50):  # over its budget now
                s.sendto(flood, listener.address)
            other = w.status(w.StatusFields(dx_call="K1ABC", dx_grid="FN42"))
            wsjtx.sendto(other, listener.address)
            wait_until(lambda: any(h.call == "K1ABC" for h in ears.got), 10, "the other heard")
            heard = len(ears.got)
            assert listener.counts.over_budget > 0 and heard < 160 + 50 + 1
            said = [r for r in caplog.records if "over the budget" in r.getMessage()]
            assert len(said) == 1
            clock.t += 10.0
            s.sendto(flood, listener.address)
            wait_until(lambda: len(ears.got) > heard, 10, "heard again")
    finally:
        listener.stop()


def test_wsjtx_is_heard_through_a_flood_of_heartbeats_from_many_local_sockets() -> None:
    """Rule 5 (an attack pass): eight local sockets flooding the port with well-formed
    heartbeats took the cap for all senders together, and 8 of WSJT-X's 10 statuses were
    dropped, the transmission's hold among them. In virtual time (the clock stands still,
    nothing refills): the flood spends the cap for all, and WSJT-X, whose status was heard
    before it, is still heard, within its own budget."""
    clock = FakeClock()
    ears = Ears("a")
    listener = WsjtxListener(0, "127.0.0.1", clock=clock, rotators=[ears])  # type: ignore[list-item]
    listener.start()
    try:
        beat = w.heartbeat("GridTracker")
        with contextlib.ExitStack() as stack:
            wsjtx = stack.enter_context(socket.socket(socket.AF_INET, socket.SOCK_DGRAM))
            wsjtx.sendto(w.status(w.StatusFields(dx_call="K1ABC")), listener.address)
            wait_until(lambda: len(ears.got) == 1, slow(10), "WSJT-X heard")
            sent = 0
            for _ in range(8):  # each up to its own budget: the cap for all spent between them
                s = stack.enter_context(socket.socket(socket.AF_INET, socket.SOCK_DGRAM))
                for _ in range(6):  # in batches the reader keeps up with
                    for _ in range(40):
                        s.sendto(beat, listener.address)
                    sent += 40
                    wait_until(lambda n=sent: _read(listener) >= n, slow(10), "read")
            assert listener.counts.over_budget > 0  # (the cap for all spent)
            for call in ("JA1ABC", "VK2XYZ"):
                wsjtx.sendto(w.status(w.StatusFields(dx_call=call)), listener.address)
            wait_until(lambda: len(ears.got) == 3, slow(10), "WSJT-X heard through the flood")
        assert [h.call for h in ears.got] == ["K1ABC", "JA1ABC", "VK2XYZ"]
    finally:
        listener.stop()


def _read(listener: WsjtxListener) -> int:
    """The datagrams the listener has read that were no status: ignored or dropped."""
    return listener.counts.ignored + listener.counts.over_budget
