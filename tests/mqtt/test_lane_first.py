"""The stop lane goes first (interfaces/mqtt/lane.py rule 4): the main connection's thread, before
each message it hands on, waits while the lane's socket has bytes the lane has not read yet, so a
stop published beside a backlog of targets is read and carried out before the next target
(the reader of a backlog otherwise keeps the interpreter lock and a core for itself). A
socket pair stands for the lane's connection to the broker; a clock the test moves stands for
the time that passes."""

from __future__ import annotations

import socket
import threading
from collections.abc import Iterator

import pytest

from bridge.interfaces.mqtt.connection import Connection
from bridge.interfaces.mqtt.lane import YIELD_BUDGET_S, YIELD_MAX_S, YIELD_S, StopLane
from bridge.settings import MqttSettings
from tests.support.waiting import slow

STOP = b"\x30\x0drotor/stopSTOP"  # a PUBLISH, as it waits on the lane's socket


class Lane:
    def __init__(self) -> None:
        self.broker, self.ours = socket.socketpair()
        self.lane = StopLane(
            MqttSettings(host="127.0.0.1", port=1), subscriptions=[], on_message=print
        )
        self.lane._client.socket = lambda: self.ours  # type: ignore[method-assign]
        self.lane.connected.set()
        self.now = 100.0
        self.steps: list[float] = []
        self.step_s = YIELD_S  # how long a step takes before the main thread runs again

    def fake_time(self) -> None:
        self.lane.clock = lambda: self.now
        self.lane.sleep = self._sleep

    def _sleep(self, s: float) -> None:
        self.steps.append(s)
        self.now += self.step_s


@pytest.fixture
def lane() -> Iterator[Lane]:
    bench = Lane()
    yield bench
    bench.broker.close()
    bench.ours.close()


def test_the_main_connection_waits_while_the_lane_has_a_stop_to_read(lane: Lane) -> None:
    lane.lane.clock = lambda: lane.now  # no time passes: only the lane's read ends the wait
    lane.broker.sendall(STOP)
    handed_on = threading.Event()

    def main_connection() -> None:
        lane.lane.first()
        handed_on.set()  # the next target would go to the judge now

    thread = threading.Thread(target=main_connection)
    thread.start()
    assert not handed_on.wait(0.05)  # a quiet period, not a deadline: it waits for the lane
    lane.ours.recv(64)  # the lane's thread reads its stop
    assert handed_on.wait(slow(5))
    thread.join(slow(5))


def test_with_nothing_on_the_lane_the_main_connection_never_waits(lane: Lane) -> None:
    lane.fake_time()
    for _ in range(100):
        lane.lane.first()
    assert lane.steps == []


def test_a_lane_that_is_down_is_not_waited_for(lane: Lane) -> None:
    lane.fake_time()
    lane.broker.sendall(STOP)
    lane.lane.connected.clear()  # (its socket may still hold bytes: they are not its news)
    lane.lane.first()
    lane.lane._client.socket = lambda: None  # type: ignore[method-assign]
    lane.lane.connected.set()
    lane.lane.first()
    assert lane.steps == []


def test_a_lane_that_never_reads_holds_each_message_back_only_so_long(lane: Lane) -> None:
    lane.fake_time()
    lane.broker.sendall(STOP)  # never read: a lane thread that is stuck
    lane.lane.first()
    assert len(lane.steps) == pytest.approx(YIELD_MAX_S / YIELD_S, abs=1)


def test_the_bounds_count_the_time_that_passed_not_the_steps_asked_for(lane: Lane) -> None:
    """On a busy machine one step of 0.2 ms took 93 ms before the main thread ran again: the
    main connection then waits one step a message, and no more once the second's budget is
    spent (counting steps, one message waited seconds)."""
    lane.fake_time()
    lane.step_s = 0.093
    lane.broker.sendall(STOP)
    for _ in range(100):  # a hundred targets within the same second
        lane.lane.first()
    assert len(lane.steps) == 2  # 93 ms, then the rest of the 0.1 s budget
    assert lane.now - 100.0 <= YIELD_BUDGET_S + lane.step_s


def test_a_flood_on_the_lane_costs_the_main_connection_a_bounded_share_of_each_second(
    lane: Lane,
) -> None:
    """Junk flooding the stop and lock topics keeps the lane's socket busy: the main connection
    then waits YIELD_BUDGET_S in a second at most, not YIELD_MAX_S for every target."""
    lane.fake_time()
    lane.broker.sendall(STOP)
    for _ in range(1000):
        lane.lane.first()
    assert lane.now - 100.0 == pytest.approx(YIELD_BUDGET_S, abs=YIELD_S)
    lane.now += 1.0  # the next second: the lane goes first again
    lane.steps.clear()
    lane.lane.first()
    assert len(lane.steps) == pytest.approx(YIELD_MAX_S / YIELD_S, abs=1)


def test_the_main_connection_calls_it_before_every_message_and_survives_it() -> None:
    calls: list[str] = []
    conn = Connection(
        MqttSettings(host="127.0.0.1", port=1),
        "main",
        subscriptions=[],
        on_message=lambda topic, *a: calls.append(f"message {topic}"),
    )

    class Msg:
        topic = "rotor/target"
        payload = b"120"
        retain = False
        properties = None

    conn.before_message = lambda: calls.append("lane first")
    conn._on_message(conn._client, None, Msg())  # type: ignore[arg-type]
    assert calls == ["lane first", "message rotor/target"]

    def broken() -> None:
        raise RuntimeError("a bug")

    conn.before_message = broken
    conn._on_message(conn._client, None, Msg())  # type: ignore[arg-type]
    assert calls[-1] == "message rotor/target"  # the message still goes on
