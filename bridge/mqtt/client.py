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
   reason and retried, never a crash.
"""

from __future__ import annotations

import logging
import ssl
import sys
import threading
from collections import deque
from collections.abc import Callable

import paho.mqtt.client as paho
from paho.mqtt.enums import CallbackAPIVersion
from paho.mqtt.subscribeoptions import SubscribeOptions

from bridge.settings import MqttSettings

log = logging.getLogger(__name__)

MessageHandler = Callable[[str, bytes, bool], None]
EVENT_BACKLOG = 50
COMMAND_QOS = 0


class MqttClient:
    def __init__(
        self,
        settings: MqttSettings,
        *,
        will_topic: str,
        subscriptions: list[str],
        on_message: MessageHandler,
        on_connect: Callable[[], None] | None = None,
        reconnect_min_s: int = 1,
        reconnect_max_s: int = 30,
    ) -> None:
        self._settings = settings
        self._will_topic = will_topic
        self._subscriptions = subscriptions
        self._handler = on_message
        self._on_connect_hook = on_connect
        self._retained: dict[str, bytes] = {}
        self._backlog: deque[tuple[str, str | bytes]] = deque(maxlen=EVENT_BACKLOG)
        self._lock = threading.Lock()
        self.connected = threading.Event()
        self._last_refusal: str | None = None
        self._stopping = False
        self._v5 = settings.protocol == "5"
        c = paho.Client(
            callback_api_version=CallbackAPIVersion.VERSION2,
            client_id=settings.effective_client_id(),
            protocol=paho.MQTTv5 if self._v5 else paho.MQTTv311,
            **({} if self._v5 else {"clean_session": True}),
        )
        c.will_set(will_topic, b"offline", qos=1, retain=True)
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
        c.reconnect_delay_set(reconnect_min_s, reconnect_max_s)
        c.on_connect = self._on_connect
        c.on_connect_fail = self._on_connect_fail
        c.on_disconnect = self._on_disconnect
        c.on_message = self._on_message
        self._client = c
        self._retained[will_topic] = b"online"

    def add_subscriptions(self, topics: list[str]) -> None:
        """More topic filters (features such as discovery); before ``start()``."""
        self._subscriptions = [*self._subscriptions, *topics]

    # -- lifecycle --------------------------------------------------------------------------
    def start(self) -> None:
        s = self._settings
        log.info("connecting to MQTT broker %s:%d as %s", s.host, s.port, s.effective_client_id())
        if self._v5:
            self._client.connect_async(s.host, s.port, keepalive=s.keepalive_s, clean_start=True)
        else:
            self._client.connect_async(s.host, s.port, keepalive=s.keepalive_s)
        self._client.loop_start()

    def stop(self, timeout_s: float = 2.0) -> None:
        """Publish offline, flush, disconnect."""
        self._stopping = True
        if self.connected.is_set():
            info = self._client.publish(self._will_topic, b"offline", qos=1, retain=True)
            try:
                info.wait_for_publish(timeout_s)
            except (RuntimeError, ValueError):
                pass
        self._client.disconnect()
        self._client.loop_stop()

    # -- publishing (any thread) ----------------------------------------------------------
    def publish_retained(
        self, topic: str, payload: str | bytes, *, only_if_changed: bool = True
    ) -> None:
        data = payload.encode() if isinstance(payload, str) else payload
        # cache, connected check and publish under one lock, so a connect that re-publishes the
        # cache cannot overtake a newer value with an older one (paho's publish only enqueues)
        with self._lock:
            if only_if_changed and self._retained.get(topic) == data:
                return
            self._retained[topic] = data
            if self.connected.is_set():
                self._client.publish(topic, data, qos=1, retain=True)

    def clear_retained(self, topic: str) -> None:
        """Delete a retained message from the broker (empty retained payload)."""
        with self._lock:
            self._retained.pop(topic, None)
            if self.connected.is_set():
                self._client.publish(topic, b"", qos=1, retain=True)

    def republish_retained(self, skip_prefix: str | None = None) -> None:
        """Send the retained messages we own again (Home Assistant came back, for example)."""
        with self._lock:
            if not self.connected.is_set():
                return
            for topic, data in self._retained.items():
                if skip_prefix is None or not topic.startswith(skip_prefix):
                    self._client.publish(topic, data, qos=1, retain=True)

    def publish_event(self, topic: str, payload: str | bytes) -> None:
        with self._lock:
            if self.connected.is_set():
                self._client.publish(topic, payload, qos=1, retain=False)
            else:
                self._backlog.append((topic, payload))

    def publish_offline_now(self, topics: list[str], timeout_s: float = 1.0) -> None:
        """At shutdown: mark these retained topics offline and wait until the broker has them."""
        infos = []
        for topic in topics:
            with self._lock:
                self._retained[topic] = b"offline"
            if self.connected.is_set():
                infos.append(self._client.publish(topic, b"offline", qos=1, retain=True))
        for info in infos:
            try:
                info.wait_for_publish(timeout_s)
            except (RuntimeError, ValueError):
                pass

    # -- paho callbacks (paho's thread) ---------------------------------------------------
    def _on_connect(self, client, userdata, flags, reason_code, properties) -> None:  # noqa: ANN001
        if reason_code.is_failure:
            text = str(reason_code)
            if text != self._last_refusal:
                log.error("MQTT broker refused the connection: %s (retrying)", text)
                self._last_refusal = text
            return
        self._last_refusal = None
        log.info("connected to MQTT broker")
        # subscribe before saying `online`: the broker handles our packets in order, so a
        # client that sends a command the moment it sees `online` is already heard
        if self._v5:
            opts = SubscribeOptions(qos=COMMAND_QOS, retainAsPublished=True)
            client.subscribe([(topic, opts) for topic in self._subscriptions])
        else:
            client.subscribe([(topic, COMMAND_QOS) for topic in self._subscriptions])
        client.publish(self._will_topic, b"online", qos=1, retain=True)
        with self._lock:
            for topic, data in self._retained.items():
                if topic != self._will_topic:
                    client.publish(topic, data, qos=1, retain=True)
            for topic, event in self._backlog:
                client.publish(topic, event, qos=1, retain=False)
            self._backlog.clear()
            self.connected.set()
        if self._on_connect_hook is not None:
            self._on_connect_hook()

    def _on_connect_fail(self, client, userdata) -> None:  # noqa: ANN001
        # paho calls this inside its `except OSError`: the exception says why
        exc = sys.exc_info()[1]
        if isinstance(exc, ssl.SSLError):
            text = f"TLS handshake with the MQTT broker failed: {exc} (check tls.ca_file/cert_file)"
        else:
            text = f"cannot connect to the MQTT broker: {exc or 'unknown error'}"
        if text != self._last_refusal:
            log.error("%s (retrying with back-off)", text)
            self._last_refusal = text

    def _on_disconnect(self, client, userdata, flags, reason_code, properties) -> None:  # noqa: ANN001
        was = self.connected.is_set()
        self.connected.clear()
        if was and not self._stopping:
            log.warning("disconnected from MQTT broker (%s); reconnecting", reason_code)

    def _on_message(self, client, userdata, msg) -> None:  # noqa: ANN001
        try:
            self._handler(msg.topic, bytes(msg.payload), bool(msg.retain))
        except Exception:  # a handler bug must not kill paho's network thread
            log.exception("error handling MQTT message on %s", msg.topic)
