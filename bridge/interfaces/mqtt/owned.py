"""The owned-topic judge: whether a retained value heard on one of the bridge's own topics is
its own, and when to put its own back and say so. Pure: a clock in, decisions out; no paho
client, no lock (the client asks under its own lock, client.py).

Rules (numbered as the bridge's MQTT rules; client.py keeps the index of all of them):
10. The bridge owns its retained topics (``watch``: state, status, lock and option states, its
   online/offline): it subscribes to them (MQTT 5: without its own messages) and a value there that
   it did not publish, from another client, is replaced with its own at once (at most once per
   FOREIGN_FIX_S per topic, ``put_back``; a live one that comes sooner is put back when that
   interval is over, ``owed``: a review found a second stray ``lock/state OFF`` within 2 s of
   the first left on the broker for as long as the lock stayed on) and logged once a minute
   (FOREIGN_LOG_S) per topic: a stray retained ``lock/state OFF`` must not tell a dashboard the
   lock is off while it is on. Live is what another client publishes while the bridge listens:
   MQTT sends it with the retain flag clear (MQTT 3.1.1 always; MQTT 5 because the bridge
   subscribes without retain-as-published), and a value the broker held with it set, for a
   subscription it answers. A held value that comes within the interval is not owed: it is
   what the broker held when it answered a subscription, older than the put-back already sent
   (a broker that answers a second subscription late sends it again). The
   availability and option-state topics are read by stale.py's filters too, with
   retain-as-published: under MQTT 5 a stray there comes twice, the owned copy first from
   mosquitto (a review); in the other order it is put back twice, 2 s apart, and a broker that
   merges the two copies with the flag set owes nothing, as before. A stale filter that is an
   owned one (one rotator on the base topic) is not subscribed twice (client.py
   ``_filters``): mosquitto keeps a filter's first options, and the stray was never owed. Nothing
   is owed once the bridge has sent its own value again (``sent``, a new connection). What
   the broker held from before the connection (our own last will, a value of a run that ended)
   arrives within SETTLE_AFTER_CONNECT_S of it, or before the connection's first look has ended
   (``settling``: the broker sends what it held before the hello comes back, look.py rule 14), and
   is put back without a word: only a live stranger is news. (An attack pass: with 20,000 retained
   topics planted under the base topic, the bridge's own ``offline`` of its last run came 1.5 s
   after the connect and was said as another client's, "a second bridge on this base topic?", on
   every start.) Under MQTT 3.1.1 the bridge hears its own messages too, in the order sent: one it
   sent on this connection and has not heard back yet (``sent``) is no stranger, however far the
   connection lags behind (a flood of commands read before them): every one is kept until it or a
   later one comes back (the broker keeps the order, so the older ones were dropped), as a keyed
   hash of its payload (``_digest``: a stranger cannot aim at one, and a backlog of long payloads
   costs no memory); ECHOES_KEPT only bounds memory against a broker that loses our messages without
   end. The bridge's own last will (``will``, the broker publishes it when the bridge's connection
   dies, and at its own shutdown, right before it closes the connection) is put back, and said only
   if the connection outlives it (client.py, WILL_OUTLIVED_S): then it was a stranger's.
   Whether a topic is owned (``owns``) gives MQTT's answer for the filters watched (paho's
   ``topic_matches_sub``, ``$`` topics included), from a set of the exact topics and one
   pattern compiled for the wildcard filters at ``watch``: every message heard and every
   publish under MQTT 3.1.1 asks it, hundreds of them at start-up.
"""

from __future__ import annotations

import hashlib
import os
import re
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

from paho.mqtt.subscribeoptions import SubscribeOptions

FOREIGN_FIX_S = 2.0
FOREIGN_LOG_S = 60.0
SETTLE_AFTER_CONNECT_S = 1.0  # retained values that arrive this soon after a connect are old
# MQTT 3.1.1: echoes per topic sent and not yet heard back, at most (rule 10: memory only, about
# 50 bytes each, for a broker that never sends them back: an ACL that drops what we may read).
# A flood of 10,000 targets read before them lags the main connection by one status per target
ECHOES_KEPT = 16384
_KEY = os.urandom(16)  # rule 10: per process, so nobody else can make a payload hash alike


def _digest(data: bytes) -> bytes:
    return hashlib.blake2b(data, digest_size=8, key=_KEY).digest()


@dataclass(frozen=True)
class PutBack:
    """What to do about a stranger's value: ``send`` our own again now; ``say`` so in the log."""

    send: bool
    say: bool


class OwnedTopics:
    def __init__(self, clock: Callable[[], float], *, hears_own: bool) -> None:
        """``hears_own``: the broker sends the bridge its own messages back (MQTT 3.1.1; MQTT 5
        subscribes with no-local)."""
        self._clock = clock
        self.hears_own = hears_own  # (set again when mqtt.protocol "auto" steps down)
        self.filters: list[str] = []
        self._owns = matcher([])
        self._echoes: dict[str, deque[bytes]] = {}  # digests sent, not heard back (hears_own)
        self.will: tuple[str, bytes] | None = None  # the bridge's own last will
        self._fixed_at: dict[str, float] = {}
        self._owed: set[str] = set()  # strangers' values come within FOREIGN_FIX_S (``owed``)
        self._logged_at: dict[str, float] = {}
        self.connected_at = -1e18  # the clock at the last accepted connection

    def watch(self, filters: list[str]) -> None:
        self.filters = list(filters)
        self._owns = matcher(self.filters)

    def subscriptions(self) -> list[tuple[str, int | SubscribeOptions]]:
        """What to subscribe to on every connect: MQTT 5 without our own messages back
        (no-local); MQTT 3.1.1 hears them, and ``ours`` knows them."""
        if self.hears_own:
            return [(f, 0) for f in self.filters]
        mine = SubscribeOptions(qos=0, noLocal=True, retainAsPublished=False)  # (live or held)
        return [(f, mine) for f in self.filters]

    def owns(self, topic: str) -> bool:
        return self._owns(topic)

    def connected(self) -> None:
        """A new connection: what was in flight before is gone with the old one, and every
        value of ours goes out again (nothing is owed)."""
        self.connected_at = self._clock()
        self._echoes.clear()
        self._owed.clear()

    def sent(self, topic: str, data: bytes) -> None:
        """The bridge published ``data`` on ``topic``: when it comes back, it is ours; and no
        put-back is owed there any more (a review: the lock released meanwhile, the owed
        put-back told every subscriber the new value a second time)."""
        self._owed.discard(topic)
        if self.hears_own and self.filters and self.owns(topic):
            self._echoes.setdefault(topic, deque(maxlen=ECHOES_KEPT)).append(_digest(data))

    def ours(self, topic: str, payload: bytes, held: bytes) -> bool:
        """Whether ``payload`` heard on an owned ``topic`` is the bridge's: an echo of one it
        sent (the older ones before it are gone: the broker keeps the order), or the value it
        holds."""
        echoes = self._echoes.get(topic)
        if echoes:
            digest = _digest(payload)
            if digest in echoes:
                while echoes.popleft() != digest:
                    pass
                return True
        return payload == held

    def is_will(self, topic: str, payload: bytes) -> bool:
        """Whether this is the bridge's own last will (put back without a word, rule 10)."""
        return self.hears_own and (topic, payload) == self.will

    def put_back(self, topic: str, *, live: bool, settling: bool = False) -> PutBack:
        """A stranger's value on ``topic``, ``live`` or one the broker held (its retain flag
        set): ours again at most once per FOREIGN_FIX_S (a live one sooner: when the interval is
        over, ``owed``), said at most once per FOREIGN_LOG_S, and not at all just after a
        connect or while ``settling`` (the first look of the connection under way)."""
        now = self._clock()
        if now - self._fixed_at.get(topic, -FOREIGN_FIX_S) < FOREIGN_FIX_S:
            if live:
                self._owed.add(topic)  # put back when the interval is over (``owed``)
            return PutBack(send=False, say=False)
        self._fixed_at[topic] = now
        self._owed.discard(topic)
        if settling or now - self.connected_at < SETTLE_AFTER_CONNECT_S:
            return PutBack(send=True, say=False)
        if now - self._logged_at.get(topic, -FOREIGN_LOG_S) < FOREIGN_LOG_S:
            return PutBack(send=True, say=False)
        self._logged_at[topic] = now
        return PutBack(send=True, say=True)

    @property
    def owing(self) -> bool:
        """Whether a put-back is owed (``owed``), read without the client's lock."""
        return bool(self._owed)

    def owed(self) -> list[str]:
        """The topics whose stranger's value came within FOREIGN_FIX_S of the last put-back and
        whose interval is over now: to be put back now (rule 10; each counts as a put-back)."""
        if not self._owed:
            return []
        now = self._clock()
        due = [t for t in self._owed if now - self._fixed_at[t] >= FOREIGN_FIX_S]
        for topic in due:
            self._owed.discard(topic)
            self._fixed_at[topic] = now
        return due


def matcher(filters: list[str]) -> Callable[[str], bool]:
    """Whether a topic is one ``filters`` match, as MQTT matches them (rule 10's ``owns``;
    client.py rule 14's filters subscribed with retain-as-published): a set of the exact
    filters and one pattern compiled for the wildcard ones."""
    exact = frozenset(f for f in filters if not _is_wild(f))
    wild = [f for f in filters if _is_wild(f)]
    pattern = re.compile("|".join(map(_pattern, wild)), re.DOTALL) if wild else None

    def matches(topic: str) -> bool:
        return topic in exact or (pattern is not None and pattern.fullmatch(topic) is not None)

    return matches


def _is_wild(topic_filter: str) -> bool:
    return any(level in ("+", "#") for level in topic_filter.split("/"))


def _pattern(topic_filter: str) -> str:
    """One wildcard filter as a regular expression for the whole topic, as MQTT matches: ``+``
    one level (an empty one too), a last ``#`` the parent level and everything under it, and a
    wildcard first level never a topic that starts with ``$``."""
    levels = topic_filter.split("/")
    tail = ""
    if levels[-1] == "#":
        levels = levels[:-1]
        tail = "(?:/.*)?" if levels else ".*"
    body = "/".join("[^/]*" if level == "+" else re.escape(level) for level in levels)
    head = r"(?!\$)" if not levels or levels[0] == "+" else ""
    return f"(?:{head}{body}{tail})"
