"""One live bridge per base topic (issue 14, item 11). Pure: payloads in, a verdict out; the
client (client.py rule 14) asks at the right moments.

Two bridges on one base topic (a second host given a copy of the configuration, a test
instance beside the real one) publish over each other's state, put their own values back
against each other for ever, and each deletes the other's Home Assistant discovery as stale:
0 of 26 configs were left.

Rules:
1. Each bridge says who it is, retained, on ``B/bridge/info``: its instance id (the MQTT
   client id: unique per installation and stable across its restarts,
   MqttSettings.effective_client_id), host, process id and start time, with the problems the
   broker made (client.py rule 11).
2. First look: on every connect, before it publishes or deletes anything, the bridge reads the
   retained ``B/bridge/info`` and ``B/bridge/state`` the broker holds. Another instance's
   info with the state ``online``: that bridge is live, and this one refuses to run (exit code
   2, naming it). With ``offline`` (its last will, or its clean stop) or no state: it is gone,
   and this one takes the base topic over. No info, or its own: the base topic is its own.
   (A bridge that crashed less than 1.5 keepalives ago still looks live: the broker has not
   sent its will yet. The refusal says so.)
3. Discovery: configs under the bridge's node ids that it no longer generates (a rotator
   removed from the configuration) are deleted only when the base topic was its own at the
   first look, and only those the broker held then: a config published later is another
   client's, never this bridge's to delete. After a take-over the other instance's configs
   are left alone and named in the log.
4. Live: another instance's info arriving while the bridge runs means two bridges passed
   their first looks at the same moment. The younger one (the later start; an equal start:
   the greater instance id) yields; the older puts its own info back (client.py rule 10) and
   goes on. A bridge refused at a reconnect's first look (rule 2), after it ran, yields the
   same way (a review: mid-turn, a broker back with another's info and ``online``, forged or
   a second bridge started during the outage, ended it for good with no stop). Yielding
   stops every rotator at once, and again once no front end can move one after it (a review:
   stopped only then, a turn went on while the web console took up to 10 s to close; another:
   a front end still open then turned it again, so nothing but a halt is taken meanwhile), and
   exits with code 1, which systemd restarts:
   the next start's first look (rule 2) decides on what the broker holds, refusing (code 2)
   while the other is there and online. One message proves no other bridge (an attack pass:
   one forged, non-retained info on ``B/bridge/info`` ended a bridge mid-turn for good, code
   2, its stop express with it, and the STOP after it reached nothing: the rotor ran on).
5. One bridge per tree of topics, not only per base topic (attack 18: a second bridge on
   ``rotor/tower``, the first bridge's rotator ``tower``, passed its look, which read only
   ``rotor/tower/bridge/info``; a target on ``rotor/tower/target`` then turned both rotors, and
   the two put their states back over each other's). Rule 1's info names the bridge's
   ``topics``: each rotator's and group's topic (``R``, ``G``). A topic ``inner`` lies in
   ``outer``'s tree when it is ``outer`` itself or under it by one of the names a bridge uses
   under a root (``names``: a rotator's ``target``, ``lock``, ``option``..., the base topic's
   ``bridge`` and ``spots``; one namespace, topics.py ``_check_suffixes``); two bridges overlap
   when a topic of one (its base topic or one of its ``topics``) lies in the tree of one of the
   other's (``overlap``). A bridge on ``rotor/site2`` beside one on ``rotor`` does not
   (``site2`` is no such name: its topics are none of the other's; review 93 keeps it working,
   stale.py rule 3); one on ``rotor/tower`` beside the rotator ``rotor/tower`` does, and so does
   one on ``rotor`` whose rotator ``x`` is ``rotor/x`` beside a bridge on ``rotor/x``.
   The first look reads, besides its own, the info and state of every topic that is its base
   topic's or a rotator's or group's topic or above one (``watched``: ``rotor`` and
   ``rotor/tower`` for base ``rotor/tower``; ``rotor/x`` for a rotator ``rotor/x``): another
   instance there, ``online`` (rule 2: an ``offline`` or missing state is a bridge gone, whose
   leftovers never refuse a start), whose topics overlap this bridge's, refuses the start as
   rule 2 does (code 2), naming ``mqtt.base_topic`` and both topics; a reconnect's look (the
   bridge ran) judges it as one met while running, below (a bridge started during the outage
   is the younger: it yields, not this one). An info without ``topics`` (a bridge from before
   them) counts as its base topic alone. While the bridge runs it keeps reading them: another
   instance that comes online there overlapping it (two started at once; one of an older
   version, which looks only at its own base topic) makes the younger yield as rule 4; the
   older says it, in the log at ERROR and on ``B/bridge/info`` while it lasts, and goes on (it
   cannot move the other off its topics, and stopping its own rotators would leave them to the
   other's targets with no bridge to stop them). Not seen: a bridge whose base topic is none
   of the watched ones (a rotator of its with a ``topic`` of its own, outside its base topic;
   or a base topic under one of this bridge's names, ``rotor/tower/lock``): the broker's ACL
   (docs/deployment.md) is the guard there. The younger yields as rule 4's, with one
   difference (review 67: copied from rule 4, it left its ``B/bridge/state`` retained
   ``online`` beside an info naming its topics, and the older bridge's next start, an upgrade
   or a reboot, was refused for good, code 2): under rule 5 that state topic is its own, so it
   says ``offline`` there, and on the availability of each of its rotators and groups whose
   topic is none of the other's (look.py ``left_offline``), before it goes.
6. What a client may forge, and where (review 67). A watched topic inside the bridge's own
   tree (its rotators' topics, anything under its base topic: ``within``) is written only by
   whoever the broker's ACL lets write there, who could forge its own ``B/bridge/info`` as
   well: an info there is believed as rule 4 believes its own. One above it
   (``shack/bridge/info`` for base ``shack/rotor``) is outside: a client the ACL keeps off
   ``shack/rotor/#`` but lets write ``shack/#`` (a home-automation user) forged an older
   info naming ``shack/rotor``, and the running bridge yielded, every restart refused after.
   A real bridge overlapping this one from above has a rotator on this bridge's base topic,
   and so publishes that rotator's ``R/info`` there, inside this bridge's tree, naming its
   rotator id (``rotator_there``: an id that is none of this bridge's own rotators' ids,
   ``rotator_ids``: its leftover of an earlier run, its one rotator on the base topic before
   it had several, names one of them). So an info
   outside counts only while the ``R/info`` on this bridge's base topic is another rotator's
   (the evidence topic, read on every look and while the bridge runs), and only as that
   overlap: its rotator on this bridge's base topic, where its info names that topic, or no
   topics at all (a station of the version before rule 5, whose rotator ``tower`` holds
   ``rotor/tower/...``: review 67, the likeliest order on the air, a new host installed before
   the station is upgraded). Otherwise it refuses nothing, ends nothing and is said nowhere.
   Not seen from this side: another bridge above whose rotator on this base topic has the id
   of one of this bridge's rotators (its ``R/info`` looks like this bridge's leftover), or
   whose rotator's topic is one of this bridge's rotators' topics (not its base topic); the
   other bridge, whose tree holds this one's info, sees this one (it yields if the younger,
   else it says it), and its own start beside this one is refused.
7. What is said of an overlapping bridge is bounded (review 67: a watched state flapping
   ``online`` and ``offline`` wrote two log lines a flap and republished ``B/bridge/info``
   each time): the log has a few lines of each watched base topic at once, then one a minute,
   saying how many it left out (client.py's limiter, handed to look.py); ``B/bridge/info``
   says the last verdict, at most once a second (client.py OVERLAPS_SAID_EVERY_S).
"""

from __future__ import annotations

import enum
import json
import os
import socket
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

MAX_TOPICS = 4096  # rule 5: topics read from an info at most (a forged one is junk past them)


@dataclass(frozen=True)
class Instance:
    id: str
    host: str
    pid: int
    started_unix: float
    topics: tuple[str, ...] = ()  # rule 5: its rotators' and groups' topics

    @staticmethod
    def me(instance_id: str, topics: Iterable[str] = ()) -> Instance:
        return Instance(
            instance_id, socket.gethostname(), os.getpid(), round(time.time(), 3), tuple(topics)
        )

    def info(self, problems: list[str]) -> str:
        """Rule 1: the retained ``B/bridge/info`` payload."""
        doc = {
            "instance": self.id,
            "host": self.host,
            "pid": self.pid,
            "started": self.started_unix,
            "topics": list(self.topics),
            "problems": problems,
        }
        return json.dumps(doc, separators=(",", ":"))

    @staticmethod
    def parse(payload: bytes) -> Instance | None:
        """The instance an info payload names; None for anything else (an older bridge's
        ``{"problems": [...]}``, junk, an empty deletion). Junk is anything another client may
        retain there: JSON nested past the parser's depth, a start past a float's range (an
        attack pass: each raised in the first look, on paho's thread, at every connect, and the
        bridge never ran while the forged message stayed on the broker)."""
        try:
            doc = json.loads(payload)
        except (ValueError, RecursionError):  # (UnicodeDecodeError is a ValueError)
            return None
        if not isinstance(doc, dict):
            return None
        iid, host, pid, started = (doc.get(k) for k in ("instance", "host", "pid", "started"))
        if not isinstance(iid, str) or not iid:
            return None
        try:
            started_unix = float(started) if isinstance(started, int | float) else 0.0
        except OverflowError:
            return None
        listed = doc.get("topics")
        topics = (
            tuple(t for t in listed[:MAX_TOPICS] if isinstance(t, str) and t)
            if isinstance(listed, list)
            else ()
        )
        return Instance(
            iid,
            host if isinstance(host, str) else "?",
            pid if isinstance(pid, int) and not isinstance(pid, bool) else 0,
            started_unix,
            topics,
        )

    def described(self) -> str:
        return f"instance {self.id!r} on host {self.host!r} (pid {self.pid})"


class Verdict(enum.Enum):
    OURS = "ours"  # no bridge before, or this installation itself
    TAKE_OVER = "take over"  # another instance's, gone
    REFUSE = "refuse"  # another instance, live


def first_look(me: Instance, info: bytes | None, state: bytes | None) -> Verdict:
    """Rule 2."""
    other = Instance.parse(info) if info else None
    if other is None or other.id == me.id:
        return Verdict.OURS
    return Verdict.REFUSE if (state or b"").strip() == b"online" else Verdict.TAKE_OVER


def yields_to(me: Instance, other: Instance) -> bool:
    """Rule 4: whether ``me`` is the younger of two live bridges and must go."""
    if other.id == me.id:
        return False
    return (me.started_unix, me.id) > (other.started_unix, other.id)


def refusal(base_topic: str, other: Instance, live_since_look: bool) -> str:
    """The error a refusing bridge exits with."""
    how = (
        "started at the same moment and is the older"
        if live_since_look
        else "is online (or crashed less than 1.5 keepalives ago: then start again in a minute)"
    )
    return (
        f"another bridge runs on base topic {base_topic!r}: {other.described()} {how}. "
        f"Two bridges on one base topic overwrite each other's state and Home Assistant "
        f"discovery: stop the other one, or give this one its own mqtt.base_topic"
    )


def lies_in(inner: str, outer: str, names: frozenset[str]) -> bool:
    """Rule 5: whether ``inner`` is ``outer`` or under it by one of a root's names."""
    if inner == outer:
        return True
    if not inner.startswith(outer + "/"):
        return False
    return inner[len(outer) + 1 :].split("/", 1)[0] in names


def overlap(
    mine: Sequence[str], theirs: Sequence[str], names: frozenset[str]
) -> tuple[str, str] | None:
    """Rule 5: a topic of ``mine`` and one of ``theirs`` of which one lies in the other's
    tree, if any."""
    for m in mine:
        for t in theirs:
            if lies_in(m, t, names) or lies_in(t, m, names):
                return m, t
    return None


def above(topic: str) -> list[str]:
    """Rule 5: ``topic`` and every topic above it (``a``, ``a/b`` for ``a/b``)."""
    levels = topic.split("/")
    return ["/".join(levels[:i]) for i in range(1, len(levels) + 1)]


def overlapping(
    base_topic: str, where: str, other: Instance, mine: str, theirs: str, *, live: bool = False
) -> str:
    """Rule 5: the error a bridge refuses (or yields) with, one line; ``live``: met while
    running (what the older one says)."""
    how = (
        "came online while this one runs"
        if live
        else "is online (or crashed less than 1.5 keepalives ago: then start again in a minute)"
    )
    ours = f"{'base' if mine == base_topic else 'rotator or group'} topic {mine!r}"
    its = f"{'base' if theirs == where else 'rotator or group'} topic {theirs!r}"
    what = (
        f"this bridge's {ours} is its {its}"
        if mine == theirs
        else f"this bridge's {ours} and its {its} share topics"
    )
    return (
        f"another bridge's topics overlap this one's (mqtt.base_topic {base_topic!r}): "
        f"{other.described()}, base topic {where!r}, {how}, and {what}. A target on one turns "
        f"both rotors and each overwrites the other's state: stop the other one, or give this "
        f"one an mqtt.base_topic (and rotator topics) outside the other's"
    )


def within(topic: str, roots: Sequence[str]) -> bool:
    """Rule 6: whether ``topic`` is one of ``roots`` or anywhere under one (what an ACL that
    gives a bridge ``root/#`` lets it, and no one kept off it, write)."""
    return any(topic == r or topic.startswith(r + "/") for r in roots)


def rotator_there(info: bytes | None, mine: frozenset[str]) -> bool:
    """Rule 6: whether ``info`` (the retained ``R/info`` on this bridge's base topic) is another
    bridge's rotator's: it names a rotator id, none of ``mine`` (this bridge's rotators' ids:
    its own leftover of an earlier run names one)."""
    if not info:
        return False
    try:
        doc = json.loads(info)
    except (ValueError, RecursionError):
        return False
    rid = doc.get("id") if isinstance(doc, dict) else None
    return isinstance(rid, str) and bool(rid) and rid not in mine


@dataclass(frozen=True)
class Claim:
    """What the client needs to take its first look (client.py rule 14)."""

    me: Instance
    base_topic: str
    info_topic: str
    hello_topic: str
    # rule 5: the names a bridge uses under a root (topics.py ``Topics.names``); none: rule 5
    # is not looked at (the base topic alone, rule 2)
    names: frozenset[str] = field(default_factory=frozenset)
    # rule 6: this bridge's rotators' ids (a retained R/info naming one is its own leftover)
    rotator_ids: frozenset[str] = field(default_factory=frozenset)

    @property
    def mine(self) -> list[str]:
        """Rule 5: this bridge's topics: its base topic, its rotators' and groups'."""
        return [self.base_topic, *(t for t in self.me.topics if t != self.base_topic)]

    @property
    def watched(self) -> list[str]:
        """Rule 5: the base topics whose info and state the looks read, besides its own."""
        if not self.names:
            return []
        found = {p for t in self.mine for p in above(t)}
        found.discard(self.base_topic)
        return sorted(found)

    def outside(self, where: str) -> bool:
        """Rule 6: whether a watched base topic is outside this bridge's own tree (above its
        base topic): a client the ACL keeps off that tree may write there."""
        return not within(where, self.mine)
