"""Configuration: the top of the file, its loading and its rules are settings/config.py's; one
module per table beside it (settings/mqtt.py, settings/rotator.py, ...).

The package itself imports nothing: each name below is config.py's, imported at its first use
(PEP 562). So a process that needs one table alone imports that module and what it imports,
not every table and pydantic-settings: the stop express's child (interfaces/mqtt/express.py
rule 1) takes the broker's table (settings/mqtt.py) and starts in a third of the CPU.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from bridge.settings.config import DEFAULT_SILENCE_TIMEOUT_S as DEFAULT_SILENCE_TIMEOUT_S
    from bridge.settings.config import ENV_PREFIX as ENV_PREFIX
    from bridge.settings.config import ConfigError as ConfigError
    from bridge.settings.config import DxClusterSettings as DxClusterSettings
    from bridge.settings.config import GroupSettings as GroupSettings
    from bridge.settings.config import HomeAssistantSettings as HomeAssistantSettings
    from bridge.settings.config import MqttSettings as MqttSettings
    from bridge.settings.config import RotatorSettings as RotatorSettings
    from bridge.settings.config import Settings as Settings
    from bridge.settings.config import StationSettings as StationSettings
    from bridge.settings.config import TlsSettings as TlsSettings
    from bridge.settings.config import TrackingSettings as TrackingSettings
    from bridge.settings.config import WebSettings as WebSettings
    from bridge.settings.config import WsjtxSettings as WsjtxSettings
    from bridge.settings.config import format_validation_error as format_validation_error
    from bridge.settings.config import load_settings as load_settings
    from bridge.settings.config import pty_takes as pty_takes
    from bridge.settings.config import read_toml as read_toml
    from bridge.settings.config import settings_from as settings_from
    from bridge.settings.config import state_file_in as state_file_in

__all__ = [
    "DEFAULT_SILENCE_TIMEOUT_S",
    "ENV_PREFIX",
    "ConfigError",
    "DxClusterSettings",
    "GroupSettings",
    "HomeAssistantSettings",
    "MqttSettings",
    "RotatorSettings",
    "Settings",
    "StationSettings",
    "TlsSettings",
    "TrackingSettings",
    "WebSettings",
    "WsjtxSettings",
    "format_validation_error",
    "load_settings",
    "pty_takes",
    "read_toml",
    "settings_from",
    "state_file_in",
]
_NAMES = frozenset(__all__)


def __getattr__(name: str) -> Any:
    """config.py's ``name``, imported now; any other name (a submodule not imported yet among
    them: ``from bridge.settings import report`` asks here first) is not the package's."""
    if name not in _NAMES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    from bridge.settings import config

    value = getattr(config, name)
    globals()[name] = value
    return value
