"""An MQTT probe: a client that records every message under its topic filters, stamped on arrival
(time.monotonic, the emulators' clock too), and waits on what arrives with a deadline.

Small packets on loopback would otherwise wait for a delayed TCP ACK (about 40 ms a round trip),
so the probe sets TCP_NODELAY; brokers that must be as quick say ``set_tcp_nodelay true``.
"""

from __future__ import annotations

import contextlib
import os
import socket
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import paho.mqtt.client as paho
from paho.mqtt.enums import CallbackAPIVersion

from tests.support.waiting import slow, wait_until

SYNC_PREFIX = "probe-sync/"  # Probe.caught_up's round trips


@dataclass
class Message:
    topic: str
    payload: bytes
    retain: bool
    t: float
    qos: int = 0

    @property
    def text(self) -> str:
        return self.payload.decode()


def _nodelay(client: Any, userdata: Any, sock: Any) -> None:
    with contextlib.suppress(OSError, AttributeError):
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)


class Probe:
    """Subscribed at QoS 1 to ``topic_filter`` (several: "a|b"; none: ""), again after every
    reconnect; optionally with a user name/password and TLS (``tls``: paho's tls_set keywords).
    Made once the broker has acknowledged the subscription (its SUBACK), not at the CONNACK:
    paho's thread writes the SUBSCRIBE after that, and a message published meanwhile (a busy
    machine runs the test first) was lost to the probe (tests/mqtt/test_probe_subscribed.py)."""

    #: what a wait that runs out raises (the benchmarks' recorder raises their own error)
    timeout_error: type[Exception] = AssertionError

    def __init__(
        self,
        port: int,
        topic_filter: str = "#",
        client_id: str | None = None,
        *,
        username: str | None = None,
        password: str | None = None,
        tls: dict[str, str] | None = None,
        max_inflight: int = 20,
        keepalive_s: int = 10,
    ) -> None:
        self.messages: list[Message] = []
        self._cond = threading.Condition()
        self._connected = threading.Event()  # connected and, with a filter, subscribed
        self._subscribe_mid: int | None = None
        self.filter = topic_filter
        # caught_up's round trips: a topic of this probe's own, never recorded
        self._sync_topic = f"{SYNC_PREFIX}{os.getpid()}-{id(self)}"
        self._sync_n = 0  # the last one sent
        self._synced = 0  # the last one back
        c = paho.Client(CallbackAPIVersion.VERSION2, client_id=client_id or f"probe-{id(self)}")
        if username is not None:
            c.username_pw_set(username, password)
        if tls is not None:
            c.tls_set(**tls)
        c.on_socket_open = _nodelay
        c.max_inflight_messages_set(max_inflight)
        c.on_connect = self._on_connect
        c.on_message = self._on_message
        c.on_subscribe = self._on_subscribe
        c.reconnect_delay_set(0.1, 0.5)  # type: ignore[arg-type]
        c.connect_async("127.0.0.1", port, keepalive=keepalive_s)
        c.loop_start()
        self.client = c
        try:
            wait_until(self._connected.is_set, 10, "probe subscribed", error=self.timeout_error)
        except Exception:
            self.close()
            raise

    def _on_connect(self, client, userdata, flags, rc, props) -> None:  # noqa: ANN001
        filters = [(f, 1) for f in self.filter.split("|") if f]
        if not filters:  # a client that only publishes
            self._connected.set()
            return
        filters.append((self._sync_topic, 1))
        _rc, self._subscribe_mid = client.subscribe(filters)  # (its SUBACK comes after this)

    def _on_subscribe(self, client, userdata, mid, reason_codes, props) -> None:  # noqa: ANN001
        if mid == self._subscribe_mid:
            self._connected.set()

    def _on_message(self, client, userdata, msg) -> None:  # noqa: ANN001
        with self._cond:
            if msg.topic.startswith(SYNC_PREFIX):  # (another probe's, under "#": not recorded)
                if msg.topic == self._sync_topic:
                    self._synced = max(self._synced, int(msg.payload))
                    self._cond.notify_all()
                return
            self.messages.append(
                Message(msg.topic, bytes(msg.payload), bool(msg.retain), time.monotonic(), msg.qos)
            )
            self._cond.notify_all()

    def publish(
        self,
        topic: str,
        payload: str | bytes,
        retain: bool = False,
        qos: int = 1,
        timeout_s: float = 5.0,
    ) -> bool:
        """Sent, and acknowledged by the broker (QoS 1), waited for ``slow(timeout_s)``: whether
        it was (paho's wait ends silently at its deadline; a caller that needs the broker to
        have read the message first asserts it)."""
        info = self.client.publish(topic, payload, qos=qos, retain=retain)
        info.wait_for_publish(slow(timeout_s))
        return info.is_published()

    def caught_up(self, timeout_s: float = 10.0) -> float:
        """A round trip through the broker: once it returns, every message the broker sent
        this probe before has arrived and been stamped. Returns the clock then, for a wait's
        ``after``: a message stamped later was sent after the call. (A message published just
        before a bridge stopped could otherwise arrive, on a busy machine, after a ``t`` read
        right after the stop, and pass for the next run's: a CI run saw a restarted rotator's
        ``online`` that was the first run's, and its target went to no bridge.)"""
        if not self.filter:
            raise ValueError("caught_up needs a probe that subscribes")
        with self._cond:
            self._sync_n = n = self._sync_n + 1
        self.publish(self._sync_topic, str(n).encode())
        deadline = time.monotonic() + slow(timeout_s)
        with self._cond:
            while self._synced < n:
                left = deadline - time.monotonic()
                if left <= 0:
                    raise self.timeout_error(f"the probe's round trip {n} did not come back")
                self._cond.wait(left)
        return time.monotonic()

    def mark(self) -> int:
        """Where the messages received from now on start (``wait(..., start=mark)``)."""
        with self._cond:
            return len(self.messages)

    def on(self, topic: str) -> list[Message]:
        with self._cond:
            return [m for m in self.messages if m.topic == topic]

    def last(self, topic: str) -> Message | None:
        with self._cond:
            return next((m for m in reversed(self.messages) if m.topic == topic), None)

    def wait(
        self,
        predicate: Callable[[Message], bool],
        timeout_s: float = 10.0,
        what: str = "",
        start: int = 0,
        *,
        failure: Callable[[], str] | None = None,
        quiet: bool = False,
    ) -> Message:
        """The first message (from number ``start`` on) that satisfies ``predicate``; on timeout,
        ``timeout_error`` with ``failure()`` or a message naming ``what``. ``timeout_s`` is a
        deadline, scaled by ``slow``, unless ``quiet`` says the test expects the timeout (a
        quiet period, waiting.py rule 2)."""
        timeout_s = timeout_s if quiet else slow(timeout_s)
        deadline = time.monotonic() + timeout_s
        with self._cond:
            i = start
            while True:
                while i < len(self.messages):
                    if predicate(self.messages[i]):
                        return self.messages[i]
                    i += 1
                left = deadline - time.monotonic()
                if left <= 0:
                    said = f"timed out after {timeout_s:g} s waiting for {what or predicate}"
                    raise self.timeout_error(failure() if failure else said)
                self._cond.wait(left)

    def wait_for(
        self,
        topic: str,
        predicate: Callable[[Message], bool] = lambda m: True,
        timeout_s: float = 10.0,
        after: float | None = None,
        *,
        quiet: bool = False,
    ) -> Message:
        """The first message on ``topic`` (received after ``after``) that satisfies predicate."""

        def seen() -> str:
            recent = [(m.topic, m.payload[:80]) for m in self.messages if m.topic == topic]
            waited = timeout_s if quiet else slow(timeout_s)
            return f"no matching message on {topic} in {waited:g} s; saw {recent[-10:]}"

        return self.wait(
            lambda m: m.topic == topic and (after is None or m.t >= after) and predicate(m),
            timeout_s,
            failure=seen,
            quiet=quiet,
        )

    def wait_value(
        self, topic: str, value: str, timeout_s: float = 10.0, after: float | None = None
    ) -> Message:
        return self.wait_for(topic, lambda m: m.text == value, timeout_s, after)

    def close(self) -> None:
        end_paho(self.client)


def end_paho(client: paho.Client) -> None:
    """``disconnect``, then ``loop_stop``, without paho's race between them: paho 2.1's
    ``loop_stop`` reads its thread twice, and the thread, ending on the DISCONNECT, clears it
    in between on a busy machine ("'NoneType' object has no attribute 'join'",
    eclipse-paho/paho.mqtt.python issue 872). Cleared, the thread has ended: nothing to join."""
    with contextlib.suppress(Exception):
        client.disconnect()
    try:
        client.loop_stop()
    except AttributeError:
        if getattr(client, "_thread", None) is not None:
            raise


def retained_snapshot(port: int, topic_filter: str) -> dict[str, bytes]:
    """What a new subscriber gets as retained messages right now (fresh connection)."""
    # retained messages are delivered right after SUBACK; a round trip through a topic of our
    # own, subscribed in the same SUBSCRIBE, marks the end of them
    marker = f"probe-marker/{threading.get_ident()}-{time.monotonic_ns()}"
    probe = Probe(port, f"{topic_filter}|{marker}")
    try:
        probe.publish(marker, b"end")
        probe.wait_for(marker)
        return {m.topic: m.payload for m in probe.messages if m.retain}
    finally:
        probe.close()


# -- MQTT 5 PUBLISH packets made here (paho's packing copies its buffer for every property) ------
def mqtt5_string(text: str) -> bytes:
    """A UTF-8 string as MQTT encodes it: its length in two bytes, then the bytes."""
    data = text.encode()
    return len(data).to_bytes(2, "big") + data


def variable_length(n: int) -> bytes:
    """MQTT's variable byte integer (a remaining length, a property section's): 7 bits a byte,
    low first."""
    out = bytearray()
    while True:
        n, byte = n >> 7, n & 0x7F
        out.append(byte | (0x80 if n else 0))
        if not n:
            return bytes(out)


def mqtt5_publish(
    topic: str, pairs: list[tuple[str, str]], payload: bytes, qos: int = 0, more: bytes = b""
) -> tuple[int, bytes]:
    """An MQTT 5 PUBLISH's first byte and what follows its remaining length, its user properties
    ``pairs`` (120,000 of them take paho's ``publish`` minutes: its packing copies the buffer
    for each one); ``more``: other properties, encoded, ahead of them; message id 7 at QoS 1."""
    props = more + b"".join(b"\x26" + mqtt5_string(k) + mqtt5_string(v) for k, v in pairs)
    mid = b"\x00\x07" if qos else b""
    return 0x30 | qos << 1, mqtt5_string(topic) + mid + variable_length(
        len(props)
    ) + props + payload


@contextlib.contextmanager
def raw_mqtt5(port: int, client_id: str) -> Any:
    """A socket that has connected to the broker at ``port`` with MQTT 5 (clean start, no
    login) and had its CONNACK; ``send`` it packets of ``mqtt5_publish`` (QoS 0); ended with a
    DISCONNECT."""
    with socket.create_connection(("127.0.0.1", port)) as raw:
        connect = b"\x00\x04MQTT\x05\x02\x00\x0a\x00" + mqtt5_string(client_id)
        raw.sendall(b"\x10" + variable_length(len(connect)) + connect)
        assert raw.recv(64)[0] == 0x20, "no CONNACK"

        def send(*packets: tuple[int, bytes]) -> None:
            raw.sendall(b"".join(bytes([h]) + variable_length(len(p)) + p for h, p in packets))

        yield send
        raw.sendall(b"\xe0\x00")
