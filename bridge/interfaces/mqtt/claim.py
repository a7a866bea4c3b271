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
5. Another bridge on this one's topics, above or below them (attack 18: a bridge on
   ``rotor/tower`` beside a live bridge on ``rotor`` with a rotator ``tower`` started, and one
   target turned both rotors). Each rotator's retained ``R/info`` names its bridge's instance
   too. The first look (rule 2: before anything retained goes out, command topics gated) also
   reads, inside this bridge's own topics only, the ``posts`` where another bridge would say
   who it is: ``X/info`` with ``X/availability`` for each rotator's root and the base topic
   itself (a bridge whose rotator's topic is one of ours), and ``R/bridge/info`` with
   ``R/bridge/state`` for each rotator's root under another name than the base topic (a bridge
   whose base topic is one of our rotators'). Another instance there with ``online`` beside it
   refuses this bridge as rule 2 does (code 2 at a start, a yield after it ran), naming the
   topic; its own instance never does (a restart of this installation), nor junk or an older
   bridge's ``R/info`` without one. An instance that a bridge post here says is not online (its
   last will, its clean stop) is gone, whatever its rotators' availability still says (a bridge
   killed on ``rotor`` leaves its one rotator's ``rotor/availability`` ``online`` beside its
   ``rotor/info``: rule 2 takes the base topic over then, as before); so is one whose rotator
   said ``offline`` (a clean stop): said in the log, never refused. Why only our own topics: an
   earlier try read the bridge info above the base topic, outside what the broker's ACL gives
   this bridge, and a client kept off our topics ended the bridge with a forged info there, and
   a refused bridge's leftovers there refused the older bridge for good; here a refused bridge
   has published nothing retained, and whatever the look reads only a client the ACL lets write
   our own topics could forge. Misjudged: a bridge killed outright above ours leaves its
   rotator's availability ``online`` and refuses this one until it is started and stopped
   again, or that topic deleted (the refusal says so). Not seen: a live bridge whose rotator's
   controller does not answer (its availability ``offline``); two bridges that start at the
   same moment (no live rule 4 here).
"""

from __future__ import annotations

import enum
import json
import os
import socket
import time
from dataclasses import dataclass


@dataclass(frozen=True)
class Instance:
    id: str
    host: str
    pid: int
    started_unix: float

    @staticmethod
    def me(instance_id: str) -> Instance:
        return Instance(instance_id, socket.gethostname(), os.getpid(), round(time.time(), 3))

    def info(self, problems: list[str]) -> str:
        """Rule 1: the retained ``B/bridge/info`` payload."""
        doc = {
            "instance": self.id,
            "host": self.host,
            "pid": self.pid,
            "started": self.started_unix,
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
        return Instance(
            iid,
            host if isinstance(host, str) else "?",
            pid if isinstance(pid, int) and not isinstance(pid, bool) else 0,
            started_unix,
        )

    def described(self) -> str:
        if self.host == "?" and not self.pid:  # (rule 5: a rotator's info names the id alone)
            return f"instance {self.id!r}"
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


def standing(
    me: Instance, posts: tuple[Post, ...], seen: dict[str, bytes]
) -> tuple[Instance, Post, bool] | None:
    """Rule 5: the first other instance the look saw live on one of ``posts`` (``seen``: the
    payloads of their topics), with its post and True; else the first one seen gone there,
    with False (said in the log); None when there is none."""
    gone: set[str] = set()
    found: list[tuple[Instance, Post, bool]] = []
    for post in posts:
        info = seen.get(post.info)
        other = Instance.parse(info) if info else None
        if other is None or other.id == me.id:
            continue
        live = (seen.get(post.live) or b"").strip() == b"online"
        if post.bridge and not live:
            gone.add(other.id)  # its last will, or its clean stop
        found.append((other, post, live))
    for other, post, live in found:
        if live and other.id not in gone:
            return other, post, True
    return (found[0][0], found[0][1], False) if found else None


def refusal_on(other: Instance, post: Post) -> str:
    """Rule 5's error: another bridge on one of this bridge's topics."""
    why = (
        f"{post.live} says online"
        if post.bridge
        else f"{post.live} says online (killed outright, a bridge leaves it so: then start "
        "that bridge and stop it, or delete that retained topic)"
    )
    return (
        f"another bridge runs on this bridge's topics: {other.described()} says so on "
        f"{post.info!r}, and {why}. Two bridges whose topics lie one under the other turn both "
        f"rotors on one target: stop the other one, or give each its own mqtt.base_topic, no "
        f"other bridge's topics under it"
    )


@dataclass(frozen=True)
class Post:
    """Rule 5: where another bridge would say who it is on this bridge's topics (``info``), and
    the topic beside it that says whether it is live (``live``, ``online``); ``bridge``: a
    bridge's own ``bridge/info`` (its ``bridge/state`` is its last will), not a rotator's."""

    info: str
    live: str
    bridge: bool = False


@dataclass(frozen=True)
class Claim:
    """What the client needs to take its first look (client.py rule 14)."""

    me: Instance
    base_topic: str
    info_topic: str
    hello_topic: str
    posts: tuple[Post, ...] = ()  # rule 5
