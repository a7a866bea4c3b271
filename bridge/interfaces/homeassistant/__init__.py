"""Home Assistant MQTT discovery: what it knows of the rotators (info.py), the entity table
(entities.py: pure data and builders) and the publisher that keeps it current on the broker
(publisher.py: a timer, a lock)."""

from bridge.interfaces.homeassistant.entities import ENTITIES, Entity, all_configs
from bridge.interfaces.homeassistant.info import (
    MAX_SATELLITES,
    GroupInfo,
    Identity,
    RotatorInfo,
    track_options,
)
from bridge.interfaces.homeassistant.publisher import DiscoveryPublisher

__all__ = [
    "ENTITIES",
    "MAX_SATELLITES",
    "DiscoveryPublisher",
    "Entity",
    "Identity",
    "RotatorInfo",
    "GroupInfo",
    "all_configs",
    "track_options",
]
