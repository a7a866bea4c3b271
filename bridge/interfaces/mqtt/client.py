"""The main broker connection: the bridge's presence (online/offline, its last will), the
retained state it owns and re-publishes, its events, and the first look of every connect.
connection.py builds, connects and subscribes paho's client (for the stop lane too, lane.py);
owned.py judges the bridge's own topics; delivery.py follows each publish; look.py keeps the
first look's books and claim.py gives its verdicts.

The bridge's MQTT rules, numbered once for all of mqtt/ (code and docs cite "client.py rule N"),
each written out in the module that keeps it:
- connection.py: 1 protocol, clean start, retain-as-published (for commands); 4 commands at
  QoS 0; 5 short callbacks; 6 paho's reconnect loop, a refusal said once; 7 one client id, one
  connection (the takeover back-off); 9 TCP quick-ack after every read; 17 an optional
  subscription's denial said once, no problem; 18 the largest packet the broker may send,
  said in CONNECT.
- owned.py: 10 the bridge's retained topics are its own (here: subscribed, our value put back).
- delivery.py: 11 what the broker refuses is said; 13 what paho does not take goes again.
- look.py: 14 one live bridge per base topic, the first look (here: the look is started,
  only halts are taken while it runs, ``gated``; what an earlier run left on the witnessed
  topics handed to ``witness``'s hook once it ends, before ``online``, with those it could
  not read: a probe of those it heard nothing on, then a second hello; it times out after
  LOOK_TIMEOUT_S in which nothing retained came from the broker, LOOK_MAX_S at most: a broker
  still handing over what it held answers (a live message does not: a review, a tracker's
  targets kept a look whose hello was denied open for a minute), and a slow machine reading
  a backlog of tens of thousands of retained topics took more than 5 s, its look timed out
  and was judged on half of them, the bridge's own ``offline`` of its last run then said as
  another client's. Under MQTT 5 a filter subscribed with retain-as-published (connection.py
  rule 1: the commands, and stale.py's filters, ``B/+/availability`` among them) hands a live
  message published retained on with the flag set, as the broker's replay (review 33: a
  tracker set to retain kept the look open a minute again): there the flag counts only until
  the SUBACK of the look's SUBSCRIBE, the connect's last (``_broker_held``: the broker sends
  a subscription's retained messages as it answers it, mosquitto 2.0 right after its SUBACK
  and before the next, however many; a broker that sends them later has them count on the
  bridge's own topics and the states it reads, subscribed without it, alone); 15 deletions
  said in a few lines.
- here:
2. The last will marks the bridge offline (retained, QoS 1); ``online`` is published on every
   connect, ``offline`` on a clean shutdown. While connected (after the first look, not when
   refused) the heartbeat (``heartbeat``: its topic) carries the wall clock every HEARTBEAT_S,
   QoS 0, not retained (heartbeat.py rule 1), from paho's own loop (Client.tick): a bridge whose
   broker was restored from its file says ``online`` for ever, a heartbeat only while it lives.
   Under MQTT 5 each beat names this process (``station``: the user property of heartbeat.py
   rule 7); under MQTT 3.1.1 it cannot.
3. On every connect: subscribe again and re-publish every retained message we own (the broker
   may have restarted without persistence and lost them). Retained messages are kept in a
   cache; while disconnected they only update the cache; events wait (rule 13), but for an
   error (``publish_event(..., lapses=True)``: ``R/error``, ``G/error``) while the broker is
   away (a connection was lost, none accepted since): it is dropped, counted and said once on
   the return (it was logged when it happened), since by then it may be untrue (an attack pass:
   "... does not exist" came out on the return of a port plugged back meanwhile, its rotator
   online). One from before the first connection, or while a connection's look runs, waits.
8. Retained state goes out at QoS 0 (STATE_QOS): the newest value supersedes every older one,
   so an acknowledgement buys nothing, while QoS 1 costs a PUBACK per message (half of the
   bridge's CPU with 32 rotators turning, benchmarks/) and lets paho re-send an old value over
   the fresher state re-published from the cache. Discovery configs, the bridge's
   online/offline and error events stay QoS 1; a rotator's availability is state.
16. The broker is asked whether the bridge can read back its markers (lastword.py rule 7), on
   every connect, with no clock: right before the first look's hello (rule 14), a probe goes
   to ``B/bridge/fence`` (QoS 1: under MQTT 5 a publish the ACL refuses gets its PUBACK
   reason, rule 11); the broker keeps one order for one client's messages of one QoS (the
   hello goes at QoS 1 too: MQTT promises no order between QoS levels, and aedes delivers a
   QoS 0 message before the QoS 1 one sent right before it), so if the hello comes back and
   the probe has not, the broker drops it (mosquitto 2.0 grants the subscription and drops
   the messages, without a word under MQTT 3.1.1, and for a topic denied to read under MQTT 5
   too). That is said as rule 11 says, naming the topic, from the first connection on. Both
   go out through delivery.py's ``send``, so a PUBACK that refuses either (0x87) is its own
   topic's, said and known (``markers_refused``) as any refused publish (review 35: the
   hello went out with paho's own publish, its refusal tied to no topic, so a look never
   knew both marker topics refused and the markers were never asked again, lastword.py rule
   15; and the refusal was kept under its message id, for the publish given that id hours
   later to be said refused). It is judged again on every connect: a probe that comes back
   clears the problem (``on_allowed``, never on paho's thread). Each verdict is reported on
   a thread of its own, so one may come late: under ``_fence_lock`` a report is made only if
   its verdict is still the last one (an older connection's "allowed" never clears the
   problem after a newer one's "denied", nor the
   other way round). The markers come back on the hello topic too (lastword.py rule 7), so
   whether they can come back at all (``on_markers``) is another verdict: yes as soon as this
   connection's hello or probe comes back (on paho's thread, in the connection's order); no
   only when the fence topic is denied and this connection's hello has not come back within
   the look's time (whichever of the two is known last says it, under ``_fence_lock``; a new
   connection judges anew). That hello coming back later still says yes (and, its probe not
   back before it, that the fence topic is denied, as in time: under MQTT 3.1.1 nothing else
   says so, and B/bridge/info never named it for that connection), and once back it
   (or the probe) is the last word for its connection, the look's timer firing beside it or
   not (an attack pass: a broker slow to send its retained messages, each before the hello,
   and the fence denied: the markers stayed off for the connection and rotctld's S fenced
   nothing; the timer, firing as the hello or the probe came, said them lost after it said
   them back).
12. Nothing from before a disconnect lands after the state of the new connection: paho sends
   the QoS 1 messages it still held only after ``on_connect`` has returned, behind the cache
   re-published there (a config changed while the broker stalled came back older, and
   stayed). So ``on_connect`` takes them from paho: one whose retained topic is in the cache
   is superseded by the value just sent; the others (events, deletions) go again, after it.
19. The main connection reads its own heartbeats back (heartbeat.py rule 11, ``Echo``): it
   subscribes to the heartbeat topic (QoS 0, like the beats), takes each beat it sent
   (``_tick``) as it comes back (``_intercepted``, known by its exact payload, this process's
   clock to the millisecond when it was sent; another's is dropped, as is a retained one), and
   its network thread tells the echo what it saw (``_Ears``: paho_client.py rule 11, the quiet
   an empty poll proves, and each read, judged before its messages are handled).
   ``broker_late`` says whether the broker held the bridge up and no beat sent after that is
   back yet (service.py rule 12 asks, on paho's thread, as the message is handled; any thread
   may: the echo is kept under ``_echo_lock``, which is taken with no other lock held inside
   it). A new connection starts clean. After a hold, the next beat goes at once. Being late,
   and no longer, is said on ``B/bridge/info`` (``on_late``, on a thread of its own; the last
   verdict is the one said, under ``_late_lock``). A connection none of whose beats came back
   through UNREAD_S of quiet seen with one out (an ACL that denies reading the topic:
   mosquitto grants the subscription and drops the beats) is never called late, and that is
   said as rule 11 says, once, naming the topic; a beat that comes back clears it (as rule
   16's probe). A backlog, however long (a start-up reading tens of thousands of retained
   topics, a burst of targets), sees no quiet and is never taken for that (review 57: the
   first design said it after 10 s of beats not back, whatever held them). It costs one
   message read every HEARTBEAT_S, and a clock reading and the echo's lock at each round of
   the network thread.

Locks: ``_lock`` orders the cache and every publish of it (a connect that re-publishes the
cache cannot overtake a newer value with an older one; paho's publish only enqueues). paho
calls back holding its own mutex, and a thread that publishes holds ``_lock``, then waits for
paho's: so ``on_publish`` never takes ``_lock`` (delivery.py has a lock of its own), and what a
callback hands on that publishes (a denied topic, the refusal) goes on a thread of its own
(docs/architecture.md).
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable, Iterable
from dataclasses import replace
from typing import Any, Unpack

import paho.mqtt.client as paho
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.properties import Properties
from paho.mqtt.reasoncodes import ReasonCode
from paho.mqtt.subscribeoptions import SubscribeOptions

from bridge.interfaces.mqtt.claim import Claim
from bridge.interfaces.mqtt.connection import MQTT311_LOSES, Connection, MessageHandler, Options
from bridge.interfaces.mqtt.delivery import MAX_QUEUED, Delivery, wait_published
from bridge.interfaces.mqtt.heartbeat import (
    QUIET_S,
    Beat,
    Echo,
    beat_payload,
    beat_properties,
)
from bridge.interfaces.mqtt.limiter import EventLimiter
from bridge.interfaces.mqtt.look import (
    CLEARS_SAID_AT_ONCE,
    FirstLook,
    Outcome,
    say_clear,
    say_clears,
)
from bridge.interfaces.mqtt.owned import FOREIGN_LOG_S, OwnedTopics, matcher
from bridge.interfaces.mqtt.owned import SETTLE_AFTER_CONNECT_S as SETTLE_AFTER_CONNECT_S
from bridge.settings import MqttSettings

log = logging.getLogger(__name__)

# rule 14: the witnesses' hook: what the broker held, and the witnesses it would not let the
# bridge read -> the topics it took (or must not write over), and whether each holds
Heard = Callable[[dict[str, bytes], frozenset[str]], dict[str, Callable[[], bool]]]

STATE_QOS = 0  # rule 8
# rule 14 (MQTT 5): the look's own filter beside each witness (its level ``+``), its probe heard
# there (the owned topics are no-local, and mosquitto 2.0 keeps a filter's no-local when it is
# subscribed again); no retained value sent there (the owned filter had it)
_HEAR_PROBE = SubscribeOptions(qos=0, noLocal=False, retainAsPublished=False, retainHandling=2)
# rule 10 (MQTT 3.1.1): a broker shutting down sends the bridge its own last will and closes the
# connection right after; an ``offline`` the connection outlives by this long was a stranger's
WILL_OUTLIVED_S = 1.0
LOOK_TIMEOUT_S = 5.0  # rule 14: nothing from the broker this long ends the look...
LOOK_MAX_S = 60.0  # ... and this long whatever comes (a flood of messages ends it all the same)


class _Ears:
    """Rule 19: what the network thread saw (paho_client.py rule 11), into the echo under its
    lock (paho's thread)."""

    def __init__(self, echo: Echo, lock: threading.Lock, clock: Callable[[], float]) -> None:
        self._echo, self._lock, self.clock = echo, lock, clock

    def quiet(self, until: float) -> None:
        with self._lock:
            self._echo.quiet(until)

    def reading(self) -> None:
        now = self.clock()
        with self._lock:
            self._echo.reading(now)

    def read(self) -> None:
        now = self.clock()
        with self._lock:
            self._echo.read(now)


class MqttClient(Connection):
    def __init__(
        self,
        settings: MqttSettings,
        *,
        will_topic: str,
        subscriptions: list[str],
        on_message: MessageHandler,
        on_connect: Callable[[], None] | None = None,
        on_connection_lost: Callable[[], None] | None = None,
        on_denied: Callable[[str, str], None] | None = None,
        on_allowed: Callable[[str], None] | None = None,
        on_markers: Callable[[bool], None] | None = None,
        claim: Claim | None = None,
        on_refused: Callable[[str], None] | None = None,
        fence_topic: str | None = None,
        clock: Callable[[], float] = time.monotonic,
        heartbeat: str | None = None,
        wall: Callable[[], float] = time.time,
        station: str | None = None,
        on_late: Callable[[str, bool], None] | None = None,
        **options: Unpack[Options],
    ) -> None:
        super().__init__(
            settings,
            settings.effective_client_id(),
            subscriptions=[*subscriptions, *([heartbeat] if heartbeat is not None else [])],
            on_message=on_message,
            clock=clock,
            **options,
        )
        self._will_topic = will_topic
        self._on_connect_hook = on_connect
        self._on_connection_lost = on_connection_lost
        self._on_denied = on_denied
        self._on_allowed = on_allowed  # rule 16: the fence topic works again
        self._on_markers = on_markers  # rule 16: whether the markers can come back at all
        self._retained: dict[str, tuple[bytes, int]] = {will_topic: (b"online", 1)}  # rule 3
        self._lock = threading.Lock()
        c = self._client
        c.will_set(will_topic, b"offline", qos=1, retain=True)  # rule 2
        c.max_queued_messages_set(MAX_QUEUED)  # rule 13
        self._delivery = Delivery(
            c,
            username=settings.username,
            report=self._report_denied,
            clock=clock,
            allowed=self._report_allowed,  # (its own thread: rule 16's words)
        )
        c.on_publish = self._delivery.on_publish
        self._owned = OwnedTopics(clock, hears_own=not self._v5)  # rule 10
        self._owned.will = (will_topic, b"offline")
        self._clears_said = EventLimiter(clock, CLEARS_SAID_AT_ONCE, 1.0 / FOREIGN_LOG_S)
        self._look = FirstLook(claim, will_topic) if claim is not None else None  # rule 14
        # rule 14: deletions a look asked for that are spared at its end (stale.py rule 3)
        self.spare: Callable[[str], bool] | None = None
        # rule 10: owned topics whose held value a reader also judges first (stale.py rule 4)
        self._peeks: dict[str, Callable[[str, bytes], object]] = {}
        self._on_heard: Heard | None = None  # rule 14: the witnesses' hook
        self._on_refused = on_refused
        self._held: list[paho.MQTTMessage] = []  # rule 12: taken from paho, sent at the open
        self._lapsed = 0  # rule 3: errors dropped while the broker was away, said on the return
        self._fence_topic = fence_topic  # rule 16
        self._probe: bytes | None = None  # rule 16: the probe out, None once it came back
        self._fence_lock = threading.Lock()  # rule 16: the fence's reports, one at a time
        self._look_lost = False  # rule 16: this connection's look timed out
        self._look_heard = 0.0  # rule 14: when the broker last sent anything (monotonic)
        self._replays = 0  # rule 14: the messages the broker handed over as held, so far
        # rule 14: ``_replays`` when the look's last own live message came back (the fence's
        # probe, then each hello): one more since, and the broker still hands over what it held
        self._replays_at: int | None = None
        self._look_sub: int | None = None  # rule 14: the look's SUBSCRIBE, until its SUBACK
        self._look_only: frozenset[str] | None = None  # claim rule 5: read for the look alone
        self._reading: list[str] = []  # claim rule 5: a look's vouch reads, until it ends
        # rule 14: the next round's hello, sent once the SUBACK of its vouch reads is in (the
        # SUBSCRIBE's message id, the look's number)
        self._hello_due: tuple[int, int, bytes] | None = None
        self._as_published: Callable[[str], bool] | None = None  # rule 14 (``_broker_held``)
        self._hello_out: bytes | None = None  # rule 16: this connection's hello
        self._probing: list[str] = []  # rule 14: the filters the look hears its probes on (MQTT 5)
        self._hello_back = False  # rule 16: it, or the probe, came back (in time or later)
        self.refused: str | None = None
        self.yielded = False  # claim rule 4: refused while running (not at its first look)
        self._ran = False  # a look has let this bridge run
        # rule 14: a witnessed value the hook took, left as the broker holds it: while it holds,
        # an older value (a status from before its lock was saved) is not put over it
        self._left: dict[str, tuple[bytes, Callable[[], bool]]] = {}
        # rule 14: the owned topics this connection's look deleted and nobody published on since
        self._deleted: set[str] = set()
        # delivery.py rule 13: the deletions this connection owes (the look's, clear_retained's):
        # one paho's full queue refused is sent again
        self._clearing: set[str] = set()
        self._heartbeat = heartbeat  # rule 2
        self._will_heard: tuple[float, bytes] | None = None  # rule 10: when, and what
        self._beat = Beat()
        self._wall = wall
        self._station = station  # rule 2: the process the beats name (heartbeat.py rule 7)
        self._echo = Echo()  # rule 19 (under ``_echo_lock``)
        self._echo_lock = threading.Lock()  # rule 19: paho's thread, and ``broker_late``'s
        if heartbeat is not None:  # rule 19: what the network thread saw, into the echo
            self._client.hearing = _Ears(self._echo, self._echo_lock, clock)
        self._on_late = on_late  # rule 19: said on B/bridge/info while it lasts
        self._late_lock = threading.Lock()  # rule 19: one report at a time, the last verdict
        self._late_now = False  # rule 19: the verdict (paho's thread writes it)
        self._late_said: str | None = None  # rule 19: as said (under ``_late_lock``)

    @property
    def problems(self) -> list[str]:
        """Rule 11: what the broker refused, for the bridge's own diagnostics."""
        return self._delivery.problems

    @property
    def failed_publishes(self) -> int:
        """Rule 13: publishes paho did not take, so far."""
        return self._delivery.failed_publishes

    @property
    def connected_at(self) -> float:
        """The clock at the last accepted connection (rule 10)."""
        return self._owned.connected_at

    @property
    def gated(self) -> bool:
        """Rule 14: the first look runs, or the bridge refused to run: only halts are taken."""
        return (
            self._look is not None and self._look.looking is not None
        ) or self.refused is not None

    @property
    def up(self) -> bool:
        """A connection is accepted and its command topics subscribed (its first look may
        still run): from now on a command published reaches this connection."""
        return self._up and self._subscribed

    @property
    def hears(self) -> bool:
        """A connection is accepted and its command topics' SUBSCRIBE has gone (its SUBACK
        may not have come): a command published once the broker has taken that SUBSCRIBE
        reaches this connection, after whatever it will read that was published before it;
        a marker it publishes from now on comes back after those (the stop lane's holds wait
        for it: halts.py)."""
        return self._up and self._subscribing

    def broker_late(self) -> float | None:
        """Rule 19: how long the broker held the bridge up (the quiet seen), while it is late
        now; None when it is not (or when no beat of this connection came back). Any thread."""
        with self._echo_lock:
            return self._echo.late(self._clock())

    def add_subscriptions(self, topics: list[str]) -> None:
        """More topic filters (features such as discovery); before ``start()``."""
        self._subscriptions = [*self._subscriptions, *topics]

    def witness(self, topics: set[str], on_heard: Heard) -> None:
        """Rule 14: what the broker held on ``topics`` from an earlier run (none: empty),
        handed to ``on_heard`` once the process's first look lets the bridge run, before its
        own values and ``online`` go out (paho's thread or the look's timer, the lock not
        held); before ``start()``. It returns the topics whose value it took as its own, each
        with whether it still holds: those the open leaves as the broker holds them (their
        cached values, older, are not put over them, nor a value published while they hold; the
        cache takes the broker's, so the next change goes out)."""
        if self._look is not None:
            self._look.witness(topics)
            self._on_heard = on_heard

    def watch_owned(self, filters: list[str]) -> None:
        """Rule 10: the filters of the retained topics the bridge publishes; before ``start()``."""
        self._owned.watch(filters)

    # -- lifecycle --------------------------------------------------------------------------
    def start(self) -> None:
        s = self._settings
        log.info("connecting to MQTT broker %s:%d as %s", s.host, s.port, s.effective_client_id())
        if not self._v5:
            log.warning("MQTT 3.1.1 (mqtt.protocol): %s", MQTT311_LOSES)
        self._connect()
        self._delivery.start_retrying(self._resend, lambda: self._stopping)

    def stop(self, timeout_s: float = 2.0) -> None:
        """Publish offline, flush, disconnect."""
        self._stopping = True  # rule 10 stands down: our own offline is about to come back
        self._delivery.wake()  # ends the retry thread
        with self._lock:
            self._retained[self._will_topic] = (b"offline", 1)
        if self.connected.is_set() and self.refused is None:  # refused: it is another's
            self._client.drop_out_messages()  # a full queue would refuse the offline (rule 13)
            info = self._client.publish(self._will_topic, b"offline", qos=1, retain=True)
            wait_published([info], timeout_s, self.connected)
        self._disconnect()

    def shutting_down(self) -> None:
        """The bridge is stopping: a broker that goes away now (a Ctrl-C reaches the demo's
        private broker too) is no news, and is not reconnected to with a warning."""
        self._stopping = True

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
        with self._lock:  # cache, connected check and publish: one step (see Locks)
            left = self._left.get(topic)
            if left is not None and data != left[0] and left[1]():
                return  # rule 14: the broker's value holds; this one is older
            self._left.pop(topic, None)  # (caught up with it, or it holds no more)
            held = self._retained.get(topic)
            if only_if_changed and held is not None and held[0] == data:
                return
            self._retained[topic] = (data, qos)
            if data:
                self._deleted.discard(topic)  # rule 14 (a review: MQTT 5 never hears it back)
            elif topic in self._deleted:
                return  # rule 14: the look deleted it, and it is still empty on the broker
            if self.connected.is_set():
                owned = self._owned
                if owned.hears_own or owned.owing:  # rule 10 (MQTT 5: none back, no-local)
                    owned.sent(topic, data)
                self._delivery.send(topic, data, qos, retain=True)

    def clear_retained(self, topic: str) -> None:
        """Delete a retained config from the broker (empty retained payload); said (rule 15)."""
        with self._lock:
            self._retained.pop(topic, None)
            if self._look is None:
                if self.connected.is_set():  # (delivery.py rule 13: sent again if refused)
                    self._clearing.add(topic)
                    self._delivery.send(topic, b"", 1, retain=True)
                cleared = True
            elif self._look.defer_clear(topic):  # rule 14: held by the broker before we came
                return
            else:  # published while we run: another client's (claim rule 3)
                cleared = False
        say_clear(self._clears_said, topic, cleared=cleared)

    def republish_retained(self, skip_prefix: str | None = None) -> None:
        """Send the retained messages we own again (Home Assistant came back, for example)."""
        with self._lock:
            if not self.connected.is_set():
                return
            for topic, (data, qos) in self._retained.items():
                if skip_prefix is None or not topic.startswith(skip_prefix):
                    self._owned.sent(topic, data)
                    self._delivery.send(topic, data, qos, retain=True)

    def publish_event(self, topic: str, payload: str | bytes, *, lapses: bool = False) -> None:
        """``lapses``: an error, dropped while the broker is away (rule 3)."""
        with self._lock:
            if self.connected.is_set():
                self._delivery.send(topic, payload, 1, retain=False)
            elif lapses and self._accepted_once and not self._up:
                self._lapsed += 1  # rule 3
            else:
                self._delivery.hold_event(topic, payload)  # rule 3

    def publish_marker(self, topic: str, payload: str) -> None:
        """A message to the bridge itself (lastword.py): QoS 0, now or never (no cache, no
        backlog: one that cannot go now is void with the connection), during the first look
        too. paho's publish is thread-safe; the stop lane's thread calls this."""
        if self._up:
            self._client.publish(topic, payload.encode(), qos=0)

    def publish_marker_confirmed(self, topic: str, payload: str) -> None:
        """A marker sent again (lastword.py rule 15) at QoS 1: under MQTT 5 the broker's
        PUBACK says whether its ACL refuses the topic now (rule 16: an ACL changed under a
        live connection, which no probe at connect sees); ``markers_refused`` reads it."""
        if self._up:
            self._delivery.send(topic, payload.encode(), 1, retain=False)

    def markers_refused(self, topics: tuple[str, ...]) -> bool:
        """lastword.py rule 15: whether the broker refused each of ``topics`` (a marker's
        PUBACK, or the probe) since they were last seen allowed."""
        return all(self._delivery.denied(topic) for topic in topics)

    def publish_offline_now(
        self, topics: list[str], last: dict[str, str] | None = None, timeout_s: float = 1.0
    ) -> None:
        """At shutdown: mark these retained topics offline and wait until the broker has them;
        ``last``: retained values to leave first (each stamp saying its bridge stopped,
        claim.py rule 5)."""
        infos = []
        if self.refused is not None:
            return  # rule 14: these topics are another bridge's
        said = [(t, v.encode()) for t, v in (last or {}).items()]
        for topic, payload in [*said, *((t, b"offline") for t in topics)]:
            with self._lock:
                self._retained[topic] = (payload, 1)
            if self.connected.is_set():
                infos.append(self._client.publish(topic, payload, qos=1, retain=True))
        wait_published(infos, timeout_s, self.connected)

    def _resend(self) -> None:
        """Rule 13, on delivery.py's retry thread: what paho did not take, again."""
        with self._lock:
            if not self.connected.is_set():
                return  # the connect sends everything
            dirty = self._delivery.take_dirty()
            while dirty:
                topic = dirty.pop()
                held = self._retained.get(topic)
                if held is not None:
                    sent = self._delivery.send(topic, held[0], held[1], retain=True)
                elif topic in self._clearing:  # a deletion the full queue refused
                    sent = self._delivery.send(topic, b"", 1, retain=True)
                else:
                    continue
                if not sent:  # the queue is full again (it is marked again): the rest wait
                    self._delivery.keep_dirty(dirty)  # for the next room
                    return
            for topic, event in self._delivery.take_backlog():
                self._delivery.send(topic, event, 1, retain=False)

    # -- connection.py's hooks (paho's thread) ----------------------------------------------
    def _fell_back(self, what: str) -> None:
        super()._fell_back(what)  # said, with MQTT311_LOSES
        self._owned.hears_own = True  # rule 10: our own messages come back from now on

    def _filters(self) -> list[tuple[str, Any]]:
        """Rule 10: a filter the owned-topic watch subscribes is left to it (stale.py's
        ``B/availability`` and ``B/option/+/state`` with one rotator on the base topic):
        mosquitto keeps the options a filter was first subscribed with, so the command
        subscription's options held (retain-as-published, no no-local), and a live stray passed
        for a value the broker held, never put back twice in 2 s (an attack pass). Its messages
        reach the handler all the same: they are routed by topic."""
        owned = set(self._owned.filters)
        return [(f, opts) for f, opts in super()._filters() if f not in owned]

    def _opened(self, client: paho.Client) -> None:
        """Commands subscribed before ``online`` (the broker handles our packets in order: a
        client that sends a command the moment it sees ``online`` is already heard)."""
        self._subscribe(client, self._owned.subscriptions())  # rule 10
        held = client.drop_out_messages()  # rule 12: paho would send them after this returns
        with self._lock:
            self._delivery.new_connection()
            self._held.extend(held)  # a look that never ended leaves its own
            with self._echo_lock:
                self._echo.connected()  # rule 19
            self._owned.connected()
            look = self._look
            self._look_lost = False  # rule 16: judged anew
            self._hello_out, self._hello_back = None, False
            self._hello_due = None  # (rule 14: an earlier connection's round is over)
            self._reading = []  # (claim rule 5: a clean start: none subscribed now)
            if look is not None:  # rule 14: look first
                hello = self._hello_out = look.begin()
                self._as_published = None  # rule 14: this connection's (``_broker_held``)
                subs: list[tuple[str, int | SubscribeOptions]] = [(look.claim.hello_topic, 0)]
                # (rule 14, MQTT 5: the owned topics are subscribed no-local, so a witness's
                # probe would never come back there; heard on a filter of the look's, until it
                # ends)
                wide = sorted({t.rpartition("/")[0] + "/+" for t in look.witnessed})
                self._probing = [] if self._owned.hears_own else wide
                subs += [(t, _HEAR_PROBE) for t in self._probing]
                subs += [(t, 0) for t in self._posts_only(look)]  # claim rule 5
                self._look_sub = self._subscribe(client, subs)
                if self._fence_topic is not None:  # rule 16: the probe, then the hello
                    self._probe = b"probe " + hello
                    self._delivery.send(self._fence_topic, self._probe, 1, retain=False)
                # rule 16: at QoS 1 as the probe, and through ``send`` as it goes: its PUBACK
                # is the hello topic's (review 35: paho's own publish left a refusal, 0x87,
                # tied to no topic, so the look never knew the hello refused, and kept it
                # under its message id for the next publish given that id to claim)
                self._delivery.send(look.claim.hello_topic, hello, 1, retain=False)
                self._look_heard = 0.0
                self._replays_at = None
                self._arm_look(look.looking, time.monotonic(), LOOK_TIMEOUT_S)
                return
            self._open(None)
        if self._on_connect_hook is not None:
            self._on_connect_hook()

    def _denied(self, topic: str, reason: str) -> None:
        self._delivery.deny(topic, "subscribe to", reason)

    def _closed(self, was_up: bool, reason_code: ReasonCode) -> bool:
        self._will_heard = None  # rule 10: the connection ended, so that ``offline`` was ours
        if self._look is not None:
            self._look.connection_ended()  # two assignments: no lock (paho may hold its own)
        if was_up and self._on_connection_lost is not None:  # nothing more of it will come
            self._on_connection_lost()
        return was_up and not self._stopping

    def _tick(self) -> None:
        """Rule 2: the heartbeat, when due (paho's thread, after each round of its loop); rule
        10: an ``offline`` on the will topic that the connection outlived was a stranger's.
        Called again within a second (None: paho_client.py rule 2): the beat, its echo's
        lateness (rule 19) and the will's verdict are on the clock."""
        heard = self._will_heard
        if heard is not None and self._clock() - heard[0] >= WILL_OUTLIVED_S:
            self._will_heard = None
            self._say_foreign(self._will_topic, heard[1], b"online")
        self._put_back_owed()
        topic = self._heartbeat
        if topic is None or not self.connected.is_set() or self.refused is not None:
            return
        now = self._clock()
        echo = self._echo
        with self._echo_lock:  # (rule 19: uncontended but for a test that asks)
            due = self._beat.due(now) or echo.returning  # (rule 19: at once after a late one)
            payload = beat_payload(self._wall()).encode() if due else b""
            if due:
                echo.sent(payload, now)  # rule 19 (before it can come back)
            late, unread = echo.late(now) is not None, echo.unread(now)
        if due:
            props = None
            if self._station is not None and self._v5:  # (3.1.1 has no properties)
                props = Properties(PacketTypes.PUBLISH)  # type: ignore[no-untyped-call]
                props.UserProperty = beat_properties(self._station)
            self._client.publish(topic, payload, qos=0, properties=props)
        if late != self._late_now:  # rule 19: said while it lasts
            self._late_now = late
            threading.Thread(target=self._say_late, daemon=True).start()
        if unread and not self._delivery.denied(topic):
            self._delivery.deny(
                topic,
                "read back what it publishes on",
                "none of the heartbeats this connection published there came back (the "
                "broker's ACL denies reading it?): a move the broker holds up (a broker that "
                "stalls) is then not known late, and is carried out when it comes",
            )

    def _say_late(self) -> None:
        """Rule 19 (its own thread): the last verdict on the broker's lateness, said."""
        with self._late_lock:
            late, said = self._late_now, self._late_said
            if late == (said is not None) or self._on_late is None:
                return
            if late:
                self._late_said = (
                    f"the MQTT broker holds up what the bridge publishes (a heartbeat on "
                    f"{self._heartbeat} out through {QUIET_S:g} s in which nothing came from "
                    "it): until one sent after that comes back, MQTT moves are refused (a "
                    "stamped one too); stops and locks go through"
                )
                log.warning("%s", self._late_said)
                self._on_late(self._late_said, True)
            else:
                self._late_said = None
                log.info(
                    "the MQTT broker is quick again: a heartbeat sent after it held the "
                    "bridge up came back"
                )
                assert said is not None
                self._on_late(said, False)

    def _intercepted(self, topic: str, payload: bytes, retained: bool = False) -> bool:
        if topic == self._heartbeat:  # rule 19: ours back (another's, a retained one: dropped)
            if not retained:
                with self._echo_lock:
                    ours = self._echo.back(payload, self._clock())
                if ours:
                    self._fence_back(topic)  # (a denial said before is over)
            return True
        if topic == self._fence_topic and payload.startswith(b"probe "):
            if payload == self._probe:  # rule 16: back before the hello
                self._probe = None
                self._replays_at = self._replays  # (rule 14: the broker's replays since?)
                self._markers_back()
                self._fence_back(topic)
            return True  # (one of an earlier connection's, or another bridge's)
        if self._look is not None and not payload and not retained:
            with self._lock:  # rule 14: a witness's probe back (it can be read)
                if self._look.probe_back(topic, payload, retained):
                    return True
        if self._look is not None:
            if retained and self._broker_held(topic):  # rule 14: the broker hands over what
                self._look_heard = time.monotonic()  # it held (a tracker's target does not)
                self._replays += 1
            if self._look_saw(self._look, topic, payload, retained):
                return True
        if retained and self._owned.hears_own and self._look is not None:  # rule 14: late
            late = self._look.late(topic, payload, retained)
            if late and self._on_heard is not None and self._on_heard(late, frozenset()):
                return True  # its rotator's ON goes out: the OFF the open sent is not put back
        peek = self._peeks.get(topic) if retained and payload else None
        if peek is not None:  # rule 10: judged as a value the broker held, then as ours
            peek(topic, payload)
        return bool(self._owned.filters) and self._foreign(topic, payload, live=not retained)

    def peek(self, topics: Iterable[str], on: Callable[[str, bytes], object]) -> None:
        """Rule 10: ``on`` is handed a value the broker holds on one of ``topics``, the bridge's
        own, before the owned-topic watch puts the bridge's own over it (a group's ``G/info``,
        where a rotator's ``R/info`` left retained tells a ghost rotator: stale.py rule 4; a
        review: the watch took it, and the rotator's bearing, state and lock stayed for ever)."""
        for topic in topics:
            self._peeks[topic] = on

    def _on_subscribe(
        self,
        client: paho.Client,
        userdata: Any,
        mid: int,
        reason_codes: list[ReasonCode],
        properties: Properties | None,
    ) -> None:
        if mid == self._look_sub:  # rule 14: the replays of this connect's subscriptions came
            self._look_sub = None
        super()._on_subscribe(client, userdata, mid, reason_codes, properties)
        due, look = self._hello_due, self._look
        if due is not None and due[0] == mid and look is not None:
            self._hello_due = None  # rule 14: the vouch reads' retained values go first
            if look.looking == due[1]:
                self._delivery.send(look.claim.hello_topic, due[2], 1, retain=False)

    def _broker_held(self, topic: str) -> bool:
        """Rule 14: whether a message that came retained on ``topic`` is the broker handing over
        what it held. Under MQTT 3.1.1 it is (the broker clears the flag of a live one), and
        under MQTT 5 on a topic no filter subscribed with retain-as-published reads (the
        bridge's own, a state read: the flag is cleared there too). On one that does (the
        commands, stale.py's), a live message keeps the flag it was published with: it is only
        until the SUBACK of the look's SUBSCRIBE, the connect's last, comes (the broker sends a
        subscription's retained messages as it answers it; mosquitto 2.0: each SUBACK, then
        that subscription's replay, then the next SUBACK)."""
        if not self._v5 or self._look_sub is not None:
            return True
        matches = self._as_published
        if matches is None:
            filters = self._filters()
            live = [
                f for f, o in filters if isinstance(o, SubscribeOptions) and o.retainAsPublished
            ]
            matches = self._as_published = matcher(live)
        return not matches(topic)

    def _fence_back(self, topic: str) -> None:
        """Rule 16: the probe came back; if the topic was denied before, it is not now (said on
        a thread of its own: paho's holds its mutex here, and the report publishes)."""
        if self._delivery.allow(topic) and self._on_allowed is not None:
            threading.Thread(target=self._report_allowed, args=(topic,), daemon=True).start()

    def _markers_readable(self, readable: bool) -> None:
        """Rule 16: the markers can come back (on the fence topic or the hello topic), or
        cannot (neither: the fence topic denied and this connection's hello never back)."""
        if self._on_markers is not None:
            self._on_markers(readable)

    def _report_allowed(self, topic: str) -> None:
        """Rule 16 (its own thread): said only if the topic is still allowed."""
        with self._fence_lock:
            if self._on_allowed is not None and not self._delivery.denied(topic):
                self._on_allowed(topic)

    def _report_denied(self, topic: str, problem: str) -> None:
        """Rule 11's hand-off (delivery.py calls it on a thread of its own); the fence's only
        if it is still denied (rule 16)."""
        if self._on_denied is None:
            return
        if topic != self._fence_topic:
            self._on_denied(topic, problem)
            return
        with self._fence_lock:
            if self._delivery.denied(topic):
                self._on_denied(topic, problem)
                if self._look_lost:  # rule 16: and the hello did not come back either
                    self._markers_lost()

    def _open(
        self, look: Outcome | None, taken: dict[str, Callable[[], bool]] | None = None
    ) -> None:
        """Under the lock: the state goes out (rules 3 and 12; but ``taken``, rule 14: the
        broker's value is the newer one), then the deletions a look let through (rule 14; not
        one of a topic published since it was asked), then ``connected``."""
        send = self._delivery.send
        self._delivery.take_dirty()  # every retained value goes out below
        if self._probing:  # rule 14: the probes' filters go, before anything of ours
            self._client.unsubscribe(self._probing)
            self._probing = []
        if self._reading:  # claim rule 5: the look's vouch reads too
            self._client.unsubscribe(self._reading)
            self._reading = []
        send(self._will_topic, b"online", 1, retain=True)
        heard = look.heard if look is not None and taken else None
        unread = look.unread if look is not None and taken else frozenset()
        left = set()
        for topic, holds in (taken or {}).items():
            if topic in unread and holds():  # rule 14: the broker's value, not read: nothing
                self._retained.pop(topic, None)  # goes over it while its rotator waits; the
                self._left[topic] = (b"", holds)  # next value once it does not goes out
                left.add(topic)
                continue
            # the broker's, whether or not a status was cached before (its first one may come
            # after this: a review, its OFF went out over the ON): a change goes out
            if heard is not None and topic in heard and holds():
                qos = self._retained.get(topic, (b"", STATE_QOS))[1]
                self._retained[topic] = (heard[topic], qos)
                self._left[topic] = (heard[topic], holds)
                left.add(topic)
        for topic, (data, qos) in list(self._retained.items()):
            if topic in left:
                continue
            self._owned.sent(topic, data)
            if topic != self._will_topic:
                send(topic, data, qos, retain=True)
        held, self._held = self._held, []
        for msg in held:  # rule 12 (older than the backlog's events)
            if not (msg.retain and msg.topic in self._retained):
                send(msg.topic, bytes(msg.payload), msg.qos, retain=msg.retain)
        for topic, event in self._delivery.take_backlog():
            send(topic, event, 1, retain=False)
        if self._lapsed:  # rule 3
            log.info(
                "%d error(s) from while the MQTT broker was away not published on R/error or "
                "G/error (they may no longer be true; the log has each)",
                self._lapsed,
            )
            self._lapsed = 0
        self._deleted = set()
        self._clearing = set()
        if look is not None:
            spare = self.spare  # interfaces/mqtt/stale.py rule 3: judged once all came
            # rule 14: a topic published since its deletion was asked (``clear_retained`` took
            # it out of the cache) holds the newer value: it went out above, and stays
            clears = [t for t in look.clears if t not in self._retained]
            look = replace(look, clears=[t for t in clears if spare is None or not spare(t)])
            if look.clear:
                self._clearing = set(look.clears)
                for topic in look.clears:
                    send(topic, b"", 1, retain=True)
                self._deleted = {t for t in look.clears if self._owned.owns(t)}
            say_clears(look)
        self.connected.set()

    # -- rule 14: the first look (look.py keeps its books) -----------------------------------
    def _end_look(self, n: int, timed_out: bool = False) -> None:
        look = self._look
        assert look is not None
        with self._lock:
            if look.looking != n or not self._up or self._stopping:
                return
            outcome = look.end(timed_out=timed_out)
            if outcome.refused is not None:
                self.refused = outcome.refused
                self.yielded = self._ran  # (a reconnect's look: the bridge ran: claim rule 4)
                self._stopping = True
            elif outcome.heard is None or self._on_heard is None:
                self._ran = True
                self._open(outcome)
        if self.refused is not None:
            self._refuse()
            return
        if outcome.heard is not None and self._on_heard is not None:
            # rule 14: before ``online``, so nothing that waits for it (a target sent on it)
            # finds a rotator still waiting for its lock; outside the lock (it reports)
            taken = self._on_heard(outcome.heard, outcome.unread)
            with self._lock:
                if look.looking is not None or not self._up or self._stopping:
                    return  # the connection ended meanwhile: the next one's look opens
                self._ran = True
                self._open(outcome, taken)
        if self._on_connect_hook is not None:
            self._on_connect_hook()

    def _arm_look(self, n: int | None, began: float, delay_s: float) -> None:
        timer = threading.Timer(delay_s, self._look_due, args=(n, began))
        timer.daemon = True
        timer.start()

    def _look_due(self, n: int | None, began: float) -> None:
        """Rule 14, the look's timer: it times out once nothing came from the broker for
        LOOK_TIMEOUT_S (the hello denied: the held values come at once, then silence), or
        LOOK_MAX_S after it began; else it looks again when that may be so."""
        look = self._look
        assert look is not None
        now = time.monotonic()
        with self._lock:
            if n is None or look.looking != n:
                return
        quiet_from = max(began, self._look_heard)
        left = min(quiet_from + LOOK_TIMEOUT_S, began + LOOK_MAX_S) - now
        if left > 0:
            self._arm_look(n, began, left)
            return
        self._look_timed_out(n, now - began)

    def _look_timed_out(self, n: int, waited_s: float = LOOK_TIMEOUT_S) -> None:
        look = self._look
        assert look is not None
        with self._lock:
            if look.looking != n:
                return
            self._look_lost = True  # rule 16
        if self._fence_topic is not None:
            with self._fence_lock:  # (as ``_report_denied``: one of the two sees the other)
                if self._delivery.denied(self._fence_topic):
                    self._markers_lost()
        look.say_timed_out(round(waited_s, 1))
        self._end_look(n, timed_out=True)

    def _refuse(self) -> None:
        """Never on paho's thread: the app stops the client (loop_stop joins paho's thread)."""
        message = self.refused
        assert message is not None
        log.error("%s", message)
        if self._on_refused is not None:
            threading.Thread(target=self._on_refused, args=(message,), daemon=True).start()

    def _posts_only(self, look: FirstLook) -> list[str]:
        """Claim rule 5, under the lock: the topics of the look's posts no other filter reads
        (mosquitto sends a message once per filter it matches), read for the look alone; their
        denial is no problem (rule 17)."""
        if self._look_only is None:
            read = matcher([f for f, _o in self._filters()] + list(self._owned.filters))
            above = {t for p in look.claim.posts if p.above for t in p.topics}
            posted = (t for p in look.claim.posts for t in p.topics)
            self._look_only = frozenset(t for t in posted if not read(t))
            self.optional(
                {
                    t: (
                        "a live bridge on the topic above whose rotator's controller is off is "
                        "taken for gone (interfaces/mqtt/claim.py rule 5)"
                        if t in above
                        else "another bridge whose base topic is one of this bridge's rotators' "
                        "topics is not seen there (interfaces/mqtt/claim.py rule 5)"
                    )
                    for t in self._look_only
                }
            )
        return sorted(self._look_only)

    def _look_saw(
        self, look: FirstLook, topic: str, payload: bytes, retained: bool = False
    ) -> bool:
        """Rule 14: True if the message belongs to the first look (handled here)."""
        if topic == look.claim.hello_topic and retained:  # rule 14: never a hello (nor a
            look.retained_hello(payload)  # marker: neither goes out retained); said once
            return True
        if topic == look.claim.hello_topic:
            with self._lock:
                n = look.ended_by(payload)
                again = n is not None and look.rounds > 0  # (rule 14: a later round's hello)
                # rule 14: the broker handed over what it held after the last of our own live
                # messages came back: it may still be at it (aedes), and the look asks again
                at, replaying = self._replays_at, False
                if n is not None:
                    replaying = at is not None and self._replays > at
                    self._replays_at = self._replays
                probes, reads, hello = (
                    look.next_round(replaying) if n is not None else ([], [], b"")
                )
                reads = self._reads_only(reads) if hello else []
            if n is not None:
                if not again:
                    self._markers_back()
                    self._judge_probe()
                if hello:  # rule 14: then the next round's hello ends the look, or asks again
                    for witness in probes:  # (QoS 1, as the hello after them)
                        self._delivery.send(witness, b"", 1, retain=False)
                    # claim rule 5: their retained values come before it; on the SUBACK (aedes
                    # streams a subscription's retained messages once it has sent it)
                    mid = self._subscribe(self._client, [(t, 0) for t in reads])
                    if mid is not None:
                        self._hello_due = (mid, n, hello)
                        return True
                    self._delivery.send(look.claim.hello_topic, hello, 1, retain=False)
                    return True
                self._end_look(n)
                return True
            if payload == self._hello_out:  # rule 16: back after the look's time
                self._markers_back()
                self._judge_probe()  # (its probe not back before it: the fence dropped)
                return True
            # another bridge's hello, one of ours come late, or a marker's copy (lastword.py
            # rule 7): the handler tells this process's markers from the rest
            return False
        with self._lock:
            return (
                look.saw(topic, payload)
                or topic in (self._look_only or ())
                or topic in self._reading
            )

    def _reads_only(self, reads: list[str]) -> list[str]:
        """Claim rule 5, under the lock: the round's vouch reads no other filter reads (their
        denial is no problem, rule 17), subscribed until the look ends (``_open``). One another
        filter reads is not subscribed again: its value came once, and the look kept it from
        its start, whenever it came (look.py rule 14, review 90)."""
        read = matcher([f for f, _o in self._filters()] + list(self._owned.filters))
        new = [t for t in reads if not read(t) and t not in (self._look_only or ())]
        new = [t for t in new if t not in self._reading]
        self._reading += new
        self.optional(
            {
                t: "a live bridge whose rotator on this bridge's topics has its controller off "
                "is taken for gone (interfaces/mqtt/claim.py rule 5)"
                for t in new
            }
        )
        return new

    def _markers_back(self) -> None:
        """Rule 16 (paho's thread): this connection's hello or probe is back: the markers come
        back there, the last word on them for this connection (``_markers_lost``). No lock: a
        thread that reports under ``_fence_lock`` publishes."""
        self._hello_back = True
        look = self._look
        if look is not None:  # (lastword.py rule 15: a refusal a marker's PUBACK said is over)
            self._fence_back(look.claim.hello_topic)  # (and said over: a review)
        self._markers_readable(True)

    def _markers_lost(self) -> None:
        """Rule 16, under ``_fence_lock``: the markers cannot come back, unless this
        connection's hello or probe came back (the look's timer, or the fence's denial, may be
        known as it comes: its "readable" may have gone just before this "lost", and is said
        again after it)."""
        if self._hello_back:
            return
        self._markers_readable(False)
        if self._hello_back:
            self._markers_readable(True)

    def _judge_probe(self) -> None:
        """Rule 16: the hello is back; the probe published before it is not: dropped."""
        probe, self._probe = self._probe, None
        if probe is not None and self._fence_topic is not None:
            self._delivery.deny(
                self._fence_topic,
                "read back what it publishes on",
                "a probe published there did not come back before the message published after "
                "it (the broker's ACL denies reading or writing it?); the bridge's markers then "
                "come back on its hello topic alone",
            )

    # -- rule 10: the bridge's own topics (owned.py judges) ---------------------------------
    def _foreign(self, topic: str, payload: bytes, *, live: bool) -> bool:
        """True if ``topic`` is one of ours (handled here, whatever its value)."""
        with self._lock:
            held = self._retained.get(topic)
            if payload:
                self._deleted.discard(topic)  # rule 14: not empty on the broker now
            if held is None or not self._owned.owns(topic):
                return False
            if self._stopping:
                return True  # shutting down (or refused): our offline values, or not ours
            if self._owned.ours(topic, payload, held[0]):
                return True
            look = self._look
            if look is not None and topic == look.claim.info_topic:
                self.refused = look.live_info(payload)  # claim rule 4
                if self.refused is not None:
                    self.yielded = True
                    self._stopping = True  # nothing more goes out, nothing is put back
                    self.connected.clear()  # (every publish checks it, under this lock)
            say = False
            if self.refused is None:
                settling = look is not None and look.looking is not None  # (owned.py rule 10)
                fix = self._owned.put_back(topic, live=live, settling=settling)
                if fix.send and self.connected.is_set():
                    self._put_back(topic, held)
                say = fix.say
                if say and self._owned.is_will(topic, payload):  # said later, if at all (_tick)
                    self._will_heard, say = (self._clock(), payload), False
        if self.refused is not None:
            self._refuse()
        elif say:
            self._say_foreign(topic, payload, held[0])
        return True

    def _put_back_owed(self) -> None:
        """Rule 10: a stranger's value that came too soon after the last put-back is put back
        once that interval is over (paho's thread, after a round of its loop: 1 s at most)."""
        if not self._owned.owing:  # (the usual case: no lock taken, each round)
            return
        with self._lock:
            if self._stopping or self.refused is not None or not self.connected.is_set():
                return
            for topic in self._owned.owed():
                held = self._retained.get(topic)
                if held is not None:
                    self._put_back(topic, held)

    def _put_back(self, topic: str, held: tuple[bytes, int]) -> None:
        """Rule 10, under ``_lock``: our value on ``topic`` again, over a stranger's."""
        self._owned.sent(topic, held[0])
        self._delivery.send(topic, held[0], held[1], retain=True)

    def _say_foreign(self, topic: str, payload: bytes, ours: bytes) -> None:
        log.warning(
            "another client published %r on %s, a topic of the bridge's own: put back %r "
            "(a second bridge on this base topic, or a flow publishing where it should not?)",
            payload[:40],
            topic,
            ours[:40],
        )
