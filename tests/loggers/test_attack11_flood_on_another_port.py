"""An eleventh attack pass, on the front ends together: a junk flood on the PstRotator port
drops N1MM's turns on its own port (bridge/interfaces/loggers/server.py rule 8).

One thread and one ``SourceBudgets`` served every logger socket: each sender had its own
budget, and all senders together RATE_ALL_S a second. A local program flooding the PST port
from six sockets, each within its own budget, spent the cap for all, and every datagram
that was no stop was then dropped unparsed whoever sent it: N1MM Logger+'s turn of its antenna,
on another port, for another rotator, was lost while the flood lasted (stops still went). The
WSJT-X listener keeps room for its program after an attack pass (wsjtx/server.py rule 5); the
loggers keep none. Real UDP sockets, virtual time (the clock stands still, nothing refills),
as tests/loggers/test_server.py's flood tests.
"""

from __future__ import annotations

from bridge.core.model import Source, Target
from bridge.interfaces.loggers import LoggerEndpoints
from bridge.interfaces.loggers.server import RATE_DATAGRAMS_S
from tests.loggers.test_server import Recording
from tests.support.clock import FakeClock
from tests.support.udp_logger import pst, tag, udp_socket
from tests.support.waiting import slow, wait_until

FLOODERS = 6  # senders, each within its own budget: more than the cap for all together


def test_n1mm_turns_its_antenna_through_a_junk_flood_on_the_pst_port() -> None:
    clock = FakeClock()
    tower, yagi = Recording("tower"), Recording("yagi")
    ep = LoggerEndpoints(clock=clock)
    ep.add_pst(tower, port=0)  # type: ignore[arg-type]
    ep.add_n1mm(yagi, "Yagi", port=0, report_to=("127.0.0.1", 9))  # type: ignore[arg-type]
    ep.start()
    try:
        pst_port = ep.address(ep.pst[0])[1]
        n1mm_port = ep.address(next(iter(ep.n1mm.values())))[1]
        junk, sent = pst(tag("AZIMUTH", "x")), 0
        with udp_socket() as n1mm:
            for _ in range(FLOODERS):
                with udp_socket() as s:
                    for _ in range(int(RATE_DATAGRAMS_S * 0.9) // 45):  # in batches the thread
                        for _ in range(45):  # reads before the next goes out
                            s.sendto(junk, ("127.0.0.1", pst_port))
                        sent += 45
                        wait_until(lambda n=sent: _read(ep) >= n, slow(10), "junk read")
            assert ep.over_budget > 0  # (the cap for all spent)
            aim = b"<N1MMRotor><rotor>Yagi</rotor><goazi>90</goazi></N1MMRotor>"
            n1mm.sendto(aim, ("127.0.0.1", n1mm_port))
            wait_until(lambda: _read(ep) > sent, slow(10), "N1MM's turn read")
        assert Target(90.0, None, Source.N1MM) in yagi.calls, "N1MM's turn was dropped"
    finally:
        ep.stop()


def _read(ep: LoggerEndpoints) -> int:
    """The datagrams the thread has read: parsed (junk or a turn) or dropped unparsed."""
    counts = sum(c.malformed for c in ep.counts.values())
    return counts + ep.over_budget + sum(c.commands for c in ep.counts.values())
