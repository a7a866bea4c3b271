"""The stop lane: stop and lock on an MQTT connection of their own (issue 14, item 13).

One connection delivers its messages in order: a stop published behind a flood of targets
waited until the bridge had read every one of them (100,000 targets in 10 s on 32 rotators:
stops reached their controllers 0.85 to 3.9 s late). The broker writes what a subscriber gets
on that subscriber's socket, so a second connection subscribed only to ``R/stop`` and
``R/lock`` is a lane no target is queued in; its own paho thread reads it, and the message goes
to the same handler as the main connection's (the service: the same rules for retained stops,
payloads and the lock).

Rules:
1. Subscribed to the stop and lock topics only (the main connection has them too, and its
   copies keep the order: lastword.py decides what each copy does, so a lane that is down or
   refused loses no stop, only speed). The stop topics are subscribed without the broker's
   replay of a retained stop (lastword.py rule 6). It publishes nothing: no will, no state;
   the main connection (client.py) is the bridge's presence and carries its markers.
2. Same broker settings as the main connection (credentials, TLS, protocol, clean start,
   retain-as-published, QoS 0 for commands: client.py rules 1 and 4), and the same TCP
   quick-ack (client.py rule 9). Client id: ``lane_client_id`` (the main id with ``rstop-``
   for ``rotor-``, as long; an explicit id gets ``-stop``, shortened with a hash to 23
   characters if it would be longer).
3. A lane the broker refuses (while the main connection is up: a client-id ACL, a connection
   limit) or a subscription it denies is an error, logged once and handed to ``on_denied``
   (the bridge's problems, B/bridge/info): stops then take the main connection only. Its own
   disconnects are logged at debug level (the main connection says the same). Its takeover
   back-off is client.py rule 7's, counting only connections that were accepted.
"""

from __future__ import annotations

import hashlib
import logging
import threading
import time
from collections.abc import Callable
from typing import Any

import paho.mqtt.client as paho
from paho.mqtt.properties import Properties
from paho.mqtt.reasoncodes import ReasonCode

from bridge.mqtt.client import (
    MessageHandler,
    TakeoverGuard,
    command_filters,
    connect,
    ending_of,
    new_client,
)
from bridge.settings import MqttSettings

log = logging.getLogger(__name__)


def lane_client_id(settings: MqttSettings) -> str:
    """Rule 2: as short as the main id where that one is generated (23 characters at most)."""
    main = settings.effective_client_id()
    if settings.client_id is None and main.startswith("rotor-"):
        return "rstop-" + main[len("rotor-") :]
    lane = main + "-stop"
    if len(lane) <= 23:
        return lane
    digest = hashlib.sha256(main.encode()).hexdigest()[:6]
    return f"{main[:11]}-{digest}-stop"


class StopLane:
    def __init__(
        self,
        settings: MqttSettings,
        *,
        subscriptions: list[str],
        on_message: MessageHandler,
        on_denied: Callable[[str, str], None] | None = None,
        on_new_connection: Callable[[], None] | None = None,
        no_replay: list[str] | None = None,
        reconnect_min_s: int = 1,
        reconnect_max_s: int = 30,
    ) -> None:
        self._settings = settings
        self._subscriptions = subscriptions
        self._handler = on_message
        self._on_denied = on_denied
        self._on_new_connection = on_new_connection
        self._no_replay = frozenset(no_replay or ())
        self._ended = False  # stop() was called: start() does nothing any more
        self._started = False
        self._start_lock = threading.Lock()
        self._v5 = settings.protocol == "5"
        self._guard = TakeoverGuard()
        self._slowed = False
        self._up = False
        self._reported: set[str] = set()
        self._reconnect_s = (reconnect_min_s, reconnect_max_s)
        self._sub_ids: dict[int, list[str]] = {}
        self.connected = threading.Event()
        self.client_id = lane_client_id(settings)
        c = new_client(settings, self.client_id)
        c.reconnect_delay_set(reconnect_min_s, reconnect_max_s)
        c.on_connect = self._on_connect
        c.on_connect_fail = self._on_connect_fail
        c.on_disconnect = self._on_disconnect
        c.on_message = self._on_message
        c.on_subscribe = self._on_subscribe
        self._client = c

    def start(self) -> None:
        """Once; never after ``stop()`` (a shutdown under way: the lane stays down)."""
        with self._start_lock:
            if self._ended or self._started:
                return
            self._started = True
            connect(self._client, self._settings)

    def stop(self) -> None:
        with self._start_lock:
            self._ended = True
            started = self._started
        if started:
            self._client.disconnect()
            self._client.loop_stop()

    # -- paho callbacks (the lane's own paho thread) ----------------------------------------
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
            self._report(f"the MQTT broker refused the stop lane's connection: {reason_code}")
            return
        self._up = True
        self._guard.connected(time.monotonic())
        if self._on_new_connection is not None:  # before any message of the new connection
            self._on_new_connection()
        subs = command_filters(self._subscriptions, self._no_replay, self._v5)
        if subs:
            _rc, mid = client.subscribe(subs)
            if mid is not None:
                self._sub_ids[mid] = [t for t, _ in subs]
        self.connected.set()
        log.debug("stop lane connected as %s", self.client_id)

    def _on_subscribe(
        self,
        client: paho.Client,
        userdata: Any,
        mid: int,
        reason_codes: list[ReasonCode],
        properties: Properties | None,
    ) -> None:
        for topic, code in zip(self._sub_ids.pop(mid, []), reason_codes, strict=False):
            if code.is_failure:
                self._report(
                    f"the MQTT broker does not let the bridge subscribe to {topic}: {code}", topic
                )

    def _report(self, problem: str, topic: str = "") -> None:
        """Rule 3: once per problem, an error, handed on (never on paho's thread)."""
        if problem in self._reported:
            return
        self._reported.add(problem)
        log.error(
            "%s (stops still come on the main connection, without the lane's speed; check the "
            "broker's ACL and connection limits for client id %r)",
            problem,
            self.client_id,
        )
        if self._on_denied is not None:
            threading.Thread(target=self._on_denied, args=(topic, problem), daemon=True).start()

    def _on_connect_fail(self, client: paho.Client, userdata: Any) -> None:
        self._guard.connect_failed()

    def _on_disconnect(
        self,
        client: paho.Client,
        userdata: Any,
        flags: paho.DisconnectFlags,
        reason_code: ReasonCode,
        properties: Properties | None,
    ) -> None:
        self.connected.clear()
        was, self._up = self._up, False
        if not was:  # closed before it was accepted (a connection limit): no takeover evidence
            self._report(f"the MQTT broker closed the stop lane's connection: {reason_code}")
            return
        if self._guard.disconnected(time.monotonic(), ending_of(flags, reason_code)):
            backoff = self._guard.backoff_s  # client.py rule 7: the main one says why
            client.reconnect_delay_set(backoff, max(backoff, self._reconnect_s[1]))
            self._slowed = True
        elif self._slowed:
            client.reconnect_delay_set(*self._reconnect_s)
            self._slowed = False
        log.debug("stop lane disconnected (%s)", reason_code)

    def _on_message(self, client: paho.Client, userdata: Any, msg: paho.MQTTMessage) -> None:
        try:
            self._handler(msg.topic, bytes(msg.payload), bool(msg.retain))
        except Exception:  # a handler bug must not kill paho's network thread
            log.exception("error handling MQTT message on %s", msg.topic)
