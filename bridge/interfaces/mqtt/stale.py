"""The retained topics of a rotator or group no longer configured: a rotator removed or renamed,
a group removed, a station gone from one rotator (its topics on the base topic itself) to
several. Pure: which filters to read and, for a message read, which topics to delete; the
client deletes them (client.py ``clear_retained``, rules 14 and 15).

Rules:
1. An attack pass: a rotator removed after a crash kept its retained topics for ever,
   ``R/availability`` ``online`` and ``R/state`` ``moving`` among them (the last will covers
   ``B/bridge/state`` alone), and a dashboard or a remote reading ``B/+/availability`` showed a
   rotator that no longer exists as online and turning. Each root under the base topic
   (``B/<id>``, where the bridge puts a rotator or a group by default) and the base topic itself
   tells that it was one by its retained ``availability``; one that is no configured rotator's
   or group's root has every retained topic a rotator or a group publishes there deleted
   (``stale``); its options' states, whose names depend on its model, are read each on its
   own (``B/+/option/+/state``: a model's options are not listed without importing every
   controller family, start-up CPU for nothing). Both change seldom: reading them costs
   nothing per reading, under MQTT 3.1.1 either, where the bridge hears its own messages. A
   rotator with a ``topic`` of its own elsewhere is not looked for.
2. The deletions are the first look's (client.py rule 14; claim.py rule 3): asked while it
   runs (the broker hands over its retained messages then), sent only when the base topic was
   this bridge's, and said in the log in a few lines (rule 15). An ``availability`` published
   while the bridge runs is another client's: nothing is deleted for it.
3. A root that holds a bridge's own retained state (``B/<x>/bridge/state``) is another
   bridge's base topic, nested under ours (a second station on ``rotor/site2``, one rotator on
   its base topic): its topics were deleted as a removed rotator's (a review). Such a root is
   spared at the look's end (``spared``, client.py rule 14), when every retained message the
   broker held has come, whatever order the broker sent them in. A topic of a configured
   rotator is never stale, whatever filter reads it (a rotator named ``option`` has its
   ``R/lock/state`` on ``B/option/lock/state``, which reads as an option state of a rotator
   once on the base topic), nor is anything under ``B/bridge``.
4. A rotator removed and a group given its id shares its root, whose availability
   is then the group's: the rotator's bearing, state, lock, options and ``R/info`` (by which a
   remote finds rotators) stayed for ever, a ghost rotator (a review). A rotator's ``R/info`` on
   a group's root (not the group's own ``G/info``, payloads.py ``is_group_info``: it names its
   bridge, claim.py rule 5) tells a rotator was there: its topics that a group does not publish
   are deleted (``G/info`` itself is the group's, put over it); an option state under a group's
   root is deleted by itself. ``G/info`` being one of the bridge's own topics, the owned-topic
   watch takes what the broker holds there: it is handed here first (``peeked``, client.py
   ``peek``; review 85: it was not, and a rotator made a group again left its topics for ever).
5. A rotator still configured keeps its root, but not every state topic a feature published
   there: one it no longer has (a station taken out: ``R/tracking``; ``[wsjtx]`` or the station:
   ``R/follow/state``; bridge/feature.py ``StateTopic.needs``) is published no more, and its
   last value stayed for ever (a review: the Node-RED page, which offers tracking once
   ``R/tracking`` arrives, offered it to a rotator that then refused it). Those topics
   (``unpublished``, each rotator's, exactly) are read too (through the owned-topic watch,
   client.py rule 10, which reads every feature's state), and a retained value there is
   deleted as rule 2 says. So are the status topics its model never fills (a review: the user
   swapped controllers, and Node-RED flows and Home Assistant automations kept reading the
   old one's last values): ``R/elevation`` of an azimuth-only model, ``R/bearing`` of one that
   cannot report where it points (DCU-1), ``R/version`` of one that reports none (neither box
   of a composite rotator); its option states are read as rule 1's (and through the same
   watch), and one whose name is none of its model's options (``options``: each configured
   rotator's root and the names it publishes) is deleted by itself. What it does publish (an
   MD-01's or a composite's elevation, a version that comes late, an option of its model) is
   never among them.
6. A feature of the station (bridge/feature.py ``base_topics``) keeps its topics under the
   base topic only while its service runs: with the feature taken out of the configuration
   they are published no more (attack 13: a run with ``[dxcluster]`` left its spots on
   ``B/spots``, retained, and every dashboard showed them as current for good). Those topics
   (the app's, in ``unpublished``: its service is none of the running ones) are read and
   deleted as rule 5's. Checked for the same gap (attack 13): the wind, the band map, auto-park
   and following WSJT-X keep no retained topic of their own beyond rule 5's (``R/follow/state``)
   and ``R/status``'s blocks; rotor health's ``R/health`` is published for every model (one
   that reports no position says so); a removed group's are rule 1's and 4's; Home
   Assistant's configs are its publisher's (homeassistant/publisher.py rule 6).
"""

from __future__ import annotations

from bridge.feature import registered
from bridge.interfaces.mqtt.payloads import is_group_info
from bridge.interfaces.mqtt.topics import GroupTopics, RotatorTopics, Topics


class StaleTopics:
    """Rule 1: the filters to read, and what a message read on them leaves to delete."""

    def __init__(
        self,
        topics: Topics,
        roots: set[str],
        groups: set[str] | None = None,
        unpublished: set[str] | None = None,
        options: dict[str, tuple[str, ...]] | None = None,
    ) -> None:
        self._base = topics.base
        self._roots = roots  # every configured rotator's and group's root
        self._groups = set(groups or ())  # rule 4: the groups' roots (never a rotator's)
        self._owned = set(topics.owned())  # (never one of these, whatever its root)
        self._states = [s.suffix for f in registered() for s in f.states]
        self._bridges: set[str] = {f"{topics.base}/bridge"}  # rule 3: another bridge's base
        self._unpublished = set(unpublished or ())  # rules 5, 6: states, a feature's off
        self._options = dict(options or {})  # rule 5: a configured root, its options' names

    @property
    def subscriptions(self) -> list[str]:
        b = self._base
        return [f"{b}/+/bridge/state", f"{b}/+/availability", f"{b}/availability"] + [
            f"{b}/+/option/+/state",
            f"{b}/option/+/state",
            *(f"{g}/info" for g in sorted(self._groups)),  # rule 4
            # rule 5 (one the owned-topic watch reads, client.py rule 10, comes through it: read
            # twice, it was deleted and said twice)
            *sorted(self._unpublished - self._owned),
        ]

    @property
    def peeked(self) -> list[str]:
        """Rule 4: the groups' ``G/info``, one of the bridge's own topics (claim.py rule 5), whose
        value the broker held the client hands here before its owned-topic watch puts the
        group's own over it (client.py ``peek``; review 85: the watch took it, never read here,
        and a rotator made a group again left its bearing, state and lock for ever)."""
        return [f"{g}/info" for g in sorted(self._groups) if f"{g}/info" in self._owned]

    def stale(self, topic: str, payload: bytes | None = None) -> list[str]:
        """Rule 1: what ``topic`` (read on ``subscriptions``) leaves to delete: every retained
        topic a rotator or a group publishes under a root no longer configured, for its
        availability; the option state itself, for one of its options' states; a configured
        rotator's state topic itself, for one it no longer publishes (rule 5)."""
        if topic in self._unpublished or self._not_its_option(topic):  # rule 5
            return [topic]
        head, _, under = topic.rpartition("/bridge/")
        if under == "state" and head.rpartition("/")[0] == self._base:
            self._bridges.add(head)  # rule 3
            return []
        if topic.endswith("/info") and topic[: -len("/info")] in self._groups:  # rule 4
            if is_group_info(payload):
                return []  # (the group's own, claim.py rule 5)
            return self._rotator_only(topic[: -len("/info")])
        root, leaf = self._root(topic)
        if root in self._groups and leaf == "option":  # rule 4
            return [topic]
        if root is None or root in self._roots or root in self._bridges:
            return []
        if leaf != "availability":
            return [topic] if topic not in self._owned else []  # rule 3
        g = GroupTopics(root)
        found = [*self._rotator_only(root), g.status, g.availability]  # (a rotator's too)
        return [t for t in dict.fromkeys(found) if t not in self._owned]

    def spared(self, topic: str) -> bool:
        """Rule 3, at the look's end: ``topic`` is under another bridge's base topic."""
        bridges = tuple(self._bridges)  # (one step: paho's thread may add one meanwhile, when
        # the look timed out and this runs on the timer's)
        return any(topic.startswith(bridge + "/") for bridge in bridges)

    def _rotator_only(self, root: str) -> list[str]:
        """The retained topics a rotator keeps at ``root`` that a group does not."""
        r = RotatorTopics(root)
        found = [r.bearing, r.elevation, r.state, r.version, r.presets, r.info]
        found += [r.lock_state, *(r.feature(suffix) for suffix in self._states)]
        return [t for t in found if t not in self._owned]

    def _not_its_option(self, topic: str) -> bool:
        """Rule 5: ``topic`` is a configured rotator's ``R/option/<name>/state`` for a name that
        is none of its model's options (never one of the bridge's own topics: rule 3)."""
        head, _, leaf = topic.rpartition("/")
        root, under, name = head.rpartition("/option/")
        names = self._options.get(root)
        if leaf != "state" or not under or "/" in name or names is None:
            return False
        return name not in names and topic not in self._owned

    def _root(self, topic: str) -> tuple[str | None, str]:
        """The root ``topic`` is under (the base topic or ``B/<id>``) and what it is there:
        ``availability`` or ``option``; (None, "") for any other topic."""
        head, _, leaf = topic.rpartition("/")
        if leaf == "availability":
            root = head
        elif leaf == "state" and head.rpartition("/")[0].endswith("/option"):
            root, leaf = head.rpartition("/")[0][: -len("/option")], "option"
        else:
            return None, ""
        if root == self._base or root.rpartition("/")[0] == self._base:
            return root, leaf
        return None, ""
