"""The lanes: stop, and lock, each on an MQTT connection of its own (issue 14, item 13; attack 24).

One connection delivers its messages in order: a stop published behind a flood of targets
waited until the bridge had read every one of them (100,000 targets in 10 s on 32 rotators:
stops reached their controllers 0.85 to 3.9 s late). The broker writes what a subscriber gets
on that subscriber's socket, so a second connection subscribed only to ``R/stop`` is a lane no
target is queued in; its own paho thread reads it, and the message goes to the same handler as
the main connection's (the service: the same rules for retained stops, payloads and the lock).
The lock words take a lane of their own the same way (rule 5).

Rules:
1. Subscribed to its own kind's topics only (the stop lane: the stop topics, a group's stop
   too; the lock lane: the lock topics) and the lane markers (the main connection has them,
   and its copies keep the order: lastword.py decides what each copy does, so a lane that is
   down or refused loses no stop, only speed). The stop topics are subscribed
   without the broker's replay of a retained stop (lastword.py rule 6). It publishes one
   thing only: on each connection, right behind its SUBSCRIBE, a marker that tells the main
   connection when its subscription was taken (``behind_subscribe``, lastword.py rule 17);
   no will, no state; the main connection (client.py) is the bridge's presence and carries
   every other marker.
2. Same broker settings as the main connection (credentials, TLS, protocol, clean start,
   retain-as-published, QoS 0 for commands: client.py rules 1 and 4), and the same TCP
   quick-ack (client.py rule 9): both are connection.py's Connection, which builds, connects
   and subscribes them. Under ``mqtt.protocol = "auto"`` it speaks what the main connection
   settled on (the app calls ``use_mqtt311`` before ``start``). Client id: ``lane_client_id``
   (the main id with ``rstop-``, the lock lane's ``rlock-``, for ``rotor-``, as long; an
   explicit id gets ``-stop`` or ``-lock``, shortened with a hash to 23 characters if it would
   be longer).
3. A lane the broker refuses (while the main connection is up: a client-id ACL, a connection
   limit) or a subscription it denies is an error, logged once and handed to ``on_denied``
   (the bridge's problems, B/bridge/info): stops then take the main connection only. A fight
   over its client id (another client connecting with it: an attack pass found it said
   nowhere, while stops quietly lost their connection) is logged and said on B/bridge/info
   (``on_info``) once an episode, and unsaid once a connection lasts STABLE_S (a review). Its
   other disconnects are logged at debug level (the main connection says the same). It
   judges a takeover as connection.py rule 7 does (an attempt the broker never answered, given
   up by the lane's own client, is no refusal: connection.py rule 6, said by the main
   connection), counting only connections that were
   accepted, and backs off for one TAKEOVER_FIRST_S at most (``FIGHT_BACKOFF_MAX_S``: a
   crash-looping broker can look the same, and stops must come soon after it is back); any
   other way, it tries again on connection.py rule 6's back-off for a connection that carries
   stops (``RECONNECT_MAX_S``: 2 s at most, so a STOP sent 2 s after a broker's return is
   heard). Its session stays clean (rule 2; docs/reliability.md, Limits, says why a kept one
   is not asked for).
4. The lane goes first (``first``, the main connection's ``before_message``): the main
   connection's thread calls it before each message it hands on, and while the lane's socket
   has bytes waiting it sleeps in steps of YIELD_S, up to YIELD_MAX_S in all, so the lane's
   thread takes the interpreter lock and a core, reads its stop and carries it out. A thread
   reading a backlog of targets otherwise keeps both: the lock changes hands within the switch
   interval only when the thread asking for it runs, and on a busy machine the kernel ran the
   reader instead, for up to ~90 ms. One poll of a socket per message (about a microsecond); a
   backlog is read no slower when no stop comes. The wait is a courtesy, never a condition:
   past YIELD_MAX_S the main connection goes on, and past YIELD_BUDGET_S in a second (a flood
   of anything on the stop and lock topics keeps the lane's socket busy) it waits no more in
   that second; what comes on the lane keeps its order rules (lastword.py) whenever it is read.
   Each lane is waited for in turn, within its own bounds.
5. Two lanes, one class: ``kind`` "stop" or "lock" (lastword.py rule 16). One connection
   delivers in order, so a lane that carried both kinds kept a STOP behind every lock word
   published before it: a client republishing ``R/lock OFF`` in a loop kept a DCU-1's STOP
   off the wire past the whole turn (attack 24). Each lane carries one kind, and nothing a
   neighbour can flood sits ahead of a stop but a stop; a flood of lock words delays only the
   lock words behind it. The cost: one connection more (client id ``rlock-...``).
"""

from __future__ import annotations

import hashlib
import logging
import threading
import time
from collections.abc import Callable
from typing import Unpack

import paho.mqtt.client as paho
from paho.mqtt.reasoncodes import ReasonCode

from bridge.interfaces.fdwait import readable
from bridge.interfaces.mqtt.connection import (
    STABLE_S,
    STOP_KEEPALIVE_S,
    STOP_RECONNECT_MAX_S,
    TAKEOVER_FIRST_S,
    Connection,
    Ending,
    MessageHandler,
    Options,
    takeover_message,
)
from bridge.settings import MqttSettings

log = logging.getLogger(__name__)

YIELD_S = 0.0002  # rule 4: one step of the main connection's wait
YIELD_MAX_S = 0.02  # rule 4: at most this long per message
YIELD_BUDGET_S = 0.1  # rule 4: ... and this long in all per second (a flood on the lane)


def lane_client_id(settings: MqttSettings, kind: str = "stop") -> str:
    """Rule 2: as short as the main id where that one is generated (23 characters at most);
    ``kind``: the lane's ("stop", "lock": rule 5), four letters either way."""
    main = settings.effective_client_id()
    if settings.client_id is None and main.startswith("rotor-"):
        return f"r{kind}-" + main[len("rotor-") :]
    lane = f"{main}-{kind}"
    if len(lane) <= 23:
        return lane
    digest = hashlib.sha256(main.encode()).hexdigest()[:6]
    return f"{main[:11]}-{digest}-{kind}"


class StopLane(Connection):
    FIGHT_BACKOFF_MAX_S = TAKEOVER_FIRST_S  # rule 3
    RECONNECT_MAX_S = STOP_RECONNECT_MAX_S  # connection.py rule 6: back soon after a broker
    KEEPALIVE_MAX_S = STOP_KEEPALIVE_S  # connection.py rule 6: a dead path found soon

    def __init__(
        self,
        settings: MqttSettings,
        *,
        subscriptions: list[str],
        on_message: MessageHandler,
        on_denied: Callable[[str, str], None] | None = None,
        on_info: Callable[[str, bool], None] | None = None,
        kind: str = "stop",
        **options: Unpack[Options],
    ) -> None:
        self.kind = kind  # rule 5: "stop" or "lock"
        self.name = f"{kind} lane"  # (what the log and B/bridge/info call it)
        self.client_id = lane_client_id(settings, kind)
        super().__init__(
            settings, self.client_id, subscriptions=subscriptions, on_message=on_message, **options
        )
        self._auto = False  # the main connection settles the protocol (use_mqtt311, rule 2)
        self._on_denied = on_denied
        self._stopped = False  # stop() was called: start() does nothing any more
        self._started = False
        self._start_lock = threading.Lock()
        self._reported: set[str] = set()
        self._on_info = on_info
        self._fight: str | None = None  # rule 3: a fight over the client id said, till calm
        self._opens = 0  # connections opened so far (rule 3: the one a calm check is for)
        self.clock: Callable[[], float] = time.monotonic  # rule 4 (the tests give their own)
        self.sleep: Callable[[float], None] = time.sleep
        self._window_t = -1e18  # rule 4: the second the main connection's waits are counted in
        self._yielded = 0.0

    def first(self) -> None:
        """Rule 4, on the main connection's thread: while the lane has bytes to read, wait."""
        sock = self._client.socket()
        if sock is None or not self.connected.is_set():
            return
        t0 = self.clock()
        if t0 - self._window_t >= 1.0:
            self._window_t, self._yielded = t0, 0.0
        # time that passed, not steps asked for: on a busy machine a step of YIELD_S can take
        # tens of milliseconds before this thread has the interpreter lock back
        left = min(YIELD_MAX_S, YIELD_BUDGET_S - self._yielded)
        t = t0
        try:
            while t - t0 < left and readable((sock.fileno(),), 0):
                self.sleep(YIELD_S)  # the interpreter lock and a core for the lane's thread
                t = self.clock()
        except (OSError, ValueError):  # closed meanwhile: the lane's own thread notices
            pass
        self._yielded += t - t0

    def start(self) -> None:
        """Once; never after ``stop()`` (a shutdown under way: the lane stays down)."""
        with self._start_lock:
            if self._stopped or self._started:
                return
            self._started = True
            self._connect()

    def stop(self) -> None:
        with self._start_lock:
            self._stopped = True
            started = self._started
        if started:
            self._disconnect()

    # -- connection.py's hooks (the lane's own paho thread) ---------------------------------
    def _refused(self, reason: str) -> None:
        self._report(f"the MQTT broker refused the {self.name}'s connection: {reason}")

    def _failed(self) -> None:
        pass  # the main connection says why the broker cannot be reached

    def _accepted(self) -> None:
        pass

    def _opened(self, client: paho.Client) -> None:
        self.connected.set()
        log.debug("%s connected as %s", self.name, self.client_id)
        self._opens += 1
        if self._fight is not None:  # rule 3: unsaid once a connection lasts STABLE_S
            calm = threading.Timer(STABLE_S, self._calm, args=(self._opens,))
            calm.daemon = True
            calm.start()

    def _calm(self, opened: int) -> None:
        """Rule 3: the connection opened ``opened``-th is still up STABLE_S later: the fight
        over the client id is over."""
        fight = self._fight
        if fight is None or opened != self._opens or not self.connected.is_set():
            return
        self._fight = None
        log.info("%s: its client id %r is its own again", self.name, self.client_id)
        if self._on_info is not None:
            self._on_info(fight, False)

    def _denied(self, topic: str, reason: str) -> None:
        self._report(
            f"the MQTT broker does not let the bridge subscribe to {topic}: {reason}", topic
        )

    def _closed_early(self, reason: str) -> None:
        pass  # _closed reports it, as the lane's own problem

    def _unanswered(self, waited: str) -> None:
        log.debug(
            "%s: the MQTT broker did not answer %s", self.name, waited
        )  # the main one says it

    def _closed(self, was_up: bool, reason_code: ReasonCode) -> bool:
        if not was_up and not self._gave_up:  # closed before it was accepted (a connection
            # limit): no takeover evidence; one the broker never answered is no refusal of the
            # lane's (connection.py rule 6: the main connection says it)
            self._report(f"the MQTT broker closed the {self.name}'s connection: {reason_code}")
        return was_up

    def _ended(self, reason_code: ReasonCode, ending: Ending, fight: bool) -> None:
        log.debug("%s disconnected (%s)", self.name, reason_code)  # the main connection says why
        if fight and self._fight is None:  # rule 3: a fight over its client id is its own (an
            said = takeover_message(self.client_id, ending, TAKEOVER_FIRST_S)  # attack pass:
            self._fight = f"{self.name}: {said}"  # nothing said it)
            log.error("%s", self._fight)
            if self._on_info is not None:
                self._on_info(self._fight, True)

    def _report(self, problem: str, topic: str = "") -> None:
        """Rule 3: once per problem, an error, handed on (never on paho's thread)."""
        if problem in self._reported:
            return
        self._reported.add(problem)
        log.error(
            "%s (%s words still come on the main connection, without the lane's speed; check "
            "the broker's ACL and connection limits for client id %r)",
            problem,
            self.kind,
            self.client_id,
        )
        if self._on_denied is not None:
            threading.Thread(target=self._on_denied, args=(topic, problem), daemon=True).start()
