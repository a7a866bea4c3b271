"""Stop and lock from both MQTT connections, in the order lastword.py decides (service.py rule
5): the stop lane's messages, the main connection's halts, the markers and their resend, the
retained halts, the report of a long hold. lastword.py decides; this carries its decisions out
into the rotators, each decision and the mailbox put it lets through under one lock.

One timer at a time (TICK_S, while a hold or a marker is out or a long hold is reported) sends
a marker again and reports a long hold, or a long fence (lastword.py rule 11), on
``B/bridge/info`` (``on_info``, never on paho's threads); it decides nothing (lastword.py rule
5): no hold or fence ends by it. ``stop`` (the service's stop) ends it for good: a marker out
when the bridge stopped never comes back, and its timer had looked again every second for the
rest of the process's life, sending markers on a stopped client.

Each marker of the main connection goes on the fence topic and on the hello topic
(lastword.py rule 7): a broker that drops one of them (its ACL) leaves no hold or fence
without its end.

A group's stop (``G/stop``, interfaces/mqtt/groups.py) is a stop of each of its members, on either
connection: the same decisions, member by member, in one step under the same lock (a lane's
group stop holds every member; the main connection's copy is each member's copy), and one
marker for them all, the newest. A member whose stop raises costs the others nothing: the
failure is logged and the next member is stopped.

Every stop and lock ON carried out here is first shown to the stop express (``express``,
interfaces/mqtt/express.py rule 8), which may put the rotator's targets on a hold of its own, in the
same step: the express may still be writing its frame for that stop, and a target sent before it
did would be stopped by it.

A stop or lock ON another interface carried out (the console, rotctld, a logger) fences its
rotator (lastword.py rule 11): counted before it is put (``fence_asked``, under a lock of its own
that nothing holds for longer than a count), fenced after (``fence_carried``, with a marker on
the main connection, or owed while a few are out: lastword.py rule 11); the service asks
``stale_move`` before it hands on a move (fenced, or held by a lane halt: lastword.py rule 2),
and the main connection's lock OFF is asked here. A lock ON no fence orders (the main
connection down) makes the lane's lock OFF wait for a new main connection (lastword.py rule
12).
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable

from bridge.core.afterlock import Deferring
from bridge.core.errors import Refused
from bridge.core.model import (
    Command,
    FeatureCommand,
    FollowQso,
    Lock,
    Origin,
    Source,
    Stop,
    TrackBody,
    turns_rotor,
)
from bridge.interfaces.mqtt import payloads as pl
from bridge.interfaces.mqtt.groups import Group
from bridge.interfaces.mqtt.lastword import LANES, LONG_HOLD_S, RESEND_MAX_S, LastWord
from bridge.interfaces.mqtt.ports import Publisher, RotatorPort
from bridge.interfaces.mqtt.topics import Topics

log = logging.getLogger(__name__)

# what to say on R/error once the lock is let go: (the rotator, why, the words refused, who)
Said = list[tuple[RotatorPort, str, str, Origin | None]]

TICK_S = 1.0  # the timer's period (markers sent again, long holds said)
# lastword.py rule 8's refusal, on R/error (the lock stays ON against the OFF: said, not only
# logged; a lock ON the lane read right after it reconnected is waited for the same way, one
# broker round trip, rule 9). It may be someone's lock for work on the tower: no "send again"
# the main connection subscribes (its SUBACK not come): it reads this OFF if the broker took
# its SUBSCRIBE before it, after the targets published before it, which the lock refuses; the
# lane's OFF carried out now would let them through. Not known which: said, not carried out
LOCK_OFF_SUBSCRIBING = (
    "lock OFF on the stop connection not carried out: the main connection was subscribing "
    "again and may carry it out itself, after what was published before it; if the lock is "
    "still ON, send lock OFF again"
)
# lastword.py rule 11: published before another interface's stop or lock ON, read after it
FENCED = (
    "published before a STOP or lock ON that another interface (the console, rotctld, a "
    "logger) carried out first: not carried out"
)
# lastword.py rule 2: read on the main connection while a halt from the stop lane holds the
# rotator, so published before that halt (or not known to be after it: its copy lost)
HELD = (
    "published before a STOP or lock ON that the stop connection carried out first (or not "
    "known to be after it): not carried out; send it again"
)
LOCK_OFF_FENCED = (
    "lock OFF not carried out: it was published before a lock ON that another interface (the "
    "console, a logger) carried out first; the lock stays ON (make sure nobody is working on "
    "the tower before unlocking)"
)
# lastword.py rule 12: the main connection down, the lane's lock OFF after another interface's
# lock ON that no fence ordered: it may have been published before that ON
LOCK_OFF_UNORDERED = (
    "lock OFF on the stop connection not carried out: another interface (the console, a "
    "logger) stopped or locked the rotator while the main connection was down or could not "
    "order it, and this OFF may have been published before that; the lock stays as it was "
    "(make sure nobody is working on the tower, then send lock OFF again once the bridge is "
    "connected, or use the console)"
)
# lastword.py rule 13: a lock OFF waiting under a lane hold when the main connection dropped
LOCK_OFF_LOST = (
    "lock OFF not carried out: it waited for the main connection to catch up with a STOP or "
    "lock ON from the stop connection, and that connection dropped; the lock stays ON (send "
    "lock OFF again)"
)
# lastword.py rule 13: a target by call read while a lock OFF before it waits for the marker
# (its look-up takes a place of its own: not kept behind the OFF), refused as the lock would
AFTER_WAITING_OFF = (
    "not carried out: the lock OFF before it waits for the main connection to catch up with a "
    "STOP or lock ON from the stop connection, and the rotator stays locked until then; send "
    "it again once the lock state says OFF"
)
# lastword.py rule 13: a move kept behind a waiting lock OFF that was not carried out
AFTER_OFF_REFUSED = (
    "not carried out: the lock OFF before it was not carried out (a lock ON came after it), "
    "and the rotator is locked"
)
MOVE_LOST = (
    "not carried out: it waited behind a lock OFF for the main connection to catch up with a "
    "STOP or lock ON from the stop connection, and that connection dropped; send it again"
)
LOCK_OFF_SUPERSEDED = (
    "lock OFF not carried out: it waited for the main connection to catch up with a STOP or "
    "lock ON from the stop connection, and a lock ON published after it came meanwhile; the "
    "lock stays ON"
)
LOCK_OFF_OLDER = (
    "lock OFF not carried out: a lock ON that may have been published after it came on the "
    "stop connection; the lock stays ON (make sure nobody is working on the tower before "
    "unlocking)"
)


# lastword.py rule 16: the lane each kind of halt comes on, as ``read_since`` names it
_VIA = {"stop": "lane", "lock": "lock"}


def _ends(off: Command, kept: Command) -> bool:
    """lastword.py rule 13: whether a tracking or following OFF ends the move kept behind a
    waiting lock OFF, as the mailbox's order would (mailbox.py rules 2 and 9)."""
    if isinstance(off, TrackBody):  # (everything but a feature's own moves is a target, a
        return not isinstance(kept, FeatureCommand)  # track or follow start there: a review)
    return isinstance(off, FollowQso) and isinstance(kept, FollowQso)


def switch_on(payload: bytes) -> bool:
    try:
        return pl.parse_switch(payload)
    except pl.PayloadError:
        return False


def _switch_off(payload: bytes) -> bool:
    try:
        return not pl.parse_switch(payload)
    except pl.PayloadError:
        return False


class Halts:
    def __init__(
        self,
        topics: Topics,
        publisher: Publisher,
        rotators: dict[str, RotatorPort],
        clock: Callable[[], float],
        *,
        retain_is_live: bool,
        on_problem: Callable[[str, str], None] | None,
        on_info: Callable[[str, bool], None] | None = None,
        groups: dict[str, Group] | None = None,
        report_group: Callable[[str, str, str], None] | None = None,
    ) -> None:
        """``groups``: the service's (groups added later are seen here too);
        ``report_group``: (group id, message, command) on the group's error topic."""
        self.topics = topics
        self._groups = {} if groups is None else groups
        self._report_group = report_group
        self._publisher = publisher
        self._rotators = rotators  # the service's: rotators attached later are seen here too
        self._clock = clock
        self.retain_is_live = retain_is_live
        self._on_problem = on_problem  # (topic, problem): a broker problem the bridge reports
        self._on_info = on_info  # (problem, still so): said on B/bridge/info while it lasts
        self.word = LastWord()
        # two connections, two paho threads; the owner steps under it wake the lines thread and
        # start the state writer once it has let go (kept.py rule 5)
        self._lock = Deferring()
        self._timer: threading.Timer | None = None
        self._stopped = False  # stop(): no timer from then on
        # (rotator, "hold" or "fence") -> its long hold or fence, as said (on_info)
        self._said: dict[tuple[str, str], str] = {}
        # the stop express's hold (interfaces/mqtt/express.py rule 8), asked before each halt's put
        self.express: Callable[[str], None] | None = None
        # express.py rule 11: when each connection last read a stop, a lock ON, of each rotator
        self._read: dict[tuple[str, str, str], float] = {}  # (connection, rotator, kind)
        # lastword.py rule 11: another interface's halts asked (before their put) and fenced
        # (after it), per rotator; asked under a lock of their own, which nothing else takes
        self._asked_lock = threading.Lock()
        self._asked: dict[str, int] = {}
        self._fenced: dict[str, int] = {}
        # lastword.py rule 13: a lock OFF read after the count copy of a lane halt, waiting
        # under its hold for the marker: rotator -> (who sent it, the lock ONs carried out
        # before it was read: ``_lock_ons``, ``_other_lock_ons``); one per rotator, the newest
        # (a setting: the last word counts)
        self._waiting_off: dict[str, tuple[Origin | None, int, int]] = {}
        # lastword.py rule 13: the lock ONs carried out, from either connection and from every
        # other interface (``fence_carried``, counted apart too, for the words that say it):
        # one after a waiting OFF was read makes it older
        self._lock_ons: dict[str, int] = {}
        self._other_lock_ons: dict[str, int] = {}
        # lastword.py rule 13: the newest move (a target, a track or follow word) the main
        # connection read after a waiting lock OFF, put after it at the marker: one per rotator
        # (an attack pass: a list of every one read grew with a flood, all judged at the marker
        # under this lock, the one a lane STOP needs)
        self._after_off: dict[str, tuple[Command, str, Origin | None]] = {}
        self._blind_said = False  # lastword.py rule 14: logged once
        # lastword.py rule 15: when a marker sent again was last asked of the broker while it
        # refuses them (a PUBACK said so, on a live connection or at a look; None: not so)
        self._refused_at: float | None = None
        # lastword.py rule 15: the markers were said lost by this connection's look (its hello
        # never back: reading them denied too), so a PUBACK that takes one says nothing of
        # reading them: only one back turns them on again (review 35)
        self._unread = False
        # lastword.py rule 15: said on B/bridge/info while the broker takes the markers this
        # connection's look found unreadable and none has come back (None: not said)
        self._taken_said: str | None = None
        self._asking_said = False  # lastword.py rule 15: the asking logged (once while refused)
        # lastword.py rule 15: a marker sent again at QoS 1, and whether the broker refused
        # both marker topics (the client's, set by the app; None: neither is known)
        self.publish_confirmed: Callable[[str, str], None] | None = None
        self.markers_refused: Callable[[tuple[str, ...]], bool] | None = None

    def read_since(
        self, rotator_id: str, kind: str, heard_since: Callable[[str, float], bool]
    ) -> bool:
        """express.py rule 11: whether a connection read a halt of this rotator that stands
        for a ``kind`` ("stop" or "lock") only the express read, and has had its command topics
        without a break since (``heard_since(connection, t)``): then that one reached it too, or
        is older than the halt it read. A stop or a lock ON stands for a stop; only a lock ON
        for a lock ON (a review: a STOP read after a lock ON only the express had would have
        left the rotator unlocked). An attack pass: a second after a broker restart, the
        express's second stop dropped a target sent after a STOP both connections had read.
        Only a connection that subscribes to that ``kind``'s topic vouches for it: the main
        connection, and the lane of that kind (lastword.py rule 16); review 108: the lock lane
        never reads a STOP, so its lock ON (since turned OFF, a target sent) had let a STOP only
        the express read be dropped, and the rotor turned on. A lock ON the main connection read
        still stands for a stop even after an OFF: a STOP published after it reached that
        connection too (carried out there), and one published before it is older than it."""
        kinds = ("stop", "lock") if kind == "stop" else ("lock",)
        for via in ("main", _VIA[kind]):
            for halt in kinds:
                t = self._read.get((via, rotator_id, halt))
                if t is not None and heard_since(via, t):
                    return True
        return False

    def _noted(self, via: str, rotator_id: str, kind: str) -> None:
        """``read_since``'s books: ``via`` ("main", "lane" or "lock") read a live halt (never a
        replayed one) of this ``kind`` ("stop" or "lock") for this rotator now."""
        self._read[via, rotator_id, kind] = self._clock()

    def main_gone(self) -> None:
        """The main connection dropped, or is new (before its first message): holds end with
        clearing (lastword.py rule 5)."""
        with self._lock:
            self._refused_at = None  # (lastword.py rule 15: the next connection's look asks)
            self._unread = self._asking_said = False
            for rid in self.word.main_gone():
                rot = self._rotators.get(rid)
                if rot is not None:
                    rot.release(0, clear=True)
            said: Said = []
            for rid, (origin, _, _) in self._waiting_off.items():
                rot = self._rotators.get(rid)
                if rot is not None:  # (lastword.py rule 13: its place in line is lost)
                    said.append((rot, LOCK_OFF_LOST, "lock OFF", origin))
                    said.extend(self._after_off_said(rid, rot, MOVE_LOST))
            self._waiting_off.clear()
        self._say(said)
        self._say_taken(False)

    def lane_connected(self, lanes: tuple[str, ...] = LANES) -> None:
        """A new connection of the lanes of these kinds (lastword.py rule 16)."""
        with self._lock:
            self.word.lane_connected(lanes)

    def lane_subscribing(self, lanes: tuple[str, ...] = LANES) -> list[tuple[str, str]]:
        """The lane's SUBSCRIBE is queued on its new connection, on its paho thread: the
        markers (topic, payload) it publishes right behind it, on that connection
        (lastword.py rule 17: on the fence topic and the hello topic, as every marker of the
        main connection, rule 7); none while the main connection cannot read them."""
        with self._lock:
            n = self.word.lane_subscribing(lanes)
        if n is None:
            return []
        marker = self.word.marker(n)
        return [(self.topics.bridge_fence, marker), (self.topics.bridge_hello, marker)]

    def lane_subscribed(self, lanes: tuple[str, ...] = LANES) -> None:
        """The lane's subscription is acknowledged (lastword.py rule 9), on its paho thread:
        before any message it brings."""
        with self._lock:
            n = self.word.lane_subscribed(self._clock(), lanes)
        if n is not None:
            self._send_marker(n)

    def markers_denied(self, unread: bool = True) -> None:
        """The broker does not let the main connection read its markers (lastword.py rule 7):
        none goes out; a lane's halt holds until its main copy. The holds stay. Where a
        PUBACK said so (both topics refused, rule 15), the broker is asked again every
        RESEND_MAX_S, whoever found it (a new connection's look too: review 31, an ACL mended
        by a SIGHUP a minute after a reconnect left the markers off for that connection's
        life). ``unread``: the look said so, its hello never back (the client's verdict): a
        PUBACK that takes a marker then turns them on no more, a marker back does (rule 15;
        not ``unread``, the PUBACKs of a live connection that read its markers said so)."""
        refused = self.markers_refused
        topics = (self.topics.bridge_fence, self.topics.bridge_hello)
        by_puback = refused is not None and refused(topics)  # (the client's lock: not under ours)
        with self._lock:
            ended = self.word.markers_denied()
            said = [one for rid, m in ended.items() for one in self._release((rid,), m)]
            if by_puback and self._refused_at is None:
                self._refused_at = self._clock()
            self._unread = self._unread or unread
        self._say(said)
        self._arm()

    def markers_allowed(self) -> None:
        """The hello or the probe came back on a new connection: markers go out again
        (lastword.py rule 7)."""
        with self._lock:
            self._refused_at = None  # (lastword.py rule 15: asked no more)
            self._unread = self._asking_said = False
            n = self.word.markers_allowed(self._clock())
        self._say_taken(False)
        if n is not None:  # (a hold put while they were off, or the lane's: rule 9)
            self._send_marker(n)

    def lane_markers_denied(self, lanes: tuple[str, ...] = LANES) -> None:
        """The lane cannot read its markers: no echo is expected (lastword.py rule 4)."""
        with self._lock:
            for lane in lanes:
                self.word.lane_deaf(lane)

    # -- another interface's halt (lastword.py rule 11) ---------------------------------------
    def fence_asked(self, rotator_id: str) -> None:
        """Right before another interface's stop or lock ON is put (runtime/rotator.py): from
        here on the main connection's moves for this rotator are refused until its fence is
        up and ended (``fenced``), so that none read meanwhile goes out after it. One count
        under a lock nothing else holds for longer: the stop waits for nothing."""
        with self._asked_lock:
            self._asked[rotator_id] = self._asked.get(rotator_id, 0) + 1

    def fence_carried(self, rotator_id: str, lock: bool) -> None:
        """Right after it was put (``lock``: a lock ON): its fence, and the marker that ends
        it, published after the halt was carried out."""
        with self._lock:
            heard = self._publisher.hears  # (not subscribed: nothing older will be read)
            n = self.word.fence(rotator_id, lock, self._clock()) if heard else None
            if lock and not heard:  # (lastword.py rule 12: the lane's lock OFF is no later)
                self.word.unfenced_lock(rotator_id)
            # counted once the fence is up (``fenced`` reads them the other way round)
            self._fenced[rotator_id] = self._fenced.get(rotator_id, 0) + 1
            if lock:  # (lastword.py rule 13: a lock OFF waiting now is older than this ON)
                self._lock_ons[rotator_id] = self._lock_ons.get(rotator_id, 0) + 1
                self._other_lock_ons[rotator_id] = self._other_lock_ons.get(rotator_id, 0) + 1
            else:  # (and a move kept behind it older than this stop, dropped as a stop drops)
                self._after_off.pop(rotator_id, None)
        if n is not None:
            self._send_marker(n)

    def fenced(self, rotator_id: str, lock_off: bool = False) -> bool:
        """Whether a move (``lock_off``: a lock OFF) the main connection reads now for this
        rotator was published before another interface's halt: its fence still up, or a halt
        asked and not fenced yet. Read without a lock (each read is one dict look-up): the
        main connection asks it for every move, and a lock it took that often would keep a
        stop on the lane waiting for it under a flood (a plain lock goes to whoever holds
        the interpreter lock). The fenced count first: a halt counted there has its fence up
        already; then the fence; then the asked: a halt asked after that is put after the
        move was read, and the move's halt count drops it."""
        fenced = self._fenced.get(rotator_id, 0)
        up = self.word.fenced(rotator_id, lock_off)
        return up or self._asked.get(rotator_id, 0) > fenced

    def stale_move(self, rotator_id: str) -> str | None:
        """Why a move the main connection reads now for this rotator is refused as older (its
        R/error), or None: another interface's halt fences it (``fenced``: FENCED), or a lane
        halt holds it (lastword.py rule 2: HELD; its copy, or the marker, is not read yet; read
        after the copy, it goes into the mailbox and waits there under the hold: rule 13).
        Read without a lock, as ``fenced`` is (one dict look-up more): a lane halt put after
        the look is put after the move's halt count was read, and drops it in the mailbox."""
        if self.fenced(rotator_id):
            return FENCED
        if self.word.held(rotator_id):
            return HELD
        if rotator_id in self._waiting_off:  # lastword.py rule 13: locked until it goes
            return AFTER_WAITING_OFF
        return None

    def _lane_blind(self, lane: str) -> bool:
        """lastword.py rule 14: neither connection can read the bridge's markers while the main
        connection reads its commands: a lane halt could be neither told from the echo of one
        the main connection carried out nor ever ended, so the lane carries out nothing (the
        main connection carries out every halt, in order: stops lose the lane's speed only).
        ``lane``: the kind of the lane that read it (lastword.py rule 16)."""
        blind = not self.word.markers and not self.word.lane_echoes(lane) and self._holds_possible()
        if blind and not self._blind_said:
            self._blind_said = True
            log.warning(
                "neither MQTT connection can read the bridge's markers (%s, %s denied?): stops "
                "and locks are carried out from the main connection only, in order, without "
                "the stop lane's speed",
                self.topics.bridge_fence,
                self.topics.bridge_fence_lane,
            )
        return blind

    def _holds_possible(self) -> bool:
        """Whether the main connection will read what was published before a lane halt (and
        its marker after it): from its SUBSCRIBE on, not only from its SUBACK (a target
        published between the two, read after the lane's stop, went out after it)."""
        return self._publisher.hears

    def carry(
        self,
        rot: RotatorPort,
        kind: str,
        what: str,
        hold: int | None = None,
        origin: Origin | None = None,
        echo: bool = False,
        sent_s: float | None = None,
    ) -> None:
        """A stop or a lock ON, into the mailbox (under the word lock: lastword.py's decision
        and the put are one step). ``origin``: who sent it; ``echo``: the main connection's
        copy of one the lane carried out (the audit trail has it once); ``sent_s``: its stamp
        on the steady clock (service.py rule 9)."""
        if kind == "lock":  # lastword.py rule 13: a lock OFF waiting before it is older
            self._lock_ons[rot.id] = self._lock_ons.get(rot.id, 0) + 1
        else:  # (a move kept behind that OFF is older than this stop: dropped, as a stop drops)
            self._after_off.pop(rot.id, None)
        halt = (
            Stop(Source.MQTT, origin, sent_s)
            if kind == "stop"
            else Lock(True, source=Source.MQTT, origin=origin, sent_s=sent_s)
        )
        if self.express is not None:  # its hold before the halt (interfaces/mqtt/express.py rule 8)
            try:
                self.express(rot.id)
            except Exception:  # a bug there never costs the stop
                log.exception("%s: the stop express's hold failed", rot.id)
        rot.submit(halt, what, hold=hold, echo=echo)

    def _send_marker(self, n: int) -> None:
        self._publish_marker(n)
        self._arm()

    def _publish_marker(self, n: int, confirmed: bool = False) -> None:
        """Marker ``n`` on the fence topic and on the hello topic (lastword.py rule 7: the
        first one back ends what it ends; the second, nothing more); ``confirmed``: sent
        again, at QoS 1 where the client can (lastword.py rule 15)."""
        marker = self.word.marker(n)
        publish = self.publish_confirmed if confirmed else None
        if publish is None:
            publish = self._publisher.publish_marker
        publish(self.topics.bridge_fence, marker)
        publish(self.topics.bridge_hello, marker)

    def _arm(self) -> None:
        """One timer at most looks again in TICK_S while there is something to look at."""
        with self._lock:
            asking = self._refused_at is not None  # (lastword.py rule 15; a clock may say 0.0)
            busy = self.word.holding or self.word.markers_out or self._said or asking
            if self._timer is not None or not busy or self._stopped:
                return
            timer = self._timer = threading.Timer(TICK_S, self._tick)
        timer.name = "halts"
        timer.daemon = True
        timer.start()

    def stop(self) -> None:
        """The timer ended and never armed again (the opening comment)."""
        with self._lock:
            self._stopped = True
            timer, self._timer = self._timer, None
        if timer is not None:
            timer.cancel()

    def _tick(self) -> None:
        with self._lock:
            self._timer = None
        self.resend_if_due()
        self._refused_now()
        self.say_long_holds()
        self._arm()

    def resend_if_due(self) -> None:
        """lastword.py rule 5: a marker the broker dropped is sent again (a new number); rule
        11: a fence's marker that waited for room goes once there is room; rule 15: the broker
        asked again while it refuses the markers (logged once while it does, then at debug)."""
        asked = said = False
        with self._lock:
            now = self._clock()
            n = self.word.resend_due(now)
            owed = self.word.owed_fence(now)
            if self._refused_at is not None and now - self._refused_at >= RESEND_MAX_S:
                self._refused_at = now  # (lastword.py rule 15: asked again while refused)
                n, asked = self.word.probe(), True
                said, self._asking_said = self._asking_said, True
        if asked:  # lastword.py rule 15: no marker is out, no hold waits for this one (review
            say = log.debug if said else log.info  # 35: each asking, every 30 s, was logged as
            say(  # a stop lane's marker not back, with no STOP sent): once, then at debug
                "the MQTT broker refused the bridge's markers: asking it again every %g s "
                "whether it takes them on %s and %s (a marker sent at QoS 1)",
                RESEND_MAX_S,
                self.topics.bridge_fence,
                self.topics.bridge_hello,
            )
        elif n is not None:
            log.info("a marker of the stop lane did not come back yet; sending another")
        if n is not None:
            self._publish_marker(n, confirmed=True)
        if owed is not None:
            self._send_marker(owed)

    def _refused_now(self) -> None:
        """lastword.py rule 15 (the timer): the broker refused a marker sent again on both
        topics (its ACL changed under the live connection): the markers cannot come back."""
        refused = self.markers_refused
        topics = (self.topics.bridge_fence, self.topics.bridge_hello)
        if refused is None:
            return
        if self._refused_at is not None:  # known refused: a marker sent again since, taken
            taken = not refused(topics)  # on a topic, says the ACL changed back (an attack
            if taken and not self._unread:  # pass), where this connection read them before
                log.warning("the MQTT broker takes the bridge's markers again")
                self.markers_allowed()
            elif self._unread:  # (its look found them unreadable: a publish taken says
                self._say_taken(taken)  # nothing of reading; one back turns them on)
            return
        if not self.word.markers or not refused(topics):
            return
        log.warning(
            "the MQTT broker refuses the bridge's markers on %s and %s (its ACL changed?): a "
            "stop lane's hold ends with the main connection's copy of its halt from now on",
            *topics,
        )
        self.markers_denied(unread=False)  # (asked again from now: ``_refused_at``)

    def _say_taken(self, taken: bool) -> None:
        """lastword.py rule 15: while the broker takes the markers this connection's look
        found unreadable and none has come back, said on B/bridge/info (the PUBACK cleared the
        topics' refusals there, delivery.py rule 11), and unsaid when that ends."""
        with self._lock:
            said = self._taken_said
            if taken == (said is not None):
                return
            problem = said or (
                f"the MQTT broker takes the bridge's markers on {self.topics.bridge_fence} "
                f"and {self.topics.bridge_hello} again, but the main connection has read "
                "none back since its first look found them unreadable: they stay off (a "
                "stop or lock ON from another interface fences nothing; a stop lane's hold "
                "ends with the main connection's copy of its halt) until one comes back "
                "(give the bridge's user read and write on them)"
            )
            self._taken_said = problem if taken else None
        if taken:
            log.warning("%s", problem)
        if self._on_info is not None:
            self._on_info(problem, taken)

    def say_long_holds(self) -> None:
        """lastword.py rule 5: a long hold is said while it lasts (logged once), and unsaid
        when it ends; it holds all the same."""
        with self._lock:
            now = self._clock()
            markers = self.word.markers
            held = {(rid, "hold") for rid in self.word.long_holds(now)}
            held |= {(rid, "fence") for rid in self.word.long_fences(now)}  # lastword rule 11
            ended = {key: said for key, said in self._said.items() if key not in held}
            new = {key: self._long_hold(*key, markers) for key in held if key not in self._said}
            for key in ended:
                del self._said[key]
            self._said.update(new)
        for problem in new.values():
            log.warning("%s", problem)
            if self._on_info is not None:
                self._on_info(problem, True)
        for (rid, kind), problem in ended.items():
            what = "hold of the stop lane" if kind == "hold" else "fence of another's halt"
            log.info("%s: the %s ended", rid, what)
            if self._on_info is not None:
                self._on_info(problem, False)

    def _long_hold(self, rid: str, kind: str, markers: bool) -> str:
        if kind == "fence":  # lastword.py rule 11 (only while the markers can be read)
            return (
                f"{rid}: a STOP or lock ON from another interface (the console, rotctld, a "
                f"logger) has fenced this rotator's MQTT moves for more than {LONG_HOLD_S:g} s: "
                "the main connection has not yet read the marker sent after it on "
                f"{self.topics.bridge_fence} and {self.topics.bridge_hello} (a flood of targets, "
                "a slow link, a broker that drops the bridge's messages?). Until it does, MQTT "
                "targets are refused as older; stops and locks go through"
            )
        caught_up = (
            f"its marker on {self.topics.bridge_fence} or {self.topics.bridge_hello} comes back"
            if markers
            else "it reads its own copy of the stop or lock"
        )
        return (
            f"{rid}: a stop or lock from the stop lane has held this rotator's targets for more "
            f"than {LONG_HOLD_S:g} s: the main connection has not yet read everything published "
            f"before it (a flood of targets, a slow link?). Until {caught_up}, MQTT targets "
            "read before its own copy of the stop or lock are refused as older, the others "
            "wait (lastword.py rule 13); stops and locks go through"
        )

    def marker_back(self, payload: bytes) -> None:
        with self._lock:
            n, released = self.word.marker_back(payload)
            asked = self.word.asked_back(n)  # (lastword.py rule 15)
            said = self._release(released, n)
            owed = self.word.owed_fence(self._clock()) if n else None  # lastword.py rule 11
        self._say(said)
        if asked:  # lastword.py rule 15: one asked while they were known denied came back
            log.warning(
                "a marker the bridge sent to ask the MQTT broker came back: the main "
                "connection reads its markers again"
            )
            self.markers_allowed()
        if owed is not None:
            self._send_marker(owed)

    def _release(self, released: list[str] | tuple[str, ...], marker: int) -> Said:
        """Under the lock: the holds of ``released`` up to ``marker`` end, and a lock OFF that
        waited under one is carried out, then the move kept behind it (lastword.py rule 13).
        Not the OFF if a lock ON was carried out after it was read, from anywhere, or another
        interface's halt is under way: it may be a lock ON, and the OFF was published before
        it (the move kept behind is then refused: the rotator stays locked). Their halt count
        is read here, not when they were read: a STOP carried out meanwhile dropped the move
        already and is no reason to keep the lock ON (an attack pass: a STOP published after
        the OFF left the rotator locked), and a halt put after this look refuses them at the
        judge. What to say once the lock is let go is returned (``_say``)."""
        said: Said = []
        for rid in released:
            rot = self._rotators.get(rid)
            if rot is None:
                continue
            rot.release(marker)
            off = self._waiting_off.pop(rid, None)
            if off is None:
                continue
            origin, lock_ons, others = off
            since = rot.halts  # (before the look at another interface's halt under way)
            other = others != self._other_lock_ons.get(rid, 0) or self.fenced(rid, lock_off=True)
            if other or lock_ons != self._lock_ons.get(rid, 0):
                why = LOCK_OFF_FENCED if other else LOCK_OFF_OLDER  # (the words: a review)
                said.append((rot, why, "lock OFF", origin))
                said.extend(self._after_off_said(rid, rot, AFTER_OFF_REFUSED))
                continue
            try:
                rot.submit(Lock(False, source=Source.MQTT, origin=origin), since=since)
            except Refused:  # (the judge said why: a lock ON came while it waited)
                said.extend(self._after_off_said(rid, rot, AFTER_OFF_REFUSED))
                continue
            kept = self._after_off.pop(rid, None)
            if kept is None:
                continue
            command, what, by = kept
            if self.fenced(rid):  # (another interface's halt under way: lastword.py rule 11)
                said.append((rot, FENCED, what, by))
                continue
            try:
                rot.submit(command, what, since=since)
            except Refused:
                pass  # (the judge said why)
        return said

    def _after_off_said(self, rid: str, rot: RotatorPort, why: str) -> Said:
        """Under the lock: the move kept behind a lock OFF that will not go, dropped and said."""
        kept = self._after_off.pop(rid, None)
        return [] if kept is None else [(rot, why, kept[1], kept[2])]

    def keep_after_off(
        self, rot: RotatorPort, command: Command, what: str, origin: Origin | None
    ) -> bool:
        """lastword.py rule 13: a move (a target, a track or follow start) the main connection
        reads while a lock OFF before it waits for the marker is kept, the newest only (as the
        mailbox keeps the newest target), and put after the OFF at the marker: True. A
        tracking or following OFF is not kept (False: it goes now) and drops a kept start
        it ends, as the mailbox would (a track OFF any but a feature's own move; a follow OFF
        a follow start: a review, a follow OFF took the kept target's place). False
        when no OFF waits (one dict look-up, without the lock: most messages), or another
        interface's halt fences the rotator, or a newer lane halt holds it whose copy is not
        read yet (the caller refuses it: ``stale_move``)."""
        if rot.id not in self._waiting_off:
            return False
        with self._lock:
            if rot.id not in self._waiting_off or self.stale_move(rot.id) != AFTER_WAITING_OFF:
                return False  # (fenced, or held by a newer lane halt: refused as such)
            if not turns_rotor(command):  # tracking or following OFF: it goes now (nothing
                kept = self._after_off.get(rot.id)  # tracks under the lock), and ends a
                if kept is not None and _ends(command, kept[0]):  # start kept of its kind
                    del self._after_off[rot.id]  # (mailbox.py rules 2 and 9; a review)
                return False
            self._after_off[rot.id] = (command, what, origin)
            return True

    @staticmethod
    def _say(said: Said) -> None:
        """What waited and was not carried out, said once the lock is let go."""
        for rot, why, what, origin in said:
            rot.report_refusal(why, what, origin=origin)

    def on_lane_marker(self, payload: bytes, lanes: tuple[str, ...] = LANES) -> None:
        """The lane read its marker (lastword.py rule 4): the notes of its kinds end (rule 16)."""
        with self._lock:
            self.word.lane_marker_back(payload, lanes)

    def replayed_halt(self, rot: RotatorPort, topic: str, kind: str, payload: bytes) -> None:
        """lastword.py rule 6 under MQTT 3.1.1: a replayed retained stop or lock ON, once."""
        what = pl.describe(kind, payload)
        with self._lock:
            if not self.word.retained_halt(topic, payload, replayed=True):
                log.debug("%s: retained %s on %s already carried out once", rot.id, kind, topic)
                return
            self.carry(rot, kind, what)
        self.report_retained_halt(rot, topic, kind, what)

    def report_retained_halt(self, rot: RotatorPort, topic: str, kind: str, what: str) -> None:
        rot.report_refusal(
            f"{kind} on {topic} was published retained: executed (stopping is always safe), "
            "but clear it with an empty retained message",
            what,
        )

    def on_lane(
        self,
        topic: str,
        payload: bytes,
        retain: bool,
        origin: Origin | None = None,
        late: Callable[[], str | None] = lambda: None,
        sent_s: float | None = None,
        lane: str | None = None,
    ) -> None:
        """The lanes' messages (rule 5; lastword.py rules 2-4, 6 and 16). ``late``: why a
        stamped lock OFF is too old to carry out (service.py rule 9), asked only of the OFF it
        would carry out; a stop or lock ON is never asked. ``sent_s``: a halt's stamp (carry).
        ``lane``: the kind of the lane that read it ("stop", "lock"; None: told by the topic);
        a word of the other kind is none of that lane's (lastword.py rule 16)."""
        if topic == self.topics.bridge_fence_lane:
            self.on_lane_marker(payload, LANES if lane is None else (lane,))
            return
        route = self.topics.route(topic)
        if route is None and not (retain and not payload):
            group = self.topics.group_route(topic)
            if group is not None and group[1] == "stop" and lane in (None, "stop"):
                self.lane_group_stop(group[0], topic, payload, retain, origin, sent_s)
            return
        if route is None or (retain and not payload):
            return
        rotator_id, kind, _arg = route
        rot = self._rotators.get(rotator_id)
        if rot is None or kind not in ("stop", "lock") or lane not in (None, kind):
            return
        if not retain and (kind == "stop" or switch_on(payload)):
            self._noted(_VIA[kind], rotator_id, kind)
        if kind == "lock" and not switch_on(payload):
            if retain or not _switch_off(payload):
                return  # the main connection refuses or reports it
            # lastword.py rule 12, as main_lock_off: the halt count read before the look (a lock
            # ON put after it refuses the OFF at the judge), and another interface's halt under way
            since, under_way = rot.halts, self.fenced(rotator_id, lock_off=True)
            with self._lock:  # lastword.py rule 3: the only word while it is down
                up, hears = self._publisher.up, self._publisher.hears
                if up:
                    return
                why = late() if not hears else LOCK_OFF_SUBSCRIBING
                if why is None and (under_way or self.word.lane_lock_off_unordered(rotator_id)):
                    why = LOCK_OFF_UNORDERED  # lastword.py rule 12
                if why is None and self.word.lane_behind(rotator_id, "lock"):
                    why = LOCK_OFF_OLDER  # lastword.py rule 3: the lane has a main ON to read
                if why is None:
                    what = pl.describe(kind, payload)
                    try:
                        rot.submit(
                            Lock(False, source=Source.MQTT, origin=origin), what, since=since
                        )
                    except Refused:
                        return  # (the judge said why: a lock ON came while it was judged)
            if why is not None:  # a link held it up: refused as the main connection would
                rot.report_refusal(why, pl.describe(kind, payload), origin=origin)
            return
        if retain and not self.retain_is_live:
            self.replayed_halt(rot, topic, kind, payload)
            return
        if self._lane_blind(kind):
            return
        self.live_halt(topic, payload)
        what = pl.describe(kind, payload)
        with self._lock:
            marker = self.word.lane_halt(rotator_id, kind, self._clock(), self._holds_possible())
            if marker is None:
                log.debug("%s: %s on the stop lane: already carried out", rotator_id, kind)
                return  # lastword.py rule 4: the echo of the main connection's copy
            self.carry(rot, kind, what, hold=marker or None, origin=origin, sent_s=sent_s)
        if marker and self.word.markers:
            self._send_marker(marker)
        elif marker:
            self._arm()  # (a long hold is said)

    def main_halt(
        self,
        rot: RotatorPort,
        topic: str,
        kind: str,
        what: str,
        retain: bool,
        origin: Origin | None = None,
        sent_s: float | None = None,
    ) -> None:
        """A stop or lock ON read on the main connection: carried out in order (rule 1), noted
        for rule 4; ``sent_s``: its stamp (carry)."""
        if not retain:
            self._noted("main", rot.id, kind)
        with self._lock:
            copy = self.word.main_halt(rot.id, kind, self._clock())
            # lastword.py rule 13: a waiting OFF read before this ON, on the same connection,
            # is done: this ON is the later word (or the copy of the lane's, carried out first)
            off = self._waiting_off.pop(rot.id, None) if kind == "lock" else None
            self.carry(rot, kind, what, origin=origin, echo=copy.echo, sent_s=sent_s)
            said = self._release(copy.released, copy.upto)  # lastword.py rule 9
            if off is not None:
                why = LOCK_OFF_OLDER if copy.echo else LOCK_OFF_SUPERSEDED
                said.append((rot, why, "lock OFF", off[0]))
                said.extend(self._after_off_said(rot.id, rot, AFTER_OFF_REFUSED))
        self._say(said)
        if copy.marker is not None:  # lastword.py rule 13: the holds' moves wait for it
            self._send_marker(copy.marker)
        if copy.lane_marker is not None:
            marker = self.word.marker(copy.lane_marker, lane=True)
            self._publisher.publish_marker(self.topics.bridge_fence_lane, marker)
        if retain:  # published retained, live (MQTT 5): carried out, and reported
            self.report_retained_halt(rot, topic, kind, what)

    def main_lock_off(self, rot: RotatorPort, origin: Origin | None = None) -> None:
        """A lock OFF read on the main connection (rule 8: not when older than a lane ON)."""
        since = rot.halts  # lastword.py rule 11: read before the fence is asked, so that a
        # lock ON put after that refuses it; and the lock ONs counted before it too (rule 13:
        # one carried out between the look and the lock is after the snapshot; a review)
        lock_ons = self._lock_ons.get(rot.id, 0), self._other_lock_ons.get(rot.id, 0)
        fenced = self.fenced(rot.id, lock_off=True)
        with self._lock:
            carried = not fenced and self.word.main_lock_off(rot.id)
            if carried and self.word.off_waits(rot.id):  # lastword.py rule 13: for the marker
                self._waiting_off[rot.id] = (origin, *lock_ons)
                return
            if carried:
                try:
                    rot.submit(Lock(False, source=Source.MQTT, origin=origin), since=since)
                except Refused:
                    return  # (the judge said why: a lock ON came while it was judged)
        if not carried:  # said (the lock stays ON against it), once the lock is let go: a
            why = LOCK_OFF_FENCED if fenced else LOCK_OFF_OLDER  # stop may wait
            rot.report_refusal(why, "lock OFF", origin=origin)

    def live_halt(self, topic: str, payload: bytes) -> None:
        """lastword.py rule 6 under MQTT 3.1.1: a live stop or lock ON, its payload remembered
        as carried out (it may have been published retained: its replay is no new stop)."""
        if self.retain_is_live:
            return
        with self._lock:
            self.word.live_halt(topic, payload)

    def retained_deleted(self, topic: str) -> None:
        with self._lock:
            self.word.retained_halt(topic, b"", replayed=True)  # forgotten (rule 6)

    # -- a group's stop: a stop of each member (the module's docstring) ------------------------
    def _members(self, group_id: str) -> list[RotatorPort]:
        group = self._groups.get(group_id)
        if group is None:
            return []
        return [rot for mid in group.member_ids if (rot := self._rotators.get(mid)) is not None]

    def _stop_member(
        self,
        rot: RotatorPort,
        what: str,
        hold: int | None,
        origin: Origin | None,
        echo: bool,
        sent_s: float | None = None,
    ) -> None:
        """Under the lock: one member's stop; a failure is this member's alone."""
        try:
            self.carry(rot, "stop", what, hold=hold, origin=origin, echo=echo, sent_s=sent_s)
        except Exception:
            log.exception("%s: the group's stop failed for this member", rot.id)

    def lane_group_stop(
        self,
        group_id: str,
        topic: str,
        payload: bytes,
        retain: bool,
        origin: Origin | None,
        sent_s: float | None = None,
    ) -> None:
        """A group's stop read on the lane: each member's stop carried out at once, each on
        hold (lastword.py rule 2), one marker (the newest) for them all."""
        members = self._members(group_id)
        if not members:
            return
        if retain and not self.retain_is_live:
            self.replayed_group_stop(group_id, topic, payload)
            return
        if self._lane_blind("stop"):
            return
        self.live_halt(topic, payload)
        what = pl.describe("stop", payload)
        newest = held = 0
        for rot in members:
            self._noted("lane", rot.id, "stop")
        with self._lock:
            for rot in members:
                marker = self.word.lane_halt(rot.id, "stop", self._clock(), self._holds_possible())
                if marker is None:
                    continue  # lastword.py rule 4: this member's echo
                self._stop_member(rot, what, marker or None, origin, False, sent_s)
                newest, held = max(newest, marker), held + 1
        if newest and self.word.markers:
            self._send_marker(newest)
        elif newest:
            self._arm()
        log.debug("%s: stop on the stop lane for %d member(s)", group_id, held)

    def main_group_stop(
        self,
        group_id: str,
        topic: str,
        what: str,
        retain: bool,
        origin: Origin | None = None,
        sent_s: float | None = None,
    ) -> None:
        """A group's stop read on the main connection: each member's, in order (rule 1); one
        lane marker, the newest, for the members the lane had no copy of (lastword.py rule 4)."""
        lane_marker: int | None = None
        fresh: int | None = None  # lastword.py rule 13: the newest fresh marker, one for all
        said: Said = []
        with self._lock:
            for rot in self._members(group_id):
                if not retain:  # (a review: as a member's own stop is)
                    self._noted("main", rot.id, "stop")
                copy = self.word.main_halt(rot.id, "stop", self._clock())
                self._stop_member(rot, what, None, origin, copy.echo, sent_s)
                said += self._release(copy.released, copy.upto)  # lastword.py rule 9
                if copy.lane_marker is not None:
                    lane_marker = copy.lane_marker
                if copy.marker is not None:
                    fresh = copy.marker
        self._say(said)
        if fresh is not None:
            self._send_marker(fresh)
        if lane_marker is not None:
            marker = self.word.marker(lane_marker, lane=True)
            self._publisher.publish_marker(self.topics.bridge_fence_lane, marker)
        if retain:
            self._report_retained_group_stop(group_id, topic, what)

    def replayed_group_stop(self, group_id: str, topic: str, payload: bytes) -> None:
        """lastword.py rule 6 under MQTT 3.1.1: a replayed retained group stop, once."""
        what = pl.describe("stop", payload)
        with self._lock:
            if not self.word.retained_halt(topic, payload, replayed=True):
                return
            for rot in self._members(group_id):
                self._stop_member(rot, what, None, None, False)
        self._report_retained_group_stop(group_id, topic, what)

    def _report_retained_group_stop(self, group_id: str, topic: str, what: str) -> None:
        if self._report_group is not None:
            self._report_group(
                group_id,
                f"stop on {topic} was published retained: executed (stopping is always safe), "
                "but clear it with an empty retained message",
                what,
            )
