"""Configuration: a TOML file, every value overridable from the environment, validated once.

Environment: ``ROTOR_BRIDGE_<FIELD>``, nested with ``__`` (``ROTOR_BRIDGE_MQTT__HOST=broker``).
Rotators are a list in the file; their fields are overridden by id:
``ROTOR_BRIDGE_ROTATORS__TOWER__PORT=/dev/ttyUSB1``. The file itself is ``--config`` or
``ROTOR_BRIDGE_CONFIG``.

Where the parts are: the broker's tables in settings_mqtt.py, a rotator's in
settings_rotator.py (its pointing and loggers' keys in settings_pointing.py and
settings_loggers.py), the engine values derived for keys left out in settings_defaults.py, the
files settings name in settings_files.py; check-config's report is config_report.py and
docs/configuration.md is written from these models by config_doc.py.

Rules:
1. Unknown keys and tables are errors (a typo must not silently do nothing), with the nearest
   known name suggested: ``[[rotator]]`` is "did you mean [[rotators]]?".
2. Every error names the key it is about, as the file spells it (``rotators[0].port``), one line
   per problem; the password never appears in one.
3. Loading touches no hardware: a serial port is a name here (check-config looks whether it
   exists, as a warning).
"""

from __future__ import annotations

import difflib
import os
import re
import tomllib
from pathlib import Path
from typing import Any, get_args

from pydantic import (
    BaseModel,
    Field,
    PrivateAttr,
    ValidationError,
    field_validator,
    model_validator,
)
from pydantic_settings import BaseSettings, PydanticBaseSettingsSource, SettingsConfigDict

from bridge.settings_defaults import DEFAULT_SILENCE_TIMEOUT_S
from bridge.settings_mqtt import HomeAssistantSettings, MqttSettings, TlsSettings
from bridge.settings_pointing import StationSettings, TrackingSettings
from bridge.settings_rotator import RotatorSettings

__all__ = [
    "DEFAULT_SILENCE_TIMEOUT_S",
    "ENV_PREFIX",
    "ConfigError",
    "HomeAssistantSettings",
    "MqttSettings",
    "RotatorSettings",
    "Settings",
    "StationSettings",
    "TlsSettings",
    "TrackingSettings",
    "format_validation_error",
    "load_settings",
]

ENV_PREFIX = "ROTOR_BRIDGE_"
_ROTATOR_ENV = re.compile(r"^ROTOR_BRIDGE_ROTATORS__([^_].*?)__([A-Za-z0-9_]+)$", re.IGNORECASE)


class ConfigError(Exception):
    """A configuration problem, worded for the user; the CLI prints it and exits with 2."""


def _default_state_file() -> Path:
    base = os.environ.get("STATE_DIRECTORY")  # systemd's StateDirectory=
    if base:
        return Path(base.split(":")[0]) / "state.json"
    return Path.home() / ".local" / "state" / "rotor-bridge" / "state.json"


class Settings(BaseSettings):
    """The keys at the top of the file, before any table."""

    model_config = SettingsConfigDict(
        env_prefix=ENV_PREFIX, env_nested_delimiter="__", extra="forbid", case_sensitive=False
    )

    mqtt: MqttSettings = Field(default_factory=MqttSettings, description="the [mqtt] table")
    homeassistant: HomeAssistantSettings = Field(
        default_factory=HomeAssistantSettings, description="the [homeassistant] table"
    )
    station: StationSettings = Field(
        default_factory=StationSettings, description="the [station] table"
    )
    tracking: TrackingSettings = Field(
        default_factory=TrackingSettings, description="the [tracking] table"
    )
    rotators: list[RotatorSettings] = Field(
        min_length=1, description="the [[rotators]] tables, one per rotator"
    )
    log_level: str = Field(
        "INFO",
        description="DEBUG, INFO, WARNING or ERROR; DEBUG shows every byte on the serial lines",
        examples=["DEBUG"],
    )
    state_file: Path = Field(
        default_factory=_default_state_file,
        description="where the lock and the options set at run time are kept across restarts",
        examples=["/var/lib/rotor-bridge/state.json"],
        json_schema_extra={
            "unset": "$STATE_DIRECTORY/state.json under systemd, else "
            "~/.local/state/rotor-bridge/state.json"
        },
    )
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
    data: dict[str, Any] = read_toml(path) if path else {}
    return settings_from(data, env, path)


def read_toml(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The file as a TOML document; ConfigError if it cannot be read or is no TOML."""
    try:
        with open(path, "rb") as f:
            return tomllib.load(f)
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


def settings_from(
    data: dict[str, Any],
    environ: Any = None,
    path: str | os.PathLike[str] | None = None,
) -> Settings:
    """``data`` (a TOML document) with the environment's overrides, validated (ConfigError)."""
    env = os.environ if environ is None else environ
    _apply_rotator_env(data, env)
    unknown = [k for k in data if k not in Settings.model_fields]
    if (
        "rotators" not in data
        and not unknown  # a misspelt [[rotators]] is named as that (rule 1)
        and not any(k.upper().startswith("ROTOR_BRIDGE_ROTATORS") for k in env)
    ):
        if path:
            raise ConfigError(
                f"no rotators configured in {path}: add a [[rotators]] table with id, model "
                "and port (docs/configuration.md)"
            )
        raise ConfigError(
            "no rotators configured: pass --config FILE (see config/example.toml) "
            "or set ROTOR_BRIDGE_CONFIG"
        )
    try:
        settings = Settings(**data)
    except ValidationError as exc:
        raise ConfigError(format_validation_error(exc, data, env)) from None
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


def format_validation_error(
    exc: ValidationError, data: dict[str, Any] | None = None, environ: Any = None
) -> str:
    """One line per problem, each naming the key as the file spells it (rule 2), and the
    environment variable where one set the value."""
    lines = []
    suggested: set[str] = set()
    for err in exc.errors():
        names = [str(p) for p in err["loc"] if not isinstance(p, int)]
        loc: list[str] = []
        for part in err["loc"]:
            if isinstance(part, int):
                loc[-1:] = [f"{loc[-1] if loc else ''}[{part}]"]
            else:
                loc.append(str(part))
        where = ".".join(loc) or "configuration"
        if err["type"] == "extra_forbidden":
            line, nearest = _unknown(names, where, _value_at(data, err["loc"]))
            lines.append(line)
            if nearest is not None and len(names) == 1:
                suggested.add(nearest)
            continue
        msg = err["msg"].removeprefix("Value error, ")
        if err["type"] == "missing":
            msg = "missing: it has no default"
            if where == "rotators":
                msg += "; add a [[rotators]] table with id, model and port"
        variable = _variable(err["loc"], data, environ or {})
        lines.append(f"{where} (from {variable}): {msg}" if variable else f"{where}: {msg}")
    # a misspelt table also leaves the real one missing: the suggestion says it all
    lines = [ln for ln in lines if not any(ln.startswith(f"{s}: missing") for s in suggested)]
    return "invalid configuration:\n  " + "\n  ".join(lines)


def _variable(loc: tuple[int | str, ...], data: dict[str, Any] | None, env: Any) -> str | None:
    """The environment variable that set the value at ``loc``, if one did."""
    parts = [str(p) for p in loc]
    if len(loc) >= 3 and loc[0] == "rotators" and isinstance(loc[1], int):
        rotator = _value_at(data, loc[:2])
        if not isinstance(rotator, dict) or "id" not in rotator:
            return None
        parts = ["rotators", str(rotator["id"]), *parts[2:]]
    wanted = (ENV_PREFIX + "__".join(parts)).upper()
    return next((k for k in env if k.upper() == wanted), None)


def _unknown(names: list[str], where: str, value: object) -> tuple[str, str | None]:
    """The line for an unknown key or table, with the nearest known name in the same place."""
    model = _model_at(names[:-1])
    known = list(model.model_fields) if model is not None else []
    close = difflib.get_close_matches(names[-1].lower(), known, n=1, cutoff=0.6)
    nearest = close[0] if close else None
    prefix = ".".join(names[:-1])
    is_table = isinstance(value, dict) or (
        isinstance(value, list) and bool(value) and all(isinstance(v, dict) for v in value)
    )
    if is_table:
        shown = _table(where, value)
        line = f"unknown table {shown}"
        if nearest is not None:
            full = f"{prefix}.{nearest}" if prefix else nearest
            line += f": did you mean {_table(full, _shape(model, nearest))}?"
        elif model is not None:
            tables = [
                _table(f"{prefix}.{n}" if prefix else n, _shape(model, n))
                for n, f in model.model_fields.items()
                if _model_in(f.annotation) is not None
            ]
            line += f" (the tables here: {', '.join(tables)})" if tables else ""
        return line, nearest
    line = f"{where}: unknown key"
    if nearest is not None:
        line += f": did you mean {nearest}?"
    elif known:
        line += " (typo?)"
    return line, nearest


def _table(name: str, value: object) -> str:
    return f"[[{name}]]" if isinstance(value, list) else f"[{name}]"


def _shape(model: type[BaseModel] | None, name: str) -> object:
    """A value shaped like the field ``name`` of ``model``: a list for an array of tables."""
    field = model.model_fields.get(name) if model is not None else None
    origin = getattr(field.annotation, "__origin__", None) if field is not None else None
    return [] if origin is list else {}


def _model_at(names: list[str]) -> type[BaseModel] | None:
    """The settings model whose keys are those at ``names`` (None: not a table of ours)."""
    model: type[BaseModel] = Settings
    for name in names:
        field = model.model_fields.get(name)
        if field is None:
            return None
        inner = _model_in(field.annotation)
        if inner is None:
            return None
        model = inner
    return model


def _model_in(annotation: object) -> type[BaseModel] | None:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in get_args(annotation):
        found = _model_in(arg)
        if found is not None:
            return found
    return None


def _value_at(data: dict[str, Any] | None, loc: tuple[int | str, ...]) -> object:
    value: object = data
    for part in loc:
        if isinstance(value, dict) and part in value:
            value = value[part]
        elif isinstance(value, list) and isinstance(part, int) and part < len(value):
            value = value[part]
        else:
            return None
    return value
