"""paho_client.py rules 6, 7 and 9: paho's loop on a thread of the bridge's, against a real
mosquitto. What a publish costs is measured in benchmarks/exchange_cpu.py; here, what must hold
for it: the messages a thread queues while the network thread is busy wake it once; every read
and write of the socket happens on that thread (a TLS socket is never shared); a QoS 0 message
calls no ``on_publish`` while a QoS 1 message's PUBACK still does; a broker that restarts is
reconnected to and what is published then arrives; ``loop_stop`` after ``disconnect`` writes
the DISCONNECT (the broker then drops the last will) before the thread ends; a status queued
without paho's publish is the packet paho's publish makes, and a round's go out in one send."""

from __future__ import annotations

import contextlib
import select
import socket
import threading
from collections.abc import Callable, Iterator
from typing import Any

import pytest
from paho.mqtt._packet import decode_publish
from paho.mqtt.enums import CallbackAPIVersion, MQTTErrorCode, MQTTProtocolVersion
from paho.mqtt.exception import MalformedPacket

from bridge.core import handoff
from bridge.interfaces.mqtt.heartbeat import MAX_PROPERTIES_BYTES, UNREAD_PROPERTIES
from bridge.interfaces.mqtt.paho_client import Client, Waker, new_client, unread_properties
from bridge.settings import MqttSettings
from tests.support import Mosquitto, Probe, wait_until
from tests.support.mqtt import (
    mqtt5_publish,
    mqtt5_string,
    raw_mqtt5,
    retained_snapshot,
    variable_length,
)
from tests.support.waiting import slow


class ThreadSocket(socket.socket):
    """The TCP connection paho opens, unchanged, noting which thread reads and writes it."""

    sent: list[bytes] = []  # every write, in order (the last socket's)

    def __init__(self, sock: socket.socket, threads: set[str]) -> None:
        super().__init__(sock.family, sock.type, sock.proto, fileno=sock.detach())
        self.threads = threads
        ThreadSocket.sent = []

    def send(self, data: Any, flags: int = 0) -> int:
        self.threads.add(threading.current_thread().name)
        n = super().send(data, flags)
        ThreadSocket.sent.append(bytes(data[:n]))
        return n

    def recv(self, bufsize: int, flags: int = 0) -> bytes:
        self.threads.add(threading.current_thread().name)
        return super().recv(bufsize, flags)


@pytest.fixture
def threads(monkeypatch: pytest.MonkeyPatch) -> set[str]:
    seen: set[str] = set()
    real = socket.create_connection

    def create_connection(*args: Any, **kwargs: Any) -> socket.socket:
        return ThreadSocket(real(*args, **kwargs), seen)

    monkeypatch.setattr(socket, "create_connection", create_connection)
    return seen


@contextlib.contextmanager
def connected(broker: Mosquitto, client_id: str = "net-test") -> Iterator[Client]:
    settings = MqttSettings(host="127.0.0.1", port=broker.port, client_id=client_id)
    c = new_client(settings, client_id)
    c.will_set("net/will", b"gone", qos=1)
    c.reconnect_delay_set(1, 2)
    up = threading.Event()
    c.on_connect = lambda *_a: up.set()
    c.connect_async("127.0.0.1", broker.port, keepalive=10)
    c.loop_start()
    try:
        assert up.wait(slow(10)), "never connected"
        yield c
    finally:
        c.disconnect()
        c.loop_stop()


@pytest.fixture
def client(broker: Mosquitto, threads: set[str]) -> Iterator[Client]:
    with connected(broker) as c:
        yield c


@contextlib.contextmanager
def held(
    broker: Mosquitto, probe: Probe, client_id: str, wake: Callable[[], None] | None = None
) -> Iterator[tuple[Client, threading.Event]]:
    """A connected client whose network thread a callback holds (as a slow one may) until the
    test sets the event it is given; ``wake``, if given, is called at each of its wake-ups."""
    settings = MqttSettings(host="127.0.0.1", port=broker.port, client_id=client_id)
    c = new_client(settings, client_id)
    if wake is not None:
        waking = c._wake

        def counted(*args: object) -> None:
            wake()
            waking(*args)

        c._wake = counted  # type: ignore[method-assign]
    busy, release = threading.Event(), threading.Event()

    def on_message(*_args: object) -> None:  # holds the network thread
        busy.set()
        release.wait(slow(10))

    c.on_message = on_message
    up = threading.Event()
    c.on_connect = lambda client, *_a: client.subscribe("net/hold")
    c.on_subscribe = lambda *_a: up.set()
    c.connect_async("127.0.0.1", broker.port, keepalive=10)
    c.loop_start()
    try:
        assert up.wait(slow(10)), "never subscribed"
        probe.publish("net/hold", b"x", qos=0)
        assert busy.wait(slow(10))
        yield c, release
    finally:
        release.set()
        c.disconnect()
        c.loop_stop()


def test_a_burst_queued_while_the_thread_is_busy_wakes_it_once_and_arrives_in_order(
    broker: Mosquitto, probe: Probe, threads: set[str]
) -> None:
    wakes: list[str] = []
    with held(broker, probe, "net-burst", lambda: wakes.append("")) as (c, release):
        mark = probe.mark()
        before = len(wakes)
        for i in range(50):  # a reading's publishes, and more
            c.publish("net/burst", str(i).encode(), qos=0)
        assert len(wakes) - before == 1  # one wake-up for the 50 (paho's loop: 50)
        release.set()
        for i in range(50):
            probe.wait(lambda m, i=i: m.topic == "net/burst" and m.text == str(i), start=mark)
        assert [m.text for m in probe.on("net/burst")] == [str(i) for i in range(50)]
    assert threads == {"paho-mqtt-client-net-burst"}  # never the publishing thread


def test_qos0_calls_no_on_publish_and_a_puback_still_does(
    client: Client, probe: Probe, threads: set[str]
) -> None:
    acked: list[int] = []
    done = threading.Event()

    def on_publish(_c: object, _u: object, mid: int, *_rest: object) -> None:
        acked.append(mid)
        done.set()

    client.on_publish = on_publish
    mark = probe.mark()
    for i in range(20):
        client.publish("net/state", str(i).encode(), qos=0)
    info = client.publish("net/event", b"e", qos=1)
    assert done.wait(slow(10))
    probe.wait(lambda m: m.topic == "net/event", start=mark)
    assert len(probe.on("net/state")) == 20
    assert acked == [info.mid]  # the QoS 1 message's PUBACK only (paho's loop: 21 calls)
    assert info.is_published()


def test_a_restarted_broker_is_reconnected_to(broker: Mosquitto, threads: set[str]) -> None:
    with connected(broker, "net-restart") as c:
        ups: list[int] = []
        c.on_connect = lambda *_a: ups.append(1)
        broker.restart()
        wait_until(lambda: ups and c.is_connected(), 15, "reconnected")
        probe = Probe(broker.port, "net/#")
        try:
            mark = probe.mark()
            c.publish("net/after", b"again", qos=1)
            probe.wait(lambda m: m.topic == "net/after", start=mark)
        finally:
            probe.close()


def test_loop_stop_after_disconnect_writes_the_disconnect_first(
    threads: set[str], broker: Mosquitto
) -> None:
    with connected(broker, "net-leave") as c:
        c.publish("net/last", b"1", qos=0)
    net = [t for t in threading.enumerate() if t.name == "paho-mqtt-client-net-leave"]
    assert net == []  # joined
    assert ThreadSocket.sent[-1][:1] == b"\xe0"  # DISCONNECT, the last thing written
    assert threads == {"paho-mqtt-client-net-leave"}


def test_loop_stop_joins_a_thread_already_ending_by_itself_after_disconnect(
    broker: Mosquitto,
) -> None:
    """After ``disconnect`` the thread may end by itself before ``loop_stop`` is called: held
    in its last step (closing its wake-up) until ``loop_stop`` joins it, it must still be
    waited for (a fresh-clone run once found it alive after ``loop_stop`` had returned)."""
    with connected(broker, "net-ending") as c:
        net = c._net
        assert net is not None
        waker = c._waker
        closing, joined = threading.Event(), threading.Event()
        close, join = waker.close, net.join

        def held_close() -> None:
            closing.set()
            joined.wait(slow(10))  # until loop_stop joins it (the test's end otherwise)
            close()

        def noted_join(timeout: float | None = None) -> None:
            joined.set()
            join(timeout)

        waker.close = held_close  # type: ignore[method-assign]
        net.join = noted_join  # type: ignore[method-assign]
        try:
            c.disconnect()
            assert closing.wait(slow(10)), "the thread did not end after disconnect"
            assert c._net is None  # ending by itself: loop_stop finds no thread to halt
            c.loop_stop()
            assert joined.is_set()
            assert not net.is_alive()
        finally:
            joined.set()


def test_the_waker_wakes_a_select_once_drained_stays_quiet_and_is_void_once_closed() -> None:
    waker = Waker()
    try:
        assert select.select([waker], [], [], 0)[0] == []
        waker.wake()
        waker.wake()  # (paho asks once per queue; twice is one wake-up)
        assert select.select([waker], [], [], slow(5))[0] == [waker]
        waker.drain()
        assert select.select([waker], [], [], 0)[0] == []
    finally:
        waker.close()
    waker.wake()  # after the thread ended (a late publish): nothing, no error
    waker.close()


def test_a_connection_whose_socket_has_a_high_descriptor_number_is_served(
    broker: Mosquitto, probe: Probe, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A bridge with many clients open has descriptors above 1023, which select() refuses: the
    connection must still be made, read and written (not torn down and tried again for ever).
    The connection's socket is moved above 1023 as it is made (not by taking the numbers below
    it: another thread of the test worker may give one back meanwhile)."""
    import fcntl
    import resource
    import socket as socket_module

    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if hard != resource.RLIM_INFINITY and hard < 1200:
        pytest.skip("no room for 1200 descriptors")
    resource.setrlimit(resource.RLIMIT_NOFILE, (max(soft, 1200), hard))
    made = socket_module.create_connection

    def made_high(*args: Any, **kwargs: Any) -> socket_module.socket:
        low = made(*args, **kwargs)
        high = socket_module.socket(fileno=fcntl.fcntl(low.fileno(), fcntl.F_DUPFD, 1100))
        high.settimeout(low.gettimeout())
        low.close()
        return high

    monkeypatch.setattr(socket_module, "create_connection", made_high)
    try:
        with connected(broker, "net-high-fd") as c:
            assert c.socket().fileno() > 1023  # type: ignore[union-attr]
            got = threading.Event()
            c.on_message = lambda *_a: got.set()
            c.subscribe("net/high")
            mark = probe.mark()
            c.publish("net/high", b"up", qos=1)
            probe.wait(lambda m: m.topic == "net/high", start=mark)
            assert got.wait(slow(10)), "never read"
    finally:
        monkeypatch.undo()
        resource.setrlimit(resource.RLIMIT_NOFILE, (soft, hard))


class Racing(Client):
    """A client whose ending network thread is overtaken, right after it marked itself ended,
    by a ``loop_start`` on another thread (as ``disconnect``, ``loop_stop`` finding the thread
    ended, then ``connect_async`` and ``loop_start`` may do)."""

    overtake: Any = None

    @property  # type: ignore[override]
    def _net(self) -> threading.Thread | None:
        return self.__dict__.get("net")  # type: ignore[no-any-return]

    @_net.setter
    def _net(self, thread: threading.Thread | None) -> None:
        self.__dict__["net"] = thread
        overtake, self.overtake = self.overtake, None
        if thread is None and overtake is not None:
            other = threading.Thread(target=overtake)
            other.start()
            other.join()


def test_a_loop_start_overtaking_the_ending_thread_keeps_its_own_wake_up(
    broker: Mosquitto, probe: Probe
) -> None:
    c = Racing(callback_api_version=CallbackAPIVersion.VERSION2, client_id="net-race")
    c.name = "net-race"
    ups: list[int] = []
    c.on_connect = lambda *_a: ups.append(1)
    c.connect_async("127.0.0.1", broker.port, keepalive=10)
    c.loop_start()
    try:
        wait_until(lambda: len(ups) == 1, 10, "connected")

        def again() -> None:
            c.connect_async("127.0.0.1", broker.port, keepalive=10)
            assert c.loop_start() == 0

        c.overtake = again
        c.disconnect()  # the thread writes the DISCONNECT and ends on its own
        wait_until(lambda: len(ups) == 2 and c.is_connected(), 10, "connected again")
        assert c._waker.fileno() >= 0, "the new thread's wake-up was closed by the old thread"
        mark = probe.mark()
        c.publish("net/race", b"after", qos=0)
        probe.wait(lambda m: m.topic == "net/race", start=mark)
    finally:
        c.overtake = None
        c.disconnect()
        c.loop_stop()


def test_a_callback_that_raises_does_not_end_the_network_thread(
    broker: Mosquitto, probe: Probe
) -> None:
    """paho hands a callback's exception up its loop: on our thread, it must not end the
    connection for good (connection.py rule 5: the thread goes on)."""
    settings = MqttSettings(host="127.0.0.1", port=broker.port, client_id="net-raise")
    c = new_client(settings, "net-raise")
    c.reconnect_delay_set(1, 2)
    ups: list[int] = []

    def on_connect(*_args: object) -> None:
        ups.append(1)
        if len(ups) == 1:
            raise RuntimeError("a bug in a callback")

    c.on_connect = on_connect
    c.connect_async("127.0.0.1", broker.port, keepalive=10)
    c.loop_start()
    try:
        wait_until(lambda: len(ups) >= 2 and c.is_connected(), 15, "connected again")
        mark = probe.mark()
        c.publish("net/raised", b"still here", qos=1)
        probe.wait(lambda m: m.topic == "net/raised", start=mark)
    finally:
        c.disconnect()
        c.loop_stop()


def test_a_publish_while_paho_opens_the_socket_goes_after_the_connect(
    broker: Mosquitto, probe: Probe, threads: set[str]
) -> None:
    """A status published by another thread just as paho has opened a new socket, before it
    queued its CONNECT: the broker must get the CONNECT first (a PUBLISH first is a protocol
    error, the connection dropped; under a stream of statuses, reconnecting took many tries)."""
    settings = MqttSettings(host="127.0.0.1", port=broker.port, client_id="net-first")
    c = new_client(settings, "net-first")
    ups: list[int] = []
    c.on_connect = lambda *_a: ups.append(1)
    sneaked: list[int] = []

    def on_socket_open(*_args: object) -> None:  # paho: the socket is open, no CONNECT yet
        if not sneaked:
            other = threading.Thread(target=lambda: sneaked.append(c.publish("net/x", b"s").rc))
            other.start()
            other.join()

    c.on_socket_open = on_socket_open
    mark = probe.mark()
    c.connect_async("127.0.0.1", broker.port, keepalive=10)
    c.loop_start()
    try:
        wait_until(lambda: ups and c.is_connected(), 10, "connected")
        assert sneaked == [0]  # queued, on the new socket
        assert ThreadSocket.sent[0][:1] == b"\x10"  # CONNECT, the first thing written
        assert len(ups) == 1
        probe.wait(lambda m: m.topic == "net/x", start=mark)
    finally:
        c.disconnect()
        c.loop_stop()


def test_loop_stop_ends_while_a_stalled_broker_takes_nothing(broker: Mosquitto) -> None:
    """A broker that reads nothing more (frozen, the TCP window full): stopping the bridge
    ends the thread after a short wait, not once the keepalive gives the connection up."""
    settings = MqttSettings(host="127.0.0.1", port=broker.port, client_id="net-stalled")
    c = new_client(settings, "net-stalled")
    up = threading.Event()
    c.on_connect = lambda *_a: up.set()
    c.connect_async("127.0.0.1", broker.port, keepalive=600)
    c.loop_start()
    stopper = threading.Thread(target=lambda: (c.disconnect(), c.loop_stop()))
    try:
        assert up.wait(slow(10)), "never connected"
        broker.pause()
        for _ in range(20000):  # more than the kernel's buffers take
            c.publish("net/flood", b"s" * 1000, qos=0)
        wait_until(lambda: not c.want_write() or len(c._out_packet) > 1000, 10, "a queue")
        assert c.want_write()  # the window is full
        stopper.start()
        stopper.join(slow(20))
        assert not stopper.is_alive(), "loop_stop still waits for the stalled broker"
    finally:
        broker.resume()
        stopper.join()


def test_messages_queued_in_a_round_wake_the_thread_once_when_the_round_ends(
    broker: Mosquitto, probe: Probe, threads: set[str]
) -> None:
    """Rule 6 with core/handoff.py: the statuses the serial-lines thread hands over in one
    round wake the network thread once, when the round ends, and then all arrive in order."""
    with connected(broker, "net-round") as c:
        woken: list[str] = []
        wake = c._waker.wake

        def counted() -> None:
            woken.append(threading.current_thread().name)
            wake()

        c._waker.wake = counted  # type: ignore[method-assign]
        mark = probe.mark()
        with handoff.batch():
            for i in range(16):  # a round of 16 rotators' statuses
                c.publish("net/round", str(i).encode(), qos=0)
            assert woken == []  # not yet: the round goes on
        assert woken == [threading.current_thread().name]  # once, as it ended
        for i in range(16):
            probe.wait(lambda m, i=i: m.topic == "net/round" and m.text == str(i), start=mark)
        assert [m.text for m in probe.on("net/round")] == [str(i) for i in range(16)]


class LongTick:
    """select.poll for the network thread, its 1 s wait (rule 2's tick) made a long one: what
    goes out then went out because the thread was woken, not because a second had passed."""

    def __init__(self) -> None:
        self._poll = _real_poll()

    def register(self, fd: int, mask: int = select.POLLIN | select.POLLPRI) -> None:
        self._poll.register(fd, mask)

    def unregister(self, fd: int) -> None:
        self._poll.unregister(fd)

    def poll(self, timeout: float | None = None) -> list[tuple[int, int]]:
        return self._poll.poll(600_000 if timeout == 1000 else timeout)


_real_poll = select.poll


def test_another_threads_message_is_not_held_back_by_a_round_under_way(
    broker: Mosquitto, probe: Probe, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Rule 6 with core/handoff.py: the serial-lines thread's statuses wait for its round to
    end; a message another thread publishes meanwhile (an error event from a front end's
    thread, the stop lane's marker) must not wait with them: paho asks for one wake-up per
    queue, and the wake-up it asked the lines thread for is not given until the round ends."""
    monkeypatch.setattr(select, "poll", LongTick)
    with connected(broker, "net-other") as c:
        published, release = threading.Event(), threading.Event()

        def round_under_way() -> None:  # a round of the lines thread, still serving others
            with handoff.batch():
                c.publish("net/status", b"s", qos=0)
                published.set()
                release.wait(slow(30))

        lines = threading.Thread(target=round_under_way, name="serial-lines")
        mark = probe.mark()
        lines.start()
        try:
            assert published.wait(slow(10))
            c.publish("net/error", b"refused", qos=1)  # a front end's thread
            probe.wait(lambda m: m.topic == "net/error", start=mark)
        finally:
            release.set()
            lines.join()
        probe.wait(lambda m: m.topic == "net/status", start=mark)


def _queued(c: Client, publish: Any, *args: Any, **kwargs: Any) -> bytes:
    """The packet ``publish(*args, **kwargs)`` hands paho's queue (a stand-in for the socket,
    which is all paho looks at: nothing is written)."""
    got: list[bytes] = []

    def queue(_command: int, packet: bytes | bytearray, *_rest: object) -> MQTTErrorCode:
        got.append(bytes(packet))
        return MQTTErrorCode.MQTT_ERR_SUCCESS

    c._sock = object()  # type: ignore[assignment]
    c._packet_queue = queue  # type: ignore[method-assign,assignment]
    try:
        publish(*args, **kwargs)
    finally:
        del c._packet_queue
        c._sock = None
    assert len(got) == 1
    return got[0]


@pytest.mark.parametrize("size", [0, 5, 127, 128, 16383, 16384, 70000])
def test_publish_qos0_queues_the_packet_pahos_publish_does(size: int) -> None:
    """Rule 9: the same bytes as paho's own publish, under MQTT 5 and, once the client steps
    down to 3.1.1 (rule 3), under that: a topic part kept from the first is not reused."""
    settings = MqttSettings(host="127.0.0.1", port=1883, client_id="net-bytes")
    c = new_client(settings, "net-bytes")
    payload = bytes(i % 251 for i in range(size))
    for retain in (True, False):
        for topic in ("rotor/r1/status", "rotor/é/bearing"):
            theirs = _queued(c, c.publish, topic, payload, qos=0, retain=retain)
            assert _queued(c, c.publish_qos0, topic, payload, retain) == theirs
    c.use_mqtt311()
    theirs = _queued(c, c.publish, "rotor/r1/status", payload, qos=0, retain=True)
    assert _queued(c, c.publish_qos0, "rotor/r1/status", payload, True) == theirs


def test_publish_qos0_refuses_what_pahos_publish_refuses_and_needs_a_connection() -> None:
    settings = MqttSettings(host="127.0.0.1", port=1883, client_id="net-refuse")
    c = new_client(settings, "net-refuse")
    for topic in ("rotor/+/status", "rotor/#"):
        with pytest.raises(ValueError):
            c.publish(topic, b"x", qos=0)
        with pytest.raises(ValueError):
            c.publish_qos0(topic, b"x", True)
    assert c.publish("rotor/r1/status", b"x", qos=0).rc == MQTTErrorCode.MQTT_ERR_NO_CONN
    assert c.publish_qos0("rotor/r1/status", b"x", True) == MQTTErrorCode.MQTT_ERR_NO_CONN


def test_a_rounds_statuses_go_out_in_one_send_in_order_with_other_messages(
    broker: Mosquitto, probe: Probe, threads: set[str]
) -> None:
    """Rule 9: what ``publish_qos0`` queued one after another is written with one send; a
    message paho's publish queued between them keeps its place, and every one arrives."""
    with held(broker, probe, "net-join") as (c, release):
        mark, sent = probe.mark(), len(ThreadSocket.sent)
        for i in range(16):
            c.publish_qos0(f"net/join/{i % 4}", f"a{i}".encode(), True)
        c.publish("net/join/event", b"e", qos=1)
        for i in range(3):
            c.publish_qos0("net/join/0", f"b{i}".encode(), False)
        release.set()
        texts = [f"a{i}" for i in range(16)] + ["e"] + [f"b{i}" for i in range(3)]
        probe.wait(lambda m: m.text == "b2", start=mark)
        got = [m for m in probe.messages[mark:] if m.topic.startswith("net/join/")]
        assert [m.text for m in got] == texts
        writes = ThreadSocket.sent[sent:]
        assert len([w for w in writes if b"a0" in w or b"a15" in w]) == 1  # one send for 16
        assert any(b"a0" in w and b"a15" in w and b"net/join/event" not in w for w in writes)
    assert threads == {"paho-mqtt-client-net-join"}
    retained = retained_snapshot(broker.port, "net/join/#")  # (as published: 16 retained)
    assert retained == {f"net/join/{k}": f"a{12 + k}".encode() for k in range(4)}


@pytest.mark.parametrize("size", [268_435_456, 268_435_445])
def test_publish_qos0_refuses_a_packet_mqtt_cannot_carry_as_pahos_publish_does(size: int) -> None:
    """Rule 9: no PUBLISH whose length MQTT cannot say goes out (the broker would drop the
    connection, and the retained copy would be sent again at every connect)."""
    settings = MqttSettings(host="127.0.0.1", port=1883, client_id="net-large")
    c = new_client(settings, "net-large")
    payload = bytes(size)
    c._sock = object()  # type: ignore[assignment]  # (a socket is all paho looks at)
    try:
        with pytest.raises(ValueError) as theirs:
            c.publish("rotor/r1/status", payload, qos=0, retain=True)
        with pytest.raises(ValueError) as ours:
            c.publish_qos0("rotor/r1/status", payload, True)
        assert str(ours.value) == str(theirs.value)
        assert not c._out_packet
    finally:
        c._sock = None


def test_statuses_queued_when_the_connection_drops_do_not_stop_the_reconnect(
    broker: Mosquitto, probe: Probe, threads: set[str]
) -> None:
    """Rule 9: paho's reconnect writes "connection lost" into every queued QoS 0 message's
    info; the one all of ``publish_qos0``'s share takes it (a cold review: without that, the
    reconnect raised, and every one after it)."""
    with held(broker, probe, "net-lost") as (c, release):
        for i in range(5):  # queued behind the held network thread
            c.publish_qos0("net/lost", f"s{i}".encode(), True)
        old = c.socket()
        old.shutdown(socket.SHUT_RDWR)  # the connection drops with them still queued
        release.set()
        mark = probe.mark()
        wait_until(lambda: c.socket() not in (None, old) and c.is_connected(), 15, "reconnected")
        assert c.publish_qos0("net/lost", b"after", True) == MQTTErrorCode.MQTT_ERR_SUCCESS
        probe.wait(lambda m: m.topic == "net/lost" and m.text == "after", start=mark)


# -- rule 10: a PUBLISH's properties beyond MAX_PROPERTIES_BYTES are not read -------------------
def _decoded(header: int, packet: bytes) -> Any:
    return decode_publish(header, packet, MQTTProtocolVersion.MQTTv5)


@pytest.mark.parametrize("qos", [0, 1])
def test_properties_beyond_the_bound_reach_paho_as_their_size_and_the_rest_as_it_came(
    qos: int,
) -> None:
    content_type = b"\x03" + mqtt5_string("text/plain")  # 13 bytes
    header, packet = mqtt5_publish("rotor/target", [("", "")] * 20_000, b"90", qos, content_type)
    assert len(_decoded(header, packet).properties.UserProperty) == 20_000  # (read: a second)
    cut = unread_properties(header, packet)
    assert cut is not None
    got = _decoded(header, cut)
    assert (got.topic, got.qos, got.mid, got.payload) == (b"rotor/target", qos, 7 * qos, b"90")
    assert got.properties.UserProperty == [(UNREAD_PROPERTIES, "100013")]
    assert not hasattr(got.properties, "ContentType")


def test_properties_up_to_the_bound_are_read_as_paho_reads_them() -> None:
    header, packet = mqtt5_publish("rotor/target", [("k", "v" * (MAX_PROPERTIES_BYTES - 6))], b"1")
    assert _decoded(header, packet).properties.UserProperty[0][1] == "v" * 4090
    assert len(packet) == 2 + len("rotor/target") + 2 + MAX_PROPERTIES_BYTES + 1
    assert unread_properties(header, packet) is None
    header, packet = mqtt5_publish("rotor/target", [("k", "v" * (MAX_PROPERTIES_BYTES - 5))], b"1")
    assert unread_properties(header, packet) is not None


def test_a_section_whose_length_cannot_be_read_is_left_to_paho() -> None:
    header, packet = mqtt5_publish("rotor/target", [("", "")] * 2000, b"1")
    head = packet[: 2 + len("rotor/target")]
    assert unread_properties(header, head + b"\xff\xff\xff\xff\x7f") is None  # 5 bytes long
    assert unread_properties(header, head) is None  # no length at all
    assert unread_properties(header, b"") is None


def test_a_message_with_too_many_user_properties_arrives_at_once_as_their_size(
    client: Client, broker: Mosquitto
) -> None:
    """Through a real broker: 120,000 user properties (3.7 MB; paho's reading of them took
    minutes, then the broker dropped the connection and sent the message again), between two
    plain messages: all three arrive, in order, the middle one with its size in place of its
    properties."""
    got: list[tuple[str, bytes, Any]] = []
    subscribed = threading.Event()
    client.on_message = lambda _c, _u, m: got.append(
        (m.topic, m.payload, getattr(m.properties, "UserProperty", None))
    )
    client.on_subscribe = lambda *_a: subscribed.set()
    client.subscribe("rotor/#")
    assert subscribed.wait(slow(10))
    pairs = [(f"k{i}", "v" * 20) for i in range(120_000)]
    messages = [
        mqtt5_publish("rotor/target", pairs[:1], b"80"),
        mqtt5_publish("rotor/target", pairs, b"90"),
        mqtt5_publish("rotor/stop", [], b""),
    ]
    size = sum(5 + len(k) + len(v) for k, v in pairs)  # 3,728,890 bytes
    with raw_mqtt5(broker.port, "net-raw") as send:  # a client of the test's own
        send(*messages)
        wait_until(lambda: len(got) == 3, timeout_s=slow(30))
    assert got == [
        ("rotor/target", b"80", [("k0", "v" * 20)]),
        ("rotor/target", b"90", [(UNREAD_PROPERTIES, str(size))]),
        ("rotor/stop", b"", None),
    ]


def test_a_section_longer_than_its_packet_is_refused_without_reading_its_properties() -> None:
    """BUG (reported, a cold review): a section whose declared length runs one byte past the
    packet was left to paho, which read every user property in it, in square time, before it
    found the packet short: 4 s for 40,000."""
    header, packet = mqtt5_publish("rotor/stop", [("k", "v" * 20)] * 40_000, b"")
    at = 2 + len("rotor/stop")
    size = len(packet) - at - 3  # the section's length takes 3 bytes here
    bad = packet[:at] + variable_length(size + 1) + packet[at + 3 :]
    cut = unread_properties(header, bad)
    assert cut is not None and len(cut) < at + 8  # no property of it is left for paho to read
    with pytest.raises(MalformedPacket):
        _decoded(header, bytes(cut))
