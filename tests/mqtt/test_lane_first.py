"""The stop lane goes first (mqtt/lane.py rule 4): the main connection's thread, before each
message it hands on, waits while the lane's socket has bytes the lane has not read yet, so a
stop published beside a backlog of targets is read and carried out before the next target
(the reader of a backlog otherwise keeps the interpreter lock and a core for itself). A
socket pair stands for the lane's connection to the broker."""

from __future__ import annotations

import socket
import threading
from collections.abc import Iterator

import pytest

from bridge.mqtt.connection import Connection
from bridge.mqtt.lane import YIELD_BUDGET_S, YIELD_MAX_S, YIELD_S, StopLane
from bridge.settings import MqttSettings
from tests.support.waiting import slow


@pytest.fixture
def lane() -> Iterator[tuple[StopLane, socket.socket]]:
    broker, ours = socket.socketpair()
    lane = StopLane(MqttSettings(host="127.0.0.1", port=1), subscriptions=[], on_message=print)
    lane._client.socket = lambda: ours  # type: ignore[method-assign]
    lane.connected.set()
    yield lane, broker
    broker.close()
    ours.close()


def test_the_main_connection_waits_while_the_lane_has_a_stop_to_read(
    lane: tuple[StopLane, socket.socket],
) -> None:
    stop_lane, broker = lane
    broker.sendall(b"\x30\x0drotor/stopSTOP")  # a PUBLISH waits on the lane's socket
    handed_on = threading.Event()

    def main_connection() -> None:
        stop_lane.first()
        handed_on.set()  # the next target would go to the judge now

    thread = threading.Thread(target=main_connection)
    thread.start()
    assert not handed_on.wait(0.005)  # a quiet period, not a deadline: it waits for the lane
    ours = stop_lane._client.socket()
    assert ours is not None
    ours.recv(64)  # the lane's thread reads its stop
    assert handed_on.wait(slow(5))
    thread.join(slow(5))


def test_with_nothing_on_the_lane_the_main_connection_goes_on_at_once(
    lane: tuple[StopLane, socket.socket],
) -> None:
    stop_lane, _broker = lane
    stop_lane.first()  # returns: no wait with an empty lane


def test_a_lane_that_never_reads_holds_the_main_connection_back_only_a_little(
    lane: tuple[StopLane, socket.socket],
) -> None:
    """A courtesy, never a condition: a lane whose thread is stuck costs each message of the
    main connection YIELD_MAX_S at most, and the main connection goes on."""
    stop_lane, broker = lane
    broker.sendall(b"\x30\x0drotor/stopSTOP")
    stop_lane.first()  # returns although the bytes are still there
    assert stop_lane._client.socket() is not None


def test_the_main_connection_calls_it_before_every_message() -> None:
    calls: list[str] = []
    conn = Connection(
        MqttSettings(host="127.0.0.1", port=1),
        "main",
        subscriptions=[],
        on_message=lambda topic, *a: calls.append(f"message {topic}"),
    )
    conn.before_message = lambda: calls.append("lane first")

    class Msg:
        topic = "rotor/target"
        payload = b"120"
        retain = False
        properties = None

    conn._on_message(conn._client, None, Msg())  # type: ignore[arg-type]
    assert calls == ["lane first", "message rotor/target"]


def test_a_flood_on_the_lane_costs_the_main_connection_a_bounded_share_of_each_second(
    lane: tuple[StopLane, socket.socket],
) -> None:
    """Junk flooding the stop and lock topics keeps the lane's socket busy: the main connection
    then waits YIELD_BUDGET_S in a second at most, not YIELD_MAX_S for every target."""
    stop_lane, broker = lane
    broker.sendall(b"\x30\x0drotor/stopjunk")  # never read: a lane that is always busy
    now = [100.0]
    waited: list[float] = []

    def sleep(s: float) -> None:
        waited.append(s)
        now[0] += s

    stop_lane.clock = lambda: now[0]
    stop_lane.sleep = sleep
    for _ in range(1000):  # a thousand targets within the same second
        stop_lane.first()
    assert sum(waited) == pytest.approx(YIELD_BUDGET_S, abs=YIELD_S)
    now[0] += 1.0  # the next second: the lane goes first again
    waited.clear()
    stop_lane.first()
    assert sum(waited) == pytest.approx(YIELD_MAX_S, abs=YIELD_S)
