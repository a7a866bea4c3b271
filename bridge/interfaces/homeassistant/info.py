"""What Home Assistant discovery knows of the bridge, of each rotator and of each group
(homeassistant/ rules 1 and 3, entities.py): the ids made from the base topic, a rotator's
ranges and configured features, and the track select's options. Pure data."""

from __future__ import annotations

import re
from dataclasses import dataclass, replace
from itertools import islice

from bridge.feature import registered
from bridge.interfaces.mqtt.payloads import PayloadError, parse_track
from bridge.interfaces.mqtt.topics import GroupTopics, RotatorTopics
from bridge.pointing import Pointing
from bridge.protocols.axes import Axis, bearing_is_elevation
from bridge.protocols.base import ModelSpec

_UNSAFE = re.compile(r"[^a-zA-Z0-9_-]")
MAX_SATELLITES = 100  # in the track select: a whole Celestrak "active" file has thousands
MAX_SPOTS = 20  # in the spot select: the calls of the newest DX cluster spots
# the DX cluster's feature (features/dxcluster), on for a station: its spot select's options
DXCLUSTER = "dxcluster"
NO_SPOTS = "no spots yet"  # the spot select's one option before the first spot (HA needs one)


def track_options(satellites: tuple[str, ...]) -> tuple[str, ...]:
    """The track select's options: off, the sun, the moon, the first satellites by name, each a
    name ``R/track`` takes as itself (payloads.py ``parse_track``, whose bound of 255 is also
    the longest state Home Assistant keeps). A name it refuses (longer, a tab in it, one that
    reads as JSON) is no option: picking it was refused (an attack pass); the satellite is
    tracked by its catalog number."""
    named = (name for name in satellites if _as_itself(name))
    return ("off", "sun", "moon", *islice(named, MAX_SATELLITES))


def _as_itself(name: str) -> bool:
    """Whether ``R/track`` takes ``name``, sent as Home Assistant sends an option, as that
    name."""
    try:
        return parse_track(name.encode()) == (name, None)
    except PayloadError:
        return False


def spot_options(calls: tuple[str, ...]) -> tuple[str, ...]:
    """The spot select's options: the newest spots' calls, at most MAX_SPOTS, never none."""
    return calls[:MAX_SPOTS] or (NO_SPOTS,)


@dataclass(frozen=True)
class RotatorInfo:
    """What discovery needs to know about one rotator."""

    rotator_id: str
    name: str
    spec: ModelSpec
    topics: RotatorTopics
    az_min_deg: float  # the range of azimuth targets, true bearings (rule 3)
    az_max_deg: float
    el_min_deg: float = 0.0
    el_max_deg: float = 0.0
    version: str | None = None
    presets: tuple[str, ...] = ()  # names, in the configuration's order
    has_park: bool = False
    # the station's position and a bearing that is an azimuth: targets by locator, a long
    # path, a distance, a spotted call (``of``: none for an elevation rotor on its own)
    has_station: bool = False
    nudge_step_deg: float = 10.0
    track_options: tuple[str, ...] = ()  # off, sun, moon and the TLE file's satellites
    can_follow: bool = False  # [wsjtx] and a station: R/follow (session/follow.py)
    features: frozenset[str] = frozenset()  # the registered features it has (bridge/feature.py)
    spot_options: tuple[str, ...] = ()  # [dxcluster] and a station: the newest spots' calls
    # its health measures an elevation: an az/el model's own (a rotator of two boxes shows its
    # azimuth box's health alone, runtime/composite.py)
    el_health: bool = False
    # a rotator of two boxes: the axes whose box reports a version, in the order its version
    # joins theirs (runtime/composite.py rule 3); the version entity's name says which
    versioned_boxes: tuple[str, ...] = ()
    # its entities' object ids whose plain unique id another rotator's entity has (entities.py
    # rule 8, ``unshared``): given another form of their own
    shared_ids: frozenset[str] = frozenset()

    @classmethod
    def of(
        cls,
        rotator_id: str,
        name: str,
        spec: ModelSpec,
        topics: RotatorTopics,
        pointing: Pointing,
        *,
        has_station: bool,
        nudge_step_deg: float,
        satellites: tuple[str, ...] = (),
        can_follow: bool = False,
        features: frozenset[str] = frozenset(),
        boxes: tuple[ModelSpec, ...] = (),
        version: str | None = None,
    ) -> RotatorInfo:
        """From the rotator's pointing (limits, offset, presets, park) and the settings;
        ``boxes``: a rotator of two boxes, its azimuth's and its elevation's box."""
        az_min, az_max = pointing.target_range()
        # an elevation rotor on its own refuses every place (runtime/rotator.py ``_toward``,
        # session/feature_commands.py rule 6): no locator, long path, distance or spot select
        # that could only be refused (review 70), as no track select or follow switch
        places = has_station and not bearing_is_elevation(spec)
        return cls(
            rotator_id,
            name,
            spec,
            topics,
            az_min,
            az_max,
            pointing.el_min_deg,
            pointing.el_max_deg,
            version,
            presets=tuple(pointing.presets),
            has_park=pointing.park is not None,
            has_station=places,
            nudge_step_deg=nudge_step_deg,
            track_options=(  # (what runtime/rotator.py ``can_track`` says: its bearing turned
                track_options(satellites)  # to a body's azimuth, session/feature_commands.py)
                if places and spec.can_report_position
                else ()
            ),
            can_follow=can_follow,
            features=features,
            spot_options=spot_options(()) if DXCLUSTER in features and places else (),
            el_health=spec.has_elevation and not boxes,
            versioned_boxes=tuple(
                axis.value for axis, box in zip(Axis, boxes, strict=False) if box.has_version
            ),
        )

    def with_satellites(self, satellites: tuple[str, ...]) -> RotatorInfo:
        """This rotator with the TLE file's names as they are now (if it can track at all)."""
        return (
            replace(self, track_options=track_options(satellites)) if self.track_options else self
        )

    def with_spot_calls(self, calls: tuple[str, ...]) -> RotatorInfo:
        """This rotator with the newest spots' calls (if it has the spot select at all)."""
        return replace(self, spot_options=spot_options(calls)) if self.spot_options else self

    def has(self, need: str) -> bool:
        """An entity's need: a registered feature this rotator has, a field of this info
        (configured), else a model capability."""
        if need in self.features or any(f.name == need for f in registered()):
            return need in self.features
        where = self if need in self.__dataclass_fields__ else self.spec
        return bool(getattr(where, need))


@dataclass(frozen=True)
class Identity:
    """Ids derived from the base topic, so two bridges on one broker do not collide."""

    base_topic: str

    @property
    def bridge_node(self) -> str:
        return "rotorbridge_" + _UNSAFE.sub("_", self.base_topic)

    def rotator_node(self, rotator_id: str) -> str:
        return f"{self.bridge_node}_r_{rotator_id}"

    def group_node(self, group_id: str) -> str:
        return f"{self.bridge_node}_g_{group_id}"

    def owns(self, node_id: str) -> bool:
        return node_id == self.bridge_node or node_id.startswith(
            (self.bridge_node + "_r_", self.bridge_node + "_g_")
        )


@dataclass(frozen=True)
class GroupInfo:
    """A group of rotators turned together (interfaces/mqtt/groups.py): its device in Home
    Assistant."""

    group_id: str
    name: str
    topics: GroupTopics
    members: tuple[str, ...]
