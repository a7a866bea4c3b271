"""Configuration: a TOML file, every value overridable from the environment, validated once.

Environment: ``ROTOR_BRIDGE_<FIELD>``, nested with ``__`` (``ROTOR_BRIDGE_MQTT__HOST=broker``).
Rotators are a list in the file; their fields are overridden by id:
``ROTOR_BRIDGE_ROTATORS__TOWER__PORT=/dev/ttyUSB1``. The file itself is ``--config`` or
``ROTOR_BRIDGE_CONFIG``. Unknown keys are errors (a typo must not silently do nothing).
The files settings name are checked in settings_files.py; check-config's report and warnings
are config_report.py.
"""

from __future__ import annotations

import hashlib
import math
import os
import re
import socket
import tomllib
from pathlib import Path
from typing import Any, Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    PrivateAttr,
    SecretStr,
    ValidationError,
    field_validator,
    model_validator,
)
from pydantic_settings import BaseSettings, PydanticBaseSettingsSource, SettingsConfigDict

from bridge.pointing import Pointing
from bridge.protocols import REGISTRY
from bridge.protocols.base import ModelSpec
from bridge.settings_files import check_tls_files, read_password_file
from bridge.settings_loggers import LoggerFields
from bridge.settings_pointing import PointingFields, StationSettings, TrackingSettings

ENV_PREFIX = "ROTOR_BRIDGE_"
DEFAULT_SILENCE_TIMEOUT_S = 3.0  # no valid reply this long: offline (unless polls are rarer)
_ROTATOR_ENV = re.compile(r"^ROTOR_BRIDGE_ROTATORS__([^_].*?)__([A-Za-z0-9_]+)$", re.IGNORECASE)
_SLUG = re.compile(r"^[a-z0-9][a-z0-9_-]{0,47}$")
_TOPIC_BAD = re.compile(r"[+#\x00]")


class ConfigError(Exception):
    """A configuration problem, worded for the user; the CLI prints it and exits with 2."""


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class TlsSettings(_Strict):
    enabled: bool = False
    ca_file: Path | None = None
    cert_file: Path | None = None
    key_file: Path | None = None
    insecure: bool = Field(False, description="skip the host name check (self-signed lab brokers)")

    @model_validator(mode="after")
    def _files(self) -> TlsSettings:
        # loaded here as the MQTT client will load them, so a bad file is a config error now and
        # not a traceback at start (paho's tls_set would raise it)
        check_tls_files(self.ca_file, self.cert_file, self.key_file)
        return self


class MqttSettings(_Strict):
    host: str = "127.0.0.1"
    port: int = Field(1883, ge=1, le=65535)
    username: str | None = None
    password: SecretStr | None = None
    password_file: Path | None = None
    tls: TlsSettings = TlsSettings()
    client_id: str | None = None
    keepalive_s: int = Field(30, ge=5, le=3600)
    # R/error per rotator, at most this many a second after a burst of five times as many
    error_events_per_s: float = Field(10.0, gt=0, le=10000)
    base_topic: str = "rotor"
    protocol: Literal["5", "3.1.1"] = "5"

    @field_validator("protocol", mode="before")
    @classmethod
    def _protocol(cls, v: object) -> object:
        return str(v) if isinstance(v, int | float) and not isinstance(v, bool) else v

    @field_validator("base_topic")
    @classmethod
    def _topic(cls, v: str) -> str:
        if not v or v.startswith("/") or v.endswith("/") or _TOPIC_BAD.search(v) or "//" in v:
            raise ValueError(
                "must be a plain topic like 'rotor' (no wildcards, no leading/trailing '/')"
            )
        return v

    @model_validator(mode="after")
    def _password_file(self) -> MqttSettings:
        if self.password_file is None:
            return self
        if self.password is not None:
            raise ValueError("set password or password_file, not both")
        self.password = SecretStr(read_password_file(self.password_file))
        return self

    # the state file of the installation these settings belong to (Settings fills it in)
    _state_file: str = PrivateAttr(default="")

    def effective_client_id(self) -> str:
        """``client_id``, or a default that is unique per installation and stable across restarts.

        The default is "rotor-", up to 10 characters of the host name, "-" and 6 hex digits of a
        hash of the full host name, the base topic and the state file path: at most 23
        characters, the length every MQTT 3.1.1 broker must accept, from the characters every
        broker takes (plus "-"). Two bridges on one host (a second installation, the demo beside
        the real one) differ in state file or base topic, so they do not take each other's
        session over; one installation keeps its id. Two hosts sharing one configuration with
        an explicit client_id still collide: the client reports that (mqtt/client.py rule 7).
        """
        if self.client_id:
            return self.client_id
        host = socket.gethostname()
        key = f"{host}\n{self.base_topic}\n{self._state_file}".encode()
        digest = hashlib.sha256(key).hexdigest()[:6]
        short = re.sub(r"[^a-z0-9-]", "", host.split(".")[0].lower())[:10].strip("-")
        return f"rotor-{short}-{digest}" if short else f"rotor-{digest}"


class HomeAssistantSettings(_Strict):
    enabled: bool = True
    discovery_prefix: str = "homeassistant"
    status_topic: str = "homeassistant/status"
    birth_delay_s: float = Field(
        10.0, ge=0, le=300, description="wait after Home Assistant's birth before re-publishing"
    )

    @field_validator("discovery_prefix", "status_topic")
    @classmethod
    def _topic(cls, v: str) -> str:
        return MqttSettings._topic(v)


class RotatorSettings(PointingFields, LoggerFields):
    id: str
    name: str | None = None
    model: str
    port: str
    baud: int | None = Field(None, gt=0)
    topic: str | None = None
    # None: the model's, from its line rate (ModelSpec.default_idle_poll_interval_s)
    idle_poll_interval_s: float | None = Field(None, gt=0, le=3600)
    moving_poll_interval_s: float = Field(0.2, gt=0, le=60)
    tolerance_deg: float = Field(3.0, ge=0, le=45)
    brake_delay_s: float | None = Field(None, ge=0, le=60)
    stall_timeout_s: float = Field(10.0, gt=0, le=600)
    settle_s: float = Field(1.5, gt=0, le=60)
    deadband_deg: float = Field(2.0, ge=0, le=45)
    noise_deg: float | None = Field(
        None, ge=0, le=20, description="a still rotor's readings wander this much (model default)"
    )
    # None: DEFAULT_SILENCE_TIMEOUT_S, longer where idle polls are rarer (see the property)
    silence_timeout_s: float | None = Field(None, gt=0, le=600)
    # at least 0.5 deg/s (a whole turn in 12 minutes): the wait for a SatEL's lost after-move
    # report is twice the travel time at these speeds, and a slip like 0.05 would make it hours
    az_speed_deg_s: float | None = Field(
        None, ge=0.5, le=360, description="how fast the rotor really turns (model default)"
    )
    el_speed_deg_s: float | None = Field(None, ge=0.5, le=360)
    az_min_deg: float | None = None
    az_max_deg: float | None = None
    el_min_deg: float | None = None
    el_max_deg: float | None = None
    # Hamlib rotctld-compatible TCP port (bridge/rotctld/); no authentication, hence loopback
    rotctld_port: int | None = Field(None, ge=1, le=65535)
    rotctld_bind: str = "127.0.0.1"
    # a rotctld client that sends nothing this long is disconnected (16 idle ones took every slot)
    rotctld_idle_timeout_s: float = Field(300.0, ge=1, le=86400)
    # az_offset_deg, presets, park_az_deg/park_el_deg, park_after_idle_s, keep_out and
    # nudge_step_deg: settings_pointing.py

    @field_validator("id")
    @classmethod
    def _id(cls, v: str) -> str:
        if not _SLUG.match(v) or v == "bridge":
            raise ValueError(
                "must be a short slug: lower-case letters, digits, '-' or '_' (and not 'bridge')"
            )
        return v

    @field_validator("model")
    @classmethod
    def _model(cls, v: str) -> str:
        if v not in REGISTRY:
            raise ValueError(f"unknown model {v!r}; known models: {', '.join(sorted(REGISTRY))}")
        return v

    @field_validator("topic")
    @classmethod
    def _topic(cls, v: str | None) -> str | None:
        if v is not None:
            MqttSettings._topic(v)
        return v

    @model_validator(mode="after")
    def _limits(self) -> RotatorSettings:
        spec = self.spec
        lo = spec.az_min_deg if self.az_min_deg is None else self.az_min_deg
        hi = spec.az_max_deg if self.az_max_deg is None else self.az_max_deg
        if not spec.az_min_deg <= lo < hi <= spec.az_max_deg:
            raise ValueError(
                f"azimuth limits {lo:g}..{hi:g} must lie inside the {spec.display_name}'s "
                f"range {spec.az_min_deg:g}..{spec.az_max_deg:g} with min < max"
            )
        if spec.has_elevation:
            elo, ehi = self.effective_el_limits
            if not spec.el_min_deg <= elo < ehi <= spec.el_max_deg:
                raise ValueError(
                    f"elevation limits {elo:g}..{ehi:g} must lie inside the "
                    f"{spec.display_name}'s range {spec.el_min_deg:g}..{spec.el_max_deg:g}"
                )
        elif self.el_min_deg is not None or self.el_max_deg is not None:
            raise ValueError(f"the {spec.display_name} has no elevation axis (el_min/max_deg)")
        elif self.el_speed_deg_s is not None:
            raise ValueError(f"the {spec.display_name} has no elevation axis (el_speed_deg_s)")
        idle_s = self.effective_idle_poll_interval_s
        if self.moving_poll_interval_s > idle_s:
            raise ValueError(
                f"moving_poll_interval_s must not exceed idle_poll_interval_s ({idle_s:g})"
            )
        silence_s = self.silence_timeout_s
        if spec.can_report_position and silence_s is not None and silence_s <= idle_s:
            raise ValueError(
                f"silence_timeout_s {silence_s:g} must be longer than the idle poll interval "
                f"({idle_s:g} s): a controller asked that seldom would be declared offline "
                "between two polls"
            )
        if spec.can_report_position and self.settle_s < 2 * self.moving_poll_interval_s:
            raise ValueError(
                "settle_s must be at least two moving poll intervals: stillness needs two readings"
            )
        self.check_pointing(self.pointing)
        return self

    @property
    def spec(self) -> ModelSpec:
        return REGISTRY[self.model]

    @property
    def pointing(self) -> Pointing:
        """The judge's terms (settings_pointing.py) on this model and limits."""
        return self.pointing_for(self.spec, self.effective_az_limits, self.effective_el_limits)

    @property
    def effective_baud(self) -> int:
        return self.baud or self.spec.baud

    @property
    def effective_brake_delay_s(self) -> float:
        return self.spec.brake_delay_s if self.brake_delay_s is None else self.brake_delay_s

    @property
    def effective_noise_deg(self) -> float:
        return self.spec.noise_deg if self.noise_deg is None else self.noise_deg

    @property
    def effective_track_step_deg(self) -> float:
        """How far the body moves before tracking sends the next target: the tolerance."""
        return self.tolerance_deg if self.track_step_deg is None else self.track_step_deg

    @property
    def effective_speeds_deg_s(self) -> tuple[float, float]:
        return self.spec.speeds_deg_s(self.az_speed_deg_s, self.el_speed_deg_s)

    @property
    def effective_idle_poll_interval_s(self) -> float:
        """The user's, else the model's at this baud rate: idle polls take at most 5 % of the
        line (1.0 s on fast lines; Rot2Prog at 600 baud 9.3 s)."""
        if self.idle_poll_interval_s is not None:
            return self.idle_poll_interval_s
        return self.spec.default_idle_poll_interval_s(self.effective_baud)

    @property
    def effective_silence_timeout_s(self) -> float:
        """The user's, else DEFAULT_SILENCE_TIMEOUT_S, or two idle polls plus a reply time where
        polls are rarer than that allows: one lost reply is ridden out, two in a row are not."""
        if self.silence_timeout_s is not None:
            return self.silence_timeout_s
        two_polls = 2 * self.effective_idle_poll_interval_s + self.spec.reply_timeout_s
        return max(DEFAULT_SILENCE_TIMEOUT_S, math.ceil(two_polls * 10 - 1e-9) / 10)

    @property
    def effective_el_limits(self) -> tuple[float, float]:
        spec = self.spec
        return (
            spec.el_min_deg if self.el_min_deg is None else self.el_min_deg,
            spec.el_max_deg if self.el_max_deg is None else self.el_max_deg,
        )

    @property
    def effective_az_limits(self) -> tuple[float, float]:
        spec = self.spec
        return (
            spec.az_min_deg if self.az_min_deg is None else self.az_min_deg,
            spec.az_max_deg if self.az_max_deg is None else self.az_max_deg,
        )


def _default_state_file() -> Path:
    base = os.environ.get("STATE_DIRECTORY")  # systemd's StateDirectory=
    if base:
        return Path(base.split(":")[0]) / "state.json"
    return Path.home() / ".local" / "state" / "rotor-bridge" / "state.json"


class Settings(BaseSettings):
    model_config = SettingsConfigDict(
        env_prefix=ENV_PREFIX, env_nested_delimiter="__", extra="forbid", case_sensitive=False
    )

    mqtt: MqttSettings = MqttSettings()
    homeassistant: HomeAssistantSettings = HomeAssistantSettings()
    station: StationSettings = StationSettings()  # settings_pointing.py
    tracking: TrackingSettings = TrackingSettings()
    rotators: list[RotatorSettings] = Field(min_length=1)
    log_level: str = "INFO"
    state_file: Path = Field(default_factory=_default_state_file)
    # mqtt.password is written in the configuration file itself (check-config warns)
    _password_in_file: bool = PrivateAttr(default=False)

    @field_validator("log_level")
    @classmethod
    def _level(cls, v: str) -> str:
        v = v.upper()
        if v not in ("DEBUG", "INFO", "WARNING", "ERROR"):
            raise ValueError("must be DEBUG, INFO, WARNING or ERROR")
        return v

    @model_validator(mode="after")
    def _unique(self) -> Settings:
        seen: dict[str, str] = {}
        for r in self.rotators:
            if r.id in seen:
                raise ValueError(f"rotator id {r.id!r} is used twice")
            seen[r.id] = r.port
        ports = [r.port for r in self.rotators]
        dup = {p for p in ports if ports.count(p) > 1}
        if dup:
            raise ValueError(f"port {sorted(dup)[0]} is given to two rotators")
        rotctld = [r.rotctld_port for r in self.rotators if r.rotctld_port is not None]
        if len(set(rotctld)) != len(rotctld):
            raise ValueError("two rotators share one rotctld_port")
        pst = [r.pst_udp_port for r in self.rotators if r.pst_udp_port is not None]
        n1mm_ports = {r.n1mm_udp_port for r in self.rotators if r.n1mm_rotor_name is not None}
        if len(set(pst)) != len(pst) or set(pst) & n1mm_ports:
            raise ValueError("two rotators share one pst_udp_port (or it is an n1mm_udp_port)")
        names = [
            (r.n1mm_udp_bind, r.n1mm_udp_port, r.n1mm_rotor_name)
            for r in self.rotators
            if r.n1mm_rotor_name is not None
        ]
        if len(set(names)) != len(names):
            raise ValueError("two rotators have one n1mm_rotor_name on one N1MM port")
        topics = [self.rotator_topic(r) for r in self.rotators]
        if len(set(topics)) != len(topics):
            raise ValueError("two rotators share one topic")
        prefix = self.homeassistant.discovery_prefix
        if self.homeassistant.enabled and (
            prefix == self.mqtt.base_topic or self.mqtt.base_topic.startswith(prefix + "/")
        ):
            raise ValueError("homeassistant.discovery_prefix must differ from mqtt.base_topic")
        return self

    @model_validator(mode="after")
    def _installation(self) -> Settings:
        self.mqtt._state_file = str(self.state_file.expanduser().absolute())
        return self

    def rotator_topic(self, r: RotatorSettings) -> str:
        if r.topic:
            return r.topic
        base = self.mqtt.base_topic
        return base if len(self.rotators) == 1 else f"{base}/{r.id}"

    @classmethod
    def settings_customise_sources(
        cls,
        settings_cls: type[BaseSettings],
        init_settings: PydanticBaseSettingsSource,
        env_settings: PydanticBaseSettingsSource,
        dotenv_settings: PydanticBaseSettingsSource,
        file_secret_settings: PydanticBaseSettingsSource,
    ) -> tuple[PydanticBaseSettingsSource, ...]:
        # Rotator overrides by id are merged into the file's list by load_settings; the env source
        # must not see them, or it would replace the list with a dict.
        env_vars = getattr(env_settings, "env_vars", None)
        if isinstance(env_vars, dict):
            for key in [k for k in env_vars if k.lower().startswith("rotor_bridge_rotators__")]:
                del env_vars[key]
        return (env_settings, init_settings)  # environment beats the file


def load_settings(
    path: str | os.PathLike[str] | None, environ: dict[str, str] | None = None
) -> Settings:
    """Read, merge and validate; raise ConfigError with one message per problem."""
    env = os.environ if environ is None else environ
    path = path or env.get("ROTOR_BRIDGE_CONFIG")
    data: dict[str, Any] = {}
    if path:
        try:
            with open(path, "rb") as f:
                data = tomllib.load(f)
        except FileNotFoundError:
            raise ConfigError(f"config file {path} not found") from None
        except OSError as exc:
            raise ConfigError(f"config file {path}: {exc.strerror}") from None
        except tomllib.TOMLDecodeError as exc:
            raise ConfigError(f"config file {path} is not valid TOML: {exc}") from None
        except UnicodeDecodeError as exc:
            raise ConfigError(
                f"config file {path} is not UTF-8 text (byte {exc.start}): save it as UTF-8"
            ) from None
    _apply_rotator_env(data, env)
    if "rotators" not in data and not any(
        k.upper().startswith("ROTOR_BRIDGE_ROTATORS") for k in env
    ):
        raise ConfigError(
            "no rotators configured: pass --config FILE (see config/example.toml) "
            "or set ROTOR_BRIDGE_CONFIG"
        )
    try:
        settings = Settings(**data)
    except ValidationError as exc:
        raise ConfigError(format_validation_error(exc, data)) from None
    mqtt = data.get("mqtt")
    settings._password_in_file = isinstance(mqtt, dict) and "password" in mqtt
    return settings


def _apply_rotator_env(data: dict[str, Any], env: Any) -> None:
    for key, value in env.items():
        m = _ROTATOR_ENV.match(key)
        if not m:
            continue
        rid, field = m.group(1).lower(), m.group(2).lower()
        for r in data.get("rotators", []):
            if isinstance(r, dict) and str(r.get("id", "")).lower() == rid:
                r[field] = value
                break
        else:
            raise ConfigError(f"{key}: no rotator with id {rid!r} in the configuration")


def format_validation_error(exc: ValidationError, data: dict[str, Any] | None = None) -> str:
    lines = []
    for err in exc.errors():
        loc: list[str] = []
        for part in err["loc"]:
            if isinstance(part, int):
                loc[-1:] = [f"{loc[-1] if loc else ''}[{part}]"]
            else:
                loc.append(str(part))
        where = ".".join(loc) or "configuration"
        msg = err["msg"].removeprefix("Value error, ")
        if err["type"] == "extra_forbidden":
            msg = "unknown setting (typo?)"
        lines.append(f"{where}: {msg}")
    return "invalid configuration:\n  " + "\n  ".join(lines)
