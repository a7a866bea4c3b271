"""Every MQTT topic string of the bridge lives here and nowhere else (docs/architecture.md,
rule 4), but a registered feature's: its package declares its topics as suffixes under ``R/``
or ``B/`` (bridge/feature.py), and the table here iterates the registry for them
(``Topics.features``); stop and lock stay hard-wired, first.

R = a rotator's topic (the base topic itself when exactly one rotator is configured,
``<base>/<id>`` otherwise), B = the base topic.

Two topics under ``B/bridge/`` are the bridge's messages to itself, not for other clients:
- ``B/bridge/hello``: the first look (interfaces/mqtt/look.py, client.py rule 14). On every connect,
  before it publishes anything else, the bridge publishes ``<instance id> <n>`` there (its MQTT
  client id and the number of the look in this run), QoS 0, NOT retained, and waits for it to
  come back: the retained ``B/bridge/info`` and ``B/bridge/state`` that arrive before it are
  what the broker held. So a client watching ``B/#`` while the bridge (re)connects sees it as
  the bridge's first message; one that subscribes later never does (nothing of it stays on the
  broker). Other clients ignore it; a hello that is not the bridge's own look ends nothing.
  Each marker on ``B/bridge/fence`` is published there too (lastword.py rule 7). The
  broker's ACL must let the bridge publish and subscribe there: without it every connect
  waits LOOK_TIMEOUT_S (5 s) after the broker's last message and deletes no stale discovery.
- ``B/bridge/fence`` and ``B/bridge/fence/lane``: the markers of the last word
  (interfaces/mqtt/lastword.py), ``B/bridge/fence/express`` the stop express's sync words (its rule
  8), QoS 0, not retained, seen only while stops and locks come in.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from bridge.feature import Feature, registered

# the core commands' names, as ``Topics.route`` gives them (a feature's may be none of them)
CORE_KINDS = frozenset(
    ("target", "target_elevation", "stop", "lock", "preset", "park", "nudge", "option")
)
GROUP_KINDS = frozenset(("target", "stop"))  # the commands a group takes (groups.py)


@dataclass(frozen=True)
class RotatorTopics:
    root: str

    # inbound (commands)
    @property
    def target(self) -> str:
        return f"{self.root}/target"

    @property
    def target_elevation(self) -> str:
        return f"{self.root}/target/elevation"

    @property
    def stop(self) -> str:
        return f"{self.root}/stop"

    @property
    def lock(self) -> str:
        return f"{self.root}/lock"

    @property
    def preset(self) -> str:
        return f"{self.root}/preset"

    @property
    def park(self) -> str:
        return f"{self.root}/park"

    @property
    def nudge(self) -> str:
        return f"{self.root}/nudge"

    def option(self, name: str) -> str:
        return f"{self.root}/option/{name}"

    def feature(self, suffix: str) -> str:
        """A registered feature's topic (bridge/feature.py): ``R/<suffix>``."""
        return f"{self.root}/{suffix}"

    @property
    def option_filter(self) -> str:
        return f"{self.root}/option/+"

    # outbound
    @property
    def bearing(self) -> str:
        return f"{self.root}/bearing"

    @property
    def elevation(self) -> str:
        return f"{self.root}/elevation"

    @property
    def state(self) -> str:
        return f"{self.root}/state"

    @property
    def status(self) -> str:
        return f"{self.root}/status"

    @property
    def version(self) -> str:
        return f"{self.root}/version"

    @property
    def availability(self) -> str:
        return f"{self.root}/availability"

    @property
    def error(self) -> str:
        return f"{self.root}/error"

    @property
    def presets(self) -> str:
        return f"{self.root}/presets"

    @property
    def info(self) -> str:
        return f"{self.root}/info"

    @property
    def lock_state(self) -> str:
        return f"{self.root}/lock/state"

    def option_state(self, name: str) -> str:
        return f"{self.root}/option/{name}/state"

    # the audit trail (runtime/operators.py)
    @property
    def audit(self) -> str:
        """Not retained: every command judged, executed or refused."""
        return f"{self.root}/audit"


@dataclass(frozen=True)
class GroupTopics:
    """A group's topics (interfaces/mqtt/groups.py), ``G`` = ``<base>/<group id>``."""

    root: str

    @property
    def target(self) -> str:
        return f"{self.root}/target"

    @property
    def stop(self) -> str:
        return f"{self.root}/stop"

    @property
    def status(self) -> str:
        return f"{self.root}/status"

    @property
    def availability(self) -> str:
        return f"{self.root}/availability"

    @property
    def error(self) -> str:
        return f"{self.root}/error"

    @property
    def info(self) -> str:
        """The group's info, its bridge's stamp in it (claim.py rule 5)."""
        return f"{self.root}/info"


@dataclass(frozen=True)
class DiscoveryTopics:
    """Home Assistant MQTT discovery: ``<prefix>/<platform>/<node_id>/<object_id>/config``."""

    prefix: str

    def config(self, platform: str, node_id: str, object_id: str) -> str:
        return f"{self.prefix}/{platform}/{node_id}/{object_id}/config"

    @property
    def config_filter(self) -> str:
        return f"{self.prefix}/+/+/+/config"

    @property
    def subtree(self) -> str:
        """What every discovery topic starts with (the prefix and its separator)."""
        return f"{self.prefix}/"

    def parse_config(self, topic: str) -> tuple[str, str, str] | None:
        """(platform, node_id, object_id) of a config topic under the prefix, else None."""
        parts = topic.split("/")
        head = self.prefix.split("/")
        if len(parts) != len(head) + 4 or parts[: len(head)] != head or parts[-1] != "config":
            return None
        return parts[-4], parts[-3], parts[-2]


class Topics:
    def __init__(
        self,
        base: str,
        roots: dict[str, str],
        groups: dict[str, str] | None = None,
        features: Sequence[Feature] | None = None,
    ) -> None:
        """``groups``: each group's root (settings/ ``group_topic``), by its id; ``features``:
        the registry's (bridge/feature.py ``registered``) unless given."""
        self.base = base
        self.features = tuple(registered() if features is None else features)
        self._commands = {c.suffix: c.kind for f in self.features for c in f.commands}
        self.commands = {c.kind: c for f in self.features for c in f.commands}  # by kind
        _check_suffixes(self.features)
        self._rotators = {rid: RotatorTopics(root) for rid, root in roots.items()}
        self._groups = {gid: GroupTopics(root) for gid, root in (groups or {}).items()}
        # route's table, each rotator's topics built once: every message on the main connection
        # and the stop lane is routed, the bridge's own discovery configs coming back included
        self._routes = tuple(
            (rid, _core_commands(t), t.root + "/", t.root + "/option/")
            for rid, t in self._rotators.items()
        )
        # group_route's table: a group's target and stop, and every other command topic a
        # rotator has, under the group's root (service.py rule 10: refused there, not lost)
        self._group_routes: dict[str, tuple[str, str]] = {}
        for gid, g in self._groups.items():
            as_rotator = RotatorTopics(g.root)
            for topic, kind in _core_commands(as_rotator).items():
                self._group_routes[topic] = gid, kind
            for suffix, kind in self._commands.items():
                self._group_routes[as_rotator.feature(suffix)] = gid, kind

    @property
    def bridge_state(self) -> str:
        return f"{self.base}/bridge/state"

    @property
    def bridge_info(self) -> str:
        return f"{self.base}/bridge/info"

    @property
    def bridge_hello(self) -> str:
        """Where a bridge's first look goes to come back to it (QoS 0, not retained: see the
        module's docstring; interfaces/mqtt/look.py)."""
        return f"{self.base}/bridge/hello"

    @property
    def bridge_heartbeat(self) -> str:
        """The bridge's heartbeat: its clock every few seconds, not retained (heartbeat.py)."""
        return f"{self.base}/bridge/heartbeat"

    @property
    def bridge_fence(self) -> str:
        """Where the bridge's markers go to come back on the main connection (lastword.py)."""
        return f"{self.base}/bridge/fence"

    @property
    def bridge_fence_lane(self) -> str:
        """The markers the stop lane reads (lastword.py rule 4)."""
        return f"{self.base}/bridge/fence/lane"

    @property
    def bridge_fence_express(self) -> str:
        """The stop express's own sync words, published and read by it (express.py rule 8)."""
        return f"{self.base}/bridge/fence/express"

    def under_base(self, suffix: str) -> str:
        """A registered feature's topic under the base topic (bridge/feature.py
        ``base_topics``: the DX cluster's ``B/spots``): ``B/<suffix>``."""
        return f"{self.base}/{suffix}"

    def rotator_of(self, topic: str) -> str | None:
        """The rotator whose topic ``topic`` is under, if any (the longest root wins)."""
        best: tuple[int, str] | None = None
        for rid, t in self._rotators.items():
            if topic == t.root or topic.startswith(t.root + "/"):
                if best is None or len(t.root) > best[0]:
                    best = (len(t.root), rid)
        return None if best is None else best[1]

    def rotator(self, rotator_id: str) -> RotatorTopics:
        return self._rotators[rotator_id]

    def group(self, group_id: str) -> GroupTopics:
        return self._groups[group_id]

    def group_route(self, topic: str) -> tuple[str, str] | None:
        """A group's command topic as (group id, "target" or "stop"); a rotator's command topic
        under a group's root, which no group takes, as (group id, that command's name:
        "lock", "option", ...), so that it is refused (service.py rule 10); else None."""
        found = self._group_routes.get(topic)
        if found is not None:
            return found
        for gid, g in self._groups.items():
            name = topic.removeprefix(f"{g.root}/option/")
            if name != topic and name and "/" not in name:
                return gid, "option"
        return None

    def subscriptions(self) -> list[str]:
        """The command topics of the main connection (stop and lock too: service.py rule 5),
        and the bridge's own markers (lastword.py rule 2)."""
        subs: list[str] = []
        for g in self._groups.values():
            subs += [g.target, g.stop]
        subs += [t for _gid, t in self.group_refusals()]
        for t in self._rotators.values():
            subs += [t.target, t.target_elevation, t.stop, t.lock, t.option_filter]
            subs += [t.preset, t.park, t.nudge]
            subs += [t.feature(suffix) for suffix in self._commands]  # the registry's
        return [*subs, self.bridge_fence]

    def group_refusals(self) -> list[tuple[str, str]]:
        """A rotator's other command topics under each group's root, as (group id, filter):
        read only to refuse what comes there (service.py rule 10)."""
        refusals = [
            (gid, t) for t, (gid, kind) in self._group_routes.items() if kind not in GROUP_KINDS
        ]
        return refusals + [
            (gid, RotatorTopics(g.root).option_filter) for gid, g in self._groups.items()
        ]

    def stop_lane(self) -> list[str]:
        """Stop also on a connection of its own (lane.py), behind no flood of targets, nor of
        lock words (lastword.py rule 16); subscribed on both without the broker's replay of a
        retained message (lastword.py rule 6)."""
        subs = [t.stop for t in self._rotators.values()]
        return subs + [g.stop for g in self._groups.values()]

    def lock_lane(self) -> list[str]:
        """Lock also on a connection of its own (lane.py, lastword.py rule 16): behind no flood
        of targets, and no flood of lock words ahead of a stop; without the replay too."""
        return [t.lock for t in self._rotators.values()]

    def owned(self) -> list[str]:
        """Filters for the retained topics the bridge publishes (client.py rule 10 watches them
        for values it did not publish); none overlaps a command filter."""
        subs = [self.bridge_state, self.bridge_info]
        for t in self._rotators.values():
            subs += [t.bearing, t.elevation, t.state, t.status, t.version, t.availability]
            subs += [f"{t.root}/option/+/state", t.lock_state, t.presets, t.info]
            subs += [t.feature(s.suffix) for f in self.features for s in f.states]
        for g in self._groups.values():
            subs += [g.status, g.availability, g.info]
        return subs

    def posts(self) -> list[str]:
        """claim.py rule 5: where, on this bridge's own topics, another bridge would say who it
        is (what stands there says whether it is a bridge's info or a rotator's, and so which
        topic beside it says whether it is live): ``B/bridge/info`` (rule 2's),
        ``R/bridge/info`` for each rotator's and group's root but the base topic, ``X/info``
        for each rotator's and group's root and the base topic (review 77: a group's target
        turned another bridge's rotor on its topic)."""
        roots = [t.root for t in self._rotators.values()] + [g.root for g in self._groups.values()]
        roots = list(dict.fromkeys([*roots, self.base]))
        found = [self.bridge_info]
        found += [Topics(x, {}).bridge_info for x in roots if x != self.base]
        found += [RotatorTopics(x).info for x in roots]
        return found

    def above(self) -> list[str]:
        """claim.py rule 5: ``A/bridge/info`` for each topic ``A`` above the base topic, where a
        bridge whose rotator's topic is one of ours says who it is and, beside it, whether it is
        live (read only to vouch for that rotator's stamp: its controller off, review 77)."""
        levels = self.base.split("/")
        return [Topics("/".join(levels[:n]), {}).bridge_info for n in range(len(levels) - 1, 0, -1)]

    def route(self, topic: str) -> tuple[str, str, str | None] | None:
        """Map an inbound topic to (rotator id, command, argument), or None if it is not ours:
        the first rotator, in their order, whose core command, registered feature's command or
        option it is."""
        for rid, core, under, options in self._routes:
            kind = core.get(topic)
            if kind is not None:
                return rid, kind, None
            if topic.startswith(under):
                named = self._commands.get(topic[len(under) :])  # a registered feature's command
                if named is not None:
                    return rid, named, None
                if topic.startswith(options) and "/" not in topic[len(options) :]:
                    return rid, "option", topic[len(options) :]
        return None


def _core_commands(t: RotatorTopics) -> dict[str, str]:
    """A rotator's core command topics (but its options), each with its command's name."""
    kinds = ("target", "target_elevation", "stop", "lock", "preset", "park", "nudge")
    return {getattr(t, kind): kind for kind in kinds}


def _check_suffixes(features: Sequence[Feature]) -> None:
    """bridge/feature.py rule 3: a feature's topic is no core topic (stop and lock above all),
    none of the bridge's own (``B/bridge/...``) and no other feature's, nor is its command's
    name a core command's or another's (``R/target`` would be parsed by the feature's parser);
    ValueError naming it, before anything is subscribed. A suffix under a rotator's root and
    one under the base topic share one namespace: with one rotator the root is the base topic
    (``R/spots`` is the DX cluster's ``B/spots``, ``R/bridge/fence`` the last word's markers).
    A wildcard or an empty level names no topic."""
    core = RotatorTopics("")
    taken = {
        getattr(core, name).lstrip("/")
        for name in dir(RotatorTopics)
        if isinstance(getattr(RotatorTopics, name), property)
    }
    for feature in features:
        suffixes = [("R", c.suffix) for c in feature.commands]
        suffixes += [("R", s.suffix) for s in feature.states]
        suffixes += [("B", suffix) for suffix in feature.base_topics]
        for where, suffix in suffixes:
            levels = suffix.split("/")
            if suffix and ("" in levels or "+" in suffix or "#" in suffix):
                raise ValueError(f"feature {feature.name}: {where}/{suffix} is no topic name")
            if not suffix or suffix in taken or levels[0] in ("option", "bridge"):
                raise ValueError(f"feature {feature.name}: topic {where}/{suffix} is taken")
            taken.add(suffix)
    # a command is parsed and routed by its name (interfaces/mqtt/service.py)
    kinds = set(CORE_KINDS)
    for feature in features:
        for command in feature.commands:
            if command.kind in kinds:
                raise ValueError(f"feature {feature.name}: command name {command.kind} is taken")
            kinds.add(command.kind)


@dataclass(frozen=True)
class StationTopics:
    """A station's topics as a client far from it sees them (bridge/remote/): it knows the
    station's base topic, not its rotators' roots, and finds them by their ``R/info``. The
    roots follow the bridge's default (settings/ ``rotator_topic``): ``B`` with one rotator,
    ``B/<id>`` with several."""

    base: str

    @property
    def bridge_state(self) -> str:
        return Topics(self.base, {}).bridge_state

    @property
    def bridge_heartbeat(self) -> str:
        return Topics(self.base, {}).bridge_heartbeat

    def rotator(self, rotator_id: str | None) -> RotatorTopics:
        """The rotator ``rotator_id``'s topics, or the one rotator's (None)."""
        return RotatorTopics(self.base if rotator_id is None else f"{self.base}/{rotator_id}")

    def subscriptions(self) -> list[str]:
        """What a remote reads: the bridge's state and heartbeat, and each rotator's
        description, status, availability, presets, error events, control lease and lock,
        whether the station has one rotator or several."""
        one, each = self.rotator(None), self.rotator("+")
        read = [s.suffix for f in registered() for s in f.states if s.remote]  # R/control
        return [self.bridge_state, self.bridge_heartbeat] + [
            t
            for r in (one, each)
            for t in (
                r.info,
                r.status,
                r.availability,
                r.presets,
                r.error,
                *(r.feature(suffix) for suffix in read),
                r.lock_state,
            )
        ]

    def described(self, topics: list[str]) -> list[str]:
        """The ids of the rotators among ``topics`` that have a ``B/<id>/info`` (the bridge's
        own ``B/bridge/info`` is not one)."""
        found = []
        for topic in topics:
            rest = topic.removeprefix(self.base + "/")
            rid, _, leaf = rest.partition("/")
            if rest != topic and leaf == "info" and rid and rid != "bridge":
                found.append(rid)
        return sorted(found)
