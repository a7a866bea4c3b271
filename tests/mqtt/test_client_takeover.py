"""MQTT rule 7 (bridge/interfaces/mqtt/connection.py):
two bridges with one client id back off instead of
fighting; anything else keeps paho's quick reconnects. The rule in virtual time, then the MQTT 5
reason code on a real socket. (Two real processes on a real mosquitto:
tests/faults/test_broker.py.)"""

from __future__ import annotations

import logging
import socket
import threading
import time

import pytest

from bridge.interfaces.mqtt.client import MqttClient
from bridge.interfaces.mqtt.connection import (
    FLAP_COUNT,
    STABLE_S,
    TAKEOVER_FIRST_S,
    TAKEOVER_MAX_S,
    TakeoverGuard,
    listening,
)
from bridge.settings import MqttSettings
from tests.support import slow, wait_until


def test_a_takeover_backs_off_doubling_up_to_a_minute() -> None:
    g = TakeoverGuard()
    now = 0.0
    delays = []
    for _ in range(7):
        g.connected(now)
        now += 1.0
        assert g.disconnected(now, "taken over")
        delays.append(g.backoff_s)
        now += g.backoff_s
    assert delays == [TAKEOVER_FIRST_S, 10, 20, 40, TAKEOVER_MAX_S, TAKEOVER_MAX_S, TAKEOVER_MAX_S]


def test_a_connection_that_lasts_ends_the_episode() -> None:
    g = TakeoverGuard()
    g.connected(0.0)
    assert g.disconnected(1.0, "taken over")
    g.reported = True
    g.connected(10.0)
    assert g.disconnected(10.0 + TAKEOVER_MAX_S + 1, "other")  # still fighting
    g.connected(100.0)
    assert not g.disconnected(100.0 + STABLE_S, "dropped")  # a broker crash, much later
    assert (g.backoff_s, g.reported) == (0, False)
    g.connected(1000.0)
    assert g.disconnected(1001.0, "taken over")  # a new episode is reported again
    assert (g.backoff_s, g.reported) == (TAKEOVER_FIRST_S, False)


def test_without_a_reason_code_repeated_drops_count_as_a_takeover() -> None:
    """Both sides of the fight: the one kicked at once, and the one kicked after the other's
    growing back-off (its connections last longer, but never STABLE_S)."""
    for lasted in ([1.0] * FLAP_COUNT, [1.0, TAKEOVER_FIRST_S, STABLE_S - 1][:FLAP_COUNT]):
        g = TakeoverGuard()
        now = 0.0
        verdicts = []
        for seconds in lasted:
            g.connected(now)
            now += seconds
            verdicts.append(g.disconnected(now, "dropped"))
            now += 1.0
        assert verdicts == [False] * (FLAP_COUNT - 1) + [True], lasted
        assert g.backoff_s == TAKEOVER_FIRST_S


def test_a_broker_that_goes_away_in_between_is_no_takeover() -> None:
    g = TakeoverGuard()
    now = 0.0
    for _ in range(3 * FLAP_COUNT):
        g.connected(now)
        now += 1.0
        assert not g.disconnected(now, "dropped")
        g.connect_failed()  # refused or unreachable: the broker restarts
        now += 2.0
    assert g.backoff_s == 0


def test_a_broker_whose_port_is_closed_after_each_drop_is_no_takeover_even_mid_episode() -> None:
    """connection.py rule 7: a broker killed and started again at once (systemd's 100 ms) is
    back by the next reconnect, so its drops look like a fight's; the port it closed with
    them tells them apart ("gone"), and no back-off follows, even after an episode began."""
    g = TakeoverGuard()
    now = 0.0
    for _ in range(3 * FLAP_COUNT):
        g.connected(now)
        now += 1.0
        assert not g.disconnected(now, "gone")
        now += 1.0
    assert g.backoff_s == 0
    for _ in range(FLAP_COUNT):  # a fight: the back-off is set ...
        g.connected(now)
        now += 1.0
        fight = g.disconnected(now, "dropped")
    assert fight and g.backoff_s == TAKEOVER_FIRST_S
    g.connected(now)
    assert not g.disconnected(now + 1.0, "gone")  # ... and a crash then slows nothing


def test_the_look_at_the_brokers_port_tells_a_listening_one_from_a_closed_one() -> None:
    """connection.py rule 7's ``listening``: a TCP connection taken, or refused (nothing
    listens on the port any more)."""
    server = socket.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]
    assert listening("127.0.0.1", port)
    server.close()
    assert not listening("127.0.0.1", port)


def test_keepalive_timeouts_and_other_reasons_are_no_evidence() -> None:
    g = TakeoverGuard()
    now = 0.0
    for i in range(3 * FLAP_COUNT):
        g.connected(now)
        now += 1.0
        assert not g.disconnected(now, "other" if i % (FLAP_COUNT - 1) == 0 else "dropped")
        now += 1.0
    assert g.backoff_s == 0


def simulate_two_bridges(minutes: float, v5: bool) -> tuple[list[float], list[float]]:
    """Two bridges with one client id on one broker: each accepted connection kicks the other.

    paho's side: a kicked bridge waits its back-off (1 s, paho's minimum, outside an episode)
    and connects again; the broker accepts every connection. Returns the connect times.
    """
    guards = [TakeoverGuard(), TakeoverGuard()]
    due = [0.0, 0.4]  # the second one starts a little later
    holder: int | None = None
    connects: list[list[float]] = [[], []]
    end = minutes * 60
    while min(due) < end:
        who = 0 if due[0] <= due[1] else 1
        now = due[who]
        due[who] = float("inf")
        if holder is not None:  # the broker drops the older connection
            g = guards[holder]
            if g.disconnected(now, "taken over" if v5 else "dropped"):
                due[holder] = now + g.backoff_s
            else:
                due[holder] = now + 1.0
        guards[who].connected(now)
        connects[who].append(now)
        holder = who
    return connects[0], connects[1]


def per_window(times: list[float], start: float, end: float, width_s: int = 60) -> list[int]:
    """Connections in every window of width_s (5 s apart) between start and end."""
    stops = range(int(start), int(end) - width_s + 1, 5)
    return [sum(1 for t in times if w <= t < w + width_s) for w in stops]


def test_two_bridges_with_one_client_id_make_a_bounded_number_of_connections() -> None:
    for v5 in (True, False):
        a, b = simulate_two_bridges(10, v5)
        for mine in (a, b):
            # neither spins: a handful in the first minute, then at most one a minute ...
            assert max(per_window(mine, 0, 60)) <= 6, (v5, a, b)
            assert max(per_window(mine, 120, 600)) <= 1, (v5, a, b)
            # ... and neither gives up: they take turns, one connection each in two minutes
            assert min(per_window(mine, 120, 600, width_s=2 * TAKEOVER_MAX_S + 1)) >= 1, (v5, a, b)


# -- the MQTT 5 way, on a real socket ------------------------------------------------------------
class TakeoverBroker:
    """Just enough of an MQTT 5 broker to accept every connection and, once the client has
    subscribed, tell it "session taken over" (DISCONNECT 0x8E), as a broker does when a second
    client connects with the same id. (The mosquitto these tests run, 2.0.11, only drops the
    socket: tests/faults/test_broker.py covers that way.)"""

    def __init__(self) -> None:
        self._server = socket.create_server(("127.0.0.1", 0))
        self.port = self._server.getsockname()[1]
        self.accepted: list[float] = []  # when each CONNECT was answered
        self._thread = threading.Thread(target=self._serve, daemon=True)
        self._thread.start()

    def _serve(self) -> None:
        while True:
            try:
                conn, _ = self._server.accept()
            except OSError:
                return  # closed
            with conn:
                try:
                    self._session(conn)
                except OSError:
                    pass

    def _session(self, conn: socket.socket) -> None:
        while True:
            kind = self._packet(conn)
            if kind is None:
                return
            if kind == 0x10:  # CONNECT: accepted, no properties
                conn.sendall(b"\x20\x03\x00\x00\x00")
                self.accepted.append(time.monotonic())
            elif kind == 0x80:  # SUBSCRIBE: the client is settled in; now another one "arrives"
                conn.sendall(b"\xe0\x02\x8e\x00")
                return

    @staticmethod
    def _packet(conn: socket.socket) -> int | None:
        try:
            head = conn.recv(1)
        except ConnectionResetError:  # (the client left with bytes unread: its connection's end)
            return None
        if not head:
            return None
        length, shift = 0, 0
        while True:
            byte = conn.recv(1)
            if not byte:
                return None
            length |= (byte[0] & 0x7F) << shift
            shift += 7
            if not byte[0] & 0x80:
                break
        while length:
            chunk = conn.recv(length)
            if not chunk:
                return None
            length -= len(chunk)
        return head[0] & 0xF0

    def close(self) -> None:
        self._server.close()


def connect_until(
    broker: TakeoverBroker | CrashingBroker,
    count: int,
    timeout_s: float,
    caplog: pytest.LogCaptureFixture,
) -> None:
    """The bridge's main connection to ``broker`` until it was accepted ``count`` times (the
    connection's log in ``caplog``); the broker closed after."""
    settings = MqttSettings(port=broker.port, client_id="tower-bridge", protocol="5")
    client = MqttClient(
        settings, will_topic="rotor/bridge/state", subscriptions=["rotor/target"], on_message=print
    )
    caplog.set_level(logging.INFO, logger="bridge.interfaces.mqtt.connection")
    client.start()
    try:
        wait_until(lambda: len(broker.accepted) >= count, timeout_s, f"{count} connections")
    finally:
        client.stop()
        broker.close()


def test_mqtt5_session_taken_over_is_logged_once_and_slows_reconnects(
    caplog: pytest.LogCaptureFixture,
) -> None:
    broker = TakeoverBroker()
    connect_until(broker, 3, 3 * TAKEOVER_FIRST_S + 10, caplog)
    first, second, third = broker.accepted[:3]
    # paho alone would be back after 1 s every time; a connection taken late (a busy machine)
    # shortens the gap after it by as much: that allowance is a deadline, scaled
    assert second - first >= TAKEOVER_FIRST_S - slow(0.5)
    assert third - second >= 2 * TAKEOVER_FIRST_S - slow(0.5)
    errors = [r.getMessage() for r in caplog.records if r.levelno >= logging.ERROR]
    assert len(errors) == 1, errors
    assert "session taken over" in errors[0] and "'tower-bridge'" in errors[0]
    warnings = [r for r in caplog.records if r.levelno == logging.WARNING]
    assert warnings == []  # the error says it all; no warning per kick


class CrashingBroker:
    """A broker that crashes once each client has subscribed: the connection and its port
    close together, and the port opens again RESTART_S later (connection.py rule 7's "gone":
    what a broker systemd restarts looks like, with time to spare for a busy machine: the
    bridge's look at the port comes in paho's thread after the drop, and with 12 workers on 2
    cores it came after 0.5 s once, the port open again: a fight, rightly; still before paho's
    reconnect 1 s after the drop, which is what makes the look matter)."""

    RESTART_S = 0.8

    def __init__(self) -> None:
        self._server = socket.create_server(("127.0.0.1", 0))
        self.port = self._server.getsockname()[1]
        self.accepted: list[float] = []
        self._closed = False
        self._thread = threading.Thread(target=self._serve, daemon=True)
        self._thread.start()

    def _serve(self) -> None:
        while not self._closed:
            try:
                conn, _ = self._server.accept()
            except OSError:
                return
            with conn:
                while (kind := TakeoverBroker._packet(conn)) is not None:
                    if kind == 0x10:
                        conn.sendall(b"\x20\x03\x00\x00\x00")
                        self.accepted.append(time.monotonic())
                    elif kind == 0x80:  # settled in: the broker dies, its port with it
                        self._server.close()
                        break
            if self._closed:
                return
            time.sleep(self.RESTART_S)
            self._server = socket.create_server(("127.0.0.1", self.port))

    def close(self) -> None:
        self._closed = True
        self._server.close()


def test_a_broker_restarted_again_and_again_is_no_fight_and_slows_no_reconnect(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """connection.py rule 7: each drop comes with the broker's port closed (a crash); paho's
    1 s later it is back. FLAP_COUNT such drops and more were taken for a fight over the
    client id, and the bridge waited 5 s, 10 s, ... up to a minute between reconnects."""
    broker = CrashingBroker()
    connect_until(broker, FLAP_COUNT + 2, 30, caplog)
    gaps = [b - a for a, b in zip(broker.accepted, broker.accepted[1:], strict=False)]
    assert all(gap < TAKEOVER_FIRST_S for gap in gaps), gaps  # (each about 1.5 s here)
    errors = [r.getMessage() for r in caplog.records if r.levelno >= logging.ERROR]
    assert errors == []
