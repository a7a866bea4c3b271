"""interfaces/mqtt/remote.py rule 8 across readers: the remote refuses a move seen before a
STOP or lock ON it sent, but a seen time is a reader's LOWER bound (the last look that found
its socket or connection empty: tcplines.py rule 9, loggers/server.py rule 9 without kernel
stamps), and two readers' lower bounds do not order their messages.

Sequence (the remote on Windows or macOS: no datagram stamps): the rotctld client's
connection was last found empty at 8.9 s, its thread then asleep over its budget (or the
computer busy); the loggers' thread looks at PstRotator's port at 8.95 s and finds it empty;
PstRotator's turn comes at 9.0 s; the rotctld ``S`` at 9.2 s. The rotctld thread wakes first:
its ``S`` is dated 8.9 s, read at 9.3 s, and goes out. Then the loggers' thread reads the turn,
dated 8.95 s: after the STOP's seen time, so the remote let it through, stamped 8.95 s, after
the STOP's stamp, and the station turned the rotor after the STOP that came after the turn.

The fix: a move is ordered after another reader's halt only if it was seen after that halt
was read (its latest possible arrival; a kernel's stamp where there is one); against its own
reader's halt (one connection, one port and sender: read in the order they came) the seen
times still order them. The cost: a move another program sent right after a STOP, seen before
the STOP was read, is refused once (Gpredict's next ``P`` goes).
"""

from __future__ import annotations

import logging
import time

import pytest

from bridge.core.errors import RefusalCode, Refused
from bridge.emulators.rotorez_models import BEARING_OUTCOMES
from bridge.interfaces import tcplines
from tests.integration.test_attack_fence_pause import read_gate
from tests.integration.test_rotctld_integration import _replies, connect
from tests.remote.test_attack5_floor_other_front_end import _link, _sent
from tests.remote.test_stale_after_halt import _decided, _remote, gate_the_loggers
from tests.support import Probe, wait_until
from tests.support.mosquitto import free_port
from tests.support.remote import ask
from tests.support.rig import Rig
from tests.support.waiting import slow

BASE = 1_700_000_000.0
AFTER = ("rotor/stop", "rotor/lock")
PST = ("pst", "127.0.0.1", 12000, ("127.0.0.1", 12001))  # (loggers/commands.py's reader)
ROTCTLD = "rotctld PstRotator"  # (a tcplines Fence: one per connection)


def test_a_logger_turn_that_came_before_a_rotctld_stop_read_first_is_refused() -> None:
    clock, link, fake = _link()
    t0 = clock.t
    clock.t = t0 + 9.3  # the rotctld thread wakes, reads the S (dated 8.9 s) and sends it
    link.station_clock.heard(BASE + clock.t)
    link.send("rotor/stop", "stop", "DL1ABC", 5, seen_s=t0 + 8.9, reader=ROTCTLD)
    clock.t = t0 + 9.4  # the loggers' thread reads the turn that came at 9.0 s (dated 8.95 s)
    with pytest.raises(Refused) as refused:
        link.send(
            "rotor/target", '{"azimuth":200}', "DL1ABC", 5, seen_s=t0 + 8.95, after=AFTER,
            reader=PST,
        )  # fmt: skip
    assert refused.value.code is RefusalCode.STALE
    assert [topic for topic, _props in fake.published] == ["rotor/stop"], (
        "a turn that may have come before the STOP went out after it, stamped after it: the "
        "station turns the rotor"
    )


def test_a_pstrotator_turn_sent_before_a_rotctld_stop_does_not_turn_the_rotor_after_it(
    station: Rig,
    probe: Probe,
    monkeypatch: pytest.MonkeyPatch,
    caplog: pytest.LogCaptureFixture,
) -> None:
    """The sequence above on a real station and the remote in this process, its loggers
    without datagram stamps: PstRotator's turn sent before the rotctld client's ``S``, the
    ``S`` read first (the loggers' thread held right before its read), the turn dated after
    the ``S``'s seen time (the loggers' look at its port made after the rotctld connection's
    last look). The rotor must not turn to the turn's 200."""
    from bridge.interfaces.loggers import server
    from tests.support.udp_logger import PstClient, reserve_pst_ports

    loggers_gate, loggers_waiting = gate_the_loggers(monkeypatch, kernel_stamps=False)
    tcp_gate, spent = read_gate(monkeypatch, tcplines)
    looks: list[float] = []  # when each of the loggers' looks began
    look = server.LoggerEndpoints._look

    def counted(self: object, *args: object, **kw: object) -> object:
        looks.append(time.monotonic())
        return look(self, *args, **kw)  # type: ignore[arg-type]

    monkeypatch.setattr(server.LoggerEndpoints, "_look", counted)
    caplog.set_level(logging.WARNING)
    port = free_port()
    pst_port, replies = reserve_pst_ports()
    remote = _remote(port, station.broker.port, pst_udp_port=pst_port)
    try:
        wait_until(lambda: ask(port, b"P 30 0\n") == b"RPRT 0\n", 20, "the remote taking a move")
        station.arrived("tower", 30)
        moves = len(station.emus["tower"].frames(*BEARING_OUTCOMES))
        errors = probe.mark()
        with connect(port) as sock, PstClient(pst_port, replies=replies) as client:
            spent.clear()
            sock.sendall(b"p\n")
            _replies(sock, 2)  # its thread is reading
            assert spent.wait(slow(10)), "the rotctld thread past its first read"
            tcp_gate.clear()  # over its budget from the end of its next read on
            sock.sendall(b"p\n")
            _replies(sock, 2)  # read: its connection last found empty before now, then asleep
            mark = time.monotonic()
            # two looks at PstRotator's port begun after that: the turn is dated after it
            wait_until(lambda: sum(t > mark for t in looks) >= 2, 10, "the loggers' looks")
            loggers_gate.clear()  # the loggers' thread held at its next read
            client.command("<AZIMUTH>200</AZIMUTH>")  # sent first
            assert loggers_waiting.wait(slow(10)), "the loggers' thread woke for the turn"
            sock.sendall(b"S\n")  # sent after the turn, unread
            tcp_gate.set()
            assert _replies(sock, 1) == b"RPRT 0\n"  # the STOP went out
            loggers_gate.set()  # now the turn is read

            def refused_here() -> bool:
                return any(
                    "200" in r.getMessage() and "STOP" in r.getMessage() for r in caplog.records
                )

            turned = _decided(station, probe, moves, errors, b"RPRT 0", refused_here)
            assert not turned(), "PstRotator's turn sent before the STOP turned the rotor after it"
        # the next move from either program goes
        assert ask(port, b"P 60 0\n") == b"RPRT 0\n"
        station.arrived("tower", 60)
    finally:
        remote.stop()
        replies.close()


def test_a_move_read_after_its_own_readers_stop_is_ordered_by_seen_times() -> None:
    """One connection's ``P 300 0``, ``S``, ``P 200 0``, read in one go (one seen time, 8.9 s,
    read at 9.3 s): its own reader's, so the ``S``'s read time does not refuse the second
    target; it ends at 200, stamped no earlier than the ``S``."""
    clock, link, fake = _link()
    t0 = clock.t
    clock.t = t0 + 9.3
    link.station_clock.heard(BASE + clock.t)
    for topic, payload in (("rotor/target", '{"azimuth":300}'), ("rotor/stop", "stop")):
        link.send(topic, payload, "DL1ABC", 5, seen_s=t0 + 8.9, after=AFTER, reader=ROTCTLD)
    link.send(
        "rotor/target", '{"azimuth":200}', "DL1ABC", 5, seen_s=t0 + 8.9, after=AFTER,
        reader=ROTCTLD,
    )  # fmt: skip
    (_, _), (_, stop), (topic, last) = fake.published
    assert topic == "rotor/target" and _sent(last) >= _sent(stop)


def test_a_stop_stamped_by_the_kernel_refuses_only_what_was_seen_before_it_came() -> None:
    """A logger's STOP with the kernel's stamp (Linux: its arrival known, loggers/commands.py
    rule 8, handed on as ``read_s``), read late at 9.5 s: Gpredict's ``P`` seen at 9.05 s, after
    the stamp, goes; one seen at 8.95 s, before it, is refused."""
    clock, link, fake = _link()
    t0 = clock.t
    clock.t = t0 + 9.5
    link.station_clock.heard(BASE + clock.t)
    link.send(
        "rotor/stop", "stop", "DL1ABC", 5, seen_s=t0 + 9.0, reader=PST, read_s=t0 + 9.0 + 1e-6
    )
    with pytest.raises(Refused):
        link.send(
            "rotor/target", '{"azimuth":100}', "DL1ABC", 5, seen_s=t0 + 8.95, after=AFTER,
            reader=ROTCTLD,
        )  # fmt: skip
    link.send(
        "rotor/target", '{"azimuth":101}', "DL1ABC", 5, seen_s=t0 + 9.05, after=AFTER,
        reader=ROTCTLD,
    )  # fmt: skip
    assert fake.published[-1][0] == "rotor/target"


def test_every_other_readers_latest_halt_counts() -> None:
    """Three readers' STOPs, read at 9.0 s (``a``), 9.2 s (``c``) and 9.5 s (``b``): a move is
    judged against the latest read of any reader's but its own."""
    clock, link, _fake = _link()
    t0 = clock.t

    def move(reader: str, seen: float) -> bool:
        try:
            link.send(
                "rotor/target", '{"azimuth":1}', "DL1ABC", 5, seen_s=t0 + seen, after=AFTER,
                reader=reader,
            )  # fmt: skip
        except Refused:
            return False
        return True

    for reader, read in (("a", 9.0), ("c", 9.2), ("b", 9.5)):
        clock.t = t0 + read
        link.station_clock.heard(BASE + clock.t)
        link.send("rotor/stop", "stop", "DL1ABC", 5, seen_s=t0 + 8.0, reader=reader)
    assert move("b", 9.3)  # (after c's, the latest but its own)
    assert not move("b", 9.1)  # (before c's)
    assert not move("a", 9.4)  # (before b's)
    assert move("a", 9.6)
    clock.t = t0 + 10.0
    link.send("rotor/stop", "stop", "DL1ABC", 5, seen_s=t0 + 9.9, reader="b")
    assert not move("a", 9.95)  # (b's again, read at 10 s)
    assert move("b", 9.95)  # (its own, seen at 9.9 s)


@pytest.mark.parametrize("fionread", [True, False], ids=["linux", "windows"])
def test_gpredict_tracks_on_after_a_stop_from_pstrotator(
    station: Rig, probe: Probe, monkeypatch: pytest.MonkeyPatch, fionread: bool
) -> None:
    """The cost, and that it is paid once: PstRotator's STOP waits unread (the loggers'
    thread held, no datagram stamps: dated from the look before it came); Gpredict's
    connection is read (last found empty after the STOP came), then its thread sleeps over its
    budget and its ``P 100 0`` waits unread; the STOP is read and goes; then the ``P``, whose
    bytes may have come before the STOP was read, is refused (an error reply: Gpredict counts
    it and carries on); Gpredict's next ``P`` goes and the rotor turns to it. (Linux: the
    remote's rotctld fence refuses that ``P`` first, its bytes counted before the halt; on
    Windows, no FIONREAD, the link's rule 8 does.)"""
    from tests.support.udp_logger import PstClient, reserve_pst_ports

    if not fionread:

        def no_fionread(fd: int) -> int:
            raise OSError("no FIONREAD here")  # (Windows: tcplines.unread)

        monkeypatch.setattr(tcplines, "unread", no_fionread)
    loggers_gate, loggers_waiting = gate_the_loggers(monkeypatch, kernel_stamps=False)
    tcp_gate, spent = read_gate(monkeypatch, tcplines)
    port = free_port()
    pst_port, replies = reserve_pst_ports()
    remote = _remote(port, station.broker.port, pst_udp_port=pst_port)
    try:
        wait_until(lambda: ask(port, b"P 30 0\n") == b"RPRT 0\n", 20, "the remote taking a move")
        station.arrived("tower", 30)
        with connect(port) as sock, PstClient(pst_port, replies=replies) as client:
            loggers_gate.clear()
            t = time.monotonic()
            client.command("<STOP>1</STOP>")  # PstRotator's STOP
            assert loggers_waiting.wait(slow(10)), "the loggers' thread woke for the STOP"
            spent.clear()
            sock.sendall(b"p\n")
            _replies(sock, 2)  # Gpredict's connection is read
            assert spent.wait(slow(10)), "the rotctld thread past its first read"
            tcp_gate.clear()  # over its budget from the end of its next read on
            sock.sendall(b"p\n")
            _replies(sock, 2)  # read (found empty after the STOP came), then asleep
            sock.sendall(b"P 100 0\n")  # unread
            loggers_gate.set()  # the STOP is read and goes
            probe.wait_for("rotor/audit", lambda m: b"stop" in m.payload, after=t)
            tcp_gate.set()
            first = _replies(sock, 1)
            assert first.startswith(b"RPRT -"), f"the P read after the STOP: {first!r}"
            sock.sendall(b"P 101 0\n")  # Gpredict's next P
            assert _replies(sock, 1) == b"RPRT 0\n"
        station.arrived("tower", 101)
    finally:
        remote.stop()
        replies.close()
