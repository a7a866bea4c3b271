"""COLD REVIEW 34 (505a912c): interfaces/loggers/server.py rule 9, where the system gives no
datagram stamps (Windows, macOS: where the remote runs).

The rule: "a datagram read after a stop from the same socket keeps its date: one socket's
datagrams are read in the order they came (``AZIMUTH 300``, ``STOP``, ``AZIMUTH 200`` ends at
200)". But a turn is dated just before ANY stop another socket gave that was read after its
bound (``_before_halts``), whichever rotator that stop was for and though its own port gave a
stop before it. Two rotators, each with its PstRotator port: rotator X's STOP, and on Y's port
``AZIMUTH 300``, ``STOP``, ``AZIMUTH 200``, all come while the loop waits (one bound, the look
before the wait, for every datagram read at that wake-up), X's port served first. Y's
``AZIMUTH 200`` is dated before X's STOP's date, so before Y's own STOP (same bound): the
remote refuses it as seen before Y's STOP (remote.py rule 8, SEEN_BEFORE_HALT), and Y stays
where its STOP left it, though its operator's 200 came after that STOP on the same port. X's
STOP says nothing of Y's turns.
"""

from __future__ import annotations

import time
from collections.abc import Iterator

import pytest

from tests.loggers.test_unstamped_order import STOP, Rig, pst_ports, turn


@pytest.fixture
def two(monkeypatch: pytest.MonkeyPatch) -> Iterator[Rig]:
    """As test_unstamped_order.py's rig, each port another rotator's (X's, then Y's)."""
    with pst_ports(monkeypatch, ("x", "y")) as r:
        yield r


def test_a_turn_after_its_own_ports_stop_is_not_dated_before_it_for_another_rotators_stop(
    two: Rig,
) -> None:
    x, y = two.ports
    two.send(x, STOP)  # rotator X's STOP
    for data in (turn(300), STOP, turn(200)):  # rotator Y's operator: 300, STOP, then 200
        two.send(y, data)
    looked = time.monotonic()  # (all came during one wait: one bound, the look before it)
    two.ep._serve(two.sock(x), looked)  # noqa: SLF001  (X's port served first)
    two.ep._serve(two.sock(y), looked)  # noqa: SLF001
    assert two.dated(y, turn(200)) >= two.dated(y, STOP), (
        "rotator Y's AZIMUTH 200, read after Y's STOP on Y's own port, is dated before that "
        "STOP (just before rotator X's STOP, read first): the remote refuses it as seen "
        f"before Y's STOP ({two.seen})"
    )
