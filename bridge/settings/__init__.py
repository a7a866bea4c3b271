"""Configuration: the top of the file, its loading and its rules are settings/config.py's; one
module per table beside it (settings/mqtt.py, settings/rotator.py, ...).

The package itself imports nothing: each name below is its module's, imported at its first
use (PEP 562). So a process that needs one table alone imports that module and what it imports,
not every table and pydantic-settings: the stop express's child (interfaces/mqtt/express.py
rule 1) takes the broker's table (settings/mqtt.py) alone.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # (each from the module that makes it)
    from bridge.settings.config import ENV_PREFIX as ENV_PREFIX
    from bridge.settings.config import ConfigError as ConfigError
    from bridge.settings.config import Settings as Settings
    from bridge.settings.config import format_validation_error as format_validation_error
    from bridge.settings.config import load_settings as load_settings
    from bridge.settings.config import pty_takes as pty_takes
    from bridge.settings.config import read_toml as read_toml
    from bridge.settings.config import settings_from as settings_from
    from bridge.settings.config import state_file_in as state_file_in
    from bridge.settings.defaults import DEFAULT_SILENCE_TIMEOUT_S as DEFAULT_SILENCE_TIMEOUT_S
    from bridge.settings.dxcluster import DxClusterSettings as DxClusterSettings
    from bridge.settings.groups import GroupSettings as GroupSettings
    from bridge.settings.mqtt import HomeAssistantSettings as HomeAssistantSettings
    from bridge.settings.mqtt import MqttSettings as MqttSettings
    from bridge.settings.mqtt import TlsSettings as TlsSettings
    from bridge.settings.pointing import StationSettings as StationSettings
    from bridge.settings.pointing import TrackingSettings as TrackingSettings
    from bridge.settings.rotator import RotatorSettings as RotatorSettings
    from bridge.settings.web import WebSettings as WebSettings
    from bridge.settings.wsjtx import WsjtxSettings as WsjtxSettings

_WHERE = {  # each name the package gives, by the module that makes it
    "DEFAULT_SILENCE_TIMEOUT_S": "defaults",
    "ENV_PREFIX": "config",
    "ConfigError": "config",
    "DxClusterSettings": "dxcluster",
    "GroupSettings": "groups",
    "HomeAssistantSettings": "mqtt",
    "MqttSettings": "mqtt",
    "RotatorSettings": "rotator",
    "Settings": "config",
    "StationSettings": "pointing",
    "TlsSettings": "mqtt",
    "TrackingSettings": "pointing",
    "WebSettings": "web",
    "WsjtxSettings": "wsjtx",
    "format_validation_error": "config",
    "load_settings": "config",
    "pty_takes": "config",
    "read_toml": "config",
    "settings_from": "config",
    "state_file_in": "config",
}
__all__ = sorted(_WHERE)


def __getattr__(name: str) -> Any:
    """``name`` from the module that makes it, imported now; any other name (a submodule not
    imported yet among them: ``from bridge.settings import report`` asks here first) is not
    the package's."""
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value
