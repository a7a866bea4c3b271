"""What becomes of a publish: paho's refusals, the broker's refusals, and what is sent again.
The main connection (client.py) publishes through ``send`` and keeps the retained cache; this
module keeps the message ids in flight, the denied topics, the retained topics to send again
and the backlog of events, and runs the thread that retries them.

Locks: the client's lock is held around ``send``, ``take_*`` and ``hold_event`` (one order of
publishes); ``_ids_lock`` alone guards the message ids, because paho calls ``on_publish`` holding
its own mutex and a thread that publishes holds the client's lock and then waits for paho's: the
client's lock taken in ``on_publish`` would deadlock (docs/architecture.md).

Rules (numbered as the bridge's MQTT rules; client.py keeps the index of all of them):
11. What the broker refuses is said: a subscription it denies (SUBACK, via connection.py; an
   optional one only in the log, rule 17) or a QoS 1 publish it will not take (PUBACK, MQTT 5;
   0x87 "not authorised" from an ACL; any other reason, a quota, loses that message and
   denies nothing: logged as a warning at most once in FAILED_LOG_S) is logged as an error
   once per topic (until the broker is seen to take it: ``allow``, a probe back, or, for a
   publish it refused, a PUBACK that took a QoS 1 message on it, said through ``allowed``),
   naming the topic, kept in ``problems`` and handed to ``on_denied`` (the app shows it in
   the rotator's status and on ``B/bridge/info``), never on paho's thread. A denied QoS 0
   publish (state) gets no answer from any broker: the bridge cannot see it.
13. A publish paho does not take (its QoS 1 queue full: at most MAX_QUEUED messages, so a
   stalled broker cannot grow the bridge's memory without bound; no connection) is not taken
   for sent: a retained topic is marked dirty and sent again as soon as the broker
   acknowledges anything (room again) and on every connect, its newest value or, for a
   deletion the client still owes (``MqttClient._clearing``: 2,000 removed rotators' state,
   the first look's deletions past MAX_QUEUED, stayed on the broker for good, an attack
   pass), the deletion; a round of those stops at the first paho refuses again (the rest
   wait for the next room, not tried under the client's lock to fail); an event waits in the bounded
   backlog (EVENT_BACKLOG, the oldest dropped first). Said once a minute at most
   (FAILED_LOG_S), with the count so far.
"""

from __future__ import annotations

import logging
import threading
import time
from collections import deque
from collections.abc import Callable

import paho.mqtt.client as paho
from paho.mqtt.enums import MQTTErrorCode
from paho.mqtt.reasoncodes import ReasonCode

log = logging.getLogger(__name__)

EVENT_BACKLOG = 50  # rule 13
MAX_QUEUED = 4096  # rule 13: QoS 1 messages paho holds for the broker, at most
NOT_AUTHORIZED = 0x87  # rule 11: the one PUBACK reason that says the topic is denied
MAX_UNACKED = 10_000  # rule 11: QoS 1 message ids remembered, at most
FAILED_LOG_S = 60.0  # rule 13
_SUCCESS = MQTTErrorCode.MQTT_ERR_SUCCESS  # (looked up once: every publish compares with it)


class Delivery:
    def __init__(
        self,
        client: paho.Client,
        *,
        username: str | None,
        report: Callable[[str, str], None],
        clock: Callable[[], float],
        allowed: Callable[[str], None] | None = None,
    ) -> None:
        """``report(topic, problem)``: rule 11's hand-off, called on a thread of its own;
        ``allowed(topic)``: a denied topic the broker took again (a PUBACK), the same way."""
        self._allowed = allowed
        self._client = client
        # paho_client.py rule 9, where the client has it (our own connections' do)
        self._publish_qos0: Callable[[str, bytes, bool], MQTTErrorCode] | None = getattr(
            client, "publish_qos0", None
        )
        self._username = username
        self._report = report
        self._clock = clock
        self._pub_topics: dict[int, str] = {}  # a QoS 1 publish's message id -> its topic
        self._acked_early: dict[int, ReasonCode] = {}  # acknowledged before its id was noted
        self._ids_lock = threading.Lock()
        self._denied: dict[str, str] = {}  # rule 11: each denied topic reported once, its problem
        # rule 11: the denials a PUBACK said (a refused publish), which a PUBACK that takes a
        # message on the topic ends; a refused SUBSCRIBE or a probe not read back it does not
        # (a review: a publish taken says nothing of reading)
        self._refused_by_puback: set[str] = set()
        self.problems: list[str] = []  # rule 11, for the bridge's own diagnostics
        self._dirty: set[str] = set()  # rule 13: retained topics whose last publish failed
        self._backlog: deque[tuple[str, str | bytes]] = deque(maxlen=EVENT_BACKLOG)
        self._retry = threading.Event()  # rule 13: set when the broker has room again
        self._failed_said_at = -FAILED_LOG_S
        self.failed_publishes = 0
        self._refused_said_at = -FAILED_LOG_S  # rule 11: a refusal that denies nothing
        self.refused_publishes = 0

    # -- under the client's lock ----------------------------------------------------------
    def send(self, topic: str, data: str | bytes, qos: int, *, retain: bool) -> bool:
        """paho's publish; a QoS 1 message's id kept to match its acknowledgement (rule 11).
        Whether paho took it (rule 13: else it is marked for the retry)."""
        fast = self._publish_qos0
        if not qos and fast is not None and isinstance(data, bytes):
            rc = fast(topic, data, retain)
            if rc != _SUCCESS:
                self._failed(topic, data, retain, rc)
                return False
            return True
        info = self._client.publish(topic, data, qos=qos, retain=retain)
        if info.rc != _SUCCESS and not (
            qos and info.rc == MQTTErrorCode.MQTT_ERR_NO_CONN  # paho keeps it for the connect
        ):
            self._failed(topic, data, retain, info.rc)
            return False
        if not qos:
            return True
        with self._ids_lock:
            early = self._acked_early.pop(info.mid, None)
            if early is None and len(self._pub_topics) < MAX_UNACKED:
                self._pub_topics[info.mid] = topic
        if early is not None:  # refused before we noted its id
            self._refused(topic, early)
        return True

    def hold_event(self, topic: str, payload: str | bytes) -> None:
        """Rule 13: an event while disconnected waits in the backlog."""
        self._backlog.append((topic, payload))

    def take_backlog(self) -> list[tuple[str, str | bytes]]:
        backlog = list(self._backlog)
        self._backlog.clear()
        return backlog

    def keep_dirty(self, topics: set[str]) -> None:
        """Rule 13: retained topics not tried this round (paho's queue full again): the smaller
        set joined into the larger (a retry round sends a few of thousands)."""
        if len(topics) > len(self._dirty):
            topics.update(self._dirty)
            self._dirty = topics
        else:
            self._dirty.update(topics)

    def take_dirty(self) -> set[str]:
        dirty, self._dirty = self._dirty, set()
        return dirty

    def new_connection(self) -> None:
        """The acknowledgements of the old connection never come."""
        with self._ids_lock:
            self._pub_topics.clear()
            self._acked_early.clear()

    def _failed(self, topic: str, data: str | bytes, retain: bool, rc: MQTTErrorCode) -> None:
        """Rule 13: remember a publish paho refused, for the retry thread."""
        self.failed_publishes += 1
        if retain:
            self._dirty.add(topic)
        else:
            self._backlog.append((topic, data))
        now = self._clock()
        if now - self._failed_said_at >= FAILED_LOG_S:
            self._failed_said_at = now
            log.warning(
                "publish to %s not taken by the MQTT client (%s): sent again when the broker "
                "has room (%d failed so far)",
                topic,
                paho.error_string(rc),
                self.failed_publishes,
            )

    # -- paho's thread ----------------------------------------------------------------------
    def on_publish(
        self,
        client: paho.Client,
        userdata: object,
        mid: int,
        reason_code: ReasonCode,
        properties: object,
    ) -> None:
        """paho's callback."""
        with self._ids_lock:  # never the client's lock: paho holds its own mutex here
            topic = self._pub_topics.pop(mid, None)
            if topic is None and reason_code.is_failure and len(self._acked_early) < MAX_UNACKED:
                self._acked_early[mid] = reason_code  # send has not noted the id yet
                # (only a refusal: paho calls this for every QoS 0 message too, with success)
        if topic is not None and reason_code.is_failure:
            self._refused(topic, reason_code)
        elif topic is not None and topic in self._refused_by_puback and self.allow(topic):
            if self._allowed is not None:  # (rule 11: a publish refused before is taken: its
                threading.Thread(target=self._allowed, args=(topic,), daemon=True).start()
        if self._dirty or self._backlog:  # rule 13: the broker took one, so there is room again
            self._retry.set()  # (read without the lock: a stale answer costs one wake-up)

    def _refused(self, topic: str, reason: ReasonCode) -> None:
        """Rule 11: a PUBACK that refused a message: the topic is denied on the ACL's answer
        alone (0x87); any other (0x97 a quota, 0x80 a busy broker) lost this message and says
        nothing of the topic (an attack pass: two 0x97 on the resent markers were taken for
        the ACL denying them, lastword.py rule 15)."""
        if reason.value == NOT_AUTHORIZED:
            self.deny(topic, "publish to", str(reason))
            return
        self.refused_publishes += 1  # (said once in FAILED_LOG_S, as rule 13's: a quota
        now = self._clock()  # refuses every message while it lasts; a review)
        if now - self._refused_said_at >= FAILED_LOG_S:
            self._refused_said_at = now
            log.warning(
                "the MQTT broker refused a message on %s: %s (%d refused so far)",
                topic,
                reason,
                self.refused_publishes,
            )

    def deny(self, topic: str, what: str, reason: str) -> None:
        """Rule 11: once per topic."""
        with self._ids_lock:
            if topic in self._denied:
                return
            problem = f"the MQTT broker does not let the bridge {what} {topic}: {reason}"
            self._denied[topic] = problem
            if what == "publish to" and len(self._refused_by_puback) < MAX_UNACKED:
                self._refused_by_puback.add(topic)  # (a PUBACK that takes one ends this one)
            self.problems.append(problem)
        log.error("%s (check the broker's ACL for user %r)", problem, self._username)
        # never on paho's thread: it holds paho's own mutex here, and the report publishes
        # (the client's lock, then paho's mutex: another thread may hold them the other way)
        threading.Thread(target=self._report, args=(topic, problem), daemon=True).start()

    def denied(self, topic: str) -> bool:
        """Rule 11: whether ``topic`` is denied now (the last verdict on it)."""
        with self._ids_lock:
            return topic in self._denied

    def allow(self, topic: str) -> bool:
        """Rule 11: the broker was seen to take ``topic`` after all (the ACL changed): its
        problem is gone, and a new refusal is said again. True if it had been denied."""
        with self._ids_lock:
            problem = self._denied.pop(topic, None)
            self._refused_by_puback.discard(topic)
            if problem is not None and problem in self.problems:
                self.problems.remove(problem)
        if problem is not None:
            log.warning("the MQTT broker lets the bridge use %s again", topic)
        return problem is not None

    # -- the retry thread ---------------------------------------------------------------------
    def start_retrying(self, resend: Callable[[], None], stopping: Callable[[], bool]) -> None:
        """Rule 13's thread, never paho's (it holds paho's mutex in callbacks): ``resend``
        (which takes the client's lock) each time the broker has room again."""

        def run() -> None:
            while True:
                self._retry.wait()
                self._retry.clear()
                if stopping():
                    return
                resend()

        threading.Thread(target=run, name="mqtt-retry", daemon=True).start()

    def wake(self) -> None:
        """Ends the retry thread once ``stopping()`` says so."""
        self._retry.set()


def wait_published(
    infos: list[paho.MQTTMessageInfo], timeout_s: float, connected: threading.Event
) -> None:
    """Until the broker has them all, ``timeout_s`` at most for all together, and no longer
    once the connection is gone (their acknowledgements will never come)."""
    deadline = time.monotonic() + timeout_s
    for info in infos:
        try:  # paho raises for a message it never queued (the connection had just gone)
            while not info.is_published() and connected.is_set():
                left = deadline - time.monotonic()
                if left <= 0:
                    return
                info.wait_for_publish(min(left, 0.1))
        except (RuntimeError, ValueError):
            continue
