"""The first look of every connect, as the main connection takes it (client.py rule 14), and
what is said of deleting retained configs (rule 15): bookkeeping and log lines, without paho,
a lock or a clock. The client asks under its own lock and publishes what this says; the
verdicts themselves are claim.py's.

Rules (numbered as the bridge's MQTT rules; client.py keeps the index of all of them):
14. One live bridge per base topic. On every connect, after subscribing and before publishing
   or deleting anything, the client publishes a hello to itself on ``B/bridge/hello`` (QoS 1,
   as the fence probe sent right before it, client.py rule 16; not retained: nothing of it
   stays on the broker, and it names the instance and the look's number, so a late hello of an
   earlier look, or another bridge's, ends nothing; nor does a message that comes retained
   there, whatever it says: the bridge never publishes one retained on that topic, so it is a
   forged or left-over one, said once in the process with how to delete it (``retained_hello``;
   review 94: a retained ``"<client id> 1"``, the first look of every process, came back as
   the broker answered the look's SUBSCRIBE, before the posts' values read for the look alone,
   and ended it: a bridge ran beside a live one on its topics, and one target turned both
   rotors, at every start). The broker handles one client's packets in
   order and sends the retained messages of a subscription before anything published after it:
   so the retained ``B/bridge/info`` and ``B/bridge/state`` that arrive before the hello comes
   back are all the broker held (``saw``).
   Its coming back ends the look (``end``): claim.py's verdict on what was seen. REFUSE: the
   bridge refuses to run, publishing nothing. OURS: the deletions of retained configs asked
   for during the look (``defer_clear``: Home Assistant's stale discovery) are sent, each once
   (a topic two overlapping filters read, a rotator's option state, is asked for twice: it
   was sent and named twice, interfaces/mqtt/stale.py rule 5), and none of a topic the bridge
   published after asking (client.py ``_open``: a controller's version read while the look
   ran; the deletion went out after it, and the version, unchanged, was never published
   again); nor does an owned topic the look deleted get a second deletion when the bridge
   then publishes it empty, unless another client has published on it since (``_deleted``: a
   DCU-1, which has no version, deleted the Rotor-EZ's ``R/version`` it replaced a second
   time when its first status came after the look had ended: 2 or 3 test runs in 48 under
   load).
   TAKE_OVER (said once, in the log), or a look that timed out (an ACL that denies the
   hello), or any look after one of those in this process: nothing is deleted, and the
   configs are named in the log as left alone (claim rule 3). Another instance's info
   arriving while the bridge runs is judged by claim rule 4 (``live_info``).
   The values the broker held on the topics handed to ``witness`` (each rotator's
   ``R/lock/state``) and that arrive during the look are kept too (``saw`` leaves them to the
   owned-topic judge all the same), and the first look of the process that lets the bridge run
   hands them on (``Outcome.heard``, empty if there were none: a rotator whose lock it waited
   for is free then): what an earlier run said, before this one published anything
   (runtime/kept.py rule 10). A later look's are the bridge's own: none are handed on (None).
   They are handed on before ``online`` and the cached values go out, and a value the hook
   took (an ON that locked its rotator) is left as the broker holds it while it holds,
   whether or not its rotator's status was cached by then (a review: a first status made
   after the open put its OFF over the ON, Home Assistant's lock switch OFF then ON): the
   OFF cached before it is older (a review: put over it, the lock was shown OFF, and a crash
   before the lock's save left neither the file nor the broker ON), and so is a status's OFF
   from before the lock was saved (runtime/kept.py rule 2; a review of the merge: it came
   after the open, 1 start in 4). A late witness (below) its hook took is not put back as a
   stranger's value either: its rotator's ON follows.
   Not every broker sends a subscription's retained messages before what is published after
   it: aedes (Node-RED's) streams them from its store after the SUBACK, beside the messages
   that follow, so the hello can come back first and a retained ``R/lock/state`` ON after it
   (the bridge then started unlocked and put OFF over it). Under MQTT 3.1.1 a message that
   comes with the retain flag is such a replay (the broker clears the flag of a live one), of
   what the broker held when the bridge subscribed, before it published anything: so on the
   connection whose look handed the witnesses on, and until it ends (``connection_ended``), a
   witness that comes retained after the look is handed on too (``late``). Not under MQTT 5:
   the owned topics, the witnesses among them, are subscribed there without
   retain-as-published (owned.py rule 10), so the flag tells a held value from a live one
   there too, but no broker the bridge meets streams them late under MQTT 5 (aedes speaks
   MQTT 3.1.1 only), and none was tried.
   Nothing held and nothing readable look alike: a broker whose ACL lets the bridge publish a
   witness but not read it (mosquitto grants the subscription and drops what it would send
   there) showed an ON it held as nothing, the rotator started unlocked and the bridge put
   OFF over the ON (review 62). So the look that may hand the witnesses on asks, once its
   hello is back, of the witnesses it heard nothing on (``next_round``; a value heard says the
   topic can be read, and nothing is sent there: a subscriber sees no probe over a value the
   broker holds): an empty message, not retained, QoS 1, on each, then a second hello (as
   rule 16's probe: one client's messages of one QoS keep their order), which ends the look.
   Any look sends that second hello, probes or none, after subscribing claim.py rule 5's
   ``vouch_reads`` (``reads``: the bridge posts on the base topic a stamp seen names), so their
   retained values come before it: it goes once the SUBACK of that SUBSCRIBE is in (aedes
   starts a subscription's replay as it sends its SUBACK). Each hello back ends a round; the
   look asks again, a hello more (``"<id> <n> probe <k>"``), at most MAX_ROUNDS times, while
   a round brings what it did not read yet: a stamp seen since that names another base topic
   (its vouch reads, subscribed then), or any message the broker handed over as held (the
   retain flag, ``_broker_held``) after the bridge's last own live message came back (the
   fence's probe, rule 16, then each hello): that broker is still replaying what it held, and a
   stamp or a vouch read may be among what is still to come (review 94: aedes streams a
   subscription's retained messages beside what follows; the stamp on ``rotor/tower/info``
   came after the first hello, and then a vouch read's value after the second, and a live
   bridge whose tower's controller was off was taken for gone). mosquitto replays all before
   the probe: no more rounds there than the vouch reads ask for (and one after them, their
   values having come after the last hello back). One another filter of the bridge reads is
   not subscribed again, and the broker sent its value once, maybe before the stamp that names
   it: so the look keeps the newest value it hears on every bridge's info and state
   (``Y/bridge/info``, ``Y/bridge/state``: claim.py ``bridge_post``) from its start, whatever
   asked for it, and the verdict consults them (review 90: a live bridge on ``rotor/shack``'s
   ``online``, read by stale.py's ``rotor/+/bridge/state`` before the hello, was kept only once
   the hello was back, so lost, and that bridge taken for gone).
   A probe that came back before it (``probe_back``: an empty live message there during the
   look, whoever sent it) says the topic can be read; a witness whose probe did not is handed
   on as ``unread`` (a timed-out look says nothing of it). Under MQTT 5 the
   owned topics are no-local (the probe would never come back there, and mosquitto 2.0 keeps
   a filter's no-local when it is subscribed again), so the look subscribes a filter of its
   own beside each witness (its last level ``+``, no retained value sent) and unsubscribes it
   before anything of the bridge's goes out. A subscriber sees the probe (an empty message:
   neither ON nor OFF, the least one acts on) once per process, where the broker held nothing
   it could show (the bridge's own value follows, when it can read it). The hook leaves an
   unread witness as the broker holds it (none of the cached value goes out over it) while
   its rotator waits (runtime/kept.py rule 10).
15. Deleting a retained config (``clear_retained``) is said in the log, but a flood of them
   (thousands of configs published under the bridge's node ids) is a few lines: a few at once
   (CLEARS_SAID_AT_ONCE), then one a minute (client.py's FOREIGN_LOG_S, the limiter it hands
   to ``say_clear``) for each of "cleared" and "left alone", the next line saying how many
   were not logged; a look's deletions are one line, naming CLEARS_NAMED topics at most.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

from bridge.interfaces.mqtt.claim import (
    Claim,
    Instance,
    Verdict,
    bridge_post,
    first_look,
    refusal,
    refusal_on,
    standing,
    unusable_stamp,
    vouch_reads,
    yields_to,
)
from bridge.interfaces.mqtt.limiter import EventLimiter

log = logging.getLogger(__name__)

CLEARS_SAID_AT_ONCE = 3  # rule 15
CLEARS_NAMED = 10  # rule 15: topics named in one line
MAX_ROUNDS = 16  # rule 14: the hellos a look sends after its first, at most


@dataclass(frozen=True)
class Outcome:
    """How a look ended: ``refused`` (the error to exit with), or open with ``clears`` to
    delete (``clear``) or to leave alone."""

    refused: str | None
    clear: bool
    clears: list[str]
    heard: dict[str, bytes] | None = None  # rule 14: the witnesses' values (the first open)
    unread: frozenset[str] = frozenset()  # rule 14: the witnesses the broker does not let us read


class FirstLook:
    def __init__(self, claim: Claim, will_topic: str) -> None:
        self.claim = claim
        self._state_topic = will_topic  # ``B/bridge/state``
        self._looks = 0
        self.looking: int | None = None  # the look under way: its number
        # the newest value heard during the look on its info and state, the posts' topics
        # (claim rule 5) and every bridge's info and state (a vouch read's, whichever filter
        # read it: review 90)
        self._seen: dict[str, bytes] = {}
        self._clears: dict[str, None] = {}  # (in the order asked; one asked twice: once)
        self._took_over = False  # for the life of the process (claim rule 3)
        self._witnesses: frozenset[str] = frozenset()  # rule 14: their retained values kept
        self._heard: dict[str, bytes] = {}
        self._opened = False  # a look has let the bridge run: later ones hand nothing on
        self._probes: set[str] = set()  # rule 14: the witnesses whose probe is out, until back
        self.rounds = 0  # rule 14: the hellos this look sent after its first (probes, reads)
        self._late = False  # rule 14: the connection of that look lasts: its replays count
        # claim rule 5: the topics of the posts where another bridge would stand on ours
        self._posted = frozenset(t for p in claim.posts for t in p.topics)
        self.reads: list[str] = []  # claim rule 5: the stamps' bridge posts, read this look
        self._hello_said = False  # rule 14: a retained hello said in the log (once a process)
        self._unusable_said: set[str] = set()  # claim rule 5: posts whose junk stamp was said

    def witness(self, topics: set[str]) -> None:
        """Rule 14: the topics whose values of an earlier run the first look hands on."""
        self._witnesses = frozenset(topics)

    @property
    def witnessed(self) -> list[str]:
        """Rule 14: the witnesses a look under way may probe (none after the first open)."""
        return [] if self._opened else sorted(self._witnesses)

    def _hello(self, n: int, rounds: int = 0) -> bytes:
        """Rule 14: the hello that ends round ``rounds`` of look ``n`` (0: the first)."""
        hello = f"{self.claim.me.id} {n}".encode()
        if rounds == 0:
            return hello
        return hello + (b" probe" if rounds == 1 else f" probe {rounds}".encode())

    def begin(self) -> bytes:
        """A new look: the hello to publish."""
        self._looks += 1
        n = self.looking = self._looks
        self._seen = {}
        self._clears = {}
        self._heard = {}
        self._probes = set()
        self.rounds = 0
        self.reads = []
        return self._hello(n)

    def next_round(self, replaying: bool = False) -> tuple[list[str], list[str], bytes]:
        """Rule 14, once the hello of the round under way is back: the witnesses to probe (the
        first round's alone; none heard: an empty message, not retained, on each; none in a
        look that hands nothing on, after the first open), claim rule 5's vouch reads not asked
        yet this look (to subscribe first), and the hello to send after them, which ends the
        next round. Also a round with neither while the broker is ``replaying`` (it handed
        over what it held after the bridge's last live message came back: aedes, whose
        stamp or vouch read may still come). b"" when the look ends: nothing to
        ask, or MAX_ROUNDS asked already."""
        n = self.looking
        if n is None:
            return [], [], b""
        if self.rounds == 0 and not self._opened:
            self._probes = set(self._witnesses) - set(self._heard)
        probes = sorted(self._probes) if self.rounds == 0 else []
        asked = set(self.reads)
        reads = [t for t in vouch_reads(self.claim, self._seen) if t not in asked]
        if not (probes or reads or replaying):
            return [], [], b""
        if self.rounds >= MAX_ROUNDS:
            log.warning(
                "the first look asked the broker %d times more for what it held, and more "
                "came: judging on what it has%s",
                MAX_ROUNDS,
                f" (not read: {', '.join(reads)})" if reads else "",
            )
            return [], [], b""
        self.rounds += 1
        self.reads += reads
        return probes, reads, self._hello(n, self.rounds)

    def probe_back(self, topic: str, payload: bytes, retained: bool) -> bool:
        """Rule 14: whether a message is a witness's probe come back during the look (an empty
        live message there: that topic can be read; whoever sent it, it proves as much)."""
        if self.looking is None or payload or retained or topic not in self._witnesses:
            return False
        self._probes.discard(topic)
        return True

    def ended_by(self, payload: bytes) -> int | None:
        """The look that a hello heard back ends, if any."""
        n = self.looking
        if n is None:
            return None
        return n if payload == self._hello(n, self.rounds) else None  # (the round's own)

    def retained_hello(self, payload: bytes) -> None:
        """Rule 14: a retained message on the hello topic is no hello (the bridge never
        publishes one retained): it ends nothing, and is said once in the process."""
        if self._hello_said:
            return
        self._hello_said = True
        topic = self.claim.hello_topic
        log.warning(
            "the MQTT broker holds a retained message on %s (%r): the bridge's first look never "
            "publishes one retained there, so it is a forged or left-over message, and ends no "
            "look; delete it (an empty retained message: mosquitto_pub -t '%s' -r -n)",
            topic,
            payload[:40],
            topic,
        )

    def saw(self, topic: str, payload: bytes) -> bool:
        """Whether a message belongs to the look under way (and is kept for its verdict)."""
        if self.looking is None:
            return False
        if topic in self._witnesses:  # rule 14: kept, and judged as an owned topic's value
            self._heard[topic] = payload
            return False
        if topic not in (self.claim.info_topic, self._state_topic):
            if topic in self._posted or bridge_post(topic):  # claim rule 5: kept
                self._seen[topic] = payload
            return False
        self._seen[topic] = payload
        return True

    def defer_clear(self, topic: str) -> bool:
        """Whether a deletion waits for the look's verdict."""
        if self.looking is None:
            return False
        self._clears[topic] = None
        return True

    def end(self, *, timed_out: bool) -> Outcome:
        """The look under way ends (timed out: judged on what was seen)."""
        self.looking = None
        info, state = self._seen.get(self.claim.info_topic), self._seen.get(self._state_topic)
        verdict = first_look(self.claim.me, info, state)
        if verdict is Verdict.OURS and (timed_out or self._took_over):
            verdict = Verdict.TAKE_OVER  # not known to be ours: delete nothing (claim rule 3)
        clears, self._clears = list(self._clears), {}
        other = Instance.parse(info or b"")
        if verdict is Verdict.REFUSE:
            assert other is not None
            message = refusal(self.claim.base_topic, other, live_since_look=False)
            return Outcome(refused=message, clear=False, clears=[])
        claim = self.claim
        self._say_unusable()
        stands = standing(claim.me, claim.base_topic, claim.posts, self._seen)  # claim rule 5
        if stands is not None and stands.live:
            return Outcome(refused=refusal_on(stands), clear=False, clears=[])
        if stands is not None and not self._opened and stands.post.info != claim.info_topic:
            log.warning(
                "%s, gone, left %s on this bridge's topics: taken over",
                stands.other.described(),
                stands.post.info,
            )
        heard, self._heard = (None if self._opened else self._heard), {}
        # rule 14: the hello back before a witness's probe, and nothing held heard there: the
        # broker drops what it sends on that topic (its ACL; a timed-out look says nothing)
        unread = frozenset() if timed_out or heard is None else frozenset(self._probes)
        unread -= set(heard or {})
        self._probes, self.rounds = set(), 0
        self._late = not self._opened  # rule 14: the rest of its connection's replays count
        self._opened = True
        if verdict is Verdict.TAKE_OVER and not (timed_out or self._took_over):
            self._took_over = True
            log.warning(
                "taking over base topic %r from %s, which is offline",
                self.claim.base_topic,
                other.described() if other else "another bridge",
            )
        return Outcome(
            refused=None, clear=verdict is Verdict.OURS, clears=clears, heard=heard, unread=unread
        )

    def _say_unusable(self) -> None:
        """Claim rule 5: a stamp on a post whose base topic no bridge could have is no
        bridge's (``unusable_stamp``): judged as junk, and said once a process for each post."""
        for post in self.claim.posts:
            info = self._seen.get(post.info)
            if post.above or not info or post.info in self._unusable_said:
                continue
            bad = unusable_stamp(info)
            if bad is None:
                continue
            self._unusable_said.add(post.info)
            log.warning(
                "%s names a bridge on base topic %s, which %s: no bridge's stamp (a forged or "
                "damaged message?), ignored; delete it if no rotator of a bridge lives there "
                "(an empty retained message: mosquitto_pub -t '%s' -r -n)",
                post.info,
                ascii(bad[0][:40]),
                bad[1],
                post.info,
            )

    def late(self, topic: str, payload: bytes, retained: bool) -> dict[str, bytes]:
        """Rule 14: a witness the broker replays (``retained``, under MQTT 3.1.1: the caller
        asks only then) after the look that handed the witnesses on, on its connection: what to
        hand on as they were."""
        if not (retained and self._late and self.looking is None and topic in self._witnesses):
            return {}
        return {topic: payload}

    def connection_ended(self) -> None:
        """Rule 14: a new connection's replays are of what this run published."""
        self.looking = None
        self._late = False

    def say_timed_out(self, timeout_s: float) -> None:
        log.warning(
            "no answer to the bridge's first look in %g s (does the broker's ACL deny %s?): "
            "judging by what the broker showed so far, and deleting no stale discovery",
            timeout_s,
            self.claim.hello_topic,
        )

    def live_info(self, payload: bytes) -> str | None:
        """Claim rule 4: the error to exit with, if another live bridge's info means this one
        must go."""
        other = Instance.parse(payload)
        if other is not None and yields_to(self.claim.me, other):
            return refusal(self.claim.base_topic, other, live_since_look=True)
        return None


def say_clears(outcome: Outcome) -> None:
    """Rule 15: a look's deletions, one line."""
    clears = outcome.clears
    if not clears:
        return
    named = ", ".join(clears[:CLEARS_NAMED])
    rest = len(clears) - CLEARS_NAMED
    some = f"{named} and {rest} more" if rest > 0 else named
    if outcome.clear:
        log.info("cleared %d retained topic(s) this bridge no longer makes: %s", len(clears), some)
    else:
        log.warning(
            "left alone %d retained topic(s) this bridge does not generate, as the base "
            "topic was not its own (delete them by hand if that bridge is gone for good): %s",
            len(clears),
            some,
        )


def say_clear(said: EventLimiter, topic: str, *, cleared: bool) -> None:
    """Rule 15: one deletion, ``cleared`` or left alone (another client's config)."""
    left_out = said.admit("cleared" if cleared else "left alone")
    if left_out is None:
        return
    more = f" ({left_out} more like it not logged)" if left_out else ""
    if cleared:
        log.info("cleared %s, a retained topic this bridge no longer makes%s", topic, more)
    else:
        log.warning(
            "%s was published by another client: not ours to delete; left alone%s", topic, more
        )
