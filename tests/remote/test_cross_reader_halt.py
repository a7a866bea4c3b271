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
from tests.remote.test_attack5_floor_other_front_end import _link
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


@pytest.mark.xfail(strict=True, reason="two readers' lower bounds taken for their order")
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


@pytest.mark.xfail(strict=True, reason="two readers' lower bounds taken for their order")
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
