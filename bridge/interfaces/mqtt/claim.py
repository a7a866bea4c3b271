"""One live bridge per base topic (issue 14, item 11). Pure: payloads in, a verdict out; the
client (client.py rule 14) asks at the right moments.

Two bridges on one base topic (a second host given a copy of the configuration, a test
instance beside the real one) publish over each other's state, put their own values back
against each other for ever, and each deletes the other's Home Assistant discovery as stale:
0 of 26 configs were left.

Rules:
1. Each bridge says who it is, retained, on ``B/bridge/info``: its instance id (the MQTT
   client id: unique per installation and stable across its restarts,
   MqttSettings.effective_client_id), host, process id and start time, and its installation
   (rule 5: ``installation``), with the problems the broker made (client.py rule 11).
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
5. Another bridge on this one's topics, above or below them (attack 18: a bridge on ``rotor/tower``
   beside a live bridge on ``rotor`` with a rotator ``tower`` started, and one target turned both
   rotors). Each rotator's retained ``R/info`` says, under ``bridge`` (``stamp``), its bridge's
   instance and base topic; never in the bridge info's own shape, so rules 2 and 4 never take it
   for a bridge's info (review 77: a bridge on ``rotor/bridge`` put its one rotator's ``R/info`` on
   a live bridge's ``rotor/bridge/info``, read as a second bridge started at 0, and the live one
   yielded). The first look (rule 2: before anything retained goes out, command topics gated) also
   reads, inside this bridge's own topics only, the ``posts`` where another bridge would say who it
   is: ``X/info`` for each rotator's and group's root and the base topic itself (a bridge whose
   rotator's topic is one of ours), and ``R/bridge/info`` for each rotator's and group's root under
   another name than the base topic (a bridge whose base topic is one of our rotators' or groups';
   review 77: a bridge with a group ``tower`` started beside a live bridge on ``rotor/tower``).
   What stands on a post says what it is: a bridge's info (on ``Y/bridge/info``: a bridge on ``Y``)
   is live by ``Y/bridge/state`` beside it, its last will; a rotator's by ``X/availability`` beside
   it. So a live bridge's own ``rotor/bridge/info``, read by a bridge on ``rotor/bridge`` as its
   rotator's post, refuses it (review 77: it was read as a rotator's, without availability, and
   taken for gone), and the other way round. Another instance live there refuses this bridge as
   rule 2 does (code 2 at a start, a yield after it ran), naming the topic; its own installation
   never does (a restart; the stamp's ``installation``, a hash of the machine id, host and state
   file's resolved path (``state_path``; review 85: hashed as written, two installations run
   from two directories with ``state_file = "state.json"`` were one), the same whatever the base
   topic: review 82, a station killed outright on ``rotor`` and
   given its one remaining rotator's ``rotor/tower`` as base topic was refused for good by its own
   ``rotor/tower/info``, stamped with the client id it had on ``rotor``), nor junk or an older
   bridge's ``R/info`` without a stamp, nor a rotator whose bridge's base topic is this bridge's
   own: a bridge on our base topic is rules 2 and 4's, by ``B/bridge/info`` (review 77: a station
   that took its base topic over from a computer killed outright was refused for good by that
   computer's rotators' ``R/info`` and ``online``, left retained, once one of them was configured
   again), nor a stamp whose base topic no bridge could have (one the configuration refuses as
   ``mqtt.base_topic``, settings/mqtt.py ``check_topic``: a wildcard, a NUL or a lone surrogate,
   a ``$``, past MQTT's length): junk, no stamp (``stamped``), nothing read for it, said once a
   process for its post (``unusable_stamp``; review 94: ``"base_topic": "#"`` on ``rotor/info``
   made the vouch read ``#/bridge/info``, which paho refused on its thread, or the broker
   dropped the connection for, at every connect: the bridge never came online). An instance
   is gone on a base topic where a bridge post says it is not online (its last
   will, its clean stop), there alone, whatever its rotators of that base topic still say (a bridge
   killed on ``rotor/tower/x`` leaves its rotator's availability ``online``; review 77: one set of
   gone ids for every place took a live station on ``rotor`` for gone by its old, offline bridge
   state on ``rotor/tower``, where it had run before); so is a rotator that said ``offline`` (a
   clean stop): said in the log, never refused, unless its bridge is live: the look reads
   ``A/bridge/info`` and ``A/bridge/state`` for each topic ``A`` above the base topic (``above``
   posts) and, once its hello is back, those on the base topic each such stamp names
   (``vouch_reads``, subscribed before a second hello that ends the look; review 85: a live
   bridge on ``shack`` whose rotator has ``topic = "rotor/tower"``, or one on ``rotor`` whose
   rotator's topic is the looking bridge's rotator's own ``topic``, its controller off, was
   taken for gone, and one target turned both rotors; the look keeps the newest value of every
   bridge's info and state it hears from its start, ``bridge_post``, as one another filter of
   the bridge reads is sent once, maybe before the stamp: review 90, a live bridge on
   ``rotor/shack``'s ``online``, read by stale.py's ``rotor/+/bridge/state`` before the
   looking bridge on ``rotor`` asked for it, was lost), and a bridge info there naming the
   stamp's instance, ``online`` beside it, makes the stamp live whatever the rotator says
   (review 77: a live bridge whose rotator's controller is switched off, ``offline``, was taken
   for gone and a second bridge ran on its topics). What stands above (or on the stamp's base
   topic) never refuses by itself nor takes anything for gone, and never vouches for a
   stamp that says its bridge stopped: at a clean stop each ``R/info`` and ``G/info`` is left
   stamped ``"stopped": true`` (``stopped``; review 85: a retained ``online`` forged on a gone
   bridge's ``A/bridge/state``, above a station's topics, vouched for that bridge's leftover
   ``R/info`` and refused the station for as long as it stayed). Why posts on our own topics
   only: an earlier try read the bridge info above the base topic as a post, outside what the
   broker's ACL gives this bridge, and a client kept off our topics ended the bridge with a forged
   info there, and a refused bridge's leftovers there refused the older bridge for good; here a
   refused bridge has published nothing retained, and what refuses needs a stamp on our own topics,
   which only a client the ACL lets write them could forge (one above only vouches for it).
   Misjudged: a bridge killed outright above ours leaves its rotator's availability ``online`` and
   refuses this one until it is started and stopped again, or that topic deleted (the refusal says
   so). So does a station's own ``R/info`` once its host name changed (review 85: a container
   made anew, whose host name is its new id; left so: without the host name, containers of one
   image, its machine id baked in or none, would be one installation on every computer, and a
   bridge on another station's rotator topic would run). Not seen (review 77): a live bridge
   whose rotator's controller does not answer where the ACL denies this bridge the topics
   above; two bridges that start at the same moment (no live rule 4 here). A group's
   ``G/info`` is stamped as a rotator's ``R/info`` is
   (payloads.py ``group_info_json``), ``G/availability`` beside it: a bridge started on a live
   bridge's group topic ``B/<group id>`` is refused by it (review 77: a group published no info,
   and that bridge ran), as the group's bridge started second is; ``is_group_info`` keeps it
   from reading as a removed rotator's (interfaces/mqtt/stale.py rule 4) or a rotator to a
   remote.
"""

from __future__ import annotations

import enum
import hashlib
import json
import os
import socket
import time
from dataclasses import dataclass, replace
from pathlib import Path

from bridge.settings.mqtt import check_topic


@dataclass(frozen=True)
class Instance:
    id: str
    host: str
    pid: int
    started_unix: float
    installation: str = ""  # rule 5: the same across base topics (``installation``); "": none

    @staticmethod
    def me(instance_id: str, installation: str = "") -> Instance:
        return Instance(
            instance_id, socket.gethostname(), os.getpid(), round(time.time(), 3), installation
        )

    def info(self, problems: list[str]) -> str:
        """Rule 1: the retained ``B/bridge/info`` payload."""
        doc = {
            "instance": self.id,
            "host": self.host,
            "pid": self.pid,
            "started": self.started_unix,
            "problems": problems,
        }
        if self.installation:  # (rule 5: as each rotator's stamp says it)
            doc["installation"] = self.installation
        return json.dumps(doc, separators=(",", ":"))

    @staticmethod
    def parse(payload: bytes) -> Instance | None:
        """The instance a bridge's info payload names; None for anything else (an older
        bridge's ``{"problems": [...]}``, a rotator's ``R/info``: no ``started``, its stamp
        under ``bridge``, rule 5; junk, an empty deletion). Junk is anything another client may
        retain there: JSON nested past the parser's depth, a start past a float's range (an
        attack pass: each raised in the first look, on paho's thread, at every connect, and the
        bridge never ran while the forged message stayed on the broker). Only the bridge info's
        own shape (an instance and a start) names one (review 77: a rotator's ``R/info`` on
        ``rotor/bridge/info``, a bridge's on ``rotor/bridge``, read as a second bridge on
        ``rotor`` started at 0, ended the live bridge there)."""
        doc = _json(payload)
        if doc is None:
            return None
        iid, host, pid, started = (doc.get(k) for k in ("instance", "host", "pid", "started"))
        if not isinstance(iid, str) or not iid:
            return None
        if not isinstance(started, int | float) or isinstance(started, bool):
            return None
        try:
            started_unix = float(started)
        except OverflowError:
            return None
        where = doc.get("installation")
        return Instance(
            iid,
            host if isinstance(host, str) else "?",
            pid if isinstance(pid, int) and not isinstance(pid, bool) else 0,
            started_unix,
            where if isinstance(where, str) else "",
        )

    @staticmethod
    def stamped(payload: bytes) -> tuple[Instance, str] | None:
        """Rule 5: the instance (with its ``installation``, when it says one) and base topic a
        rotator's ``R/info`` names (``stamp``); None for anything else (a bridge's info, an
        older bridge's ``R/info``, junk, a stamp whose base topic no bridge could have:
        ``unusable_stamp``)."""
        mark = _mark(payload)
        if mark is None or _no_base_topic(mark[1]) is not None:
            return None
        iid, base, where = mark
        return Instance(iid, "?", 0, 0.0, where), base

    def same_installation(self, other: Instance) -> bool:
        """Rule 5: ``other`` is this installation, whatever base topic either ran on."""
        return (
            other.id == self.id
            or bool(self.installation)
            and (other.installation == self.installation)
        )

    def described(self) -> str:
        if self.host == "?" and not self.pid:  # (rule 5: a rotator's info names the id alone)
            return f"instance {self.id!r}"
        return f"instance {self.id!r} on host {self.host!r} (pid {self.pid})"


def _mark(payload: bytes) -> tuple[str, str, str] | None:
    """Rule 5: the instance, base topic and installation ("": none) a stamp says, as it says
    them; None where ``payload`` holds no stamp."""
    doc = _json(payload)
    mark = doc.get("bridge") if doc is not None else None
    if not isinstance(mark, dict):
        return None
    iid, base = mark.get("instance"), mark.get("base_topic")
    if not isinstance(iid, str) or not iid or not isinstance(base, str) or not base:
        return None
    where = mark.get("installation")
    return iid, base, where if isinstance(where, str) else ""


def _no_base_topic(base: str) -> str | None:
    """Rule 5: why ``base`` is no bridge's base topic (the configuration's own rule for one,
    settings/mqtt.py ``check_topic``: a plain topic, no wildcard, no NUL or other character
    MQTT does not carry, UTF-8, short enough for the levels a bridge adds), or None."""
    try:
        check_topic(base)
    except ValueError as e:
        return str(e)
    return None


def unusable_stamp(payload: bytes) -> tuple[str, str] | None:
    """Rule 5: a stamp whose base topic no bridge could have (``'#'``, a NUL, a lone surrogate,
    a topic past MQTT's length or past TOPIC_LEVELS_MAX levels, review 102): that base topic
    and why; None for anything else. Such a stamp is no bridge's (review 94: its vouch reads,
    ``#/bridge/info``, raised in paho or had the broker drop the connection at every connect,
    and the bridge never came online)."""
    mark = _mark(payload)
    if mark is None:
        return None
    why = _no_base_topic(mark[1])
    return None if why is None else (mark[1], why)


def _json(payload: bytes) -> dict[str, object] | None:
    try:
        doc = json.loads(payload)
    except (ValueError, RecursionError):  # (UnicodeDecodeError is a ValueError)
        return None
    return doc if isinstance(doc, dict) else None


def stamp(instance_id: str, base_topic: str, installation: str = "") -> dict[str, str]:
    """Rule 5: what each rotator's ``R/info`` says of its bridge, under ``bridge``."""
    mark = {"instance": instance_id, "base_topic": base_topic}
    if installation:
        mark["installation"] = installation
    return mark


def stopped(info: str) -> str:
    """Rule 5: a rotator's ``R/info`` (a group's ``G/info``) as its bridge leaves it at a clean
    stop: its stamp says ``"stopped": true``; anything else unchanged."""
    doc = _json(info.encode())
    mark = doc.get("bridge") if doc is not None else None
    if doc is None or not isinstance(mark, dict):
        return info
    doc["bridge"] = {**mark, "stopped": True}
    return json.dumps(doc, separators=(",", ":"))


def stamp_stopped(payload: bytes) -> bool:
    """Rule 5: the stamp in ``payload`` says its bridge stopped cleanly (``stopped``)."""
    doc = _json(payload)
    mark = doc.get("bridge") if doc is not None else None
    return isinstance(mark, dict) and mark.get("stopped") is True


MACHINE_ID = ("/etc/machine-id", "/var/lib/dbus/machine-id")  # rule 5: read for installation


def installation(state_file: str | os.PathLike[str]) -> str:
    """Rule 5: this installation's identity, the same whatever its base topic (review 82: the
    instance id, the default client id, changes with the base topic, and a station given its
    one rotator's topic as base topic was refused by its own old ``R/info`` there): 12 hex
    digits of a hash of the machine's id (``/etc/machine-id``: two computers cloned from one
    image with one host name still differ), the host name and the state file's path (one
    process per state file, state_store.py rule 7), resolved (``state_path``)."""
    machine = ""
    for path in MACHINE_ID:
        try:
            with open(path, encoding="ascii", errors="replace") as f:
                machine = f.read(64).strip()
        except OSError:
            continue
        if machine:
            break
    path = state_path(state_file)
    key = f"{machine}\n{socket.gethostname()}\n{path}".encode(errors="surrogatepass")
    return hashlib.sha256(key).hexdigest()[:12]


def state_path(state_file: str | os.PathLike[str]) -> str:
    """Rule 5: the state file's path as ``installation`` hashes it: ``~`` expanded, made
    absolute against the working directory and its links resolved (review 85: hashed as the
    configuration wrote it, two installations on one host each run from its own directory with
    ``state_file = "state.json"`` had one installation, and a bridge on the other's rotator
    topic took that rotator's stamp for its own earlier run and ran: one target turned both
    rotors). A path that cannot be resolved (a loop of links) is hashed absolute."""
    path = Path(os.fsdecode(state_file)).expanduser().absolute()
    try:
        path = path.resolve()
    except (OSError, RuntimeError):  # (a loop of links: RuntimeError before Python 3.13)
        pass
    return os.fsdecode(path)


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


@dataclass(frozen=True)
class Post:
    """Rule 5: a topic ``X/info`` where another bridge would say who it is on this bridge's
    topics. What stands there says what it is: a bridge's info (``X`` is its ``B/bridge``; live
    by ``X/state``, its last will) or a rotator's (``X`` is its root; live by
    ``X/availability``). One ``above`` (``A/bridge/info`` for each topic ``A`` above the base
    topic) is no post: what stands there never refuses by itself, it only says that the bridge
    a rotator's stamp names is live (review 77: its controller off, the rotator says
    ``offline``)."""

    info: str
    above: bool = False

    @property
    def state(self) -> str:
        return f"{self.info.rsplit('/', 1)[0]}/state"

    @property
    def availability(self) -> str:
        return f"{self.info.rsplit('/', 1)[0]}/availability"

    @property
    def topics(self) -> tuple[str, ...]:
        """What the first look reads for this post."""
        if self.above:
            return self.info, self.state
        return self.info, self.state, self.availability

    @property
    def bridge_base(self) -> str | None:
        """The base topic of a bridge whose info this topic would be (``Y/bridge/info``)."""
        return (
            self.info.removesuffix("/bridge/info") if self.info.endswith("/bridge/info") else None
        )


@dataclass(frozen=True)
class Stand:
    """Rule 5: another instance found on a post: its bridge's base topic, the topic that says
    whether it is live (``beside``) and whether it is, and whether it was a bridge's info."""

    other: Instance
    post: Post
    base: str
    beside: str
    live: bool
    bridge: bool


def standing(
    me: Instance, base_topic: str, posts: tuple[Post, ...], seen: dict[str, bytes]
) -> Stand | None:
    """Rule 5: the first other instance the look saw live on one of ``posts`` (``seen``: the
    payloads of their topics), not gone; else the first one seen gone there (said in the log);
    None when there is none."""
    gone: set[tuple[str, str]] = set()  # (instance, base topic): gone there, per place
    found: list[Stand] = []
    for post in posts:
        info = seen.get(post.info)
        if not info or post.above:
            continue
        bridge, base = Instance.parse(info), post.bridge_base
        if bridge is not None:
            if base is None or bridge.id == me.id:
                continue  # (a bridge's info where no bridge's is: not one)
            live = (seen.get(post.state) or b"").strip() == b"online"
            if not live:
                gone.add((bridge.id, base))  # its last will, or its clean stop
            found.append(Stand(bridge, post, base, post.state, live, True))
            continue
        mark = Instance.stamped(info)
        if mark is None or me.same_installation(mark[0]) or mark[1] == base_topic:
            continue  # (a rotator of a bridge on this base topic: rules 2 and 4 judge it)
        beside, live = post.availability, (seen.get(post.availability) or b"").strip() == b"online"
        if not live and not stamp_stopped(info) and _vouched(mark[0], mark[1], seen):
            beside, live = f"{mark[1]}/bridge/state", True
        found.append(Stand(mark[0], post, mark[1], beside, live, False))
    for stand in found:
        if stand.live and (stand.other.id, stand.base) not in gone:
            return stand
    return replace(found[0], live=False) if found else None


def vouch_reads(claim: Claim, seen: dict[str, bytes]) -> list[str]:
    """Rule 5: what the look reads once its hello is back, before a second one ends it: the
    bridge info and state on the base topic each stamp seen on a post names, when the stamp's
    rotator is not ``online``, it is not marked ``stopped`` and they are no post's (review 85:
    only the topics above the looking bridge's base topic were read, and a live bridge whose
    rotator has a ``topic`` of its own, or whose rotator's topic is one of the looking bridge's
    rotators' topics, its controller off, was taken for gone: one target turned both
    rotors). What another filter of the bridge read already came, maybe before the stamp, and
    was kept (``bridge_post``: review 90)."""
    posted = {t for p in claim.posts for t in p.topics}
    found: dict[str, None] = {}
    for post in claim.posts:
        info = seen.get(post.info)
        if post.above or not info:
            continue
        mark = Instance.stamped(info)
        if mark is None or mark[1] == claim.base_topic or claim.me.same_installation(mark[0]):
            continue
        if (seen.get(post.availability) or b"").strip() == b"online" or stamp_stopped(info):
            continue
        for topic in (f"{mark[1]}/bridge/info", f"{mark[1]}/bridge/state"):
            if topic not in posted:
                found[topic] = None
    return list(found)


def bridge_post(topic: str) -> bool:
    """Rule 5: ``topic`` is where a bridge says who it is or whether it is live (``Y/bridge/info``,
    ``Y/bridge/state``): the look keeps the newest value it hears there from its start, as a vouch
    read may need it (review 90: one read by another filter of the bridge came before the look
    knew it would ask, and was lost)."""
    return topic.endswith(("/bridge/info", "/bridge/state"))


def _vouched(other: Instance, base: str, seen: dict[str, bytes]) -> bool:
    """Rule 5: the bridge info on ``base`` (read on an ``above`` post, or a post) names
    ``other`` and its state beside it says ``online``: that bridge is live whatever its
    rotator says (its controller switched off)."""
    info = Instance.parse(seen.get(f"{base}/bridge/info") or b"")
    state = (seen.get(f"{base}/bridge/state") or b"").strip()
    return info is not None and info.id == other.id and state == b"online"


def refusal_on(stand: Stand) -> str:
    """Rule 5's error: another bridge on one of this bridge's topics."""
    why = (
        f"{stand.beside} says online"
        if stand.bridge or not stand.beside.endswith("/availability")
        else f"{stand.beside} says online (killed outright, a bridge leaves it so: then start "
        "that bridge and stop it, or delete that retained topic)"
    )
    return (
        f"another bridge runs on this bridge's topics: {stand.other.described()} says so on "
        f"{stand.post.info!r}, and {why}. Two bridges whose topics lie one under the other turn "
        f"both rotors on one target: stop the other one, or give each its own mqtt.base_topic, "
        f"no other bridge's topics under it"
    )


@dataclass(frozen=True)
class Claim:
    """What the client needs to take its first look (client.py rule 14)."""

    me: Instance
    base_topic: str
    info_topic: str
    hello_topic: str
    posts: tuple[Post, ...] = ()  # rule 5
