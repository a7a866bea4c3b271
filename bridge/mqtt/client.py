"""The broker connection: the only module that imports paho.

Rules:
1. paho 2.x, CallbackAPIVersion.VERSION2. MQTT 5 with a clean start and no session expiry, so
   commands sent while the bridge was away are not replayed to it; subscriptions ask for
   retain-as-published, so a command published with the retain flag is recognised as such even
   while the bridge is connected (MQTT 3.1.1 clears the flag then). ``protocol = "3.1.1"`` in the
   configuration is the fallback for brokers without MQTT 5 (clean session, same rules otherwise).
2. The last will marks the bridge offline (retained, QoS 1); ``online`` is published on every
   connect, ``offline`` on a clean shutdown.
3. On every connect: subscribe again and re-publish every retained message we own (the broker may
   have restarted without persistence and lost them). Retained messages are kept in a cache;
   while disconnected they only update the cache, non-retained events are dropped (they would be
   stale by the time the broker is back).
4. Command topics are subscribed at QoS 0 (COMMAND_QOS). The session is clean, so QoS 1 would
   buy no redelivery; what it does cost: a broker holds at most ~1000 QoS 1 messages for a
   subscriber that falls behind and then drops the NEWEST (mosquitto: "Outgoing messages are
   being dropped"), which in a flood of targets loses the final target, or a STOP. At QoS 0 a
   connected subscriber gets everything, in order. (Measured: tests/faults, 10,000-target burst.)
5. Callbacks run on paho's thread and stay short: they hand messages to the handler, which must
   not block (it drops commands into mailboxes).
6. paho owns the reconnect loop (connect_async + loop_start, exponential back-off); a refused
   connection (bad credentials) or a failed one (TLS, unreachable) is logged once with the
   reason and retried, never a crash. Rule 7 only slows that loop down.
7. One client id, one connection. A broker that gets a second connection with a client id
   closes the first ("session taken over": MQTT 5 reason 0x8E; MQTT 3.1.1 just closes the
   socket), so two processes with one id (two hosts sharing a configuration, a stale container
   beside a new one) would take each other over in a loop, each reconnect kicking the other.
   The client logs that ONCE, naming the client id and the likely cause, and backs off instead
   of fighting: TAKEOVER_FIRST_S, doubling per reconnect up to TAKEOVER_MAX_S (so at most one
   reconnect a minute), until a connection lasts STABLE_S. Brokers that say nothing (MQTT
   3.1.1; mosquitto 2.0.11 even with MQTT 5) just drop the connection, so FLAP_COUNT drops in a
   row, each less than STABLE_S after the connection was accepted and each followed by a
   connection accepted at the first try (the broker never went away), count as a takeover
   too; the side that holds the connection longer sees exactly that. A drop after a keepalive
   timeout or with another reason from the broker is no evidence. (A link that keeps breaking
   the same way earns the same back-off; the error says "most likely".) The default client id
   is unique per installation (MqttSettings.effective_client_id): only an explicit one, or a
   copied state file on a host of the same name, can collide.
8. Retained state (bearing, state, status, ...) goes out at QoS 0 (STATE_QOS): the newest value
   supersedes every older one, so an acknowledgement buys nothing, while QoS 1 costs a PUBACK
   per message (half of the bridge's CPU with 32 rotators turning, measured in benchmarks/) and
   lets paho re-send an old value it had in flight after a reconnect, over the fresher state
   re-published from the cache. Discovery configs, the bridge's own online/offline (its last
   will) and error events stay QoS 1; a rotator's availability is state like any other.
9. Whatever the broker sends is acknowledged at once, in TCP: after every read paho makes, the
   socket gets TCP_QUICKACK (Linux; elsewhere nothing changes). A broker with Nagle on (mosquitto's
   default, set_tcp_nodelay false) holds a second small packet until the first is acknowledged,
   and Linux delays the acknowledgement of a packet we do not answer (a PUBACK for our error
   event, a command that changes nothing) by 40 ms once we answer others quickly: a stop 0-3 ms
   behind a refused target reached the controller 44 ms late (p50; benchmarks/latency.py), and
   behind any target while state went out at QoS 1. The kernel leaves quick-ack mode again as
   soon as we send, so it is set after every read, not once (a system call per read). Command
   topics stay QoS 0 (rule 4): our PUBACK would acknowledge a command too, but brings back what
   rule 4 avoids.
10. The bridge owns its retained topics (``watch_owned``: state, status, lock and option
   states, its online/offline): it subscribes to them (MQTT 5: without its own messages) and a
   value there that it did not publish, from another client, is replaced with its own at once
   (at most once per FOREIGN_FIX_S per topic) and logged once a minute per topic: a stray
   retained ``lock/state OFF`` must not tell a dashboard the lock is off while it is on. Under
   MQTT 3.1.1 the bridge hears its own messages too, in the order sent: one it sent and has
   not heard back yet is no stranger.
11. What the broker refuses is said: a subscription it denies (SUBACK) or a QoS 1 publish it
   will not take (PUBACK, MQTT 5; e.g. 0x87 "not authorised" from an ACL) is logged as an error
   once per topic, naming the topic, kept in ``problems`` and handed to ``on_denied`` (the app
   shows it in the rotator's status and on ``B/bridge/info``). A denied QoS 0 publish (state)
   gets no answer from any broker: the bridge cannot see it.
12. Nothing from before a disconnect lands after the state of the new connection. paho sends
   the QoS 1 messages it still held (unacknowledged, or queued) only after ``on_connect`` has
   returned, behind the cache re-published there: a discovery config or an online changed
   while the broker stalled came back with its older value and stayed. So ``on_connect``
   takes them from paho: one whose retained topic is in the cache is superseded by the value
   just sent; the others (events, deletions) are sent again, after the state.
13. A publish paho does not take (its QoS 1 queue full: at most MAX_QUEUED messages, so a
   stalled broker cannot grow the bridge's memory without bound; no connection) is not taken
   for sent: a retained topic is marked dirty and sent again as soon as the broker
   acknowledges anything (room again) and on every connect; an event waits in the bounded
   backlog (EVENT_BACKLOG, the oldest dropped first).
14. One live bridge per base topic (claim.py): on every connect the client subscribes, then
   takes its first look before it publishes or deletes anything: it publishes a hello to
   itself, and the retained ``B/bridge/info`` and ``B/bridge/state`` that arrive before the
   hello comes back are what the broker held. Another live instance there: ``on_refused``
   (nothing is published, not even offline, and the app exits). Otherwise the state goes out
   (rule 3), and deletions of retained configs asked for during the look (Home Assistant's
   stale discovery) are sent if the base topic was this installation's. A look without an
   answer in LOOK_TIMEOUT_S (an ACL that denies the hello) goes on without it, deleting
   nothing. While it runs, another instance's info put there is judged by claim rule 4.
15. Deleting a retained config (``clear_retained``) is said in the log, but a flood of them
   (thousands of configs published under the bridge's node ids) is a few lines: a few at
   once, then one a minute (FOREIGN_LOG_S) for each of "cleared" and "left alone", the next
   line saying how many were not logged; a look's deletions are one line, naming ten at most.
"""

from __future__ import annotations

import logging
import socket
import ssl
import sys
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any, Literal

import paho.mqtt.client as paho
from paho.mqtt.enums import CallbackAPIVersion, MQTTErrorCode
from paho.mqtt.properties import Properties
from paho.mqtt.reasoncodes import ReasonCode
from paho.mqtt.subscribeoptions import SubscribeOptions

from bridge.mqtt.claim import Claim, Instance, Verdict, first_look, refusal, yields_to
from bridge.mqtt.limiter import EventLimiter
from bridge.settings import MqttSettings

log = logging.getLogger(__name__)

MessageHandler = Callable[[str, bytes, bool], None]
EVENT_BACKLOG = 50
COMMAND_QOS = 0
STATE_QOS = 0  # rule 8

# rule 7
SESSION_TAKEN_OVER = 0x8E
CONNECTION_LOST = 0x80  # paho's "Unspecified error" for a socket that closed without a word
TAKEOVER_FIRST_S = 5
TAKEOVER_MAX_S = 60
STABLE_S = 2 * TAKEOVER_MAX_S  # longer than the other side's back-off: a fight never looks stable
FLAP_COUNT = 3
Ending = Literal["taken over", "dropped", "other"]

TCP_QUICKACK: int | None = getattr(socket, "TCP_QUICKACK", None)  # rule 9; Linux only

# rule 10
FOREIGN_FIX_S = 2.0
FOREIGN_LOG_S = 60.0
CLEARS_SAID_AT_ONCE = 3  # rule 15
CLEARS_NAMED = 10  # rule 15: topics named in one line
MAX_UNACKED = 10_000  # rule 11: QoS 1 message ids remembered, at most
SETTLE_AFTER_CONNECT_S = 1.0  # retained values that arrive this soon after a connect are old
ECHOES_KEPT = 32  # MQTT 3.1.1: payloads per topic sent and not yet heard back, at most
MAX_QUEUED = 4096  # rule 13: QoS 1 messages paho holds for the broker, at most
LOOK_TIMEOUT_S = 5.0  # rule 14


class TakeoverGuard:
    """Rule 7's bookkeeping, without paho or a clock: times in, a back-off out."""

    def __init__(self) -> None:
        self.connected_at: float | None = None
        self._drops = 0  # dropped connections in a row, the broker reachable throughout
        self.backoff_s = 0  # 0: no takeover episode, paho's own reconnect delays apply
        self.reported = False

    def connected(self, now: float) -> None:
        self.connected_at = now

    def connect_failed(self) -> None:
        """The broker was unreachable or refused us: the drops before were not a fight."""
        self._drops = 0

    def disconnected(self, now: float, ending: Ending) -> bool:
        """Whether this disconnect is part of a takeover episode (``backoff_s`` is then set)."""
        lasted = now - self.connected_at if self.connected_at is not None else 0.0
        self.connected_at = None
        if lasted >= STABLE_S:
            self._drops, self.backoff_s, self.reported = 0, 0, False
        self._drops = self._drops + 1 if ending == "dropped" else 0
        if not (ending == "taken over" or self._drops >= FLAP_COUNT or self.backoff_s):
            return False
        self.backoff_s = min(TAKEOVER_MAX_S, self.backoff_s * 2 or TAKEOVER_FIRST_S)
        return True


def acknowledge_now(sock: object) -> None:
    """Rule 9: have the kernel acknowledge what was read so far now, not after its delayed-ACK
    timer (and leave its interactive mode until we next send)."""
    setsockopt = getattr(sock, "setsockopt", None)  # None before the first connect
    if TCP_QUICKACK is None or setsockopt is None:
        return
    try:
        setsockopt(socket.IPPROTO_TCP, TCP_QUICKACK, 1)
    except OSError:  # closed meanwhile: paho notices that on its own
        pass


def new_client(settings: MqttSettings, client_id: str) -> Client:
    """paho's client as both connections (this one and lane.py's) use it: rule 1's protocol
    and session, credentials and TLS."""
    v5 = settings.protocol == "5"
    c = Client(
        callback_api_version=CallbackAPIVersion.VERSION2,
        client_id=client_id,
        protocol=paho.MQTTv5 if v5 else paho.MQTTv311,
        clean_session=None if v5 else True,  # None: MQTT 5 has clean_start instead
    )
    authenticate(c, settings)
    return c


def command_filters(
    filters: list[str], no_replay: frozenset[str], v5: bool
) -> list[tuple[str, Any]]:
    """Rules 1 and 4 for both connections: command topics at COMMAND_QOS, MQTT 5 with
    retain-as-published; the filters in ``no_replay`` (stop: lastword.py rule 6) also ask the
    broker not to replay their retained message on subscribing (retain handling 2)."""
    if not v5:
        return [(topic, COMMAND_QOS) for topic in filters]
    live = SubscribeOptions(qos=COMMAND_QOS, retainAsPublished=True)
    fresh = SubscribeOptions(
        qos=COMMAND_QOS,
        retainAsPublished=True,
        retainHandling=SubscribeOptions.RETAIN_DO_NOT_SEND,
    )
    return [(topic, fresh if topic in no_replay else live) for topic in filters]


def connect(c: paho.Client, settings: MqttSettings) -> None:
    """Rule 6: paho's reconnect loop from now on (a clean start under MQTT 5, rule 1)."""
    s = settings
    if s.protocol == "5":
        c.connect_async(s.host, s.port, keepalive=s.keepalive_s, clean_start=True)
    else:
        c.connect_async(s.host, s.port, keepalive=s.keepalive_s)
    c.loop_start()


def authenticate(c: paho.Client, settings: MqttSettings) -> None:
    """Credentials and TLS from the settings."""
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


def ending_of(flags: paho.DisconnectFlags, reason_code: ReasonCode) -> Ending:
    """Rule 7: how a connection ended, as evidence of a takeover."""
    code = getattr(reason_code, "value", None)
    from_server = bool(getattr(flags, "is_disconnect_packet_from_server", False))
    if from_server and code == SESSION_TAKEN_OVER:
        return "taken over"
    if not from_server and code == CONNECTION_LOST:
        return "dropped"
    return "other"


class Client(paho.Client):
    """paho's client with rule 9: ``_loop`` (loop_start's thread) reads through loop_read."""

    def loop_read(self, max_packets: int = 1) -> MQTTErrorCode:
        rc = super().loop_read(max_packets)
        acknowledge_now(self.socket())
        return rc


class MqttClient:
    def __init__(
        self,
        settings: MqttSettings,
        *,
        will_topic: str,
        subscriptions: list[str],
        on_message: MessageHandler,
        on_connect: Callable[[], None] | None = None,
        on_new_connection: Callable[[], None] | None = None,
        on_connection_lost: Callable[[], None] | None = None,
        no_replay: list[str] | None = None,
        on_denied: Callable[[str, str], None] | None = None,
        claim: Claim | None = None,
        on_refused: Callable[[str], None] | None = None,
        reconnect_min_s: int = 1,
        reconnect_max_s: int = 30,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self._settings = settings
        self._will_topic = will_topic
        self._subscriptions = subscriptions
        self._handler = on_message
        self._on_connect_hook = on_connect
        self._on_new_connection = on_new_connection
        self._on_connection_lost = on_connection_lost
        self._command_mid: int | None = None
        self._subscribed = False
        self._no_replay = frozenset(no_replay or ())
        self._on_denied = on_denied
        self._retained: dict[str, tuple[bytes, int]] = {}  # topic -> (payload, QoS)
        self._backlog: deque[tuple[str, str | bytes]] = deque(maxlen=EVENT_BACKLOG)
        self._lock = threading.Lock()
        self.connected = threading.Event()
        self._last_refusal: str | None = None
        self._stopping = False
        self._v5 = settings.protocol == "5"
        self._clock = clock
        self._reconnect_s = (reconnect_min_s, reconnect_max_s)
        self._guard = TakeoverGuard()
        self._slowed = False  # reconnect_delay_set raised for a takeover (rule 7)
        c = new_client(settings, settings.effective_client_id())
        c.will_set(will_topic, b"offline", qos=1, retain=True)
        c.reconnect_delay_set(reconnect_min_s, reconnect_max_s)
        c.max_queued_messages_set(MAX_QUEUED)  # rule 13
        c.on_connect = self._on_connect
        c.on_connect_fail = self._on_connect_fail
        c.on_disconnect = self._on_disconnect
        c.on_message = self._on_message
        c.on_subscribe = self._on_subscribe
        c.on_publish = self._on_publish
        self._client = c
        self._sub_filters: dict[int, list[str]] = {}  # SUBSCRIBE's message id -> its filters
        self._pub_topics: dict[int, str] = {}  # a QoS 1 publish's message id -> its topic
        self._acked_early: dict[int, ReasonCode] = {}  # acknowledged before its id was noted
        self._ids_lock = threading.Lock()
        self._denied: set[str] = set()  # rule 11: each denied topic reported once
        self.problems: list[str] = []  # rule 11, for the bridge's own diagnostics
        self._retained[will_topic] = (b"online", 1)
        self._owned: list[str] = []
        self._echoes: dict[str, deque[bytes]] = {}  # rule 10, MQTT 3.1.1: sent, not heard back
        self._fixed_at: dict[str, float] = {}
        self.connected_at = -1e18  # the clock at the last accepted connection
        self._logged_at: dict[str, float] = {}
        self._clears_said = EventLimiter(clock, CLEARS_SAID_AT_ONCE, 1.0 / FOREIGN_LOG_S)
        self._dirty: set[str] = set()  # rule 13: retained topics whose last publish failed
        self._retry = threading.Event()  # rule 13: set when the broker has room again
        self.failed_publishes = 0
        # rule 14
        self._claim = claim
        self._on_refused = on_refused
        self._up = False  # a connection accepted (the first look may still run)
        self._looks = 0
        self._looking: int | None = None  # the first look under way: its number
        self._seen: dict[str, bytes] = {}  # retained info/state seen during the look
        self._held: list[paho.MQTTMessage] = []  # rule 12: taken from paho, sent at the open
        self._pending_clears: list[str] = []
        self.refused: str | None = None
        self._took_over = False

    @property
    def gated(self) -> bool:
        """Rule 14: the first look runs, or the bridge refused to run: only halts are taken."""
        return self._looking is not None or self.refused is not None

    def add_subscriptions(self, topics: list[str]) -> None:
        """More topic filters (features such as discovery); before ``start()``."""
        self._subscriptions = [*self._subscriptions, *topics]

    def watch_owned(self, filters: list[str]) -> None:
        """Rule 10: the filters of the retained topics the bridge publishes; before ``start()``."""
        self._owned = list(filters)

    # -- lifecycle --------------------------------------------------------------------------
    def start(self) -> None:
        s = self._settings
        log.info("connecting to MQTT broker %s:%d as %s", s.host, s.port, s.effective_client_id())
        connect(self._client, s)
        threading.Thread(target=self._retry_failed, name="mqtt-retry", daemon=True).start()

    def stop(self, timeout_s: float = 2.0) -> None:
        """Publish offline, flush, disconnect."""
        self._stopping = True  # rule 10 stands down: our own offline is about to come back
        self._retry.set()  # ends the retry thread
        with self._lock:
            self._retained[self._will_topic] = (b"offline", 1)
        if self.connected.is_set() and self.refused is None:  # refused: it is another's
            self._client.drop_out_messages()  # a full queue would refuse the offline (rule 13)
            info = self._client.publish(self._will_topic, b"offline", qos=1, retain=True)
            self._wait([info], timeout_s)
        self._client.disconnect()
        self._client.loop_stop()

    # -- publishing (any thread) ----------------------------------------------------------
    def publish_retained(
        self,
        topic: str,
        payload: str | bytes,
        *,
        only_if_changed: bool = True,
        qos: int = STATE_QOS,
    ) -> None:
        data = payload.encode() if isinstance(payload, str) else payload
        # cache, connected check and publish under one lock, so a connect that re-publishes the
        # cache cannot overtake a newer value with an older one (paho's publish only enqueues)
        with self._lock:
            held = self._retained.get(topic)
            if only_if_changed and held is not None and held[0] == data:
                return
            self._retained[topic] = (data, qos)
            if self.connected.is_set():
                self._expect_echo(topic, data)
                self._send(self._client, topic, data, qos, retain=True)

    def clear_retained(self, topic: str) -> None:
        """Delete a retained config from the broker (empty retained payload); said (rule 15)."""
        with self._lock:
            self._retained.pop(topic, None)
            if self._claim is None:
                if self.connected.is_set():
                    self._client.publish(topic, b"", qos=1, retain=True)
                cleared = True
            elif self._looking is not None:  # rule 14: held by the broker before we came
                self._pending_clears.append(topic)
                return
            else:  # published while we run: another client's (claim rule 3)
                cleared = False
        left_out = self._clears_said.admit("cleared" if cleared else "left alone")
        if left_out is None:
            return
        more = f" ({left_out} more like it not logged)" if left_out else ""
        if cleared:
            log.info("cleared %s, a retained config this bridge no longer makes%s", topic, more)
        else:
            log.warning(
                "%s was published by another client: not ours to delete; left alone%s",
                topic,
                more,
            )

    def republish_retained(self, skip_prefix: str | None = None) -> None:
        """Send the retained messages we own again (Home Assistant came back, for example)."""
        with self._lock:
            if not self.connected.is_set():
                return
            for topic, (data, qos) in self._retained.items():
                if skip_prefix is None or not topic.startswith(skip_prefix):
                    self._expect_echo(topic, data)
                    self._send(self._client, topic, data, qos, retain=True)

    def publish_event(self, topic: str, payload: str | bytes) -> None:
        with self._lock:
            if self.connected.is_set():
                self._send(self._client, topic, payload, 1, retain=False)
            else:
                self._backlog.append((topic, payload))

    def publish_marker(self, topic: str, payload: str) -> None:
        """A message to the bridge itself (lastword.py): QoS 0, now or never (no cache, no
        backlog: one that cannot go now is void with the connection), during the first look
        too. paho's publish is thread-safe; the stop lane's thread calls this."""
        if self._up:
            self._client.publish(topic, payload.encode(), qos=0)

    @property
    def up(self) -> bool:
        """A connection is accepted and its command topics subscribed (its first look may
        still run): from now on a command published reaches this connection."""
        return self._up and self._subscribed

    def publish_offline_now(self, topics: list[str], timeout_s: float = 1.0) -> None:
        """At shutdown: mark these retained topics offline and wait until the broker has them."""
        infos = []
        if self.refused is not None:
            return  # rule 14: these topics are another bridge's
        for topic in topics:
            with self._lock:
                self._retained[topic] = (b"offline", 1)
            if self.connected.is_set():
                infos.append(self._client.publish(topic, b"offline", qos=1, retain=True))
        self._wait(infos, timeout_s)

    def _wait(self, infos: list[paho.MQTTMessageInfo], timeout_s: float) -> None:
        """Until the broker has them all, ``timeout_s`` at most for all together, and no
        longer once the connection is gone (their acknowledgements will never come)."""
        deadline = time.monotonic() + timeout_s
        for info in infos:
            while not info.is_published() and self.connected.is_set():
                left = deadline - time.monotonic()
                if left <= 0:
                    return
                try:
                    info.wait_for_publish(min(left, 0.1))
                except (RuntimeError, ValueError):
                    break

    def shutting_down(self) -> None:
        """The bridge is stopping: a broker that goes away now (a Ctrl-C reaches the demo's
        private broker too) is no news, and is not reconnected to with a warning."""
        self._stopping = True

    # -- paho callbacks (paho's thread) ---------------------------------------------------
    def _on_connect(
        self,
        client: paho.Client,
        userdata: Any,
        flags: paho.ConnectFlags,
        reason_code: ReasonCode,
        properties: Properties | None,
    ) -> None:
        if reason_code.is_failure:
            self._guard.connect_failed()
            text = str(reason_code)
            if text != self._last_refusal:
                log.error("MQTT broker refused the connection: %s (retrying)", text)
                self._last_refusal = text
            return
        self._last_refusal = None
        self._up = True
        self._guard.connected(self._clock())
        log.info("connected to MQTT broker")
        self._subscribed = False  # until the SUBACK of the command topics (``up``)
        if self._on_new_connection is not None:  # before any message of the new connection
            self._on_new_connection()
        self._sub_filters.clear()  # before subscribing: the SUBACKs come after this returns
        # subscribe before saying `online`: the broker handles our packets in order, so a
        # client that sends a command the moment it sees `online` is already heard
        self._command_mid = self._subscribe(
            client, command_filters(self._subscriptions, self._no_replay, self._v5)
        )
        if self._v5 and self._owned:  # rule 10: not our own messages back
            mine = SubscribeOptions(qos=0, noLocal=True, retainAsPublished=True)
            self._subscribe(client, [(topic, mine) for topic in self._owned])
        elif self._owned:
            self._subscribe(client, [(topic, 0) for topic in self._owned])
        held = client.drop_out_messages()  # rule 12: paho would send them after this returns
        with self._lock:
            with self._ids_lock:  # acknowledgements of the old connection never come
                self._pub_topics.clear()
                self._acked_early.clear()
            self._held.extend(held)  # a look that never ended leaves its own
            self.connected_at = self._clock()
            self._echoes.clear()  # what was in flight before is gone with the old connection
            claim = self._claim
            if claim is not None:  # rule 14: look first
                self._looks += 1
                n = self._looking = self._looks
                self._seen = {}
                self._pending_clears = []
                self._subscribe(client, [(claim.hello_topic, 0)])
                client.publish(claim.hello_topic, f"{claim.me.id} {n}".encode(), qos=0)
                timer = threading.Timer(LOOK_TIMEOUT_S, self._look_timed_out, args=(n,))
                timer.daemon = True
                timer.start()
                return
            self._open(client, clear=False)
        if self._on_connect_hook is not None:
            self._on_connect_hook()

    def _open(self, client: paho.Client, *, clear: bool) -> None:
        """Under the lock: the state goes out (rules 3 and 12), then ``connected``."""
        self._dirty.clear()  # every retained value goes out below
        self._send(client, self._will_topic, b"online", 1, retain=True)
        for topic, (data, qos) in self._retained.items():
            self._expect_echo(topic, data)
            if topic != self._will_topic:
                self._send(client, topic, data, qos, retain=True)
        held, self._held = self._held, []
        for msg in held:  # rule 12 (older than the backlog's events)
            if not (msg.retain and msg.topic in self._retained):
                self._send(client, msg.topic, bytes(msg.payload), msg.qos, retain=msg.retain)
        backlog = list(self._backlog)
        self._backlog.clear()
        for topic, event in backlog:
            self._send(client, topic, event, 1, retain=False)
        clears, self._pending_clears = self._pending_clears, []
        if clear:
            for topic in clears:
                self._send(client, topic, b"", 1, retain=True)
        if clear and clears:
            log.info(
                "cleared %d retained config(s) this bridge no longer makes: %s",
                len(clears),
                _some(clears),
            )
        elif clears:
            log.warning(
                "left alone %d retained config(s) this bridge does not generate, as the base "
                "topic was not its own (delete them by hand if that bridge is gone for good): %s",
                len(clears),
                _some(clears),
            )
        self.connected.set()

    # -- rule 14: the first look --------------------------------------------------------------
    def _end_look(self, n: int, timed_out: bool = False) -> None:
        claim = self._claim
        assert claim is not None
        with self._lock:
            if self._looking != n or not self._up or self._stopping:
                return
            self._looking = None
            info, state = self._seen.get(claim.info_topic), self._seen.get(self._will_topic)
            verdict = first_look(claim.me, info, state)  # timed out: on what was seen
            if verdict is Verdict.OURS and (timed_out or self._took_over):
                verdict = Verdict.TAKE_OVER  # not known to be ours: delete nothing (claim 3)
            if verdict is Verdict.REFUSE:
                other = Instance.parse(info or b"")
                assert other is not None
                self.refused = refusal(claim.base_topic, other, live_since_look=False)
                self._stopping = True
            else:
                if verdict is Verdict.TAKE_OVER and not (timed_out or self._took_over):
                    self._took_over = True  # for the life of the process (claim rule 3)
                    other = Instance.parse(info or b"")
                    log.warning(
                        "taking over base topic %r from %s, which is offline",
                        claim.base_topic,
                        other.described() if other else "another bridge",
                    )
                self._open(self._client, clear=verdict is Verdict.OURS)
        if self.refused is not None:
            self._refuse()
        elif self._on_connect_hook is not None:
            self._on_connect_hook()

    def _look_timed_out(self, n: int) -> None:
        with self._lock:
            if self._looking != n:
                return
        log.warning(
            "no answer to the bridge's first look in %g s (does the broker's ACL deny %s?): "
            "judging by what the broker showed so far, and deleting no stale discovery",
            LOOK_TIMEOUT_S,
            self._claim.hello_topic if self._claim else "?",
        )
        self._end_look(n, timed_out=True)

    def _refuse(self) -> None:
        """Never on paho's thread: the app stops the client (loop_stop joins paho's thread)."""
        message = self.refused
        assert message is not None
        log.error("%s", message)
        if self._on_refused is not None:
            threading.Thread(target=self._on_refused, args=(message,), daemon=True).start()

    # -- rule 11: what the broker refused ---------------------------------------------------
    def _subscribe(self, client: paho.Client, filters: list[tuple[str, Any]]) -> int | None:
        if not filters:
            return None
        _rc, mid = client.subscribe(filters)
        if mid is not None:
            self._sub_filters[mid] = [f for f, _opts in filters]
        return mid

    def _send(
        self, client: paho.Client, topic: str, data: str | bytes, qos: int, *, retain: bool
    ) -> None:
        """paho's publish; a QoS 1 message's id kept to match its acknowledgement (rule 11)."""
        info = client.publish(topic, data, qos=qos, retain=retain)  # callers hold self._lock
        if info.rc != MQTTErrorCode.MQTT_ERR_SUCCESS and not (
            qos and info.rc == MQTTErrorCode.MQTT_ERR_NO_CONN  # paho keeps it for the connect
        ):
            self._failed(topic, data, retain, info.rc)
            return
        if not qos:
            return
        with self._ids_lock:  # never self._lock in paho's callback: paho holds its own there
            early = self._acked_early.pop(info.mid, None)
            if early is None and len(self._pub_topics) < MAX_UNACKED:
                self._pub_topics[info.mid] = topic
        if early is not None:  # refused before we noted its id
            self._deny(topic, "publish to", str(early))

    def _on_subscribe(
        self,
        client: paho.Client,
        userdata: Any,
        mid: int,
        reason_codes: list[ReasonCode],
        properties: Properties | None,
    ) -> None:
        filters = self._sub_filters.pop(mid, [])
        if mid == self._command_mid:
            self._subscribed = True  # (``up``: the commands reach us from now on)
        for topic, code in zip(filters, reason_codes, strict=False):
            if code.is_failure:
                self._deny(topic, "subscribe to", str(code))

    def _on_publish(
        self,
        client: paho.Client,
        userdata: Any,
        mid: int,
        reason_code: ReasonCode,
        properties: Properties | None,
    ) -> None:
        with self._ids_lock:
            topic = self._pub_topics.pop(mid, None)
            if topic is None and reason_code.is_failure and len(self._acked_early) < MAX_UNACKED:
                self._acked_early[mid] = reason_code  # _send has not noted the id yet
                # (only a refusal: paho calls this for every QoS 0 message too, with success)
        if topic is not None and reason_code.is_failure:
            self._deny(topic, "publish to", str(reason_code))
        if self._dirty or self._backlog:  # rule 13: the broker took one, so there is room again
            self._retry.set()  # (read without the lock: a stale answer costs one wake-up)

    # -- rule 13: what paho did not take ----------------------------------------------------
    def _failed(self, topic: str, data: str | bytes, retain: bool, rc: MQTTErrorCode) -> None:
        """Under self._lock: remember a publish paho refused, for the retry thread."""
        self.failed_publishes += 1
        if retain:
            self._dirty.add(topic)
        else:
            self._backlog.append((topic, data))
        now = self._clock()
        if now - self._logged_at.get("failed publish", -FOREIGN_LOG_S) >= FOREIGN_LOG_S:
            self._logged_at["failed publish"] = now
            log.warning(
                "publish to %s not taken by the MQTT client (%s): sent again when the broker "
                "has room (%d failed so far)",
                topic,
                paho.error_string(rc),
                self.failed_publishes,
            )

    def _retry_failed(self) -> None:
        """Rule 13's thread: never paho's (it holds paho's mutex in callbacks)."""
        while True:
            self._retry.wait()
            self._retry.clear()
            if self._stopping:
                return
            with self._lock:
                if not self.connected.is_set():
                    continue  # the connect sends everything
                dirty, self._dirty = self._dirty, set()
                for topic in dirty:
                    held = self._retained.get(topic)
                    if held is not None:
                        self._send(self._client, topic, held[0], held[1], retain=True)
                backlog = list(self._backlog)
                self._backlog.clear()
                for topic, event in backlog:
                    self._send(self._client, topic, event, 1, retain=False)

    def _deny(self, topic: str, what: str, reason: str) -> None:
        with self._ids_lock:
            if topic in self._denied:
                return
            self._denied.add(topic)
            problem = f"the MQTT broker does not let the bridge {what} {topic}: {reason}"
            self.problems.append(problem)
        log.error("%s (check the broker's ACL for user %r)", problem, self._settings.username)
        if self._on_denied is not None:
            # never on paho's thread: it holds paho's own mutex here, and the report publishes
            # (self._lock, then paho's mutex: another thread may hold them the other way round)
            args = (topic, problem)
            threading.Thread(target=self._on_denied, args=args, daemon=True).start()

    def _on_connect_fail(self, client: paho.Client, userdata: Any) -> None:
        if self._stopping:
            return
        # paho calls this inside its `except OSError`: the exception says why
        exc = sys.exc_info()[1]
        self._guard.connect_failed()
        if isinstance(exc, ssl.SSLError):
            text = f"TLS handshake with the MQTT broker failed: {exc} (check tls.ca_file/cert_file)"
        else:
            text = f"cannot connect to the MQTT broker: {exc or 'unknown error'}"
        if text != self._last_refusal:
            log.error("%s (retrying with back-off)", text)
            self._last_refusal = text

    def _on_disconnect(
        self,
        client: paho.Client,
        userdata: Any,
        flags: paho.DisconnectFlags,
        reason_code: ReasonCode,
        properties: Properties | None,
    ) -> None:
        was = self._up
        self._up = self._subscribed = False
        self.connected.clear()
        self._looking = None  # one assignment: no lock (paho may hold its own here)
        if was and self._on_connection_lost is not None:  # nothing more of it will come
            self._on_connection_lost()
        if not was or self._stopping:
            return
        ending = ending_of(flags, reason_code)
        guard = self._guard
        fight = guard.disconnected(self._clock(), ending)
        if not fight:
            if self._slowed:  # a connection lasted: paho's own delays again
                client.reconnect_delay_set(*self._reconnect_s)
                self._slowed = False
            log.warning("disconnected from MQTT broker (%s); reconnecting", reason_code)
            return
        # paho forgets its back-off on every accepted connection and starts again at the minimum
        # delay: the minimum is what slows a fight down (rule 7)
        client.reconnect_delay_set(guard.backoff_s, max(guard.backoff_s, self._reconnect_s[1]))
        self._slowed = True
        if guard.reported:
            log.debug(
                "MQTT connection closed again (%s); next try in %d s", reason_code, guard.backoff_s
            )
            return
        guard.reported = True
        cid = self._settings.effective_client_id()
        if ending == "taken over":
            what = f"MQTT session taken over: another client connected with client id {cid!r}"
        else:
            what = (
                f"the MQTT broker dropped the connection {FLAP_COUNT} times in a row without a "
                f"reason, taking new ones at once: most likely another client connects with "
                f"client id {cid!r}"
            )
        log.error(
            "%s. Two processes with one client id (two hosts sharing one configuration, a stale "
            "container still running) keep kicking each other off: stop the other one or give "
            "each its own mqtt.client_id. Backing off: %d s, doubling up to %d s between "
            "reconnects, until a connection lasts %d s",
            what,
            TAKEOVER_FIRST_S,
            TAKEOVER_MAX_S,
            STABLE_S,
        )

    def _on_message(self, client: paho.Client, userdata: Any, msg: paho.MQTTMessage) -> None:
        try:
            if self._claim is not None and self._look_saw(msg.topic, bytes(msg.payload)):
                return
            if self._owned and self._foreign(msg.topic, bytes(msg.payload)):
                return
            self._handler(msg.topic, bytes(msg.payload), bool(msg.retain))
        except Exception:  # a handler bug must not kill paho's network thread
            log.exception("error handling MQTT message on %s", msg.topic)

    def _look_saw(self, topic: str, payload: bytes) -> bool:
        """Rule 14: True if the message belongs to the first look (handled here)."""
        claim = self._claim
        assert claim is not None
        if topic == claim.hello_topic:
            with self._lock:
                n = self._looking
            if n is not None and payload == f"{claim.me.id} {n}".encode():
                self._end_look(n)
            return True  # another bridge's hello, or one of ours come late
        if topic not in (claim.info_topic, self._will_topic):
            return False
        with self._lock:
            if self._looking is None:
                return False
            self._seen[topic] = payload
        return True

    def _foreign(self, topic: str, payload: bytes) -> bool:
        """Rule 10: True if ``topic`` is one of ours (handled here, whatever its value)."""
        with self._lock:
            held = self._retained.get(topic)
            if held is None or not self._is_owned(topic):
                return False
            if self._stopping:
                return True  # shutting down (or refused): our offline values, or not ours
            echoes = self._echoes.get(topic)
            if echoes and payload in echoes:  # MQTT 3.1.1: ours, coming back in order
                while echoes.popleft() != payload:
                    pass
                return True
            if payload == held[0]:
                return True
            claim = self._claim
            if claim is not None and topic == claim.info_topic:
                other = Instance.parse(payload)  # claim rule 4
                if other is not None and yields_to(claim.me, other):
                    self.refused = refusal(claim.base_topic, other, live_since_look=True)
                    self._stopping = True  # nothing more goes out, nothing is put back
                    self.connected.clear()  # (every publish checks it, under this lock)
            quiet = self.refused is None and self._put_back(topic, held)
        if self.refused is not None:
            self._refuse()
        elif quiet:
            log.warning(
                "another client published %r on %s, a topic of the bridge's own: put back %r "
                "(a second bridge on this base topic, or a flow publishing where it should not?)",
                payload[:40],
                topic,
                held[0][:40],
            )
        return True

    def _put_back(self, topic: str, held: tuple[bytes, int]) -> bool:
        """Rule 10, under the lock: our value again (at most once per FOREIGN_FIX_S); whether
        to say so in the log."""
        now = self._clock()
        if now - self._fixed_at.get(topic, -FOREIGN_FIX_S) < FOREIGN_FIX_S:
            return False
        self._fixed_at[topic] = now
        if self.connected.is_set():
            self._expect_echo(topic, held[0])
            self._send(self._client, topic, held[0], held[1], retain=True)
        # what the broker held from before we connected (our own last will, a value of a
        # run that ended) is replaced without a word: only a live stranger is news
        if now - self.connected_at < SETTLE_AFTER_CONNECT_S:
            return False
        if now - self._logged_at.get(topic, -FOREIGN_LOG_S) < FOREIGN_LOG_S:
            return False
        self._logged_at[topic] = now
        return True

    def _expect_echo(self, topic: str, data: bytes) -> None:
        """Rule 10, MQTT 3.1.1 (under the lock): this comes back to us; it is ours."""
        if not self._v5 and self._owned and self._is_owned(topic):
            self._echoes.setdefault(topic, deque(maxlen=ECHOES_KEPT)).append(data)

    def _is_owned(self, topic: str) -> bool:
        return any(paho.topic_matches_sub(f, topic) for f in self._owned)


def _some(topics: list[str]) -> str:
    """Rule 15: at most CLEARS_NAMED topics, and how many more."""
    named = ", ".join(topics[:CLEARS_NAMED])
    rest = len(topics) - CLEARS_NAMED
    return f"{named} and {rest} more" if rest > 0 else named
