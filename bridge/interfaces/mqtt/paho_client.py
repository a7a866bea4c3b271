"""paho's client as every broker connection of the bridge builds it (connection.py uses it for
the main connection, the stop lane and the remote's link): protocol, session, credentials and
TLS (connection.py rule 1), the kernel's quick acknowledgement after every read (connection.py
rule 9, where it is explained), and a tick on paho's own thread.

Rules:
1. ``new_client`` builds paho's client for the settings: MQTT 5 or 3.1.1, credentials, TLS.
2. ``tick``, when set, is called on paho's thread after each round of its loop, for what a
   connection does on a clock without a thread of its own (the station's heartbeat, client.py
   rule 2). It must be cheap; one that raises is logged and paho's thread goes on. It returns
   when (``time.monotonic``) it must be called again, or None: within a second. A round waits
   until the first thing due: that, paho's keep-alive (a ping after its quiet, the connection
   given up when one is unanswered), rule 5's CONNACK, a ``loop_stop``'s end (rule 6); woken
   sooner by the socket or another thread. (A wait of a second at most was one wake-up a
   second of each connection: of an idle bridge's ten, four were the connections' that had
   nothing due.)
3. ``use_mqtt311`` turns a client built for MQTT 5 into one that speaks MQTT 3.1.1 with a clean
   session from its next connection on (``mqtt.protocol = "auto"``, connection.py rule 1), as
   paho itself steps down from 3.1.1 to 3.1 on a refusal: its CONNECT is built from these two
   attributes on every connect (tests/mqtt/test_protocol_fallback.py holds paho to that).
4. ``accepts_mqtt311`` asks a broker once whether it accepts an MQTT 3.1.1 connection with these
   settings (credentials, TLS, client id; no will, nothing subscribed or published): a trial
   connection, closed as soon as the broker answered, within ``timeout_s``. It blocks: never on
   paho's thread.
5. A broker that never answers the CONNECT is given CONNACK_TIMEOUT_S, then the connection is
   ended as if the broker had closed it (the socket shut down: paho sees the end as always and
   reconnects; connection.py says it, rule 6: ``connack_timed_out`` tells it from a close).
   amqtt 0.12 waits for ever on an MQTT 5 CONNECT
   that carries a will; paho alone would wait the keepalive (a minute) each time.
6. ``loop_start`` runs paho's external-loop API (``socket``, ``want_write``, ``loop_read``,
   ``loop_write``, ``loop_misc``) on a thread of ours, in place of paho's own loop, and
   ``loop_stop`` ends it as paho's does (the queue written first), but gives the queue
   STOP_WRITE_S at most: a frozen broker (the TCP window full) held paho's loop until the
   keepalive gave the connection up (a minute), and the bridge's stop with it (the socket is
   then shut down: the broker, once back, sees the end). Everything else is as with paho's
   thread: every read, write, reconnect and callback happens on that one thread (a TLS
   socket is never used by two threads), and paho's reconnect loop is kept: the same back-off
   (``reconnect_delay_set``; reset by an accepted connection), ``on_connect_fail`` called
   inside the failure, no reconnect after ``disconnect``; ``loop_stop`` joins the thread also
   when it was already ending by itself after a ``disconnect``. A callback that raises (paho hands
   its exception up the loop, which ended paho's thread) is logged and the connection made
   again: the thread goes on (connection.py rule 5). What changes is the wake-up: paho's
   own loop is woken by a byte on its socket pair for every packet a publish queues (a system
   call on the publishing thread, a wake-up of paho's thread for each message); ours is woken
   through paho's ``on_socket_register_write``, which paho calls once until the queue has been
   written, so a reading's messages cost one wake-up between them; a message queued inside a
   round of the serial-lines thread wakes it once, when the round ends (core/handoff.py), so
   the statuses of every rotator a round served cost one wake-up between them; paho is then
   told that no wake-up was asked for, so that a message another thread queues meanwhile (an
   error event, the stop lane's marker) wakes it at once, not with the round. It waits with
   poll, not select (which refuses a descriptor above 1023, as a bridge with many clients open
   has).
7. On that thread, a QoS 0 PUBLISH written calls no ``on_publish``: paho calls it to say that
   the message left the socket, building a reason code and properties each time (about as much
   CPU as the rest of the publish), while both connections use ``on_publish`` for QoS 1
   acknowledgements only (which come in ``loop_read`` and still call it).
   ``on_publish`` is set before ``loop_start``.
8. A new connection writes its CONNECT first. paho's ``publish`` queues a message as soon as
   the new socket exists, a moment before paho queues the CONNECT: a status published from
   another thread in that moment went first, which the broker reads as a protocol error (the
   connection dropped: under a stream of statuses, reconnecting took many tries). The CONNECT
   is moved ahead of it (what was queued follows it, as a publish just after the CONNECT).
9. ``publish_qos0`` queues a QoS 0 message as paho's ``publish`` does, for a fraction of its
   CPU (a status is published at every reading: paho spent 11 us on each, a third of what the
   bridge spends on a reading besides it): the packet is made of the topic's part, built and
   checked by paho once per topic and protocol, and the payload; no message id, no
   ``MQTTMessageInfo`` (paho makes a lock for each); paho's own queue, wake-up and writer, so
   everything else (the order with other threads' messages, rule 8, a reconnect's end of
   the queue) is paho's. Such messages queued one after another are written with one send
   (a round of the serial-lines thread queues the statuses of every rotator it served: one
   send each cost the network thread about as much again). Only our own connections' QoS 0
   bytes go this way (delivery.py's: the main connection's retained statuses); paho's own
   debug log (``enable_logger``, which the bridge does not turn on) does not show them.
10. An MQTT 5 PUBLISH whose properties take more than MAX_PROPERTIES_BYTES reaches paho with
   them replaced by one user property, UNREAD_PROPERTIES with their size (heartbeat.py rule
   9, where the attack that found it is told): paho reads user properties in time that grows
   with the square of their number, on the connection's only thread, and a stop carrier reads
   every message on a stop topic. Topic, payload, QoS, retain and message id are as they
   came; a section whose size cannot be read is left to paho, which refuses it, and one that
   runs past its packet is made one paho refuses at its first property (a cold review: paho
   read all of it first).
11. ``hearing``, when set, is told what the network thread saw on the socket (the main
   connection's: heartbeat.py rule 11 tells a broker that held the bridge up from a backlog by
   it): ``quiet(until)`` after a poll that found nothing to read, which proves that nothing came
   from the last read up to ``until`` (a byte that came stays in the socket until read, and
   would have made the poll say so); ``until`` is the clock before the poll, plus its whole
   wait when it waited it all out (no event: the kernel looked at least that late; and no later
   than the clock after it), never the clock after it alone (the thread may have run long
   after the kernel looked). A poll another thread woke (a publish) looks once more without
   waiting, the clock read first: nothing to read then proves quiet up to that clock (review
   61: a poll woken late in its wait proved quiet only up to its start, and a second of a
   stall went unseen at each: a target held 7.9 s went); bytes then are read at once.
   ``reading()`` right
   before a read that finds bytes, before any message in them is handled; ``read()`` when it
   is over (quiet is counted from then). TLS: bytes the SSL socket has already decrypted
   (``pending()``) are read at once and are never quiet, though the raw socket is not readable.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import socket
import ssl
import struct
import threading
import time
from collections.abc import Callable
from typing import Any, Protocol, cast

import paho.mqtt.client as paho
from paho.mqtt.enums import CallbackAPIVersion, MQTTErrorCode

from bridge.core import handoff
from bridge.core.polling import POLLERR, POLLHUP, POLLIN, POLLNVAL, POLLOUT, POLLPRI, new_poller
from bridge.interfaces.mqtt.heartbeat import MAX_PROPERTIES_BYTES, UNREAD_PROPERTIES
from bridge.settings.mqtt import MqttSettings

log = logging.getLogger(__name__)

TCP_QUICKACK: int | None = getattr(socket, "TCP_QUICKACK", None)  # connection.py rule 9; Linux only
CONNACK_TIMEOUT_S = 10.0  # rule 5
_WAIT_MOST_S = 1.0  # rule 2: a round's wait where a tick names no time
_WAIT_LONGEST_MS = 3_600_000  # rule 2: a round's longest wait (poll takes an int)
STOP_WRITE_S = 5.0  # rule 6: what loop_stop gives the queue at most
_PUBLISH_RETAINED = bytes([paho.PUBLISH | 1])  # rule 9: a QoS 0 PUBLISH's first byte
_PUBLISH = bytes([paho.PUBLISH])
_JOIN_BYTES = 65536  # rule 9: a packet of joined messages, at most about
_PACKET_MAX = 268_435_455  # rule 9: MQTT's largest payload (paho's words)
_TOPICS_KEPT = 4096  # rule 9: topic parts known, at most (a bridge's own are some hundreds)
POLL_READ = POLLIN | POLLPRI  # rule 6: what wakes the network thread to read
READ_EVENTS = POLL_READ | POLLERR | POLLHUP  # ... and what it then reads


def acknowledge_now(sock: object) -> None:
    """connection.py rule 9: have the kernel acknowledge what was read so far now, not after
    its delayed-ACK timer (and leave its interactive mode until we next send)."""
    setsockopt = getattr(sock, "setsockopt", None)  # None before the first connect
    if TCP_QUICKACK is None or setsockopt is None:
        return
    try:
        setsockopt(socket.IPPROTO_TCP, TCP_QUICKACK, 1)
    except OSError:  # closed meanwhile: paho notices that on its own
        pass


class Hearing(Protocol):
    """Rule 11: what the network thread says it saw (on that thread; each call cheap)."""

    def clock(self) -> float: ...
    def quiet(self, until: float) -> None: ...
    def reading(self) -> None: ...
    def read(self) -> None: ...


class Waker:
    """Rule 6: what wakes the network thread: an eventfd on Linux (a fifth of a socket pair's
    cost), else a socket pair. ``wake`` from any thread, once closed too (then nothing: the lock
    keeps it off a descriptor number reused by then); ``close`` and ``drain`` on the thread."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._pair: tuple[socket.socket, socket.socket] | None = None
        if hasattr(os, "eventfd"):
            self._fd = os.eventfd(0, os.EFD_NONBLOCK | os.EFD_CLOEXEC)
        else:
            r, w = socket.socketpair()
            r.setblocking(False)
            w.setblocking(False)
            self._pair, self._fd = (r, w), r.fileno()

    def fileno(self) -> int:
        return self._fd

    def wake(self) -> None:
        with self._lock, contextlib.suppress(OSError):  # full: awake already
            if self._fd < 0:
                return
            if self._pair is None:
                os.eventfd_write(self._fd, 1)
            else:
                self._pair[1].send(b"\0")

    def drain(self) -> None:
        with contextlib.suppress(OSError):
            if self._pair is None:
                os.eventfd_read(self._fd)
            else:
                self._pair[0].recv(4096)

    def close(self) -> None:
        with self._lock:
            fd, self._fd = self._fd, -1
            if fd < 0:
                return
            if self._pair is None:
                os.close(fd)
            else:
                for sock in self._pair:
                    sock.close()


class _LeanInfo:
    """Rule 9: what paho's writer tells of a QoS 0 message written (it calls every one's
    ``MQTTMessageInfo``), for the messages ``publish_qos0`` queues without one. One for all,
    keeping nothing: paho's reconnect writes "connection lost" into the ``rc`` of every QoS 0
    message still queued (without a setter that raised, and every reconnect failed so)."""

    __slots__ = ()

    @property
    def rc(self) -> MQTTErrorCode:
        return MQTTErrorCode.MQTT_ERR_SUCCESS

    @rc.setter
    def rc(self, _rc: MQTTErrorCode) -> None:
        pass

    def _set_as_published(self) -> None:
        pass


#: paho's queue holds an ``MQTTMessageInfo`` per message; of this one it calls what _LeanInfo has
_LEAN_INFO = cast(paho.MQTTMessageInfo, _LeanInfo())


#: rule 10: a property section paho refuses at its first property (a string longer than the section)
_MALFORMED = b"\x03\x26\xff\xff"


def unread_properties(header: int, packet: bytes | bytearray) -> bytearray | None:
    """Rule 10: a PUBLISH's variable header and payload (``packet``, after the fixed header whose
    first byte is ``header``) with properties longer than MAX_PROPERTIES_BYTES replaced by
    UNREAD_PROPERTIES, or, when the section runs past the packet, by one paho refuses at once;
    None to leave it as it is (short enough, or a length that cannot be read: paho says so)."""
    at = 2 + int.from_bytes(packet[:2], "big") + (2 if header & 0x06 else 0)  # topic, id
    size = shift = 0
    for i in range(at, min(at + 4, len(packet))):  # the section's length: a variable integer
        size |= (packet[i] & 0x7F) << shift
        shift += 7
        if not packet[i] & 0x80:
            break
    else:
        return None
    start = i + 1
    if size <= MAX_PROPERTIES_BYTES:
        return None
    if start + size > len(packet):  # longer than its packet: refused by paho at once (its own
        return bytearray(packet[:at]) + _MALFORMED  # reading would take the square time first)
    name, value = UNREAD_PROPERTIES.encode(), str(size).encode()
    prop = b"\x26%b%b%b%b" % (
        len(name).to_bytes(2, "big"),
        name,
        len(value).to_bytes(2, "big"),
        value,
    )
    return bytearray(packet[:at]) + bytes([len(prop)]) + prop + packet[start + size :]


class Client(paho.Client):
    """paho's client with connection.py rule 9 (every read goes through loop_read), rule 2
    (``tick``), rule 6 (``loop_start``: the network thread) and rule 9 (``publish_qos0``)."""

    tick: Callable[[], float | None] | None = None
    _tick_due = -math.inf  # rule 2: when ``tick`` asked to be called again
    hearing: Hearing | None = None  # rule 11
    name = "mqtt"  # the network thread's name: paho-mqtt-client-<name> (rule 6)
    _connect_t: float | None = None  # rule 5: when the CONNECT now unanswered went out
    connack_timed_out = False  # rule 5: this attempt was ended for want of a CONNACK
    _connect_keep: int | None = None  # ``ping_within``: the keep-alive the CONNECT says
    attempts = 0  # connection attempts so far (connection.py rule 6: one end said once)
    _net: threading.Thread | None = None  # rule 6
    _last_net: threading.Thread | None = None  # ... the last one started (loop_stop joins it)
    _leaving = False  # rule 6: ``disconnect`` was called: no reconnect
    _delays: tuple[float, float] = (1.0, 120.0)  # rule 6: paho's reconnect back-off, min, max
    _delay_s: float | None = None  # ... the last wait, None after an accepted connection
    _halt_t = 0.0  # rule 6: when loop_stop was called
    _topic_parts: dict[str, tuple[int, bytes]] | None = None  # rule 9: protocol, topic part

    def publish_qos0(self, topic: str, payload: bytes, retain: bool) -> MQTTErrorCode:
        """Rule 9: paho's ``publish(topic, payload, 0, retain).rc``."""
        parts = self._topic_parts
        if parts is None:
            parts = self._topic_parts = {}
        part = parts.get(topic)
        protocol = self._protocol
        if part is None or part[0] != protocol:
            part = (protocol, self._topic_part(topic))
            if len(parts) >= _TOPICS_KEPT:
                parts.clear()
            parts[topic] = part
        if len(payload) > _PACKET_MAX:  # (paho's checks, in paho's order)
            raise ValueError("Payload too large.")
        if self._sock is None:
            return MQTTErrorCode.MQTT_ERR_NO_CONN
        body = part[1]
        packet = bytearray(_PUBLISH_RETAINED if retain else _PUBLISH)
        self._pack_remaining_length(packet, len(body) + len(payload))  # (refuses what MQTT
        packet += body  # cannot say: "Packet too large")
        packet += payload
        return self._packet_queue(paho.PUBLISH, packet, 0, 0, _LEAN_INFO)

    def _handle_publish(self) -> MQTTErrorCode:
        """Rule 10, then paho's own."""
        if self._protocol == paho.MQTTv5:
            incoming = self._in_packet
            if len(incoming["packet"]) > MAX_PROPERTIES_BYTES:
                cut = unread_properties(incoming["command"], incoming["packet"])
                if cut is not None:
                    incoming["packet"] = cut
        return super()._handle_publish()

    def _topic_part(self, topic: str) -> bytes:
        """Rule 9: a PUBLISH's topic and (MQTT 5) its empty properties, checked as paho's
        ``publish`` checks them."""
        if self._protocol != paho.MQTTv5 and not topic:
            raise ValueError("Invalid topic.")
        data = topic.encode("utf-8")
        self._raise_for_invalid_topic(data)
        head = struct.pack("!H", len(data)) + data
        return head + b"\x00" if self._protocol == paho.MQTTv5 else head

    def reconnect(self) -> MQTTErrorCode:
        self.attempts += 1
        self._connect_t = time.monotonic()
        self.connack_timed_out = False
        if self._connect_keep is not None:  # (``ping_within``: the CONNECT says the setting's)
            self._keepalive = self._connect_keep
        rc = super().reconnect()
        self._connect_first()
        return rc

    def _connect_first(self) -> None:
        """Rule 8: the CONNECT ahead of what other threads queued while paho opened the socket
        (nothing is written before this: the thread that writes is this one)."""
        queue = self._out_packet
        for i in range(len(queue)):  # by index: other threads may append meanwhile
            packet = queue[i]
            if packet["command"] & 0xF0 == paho.CONNECT:
                if i:
                    del queue[i]
                    queue.appendleft(packet)
                return

    def reconnect_delay_set(self, min_delay: int = 1, max_delay: int = 120) -> None:
        super().reconnect_delay_set(min_delay, max_delay)
        self._delays, self._delay_s = (min_delay, max_delay), None

    def connect_async(self, *args: Any, **kwargs: Any) -> None:
        self._leaving = False
        super().connect_async(*args, **kwargs)
        self._connect_keep = self._keepalive

    def ping_within(self, seconds: int) -> None:
        """Connection.py rule 6, once a connection is accepted: a PINGREQ after ``seconds`` of
        quiet, and the connection given up ``seconds`` after one unanswered (MQTT lets a
        client ping at any time). Its CONNECT said the keep-alive asked for (or the broker's
        own, MQTT 5), and the next says it again: the broker still waits 1.5 of those for a
        word, and a CONNACK the CONNACK_TIMEOUT_S of rule 5 (review 145: at 2 s in the
        CONNECT, a broker 2.5 s slow to accept never had the connection, and one that heard
        nothing of it for 3 s dropped it). A broker's Server Keep Alive of 0 (MQTT 5: it
        asks for none) turns off its wait, not these pings (review 148: the carriers never
        found a dead path under such a broker)."""
        keep = self._keepalive
        self._keepalive = seconds if keep == 0 else min(keep, seconds)

    def disconnect(self, *args: Any, **kwargs: Any) -> MQTTErrorCode:
        self._leaving = True
        return super().disconnect(*args, **kwargs)

    # -- rule 6: the network thread --------------------------------------------------------
    def loop_start(self) -> MQTTErrorCode:
        if self._net is not None:
            return MQTTErrorCode.MQTT_ERR_INVAL
        self._waker = Waker()
        self._halt = threading.Event()
        self.on_socket_register_write = self._wake
        self._net = threading.Thread(
            target=self._serve, name=f"paho-mqtt-client-{self.name}", daemon=True
        )
        self._last_net = self._net
        self._net.start()
        return MQTTErrorCode.MQTT_ERR_SUCCESS

    def loop_stop(self) -> MQTTErrorCode:
        """Ends the network thread once the queue is written, and joins it (not from it)."""
        net = self._net
        if net is None:  # ended, or ending by itself after ``disconnect``: its end, then
            last = self._last_net
            if last is not None and last is not threading.current_thread():
                last.join()
            return MQTTErrorCode.MQTT_ERR_INVAL
        self._halt_t = time.monotonic()
        self._halt.set()
        self._waker.wake()  # at once, even inside a round of the serial-lines thread
        if threading.current_thread() is not net:
            net.join()
        return MQTTErrorCode.MQTT_ERR_SUCCESS

    def _wake(self, *_args: object) -> None:
        """paho's on_socket_register_write: something is queued to write (any thread; inside a
        round of the serial-lines thread, once at its end: rule 6)."""
        waker = self._waker
        if handoff.defer(waker, waker.wake):
            self._registered_write = False  # paho asks again: another thread's wakes at once
        else:
            waker.wake()

    def _serve(self) -> None:
        """The thread (a new ``loop_start`` may follow its end, as with paho's: from the moment
        ``_net`` is None, so what it closes then is its own wake-up, not the next thread's)."""
        waker = self._waker
        try:
            self._reconnecting()
        finally:
            self._net = None
            waker.close()

    def _reconnecting(self) -> None:
        """paho's reconnect loop (``loop_forever``'s) around ``_round``."""
        first, lost = True, False
        poller, polled = new_poller(), -1  # the socket's descriptor in the poller, -1: none
        poller.register(self._waker.fileno(), POLLIN)
        while True:
            sock = self.socket()
            if self._halt.is_set() and (sock is None or lost or not self.want_write()):
                return
            if self._halt.is_set() and time.monotonic() - self._halt_t >= STOP_WRITE_S:
                log.warning("MQTT: %g s and the broker has not taken all: stopping", STOP_WRITE_S)
                shutdown = getattr(sock, "shutdown", None)
                if shutdown is not None:
                    with contextlib.suppress(OSError):
                        shutdown(socket.SHUT_RDWR)
                return
            if sock is not None and not lost:
                fd = getattr(sock, "fileno", lambda: -1)()
                if fd != polled and polled >= 0:
                    with contextlib.suppress(KeyError):
                        poller.unregister(polled)
                polled = fd
                try:
                    lost = not self._round(sock, poller)
                except Exception:  # a callback's bug, which paho hands up: not the thread's end
                    log.exception("error on the MQTT network thread: connecting again")
                    shutdown = getattr(sock, "shutdown", None)
                    if shutdown is not None:
                        with contextlib.suppress(OSError):
                            shutdown(socket.SHUT_RDWR)  # paho reads the end as always
                continue
            if self._leaving:
                return
            if not first and not self._back_off():
                return
            first, lost = False, False
            try:
                self.reconnect()
            except OSError:  # paho's loop says so, and waits
                self._connect_failed()
            except Exception:  # a callback's bug (on_pre_connect, on_socket_open): waits too
                log.exception("error on the MQTT network thread while connecting")

    def _round(self, sock: Any, poller: Any) -> bool:
        """One round of the loop: wait (until the first thing due, rule 2) for the socket or a
        wake-up, then
        read, write what is queued, and the keepalive. False: the socket cannot be waited on.
        poll, not select: a bridge with many clients open has descriptors above 1023, which
        select refuses (the connection would be made and torn down again for ever)."""
        pending = getattr(sock, "pending", None)  # TLS: bytes already decrypted
        ready = pending() if pending is not None else 0
        hearing = self.hearing  # rule 11
        try:
            fd = sock.fileno()
            poller.register(fd, POLL_READ | POLLOUT if self.want_write() else POLL_READ)
            wait_ms = 0 if ready else self._wait_ms()
            before = hearing.clock() if hearing is not None else 0.0
            events = poller.poll(wait_ms)
        except (OSError, TypeError, ValueError):  # closed under us: reconnect
            return False
        readable = False
        for got, mask in events:
            if mask & POLLNVAL:
                return False
            if got == fd:
                readable = bool(mask & READ_EVENTS)  # an error or a hang-up too: read, it says
            else:
                self._waker.drain()
        if hearing is not None and not (ready or readable):  # rule 11: nothing came up to then
            if not events:  # waited out: the kernel looked at the wait's end
                hearing.quiet(min(before + wait_ms / 1000, hearing.clock()))
            else:  # woken (another thread's publish): a look that waits for nothing
                looked = hearing.clock()
                try:
                    again = poller.poll(0)
                except (OSError, TypeError, ValueError):
                    return False
                for got, mask in again:
                    if mask & POLLNVAL:
                        return False
                    if got == fd and mask & READ_EVENTS:
                        readable = True
                hearing.quiet(before if readable else looked)
        if ready or readable:
            if hearing is None:
                self.loop_read()
            else:
                hearing.reading()
                try:
                    self.loop_read()
                finally:
                    hearing.read()
            if self.socket() is not sock:
                return True
            if self._delay_s is not None and self.is_connected():
                self._delay_s = None  # paho starts its back-off again after a CONNACK
        if self.want_write():
            self.loop_write()
            if self.socket() is not sock:
                return True
        self.loop_misc()
        return True

    def _wait_ms(self) -> int:
        """Rule 2: how long a round may wait for its socket or a wake-up: until the first thing
        due, at least a millisecond (a due time past is looked at by ``loop_misc`` at once,
        and its look moves it on), a second at most where something asks it (a tick with no
        time; paho's private clocks not found)."""
        now = time.monotonic()
        due = now + _WAIT_MOST_S if self._tick_due == -math.inf else self._tick_due
        if self._connect_t is not None:  # rule 5
            due = min(due, self._connect_t + CONNACK_TIMEOUT_S)
        halt = getattr(self, "_halt", None)  # (None: no loop_start, a test's round)
        if halt is not None and halt.is_set():  # rule 6: STOP_WRITE_S from ``loop_stop``
            due = min(due, now + _WAIT_MOST_S)
        keepalive = self._keepalive
        if keepalive:  # paho's ``_check_keepalive`` and ``loop_misc``, as they look
            sent = getattr(self, "_last_msg_out", None)
            heard = getattr(self, "_last_bytes_received", None)
            if not isinstance(sent, float | int) or not isinstance(heard, float | int):
                due = min(due, now + _WAIT_MOST_S)
            else:
                due = min(due, min(sent, heard) + keepalive)
                if self._ping_t:
                    due = min(due, self._ping_t + keepalive)
        left_ms = (due - now) * 1000  # (inf: nothing due at all, a Server Keep Alive of 0
        if left_ms >= _WAIT_LONGEST_MS:  # on a connection whose tick names none: review 154)
            return _WAIT_LONGEST_MS
        return max(1, math.ceil(left_ms))

    def _back_off(self) -> bool:
        """paho's wait before a reconnect: min, doubling up to max. False: stopped meanwhile."""
        lo, hi = self._delays
        self._delay_s = lo if self._delay_s is None else min(self._delay_s * 2, hi)
        return not self._halt.wait(self._delay_s) and not self._leaving

    def _connect_failed(self) -> None:
        """paho's on_connect_fail, inside the ``except OSError`` that says why."""
        on_fail = self.on_connect_fail
        if on_fail is not None:
            try:
                on_fail(self, self.user_data_get())
            except Exception:  # connection.py rule 5: the thread goes on
                log.exception("error in on_connect_fail")

    def loop_write(self) -> MQTTErrorCode:
        """Rule 7: no on_publish for a QoS 0 PUBLISH written (only on the thread: paho calls
        ``loop_write`` from a publishing thread when no thread serves it)."""
        if self._net is None:
            return super().loop_write()
        self._join_lean()
        keep = self.on_publish
        self.on_publish = None
        try:
            return super().loop_write()
        finally:
            self.on_publish = keep

    def _join_lean(self) -> None:
        """Rule 9: the messages ``publish_qos0`` queued one after another at the head of the
        queue, joined into one packet (on the network thread, the queue's only taker)."""
        queue = self._out_packet
        if len(queue) < 2 or queue[0]["info"] is not _LEAN_INFO or queue[0]["pos"]:
            return
        parts: list[bytes | bytearray] = []
        size = 0
        while queue and size < _JOIN_BYTES:
            packet = queue[0]
            if packet["info"] is not _LEAN_INFO or packet["pos"]:
                break
            queue.popleft()
            parts.append(packet["packet"])
            size += len(packet["packet"])
        queue.appendleft(
            {
                "command": paho.PUBLISH,
                "mid": 0,
                "qos": 0,
                "pos": 0,
                "to_process": size,
                "packet": b"".join(parts),
                "info": _LEAN_INFO,
            }
        )

    def _unanswered(self) -> None:
        """Rule 5: a CONNECT unanswered for too long ends its connection."""
        t = self._connect_t
        if t is None:
            return
        if self.is_connected():
            self._connect_t = None
        elif time.monotonic() - t >= CONNACK_TIMEOUT_S:
            self._connect_t = None
            shutdown = getattr(self.socket(), "shutdown", None)  # None: no socket (yet)
            if shutdown is not None:
                self.connack_timed_out = True  # (connection.py rule 6 says it so)
                log.debug("no CONNACK in %g s: ending the connection", CONNACK_TIMEOUT_S)
                with contextlib.suppress(OSError):
                    shutdown(socket.SHUT_RDWR)

    def use_mqtt311(self) -> None:
        """Rule 3: MQTT 3.1.1 and a clean session from the next connection on."""
        self._protocol = paho.MQTTv311
        self._clean_session = True

    def loop_read(self, max_packets: int = 1) -> MQTTErrorCode:
        rc = super().loop_read(max_packets)
        acknowledge_now(self.socket())
        return rc

    def loop_misc(self) -> MQTTErrorCode:
        self._unanswered()
        rc = super().loop_misc()
        tick = self.tick
        self._tick_due = -math.inf  # (rule 2: within a second, unless it names a time)
        if tick is not None and rc == MQTTErrorCode.MQTT_ERR_SUCCESS:
            try:
                due = tick()
            except Exception:  # connection.py rule 5: paho's network thread goes on
                log.exception("error in the MQTT connection's tick")
            else:
                if due is not None:
                    self._tick_due = due
        elif tick is None:
            self._tick_due = math.inf  # nothing on a clock but paho's own and rule 5's
        return rc


def new_client(settings: MqttSettings, client_id: str) -> Client:
    """paho's client as both connections use it: rule 1's protocol and session, credentials
    and TLS."""
    v5 = settings.protocol != "3.1.1"  # "auto" tries MQTT 5 first (connection.py rule 1)
    c = Client(
        callback_api_version=CallbackAPIVersion.VERSION2,
        client_id=client_id,
        protocol=paho.MQTTv5 if v5 else paho.MQTTv311,
        clean_session=None if v5 else True,  # None: MQTT 5 has clean_start instead
    )
    c.name = client_id
    if settings.username is not None:
        password = settings.password.get_secret_value() if settings.password else None
        c.username_pw_set(settings.username, password)
    if settings.tls.enabled:
        c.tls_set(
            ca_certs=str(settings.tls.ca_file) if settings.tls.ca_file else None,
            certfile=str(settings.tls.cert_file) if settings.tls.cert_file else None,
            keyfile=str(settings.tls.key_file) if settings.tls.key_file else None,
            cert_reqs=ssl.CERT_REQUIRED,
        )
        c.tls_insecure_set(settings.tls.insecure)
    return c


def accepts_mqtt311(settings: MqttSettings, client_id: str, timeout_s: float = 5.0) -> bool:
    """Rule 4: whether the broker accepts an MQTT 3.1.1 connection from this client now."""
    c = new_client(settings, client_id)
    c.use_mqtt311()
    c.connect_timeout = timeout_s
    answers: list[bool] = []

    def on_connect(*args: object) -> None:
        reason = args[3]
        answers.append(not getattr(reason, "is_failure", True))

    c.on_connect = on_connect
    try:
        c.connect(settings.host, settings.port, keepalive=max(5, settings.keepalive_s))
    except (OSError, ValueError, ssl.SSLError):
        return False
    try:
        deadline = time.monotonic() + timeout_s
        while not answers and time.monotonic() < deadline:
            if c.loop(timeout=0.1) != MQTTErrorCode.MQTT_ERR_SUCCESS:
                break
    finally:
        with contextlib.suppress(Exception):
            c.disconnect()
        with contextlib.suppress(Exception):
            c.loop(timeout=0.1)  # hands the DISCONNECT to the socket
    return answers == [True]
