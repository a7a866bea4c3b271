"""The remote's file (``rotor-bridge remote -c remote.toml``): who operates, the station's broker
and which local endpoints to offer.

Rules:
1. ``[mqtt]`` is the bridge's own table (MqttSettings: TLS, password_file, ...); ``base_topic``
   is the station's. MQTT 5 only: every command carries an expiry (mqtt/remote.py rule 1).
2. An endpoint may leave ``rotator`` out only when it is the only endpoint; no two endpoints
   take one address.
3. A problem is a ConfigError naming the key as the file spells it, one line each.
4. ``[web]`` is the bridge's own table (WebSettings), with its refusal of a console beyond
   loopback without a password.
"""

from __future__ import annotations

import hashlib
import re
import socket
from typing import Any

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from bridge.settings import ConfigError, read_toml
from bridge.settings_errors import describe
from bridge.settings_mqtt import MqttSettings
from bridge.settings_web import WebSettings

ENV_PREFIX = "ROTOR_REMOTE_"  # no variables are read; describe() wants a prefix to name


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class Endpoint(_Strict):
    """``[[endpoints]]``: local ports onto one of the station's rotators."""

    rotator: str | None = Field(
        None,
        min_length=1,
        description="the station's rotator id; may be left out when the station has one",
    )
    rotctld_port: int = Field(ge=1, le=65535, description="a Hamlib rotctld port (rotctl -m 2)")
    rotctld_bind: str = Field("127.0.0.1", description="the address it listens on")


class RemoteSettings(_Strict):
    operator: str = Field(
        min_length=1,
        max_length=64,
        pattern=r"^\S(.*\S)?$",
        description="who operates (a call sign): carried with every command",
    )
    mqtt: MqttSettings = Field(default_factory=MqttSettings)
    command_expiry_s: int = Field(
        5, ge=1, le=60, description="a command not delivered within this many seconds is dropped"
    )
    moving_max_age_s: float = Field(
        10.0,
        gt=0,
        le=600,
        description="a moving rotator's status older than this reads as unknown: the station "
        "went quiet mid-move",
    )
    info_wait_s: float = Field(
        10.0, gt=0, le=120, description="how long to wait for the station's rotators at start"
    )
    endpoints: list[Endpoint] = Field(min_length=1)
    web: WebSettings = Field(
        default_factory=WebSettings,
        description="the operator console, served here for the station's rotators: the "
        "bridge's own [web] table (loopback unless password_file is set)",
    )

    @model_validator(mode="after")
    def _check(self) -> RemoteSettings:
        if self.mqtt.protocol != "5":
            raise ValueError('mqtt.protocol must be "5": commands carry a message expiry')
        if len(self.endpoints) > 1 and any(e.rotator is None for e in self.endpoints):
            raise ValueError("with several [[endpoints]], each names its rotator")
        binds = [(e.rotctld_bind, e.rotctld_port) for e in self.endpoints]
        if len(set(binds)) != len(binds):
            raise ValueError("two [[endpoints]] have one rotctld_bind and rotctld_port")
        return self

    def client_id(self) -> str:
        """``mqtt.client_id``, or one per operator and host that no bridge uses ("remote-")."""
        if self.mqtt.client_id:
            return self.mqtt.client_id
        key = f"{socket.gethostname()}\n{self.mqtt.base_topic}\n{self.operator}".encode()
        short = re.sub(r"[^a-z0-9]", "", self.operator.lower())[:8]
        return f"remote-{short}-{hashlib.sha256(key).hexdigest()[:6]}"


def load_remote_settings(path: str) -> RemoteSettings:
    """The file validated; ConfigError with one line per problem."""
    data: dict[str, Any] = read_toml(path)
    try:
        return RemoteSettings(**data)
    except ValidationError as exc:
        raise ConfigError(describe(exc, RemoteSettings, ENV_PREFIX, data, {})) from None
