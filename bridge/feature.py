"""What a feature declares (docs/architecture.md "The feature registry"): one value per
feature, listed once in the registry (bridge/features/__init__.py ``FEATURES``), that the
topic table, the MQTT service, the status payload, the Home Assistant entity table and the app
iterate instead of naming each feature. Pure data: no thread, no I/O.

A feature declares its commands (a topic under ``R/`` and the parser of its payload into one
``Command``), its retained state topics and its block in ``R/status`` (each a value read from
the status and how it is written), its Home Assistant entities (rows as data), its settings
(the model of its keys), its session part (a session/parts.py ``Part``: what wakes it, its step
and its reset, run by the session's step in the registry's order), its inputs from topics of
the user's (the wind speed), its console parts and its docs section; a feature of the station
(the DX cluster) its table of the file, its topics under the base topic and the service the app
starts when that table turns it on.

Rules:
1. Stop, lock and the last word are no feature: they stay first and hard-wired
   (interfaces/mqtt/topics.py, interfaces/mqtt/lastword.py, interfaces/mqtt/halts.py), in the order
   written there. A feature's command is judged like any (``Rotator.submit``); it is never a stop or
   a lock, and it never reaches the stop lane. A command for the feature's own session part is a
   core/model.py ``FeatureCommand`` of the feature's name, judged generically and handed to its
   ``Part.command`` (session/parts.py rule 5); what the part shows in ``R/status`` is
   ``RotatorStatus.features[name]`` (parts.py rule 6), which its StatusBlock reads.
2. The registry is an ordered tuple; its order is the order of the features' topics in the
   subscriptions, of their blocks in ``R/status`` and of their entities in discovery, and the
   order in which the session's step runs their parts (``session_parts``; the deciding ones
   before the pending target goes, the measuring ones after the poll: session/session.py
   rule 17). It matters there: tracking and following before the wind, whose storm ends them,
   and the wind before auto-park, which waits while it parks.
3. A feature's topic suffix, under ``R/`` or ``B/`` alike (with one rotator R is B), is unique
   across the core topics, the bridge's own (``B/bridge/...``) and every feature, and names a
   topic (no wildcard), and its command's name is no core command's nor another's (the topic
   table refuses them at start: interfaces/mqtt/topics.py); its first word
   is reserved from group ids (``topic_words``, read by settings/groups.py ``reserved``).
4. The registry is found by name at its first use (``registered``), as python-can finds its
   back ends: a feature spans the layers (its parser sits on interfaces/mqtt/payloads.py while
   mqtt's topic table iterates it), so an import of it from below would be a circle; the app
   hands the parts to the sessions, and a session made without them finds them here. Nothing
   heavy is imported by a declaration: a feature's service is the app's to import, and only
   when its settings turn it on (``service_on``); so is its ``check``, check-config's, which
   judges what the start would refuse with the function that start calls, and returns what
   that start would warn of (a feature with no service, tracking's TLE file, is checked
   always: its check says whether its settings name anything to judge).
5. A feature's entity sits right after the row it names (``EntityRow.after``, a row of the
   entity table's or of a feature's: where the table had it before the feature was a package),
   those after one row in the registry's order; one that names no row, after all the others.
6. A part that takes commands (``Part.command``) bears its feature's name: a
   ``FeatureCommand`` names the feature, and the judge and the session route it by the part's
   name (a declaration that differs is refused as it is made).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Generic, Protocol, TypeVar

from pydantic import BaseModel

from bridge.core.model import Command, Origin, RotatorStatus

T = TypeVar("T")

REGISTRY_MODULE = "bridge.features"  # rule 4: its ``FEATURES``


@dataclass(frozen=True)
class CommandTopic:
    """``R/<suffix>``: a command topic of the main connection (never the stop lane's: rule 1).
    ``parse`` turns its payload, from ``origin``, into one command for the judge; it raises
    interfaces/mqtt/payloads.py's PayloadError naming what was wrong (refused on ``R/error``). An
    empty payload is refused before it ("empty payload") unless it ``takes_empty``."""

    suffix: str
    kind: str  # the command's name in refusals and the audit (interfaces/mqtt/payloads.py describe)
    parse: Callable[[bytes, Origin], Command]
    takes_empty: bool = False


@dataclass(frozen=True)
class StateTopic(Generic[T]):
    """``R/<suffix>``: retained, published from each status that carries a value (``value``
    None: nothing published); with ``new_only`` only when the value is a new object (a report
    made once per move, not at every status); with ``needs`` only for a rotator that has it
    (a capability of interfaces/mqtt/ports.py ``RotatorPort``: ``can_follow``); ``after_status``:
    published after ``R/status``, not before; ``remote``: a client far from the station reads it
    (interfaces/mqtt/topics.py ``StationTopics``)."""

    suffix: str
    value: Callable[[RotatorStatus], T | None]
    render: Callable[[T], str]
    new_only: bool = False
    needs: str | None = None
    after_status: bool = False
    remote: bool = False


@dataclass(frozen=True)
class StatusBlock(Generic[T]):
    """``key`` in ``R/status``, there while ``value`` is not None. ``render`` gives the block
    (a JSON value) or, with ``rendered``, its JSON text (made once, appended last), from the
    value alone: while ``value`` gives the same object, R/status keeps the text it made of it
    (interfaces/mqtt/payloads.py ``StatusText``; a part's value is never changed after it was
    handed on, session/parts.py rule 6). ``kind``: the JSON the block is (an object, or text),
    all a remote lets through of a station's block (remote/readings.py rule 3)."""

    key: str
    value: Callable[[RotatorStatus], T | None]
    render: Callable[[T], object]
    rendered: bool = False
    kind: type[dict[str, object]] | type[str] = dict


class TopicView(Protocol):
    """What an entity's config reads of its rotator's topics (interfaces/mqtt/topics.py
    RotatorTopics)."""

    @property
    def root(self) -> str: ...

    @property
    def status(self) -> str: ...

    @property
    def target(self) -> str: ...

    def feature(self, suffix: str) -> str: ...


class RotatorView(Protocol):
    """What an entity's config reads of its rotator (interfaces/homeassistant/info.py
    RotatorInfo)."""

    @property
    def topics(self) -> TopicView: ...


@dataclass(frozen=True)
class EntityRow:
    """A Home Assistant entity of a rotator's device (interfaces/homeassistant/entities.py
    ``Entity``): ``needs`` a feature's name (configured on that rotator), a RotatorInfo field or a
    model capability; ``bridge_only``: available while the rotator is unreachable."""

    platform: str
    object_id: str
    name: str | None
    config: Callable[[RotatorView], dict[str, object]]
    needs: str | None = None
    bridge_only: bool = False
    after: str | None = None  # rule 5: the object id of the row it follows
    # the end of the entity id Home Assistant is asked for, where it is not the object id
    # (interfaces/homeassistant/entities.py rule 10)
    suffix: str | None = None


@dataclass(frozen=True)
class Input:
    """Topics of the user's (not under the base topic) a feature reads, with the handler of
    their messages (True: it was one of them). Which of them are read without
    retain-as-published (interfaces/mqtt/connection.py rule 1: the flag then says "replayed") is the
    feature's ``replayed``."""

    subscriptions: list[str]
    on_message: Callable[[str, bytes, bool], bool]


@dataclass(frozen=True)
class AppView:
    """What a feature's service is given by the app (app.py) when it starts it. ``settings``
    is the whole file (bridge/settings/ ``Settings``, above this module); ``publishers`` are
    the publishes of the feature's ``base_topics``, in their order (``B/<suffix>``, retained;
    the web console's ``on_<suffix>`` is handed each document first, when the console is on);
    ``mqtt`` is the MQTT service (interfaces/mqtt/service.py)."""

    settings: Any
    station: tuple[float, float] | None
    publishers: tuple[Callable[[str], None], ...]
    mqtt: Any
    wall: Callable[[], float]


class FeatureService(Protocol):
    """A feature's own threads (the DX cluster's client), made by its ``service`` from an
    AppView (ConfigError from bridge/settings/ if it cannot be), started after the rotators
    and stopped with the listeners; ``with_discovery`` hands it Home Assistant's publisher
    (interfaces/homeassistant/publisher.py) when discovery is on."""

    def start(self) -> None: ...

    def stop(self) -> None: ...

    def with_discovery(self, publisher: Any) -> None: ...


@dataclass(frozen=True)
class Feature:
    """One feature, as the registry lists it (the module's docstring)."""

    name: str
    docs: str  # its page for users, and section: "docs/wind.md", "docs/mqtt.md#rotor-health"
    summary: str  # one line, for docs/architecture.md's table and the logs
    commands: tuple[CommandTopic, ...] = ()
    states: tuple[StateTopic[Any], ...] = ()
    status: tuple[StatusBlock[Any], ...] = ()
    entities: tuple[EntityRow, ...] = ()
    # its keys in ``[[rotators]]`` (a model the rotator's table includes) and whether a
    # rotator's table turns it on (its entities' ``needs`` is then the feature's name)
    rotator_settings: type[BaseModel] | None = None
    configured: Callable[[BaseModel], bool] | None = None
    settings_section: tuple[str, str] = ("", "")  # its heading and line in configuration.md
    # (a rotator's settings, its rotator) -> the input it reads, from the app (None: none)
    inputs: Callable[[Sequence[tuple[Any, Any]]], Input | None] | None = None
    replayed: Callable[[BaseModel], str | None] | None = None
    # its session part: a session/parts.py ``Part`` (above this module), run by the session's
    # step in the registry's order (rule 2); the app hands them to each rotator's session
    part: Any = None
    console: tuple[str, ...] = ()  # what the web console shows of it (web/static/)
    # a feature of the station: its table in the file (the Settings field, its model: in
    # configuration.md after the core's tables), its retained topics under the base topic
    # (``B/<suffix>``: its service publishes them), and its service, "module:function" of an
    # AppView, imported and started by the app only while ``service_on(settings)`` (rule 4)
    settings_table: tuple[str, type[BaseModel]] | None = None
    base_topics: tuple[str, ...] = ()
    service: str | None = None
    service_on: Callable[[Any], bool] | None = None
    # "module:function" of the file's Settings, raising ConfigError for what the service's
    # start would stop on (its files read as the start reads them) and returning what it would
    # warn of (check-config's warnings): check-config calls it while ``service_on``, or always
    # for a feature with no service (rule 4)
    check: str | None = None

    def __post_init__(self) -> None:
        part = self.part
        if part is not None and getattr(part, "command", None) is not None:
            if part.name != self.name:  # rule 6
                raise ValueError(
                    f"feature {self.name!r}: a part that takes commands is named as its "
                    f"feature (its commands name the feature), not {part.name!r}"
                )

    def serves(self, settings: Any) -> bool:
        """Whether the file's settings turn this feature's service on (rule 4)."""
        on = self.service_on
        return self.service is not None and on is not None and on(settings)

    def on_for(self, rotator_settings: BaseModel) -> bool:
        """Whether a rotator's table turns this feature on (always, without ``configured``;
        never for a feature of the station, a ``service``: its settings turn it on for all,
        app.py asks them. An attack pass: every rotator got the DX cluster's "Turn to spot"
        in Home Assistant without a ``[dxcluster]``)."""
        if self.service is not None and self.configured is None:
            return False
        return self.configured is None or self.configured(rotator_settings)


_loaded: tuple[Feature, ...] | None = None
_blocks: tuple[tuple[Feature, ...], tuple[StatusBlock[Any], ...]] | None = None


def make_service(feature: Feature, view: AppView) -> FeatureService | None:
    """The feature's service, its module imported now (rule 4), if its settings turn it on."""
    if feature.service is None or not feature.serves(view.settings):
        return None
    module, _, name = feature.service.partition(":")
    make: Callable[[AppView], FeatureService] = getattr(importlib.import_module(module), name)
    return make(view)


def check_feature(feature: Feature, settings: Any) -> list[str]:
    """ConfigError if the feature's start, its service's where its settings turn it on, would
    stop on them; else what that start would warn of (``check``, its module imported now:
    rule 4); check-config asks every feature."""
    if feature.check is None or (feature.service is not None and not feature.serves(settings)):
        return []
    module, _, name = feature.check.partition(":")
    judge: Callable[[Any], list[str]] = getattr(importlib.import_module(module), name)
    return judge(settings)


def registered() -> tuple[Feature, ...]:
    """The registry (rule 4), in its order (rule 2)."""
    global _loaded
    if _loaded is None:
        features: tuple[Feature, ...] = importlib.import_module(REGISTRY_MODULE).FEATURES
        _loaded = features
    return _loaded


def session_parts() -> tuple[Any, ...]:
    """Every registered feature's session part (a session/parts.py ``Part``), in the
    registry's order: the order the session's step runs them (rule 2)."""
    return tuple(f.part for f in registered() if f.part is not None)


def topic_words() -> dict[str, str]:
    """The first word of every registered feature's topics, under ``R/`` and ``B/`` alike, and
    the feature that has it (rule 3: no group id may take one; settings/groups.py)."""
    words: dict[str, str] = {}
    for f in registered():
        for suffix in (*(c.suffix for c in f.commands), *(s.suffix for s in f.states)):
            words.setdefault(suffix.split("/")[0], f.name)
        for suffix in f.base_topics:
            words.setdefault(suffix.split("/")[0], f.name)
    return words


def status_blocks() -> tuple[StatusBlock[Any], ...]:
    """Every registered feature's blocks in ``R/status``, in the registry's order (made once:
    every status of every rotator goes through them)."""
    global _blocks
    features = registered()
    if _blocks is None or _blocks[0] is not features:
        _blocks = features, tuple(block for f in features for block in f.status)
    return _blocks[1]
