"""Configuration: a TOML file, every value overridable from the environment, validated once.

Environment: ``ROTOR_BRIDGE_<FIELD>``, nested with ``__`` (``ROTOR_BRIDGE_MQTT__HOST=broker``).
Rotators are a list in the file; their fields are overridden by id:
``ROTOR_BRIDGE_ROTATORS__TOWER__PORT=/dev/serial/by-id/...``. The file itself is ``--config`` or
``ROTOR_BRIDGE_CONFIG``.

Where the parts are: the broker's tables in settings/mqtt.py, a rotator's in
settings/rotator.py (its pointing and loggers' keys in settings/pointing.py and
settings/loggers.py), the console's in settings/web.py, the engine values derived for keys
left out in settings/defaults.py, the files settings name in settings/files.py, the wording of
errors in settings/errors.py, the base of every table (no unknown key, no boolean for a number,
no NUL) in settings/base.py; what MQTT's text may hold is core/text.py's.
check-config's report is settings/report.py; docs/configuration.md is written from these models
by config_doc.py.

Rules:
1. Unknown keys and tables are errors (a typo must not silently do nothing), with the nearest
   known name suggested: ``[[rotator]]`` is "did you mean [[rotators]]?".
2. Every error names the key it is about, as the file spells it (``rotators[0].port``), one line
   per problem; the password never appears in one.
3. Loading touches no hardware: a serial port is a name here (check-config looks whether it
   exists, as a warning).
4. A ``ROTOR_BRIDGE_*`` variable whose first word is no key of the file's top (but
   ``ROTOR_BRIDGE_CONFIG``) is an error naming it, as rule 1 for the file: pydantic-settings
   drops it without a word (``ROTOR_BRIDGE_MQTT_HOST``, one ``_`` where a table takes ``__``,
   left the bridge on the file's broker). So is a ``ROTOR_BRIDGE_ROTATORS__`` variable that
   names no rotator's key (``ROTOR_BRIDGE_ROTATORS__TOWER_PORT``: the settings source drops
   every such variable, and only ``ROTATORS__<ID>__<KEY>`` is read; a review: the bridge
   opened the file's port), or no rotator of the file (the file's ids are looked for whole,
   ``__`` and ``-`` in them too: _rotator_of). So is any ``ROTOR_BRIDGE_GROUPS`` variable:
   groups are set in the file only (docs/configuration.md says so); read,
   ``GROUPS__STACK__OFFSETS`` replaced the file's ``[[groups]]`` with a table and was refused
   as "groups: Input should be a valid list", naming no variable (attack 12). So is a
   variable under a key that is one value (``ROTOR_BRIDGE_LOG_LEVEL__X``,
   ``ROTOR_BRIDGE_MQTT__HOST__X``, ``ROTOR_BRIDGE_CONFIG__X``): nothing is under it (attack
   18: dropped without a word, or refused naming no variable). So are two variables that set
   one key (_one_variable_each: the environment's order chose one without a word), but a
   table of the top in JSON beside a variable of one of its keys, which is both, in any order
   (_laid_over).
5. The configuration file is read up to CONFIG_FILE_MAX bytes; a larger one is an error (an
   attack pass: ``-c /dev/zero`` or ``/dev/urandom`` ended check-config and run in a
   MemoryError traceback after taking all the memory it could). It may be a pipe
   (``-c <(...)``): only its size is judged. A UTF-8 byte-order mark at its start (Notepad
   before 2019, PowerShell 5's ``-Encoding UTF8``) is no part of the document and is dropped,
   as every MQTT payload's (interfaces/mqtt/payloads.py ``_words``): attack 28: such a file was
   refused as "Invalid statement (at line 1, column 1)", pointing at an invisible character.
   The remote's file is read by the same ``read_toml``.
6. The files the bridge writes (``state_file``, ``audit_file``, and with a console password
   the console's secret beside the state file, ``console-secret``) are neither the
   configuration file, nor each other, nor a file another key names for reading (a password,
   TLS or cty file, the TLE file): an attack pass: ``state_file`` naming the configuration
   file passed check-config, and the first lock OFF replaced the configuration with the state
   (the next start: "not valid TOML"); a password file was overwritten likewise, and a
   console password file named ``console-secret`` beside the state file by random bytes.
   A pty's link (``gs232_pty``, ``easycomm_pty``, ``dcu1_pty``) is a file the bridge writes
   too (ptylines.py rule 1 replaces a link there). No file it writes is a rotator's serial
   port, by any name (links followed), nor a serial line's or terminal's device nor a disk
   (a pty's path excepted, where a link to a crashed run's pty is its own leftover; other
   devices, ``/dev/null`` and ``/dev/full``, are files to write as far as the bridge cares).
   A rotator's pty may be another rotator's port where nothing stands or a link to a pty
   does: the bridge driving its own emulated port (the integration tests' loop-backs, which
   the first form of attack 28's fix refused). A pty's path is
   judged by the link itself, never by where a link already there points (``pty_takes``, the
   remote's ptys' judge too: remote/settings.py rule 6):
   its place (its folder resolved, then its name) is none of the other file's names: the
   other's own place, every link on its way, what it resolves to (review 87: a crashed run's
   link left on the /dev/pts number a socat pty, the rotator's port, had since stopped the
   start, "the pty's link would replace the port's name", until removed by hand). Attack 28:
   ``audit_file`` naming the port passed check-config and every audit line went down the
   controller's line (a Rotor-EZ ran a refused target's ``AM1;`` inside one), and a
   ``gs232_pty`` naming its rotator's by-id link replaced it with the pty's, so the rotator
   opened the bridge's own pty and never answered. The error names the key. ``audit_file``
   may name the process's own output by name (``/dev/stdout``, ``/dev/stderr``, ``/dev/fd/N``,
   ``/proc/self/fd/N``: runtime/audit.py rule 11, the trail in the journal or a terminal): such
   a name is judged by itself, never by where the checking process's descriptor goes (review
   87: check-config in a terminal refused, as "a character device", the file it and the
   service accepted with stdout a pipe or the journal's socket); another written file naming
   one is refused. A serial line's device node (``/dev/ttyUSB0``) is still refused.
7. A file that holds a secret (``files_secret``: the MQTT and console password files, the TLS
   key, the console's secret beside the state file, kept there by any run with a console
   password) is read as nothing else (``secret_read``): no other key that names a file to
   read (a TLS certificate, the cty or TLE file) names it, nor the configuration file, which
   may hold mqtt.password; the error names both keys. An attack pass: ``tracking.tle_file``
   naming the MQTT password file passed check-config, and the start's TLE reader logged
   "line 1: '<the password>' is not followed by a TLE" at WARNING. A certificate and its key
   in one PEM file (cert_file or ca_file and key_file alike) is the one case allowed: ssl
   reads it, and never quotes it. (The remote reads no file but its secrets and TLS files,
   which its [mqtt] table's TLS check refuses as no PEM before a rule like this one could.)
   Rules 6 and 7 name each path as ``shown_path`` spells it (settings/base.py rule 8; review
   76: a file ``~/...`` in a home folder whose name is not UTF-8 ended check-config and run in
   a UnicodeEncodeError traceback here, exit 1), and so does every refusal naming the
   configuration file, whose own path may be any bytes (settings/base.py rule 3).
8. A variable that sets one entry of a table keyed by the user's names (a rotator's
   ``presets``: ``ROTOR_BRIDGE_ROTATORS__TOWER__PRESETS__EU``; groups, the other such tables,
   are set in the file only, rule 4) sets the file's entry of that name whatever its case, as
   a variable's name is read in any case; a name the file lacks is added as the variable spells
   it; two of the file's names that differ only by case are an error naming both (an attack
   pass: ``PRESETS__EU=50`` added a preset ``eu`` beside the file's ``EU = 45``; Home
   Assistant's select showed both, and ``EU`` still turned the antenna to 45).
9. The variables Kubernetes gives every pod for a Service named ``rotor-bridge`` (its
   "service links": ``ROTOR_BRIDGE_SERVICE_HOST``, ``ROTOR_BRIDGE_SERVICE_PORT[_<NAME>]``,
   ``ROTOR_BRIDGE_PORT``, ``ROTOR_BRIDGE_PORT_<n>_<TCP|UDP|SCTP>[_PROTO|_PORT|_ADDR]``) are
   no keys, and are ignored, not refused by rule 4: a review: the bridge in such a pod ended
   "ROTOR_BRIDGE_PORT: unknown key 'port'", exit 2, and restarted into it for ever, for
   variables the user never set. Only those names, in capitals, each with a value of the
   platform's form (``tcp://10.96.0.12:8754``, a port, an address), and only while no key of
   the file's top is ``port`` or ``service...``: ``ROTOR_BRIDGE_PORT=/dev/ttyUSB0`` is still
   refused. ``run`` logs at INFO which it ignored.
"""

from __future__ import annotations

import difflib
import ipaddress
import json
import os
import re
import stat
import tomllib
import types
from pathlib import Path
from typing import Annotated, Any, Union, get_args, get_origin

from pydantic import (
    BaseModel,
    Field,
    PrivateAttr,
    ValidationError,
    field_validator,
    model_validator,
)
from pydantic_settings import (
    BaseSettings,
    PydanticBaseSettingsSource,
    SettingsConfigDict,
    SettingsError,
)

from bridge.core.readfile import stream_fd
from bridge.core.text import entity_slug, shown_path
from bridge.feature import topic_words
from bridge.protocols.axes import bearing_is_elevation
from bridge.settings import errors as settings_errors
from bridge.settings.base import plain_value
from bridge.settings.dxcluster import DxClusterSettings
from bridge.settings.groups import GroupSettings, reserved, station_words
from bridge.settings.mqtt import (
    MQTT_STRING_MAX,
    TOPIC_ROOM,
    HomeAssistantSettings,
    MqttSettings,
)
from bridge.settings.pointing import StationSettings, TrackingSettings
from bridge.settings.rotator import EMULATION_KEYS, RotatorSettings
from bridge.settings.web import WebSettings
from bridge.settings.wsjtx import WsjtxSettings

ENV_PREFIX = "ROTOR_BRIDGE_"
CONFIG_FILE_MAX = 16 << 20  # rule 5: the most of a configuration file read
_SECRET = "the console's secret kept beside state_file"  # rule 6: a file written
_OWN = "give it a file of its own"  # rule 6: what to do of a file written where another is
# rule 7: the keys that read a file as a secret, and a reader allowed to share one's file
_SECRET_KEYS = ("mqtt.password_file", "web.password_file", "mqtt.tls.key_file", _SECRET)
_TOGETHER = frozenset(  # (one PEM file of a certificate and its key; ssl quotes neither)
    {("mqtt.tls.cert_file", "mqtt.tls.key_file"), ("mqtt.tls.ca_file", "mqtt.tls.key_file")}
)
# rule 6: the keys that name a pty's link, a file the bridge writes
_PTY_KEYS = tuple(f"{key}_pty" for key in EMULATION_KEYS)
_ROTATOR_ENV = re.compile(r"^ROTOR_BRIDGE_ROTATORS__([^_].*?)__([A-Za-z0-9_]+)$", re.IGNORECASE)


class ConfigError(Exception):
    """A configuration problem, worded for the user; the CLI prints it and exits with 2."""


def state_file_in(directory: str | Path) -> Path:
    """The state file the bridge keeps in ``directory`` when ``state_file`` is left out."""
    return Path(directory) / "state.json"


def _default_state_file() -> Path:
    base = os.environ.get("STATE_DIRECTORY")  # systemd's StateDirectory=
    if base:
        return state_file_in(base.split(":")[0])
    return state_file_in(Path.home() / ".local" / "state" / "rotor-bridge")


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
    web: WebSettings = Field(default_factory=WebSettings, description="the [web] table")
    wsjtx: WsjtxSettings = Field(default_factory=WsjtxSettings, description="the [wsjtx] table")
    dxcluster: DxClusterSettings = Field(
        default_factory=DxClusterSettings, description="the [dxcluster] table"
    )
    rotators: list[RotatorSettings] = Field(
        min_length=1, description="the [[rotators]] tables, one per rotator"
    )
    groups: list[GroupSettings] = Field(
        default_factory=list,
        description="the [[groups]] tables: rotators turned together from one topic "
        "(docs/groups.md)",
        json_schema_extra={"unset": "no groups"},
    )
    log_level: str = Field(
        "INFO",
        description="DEBUG, INFO, WARNING or ERROR; DEBUG shows every byte on the serial lines",
        examples=["DEBUG"],
    )
    state_file: Path = Field(
        default_factory=_default_state_file,
        description="where the lock and the options set at run time are kept across restarts; "
        "with a console password, the console's login secret (console-secret, see the "
        "console's page) is kept beside it. A file of its own: the configuration file, the "
        "audit file, a file another key names, a pty's path, a rotator's serial port or a "
        "device is refused (it would be overwritten, or written to the device). A file "
        "there that is no state file (unreadable) starts every rotator locked, and is kept as "
        "<name>.unreadable before the bridge first writes it anew. Only a lock ON there is the "
        "last word at a start: a rotator whose lock it says OFF, or does not say, takes the "
        "lock ON the broker still holds on R/lock/state (set by a run on another state_file), "
        "said on R/error, and refuses every motion until the broker has been read (the broker "
        "down at start: until it comes, or a lock word)",
        examples=["/var/lib/rotor-bridge/state.json"],
        json_schema_extra={
            "unset": "$STATE_DIRECTORY/state.json under systemd, else "
            "~/.local/state/rotor-bridge/state.json"
        },
    )
    audit_file: Path | None = Field(
        None,
        description="the audit log: one JSON line per command executed or refused, from every "
        "interface (who, how, what, the result); rotated by size. A file of its own: the "
        "configuration file, the state file, a file another key names, a pty's path, a "
        "rotator's serial port or a device is refused. /dev/stdout, /dev/stderr, /dev/fd/N "
        "and /proc/self/fd/N are taken by name: the lines go to the bridge's own output (the "
        "journal under systemd), never rotated",
        examples=["/var/log/rotor-bridge/audit.jsonl"],
        json_schema_extra={"unset": "no audit file (R/audit is published all the same)"},
    )
    audit_max_bytes: int = Field(
        1_000_000,
        ge=10_000,
        description="the audit file's size at which it is renamed to .1 (three old files kept)",
    )
    # mqtt.password is written in the configuration file itself (check-config warns)
    _password_in_file: bool = PrivateAttr(default=False)
    _service_links: list[str] = PrivateAttr(default_factory=list)  # rule 9: set, ignored
    # settings/base.py rule 2, as every table's (a BaseSettings is no Strict)
    _plain_value = field_validator("*", mode="before")(plain_value)

    @field_validator("audit_file")
    @classmethod
    def _audit_file(cls, v: Path | None) -> Path | None:
        if v is not None and os.path.isdir(os.path.expanduser(v)):  # (an attack pass: config
            raise ValueError(  # OK, and every line lost at run)
                f"{shown_path(v)} is a folder: name a file in it ({shown_path(v / 'audit.jsonl')})"
            )
        return v

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
        ports = [p for r in self.rotators for p in r.ports]  # a composite's both
        dup = {p for p in ports if ports.count(p) > 1}
        if dup:
            raise ValueError(f"port {shown_path(sorted(dup)[0])} is given to two rotators")
        # one device under two names (a /dev/serial/by-id link and its ttyUSB0): the second
        # was offline for good, "busy: another program holds it" (an attack pass)
        device: dict[str, str] = {}
        for p in ports:
            real = os.path.realpath(p) if p else p
            if real in device:
                raise ValueError(
                    f"port {shown_path(p)} is {shown_path(device[real])} under another name "
                    f"(both {shown_path(real)}): one device "
                    "is given to two rotators (name each by its /dev/serial/by-id link: a "
                    "ttyUSB number may go to another adapter at the next boot)"
                )
            device[real] = p
        _one_each(
            [(f"rotators[{i}].rotctld_port", r.rotctld_port) for i, r in enumerate(self.rotators)]
        )
        for i, r in enumerate(self.rotators):  # both TCP: the second listener could not start
            if self.web.enabled and r.rotctld_port == self.web.port:
                raise ValueError(
                    f"web.port {self.web.port} is also rotators[{i}].rotctld_port: give the "
                    "console another port"
                )
        # a GS-232, Easycomm or DCU-1 port is no other TCP listener's (the second could not
        # start) and no PstRotator port (one number, one program to point at it)
        taken = [("web.port", self.web.port)] if self.web.enabled else []
        emulated = tuple(f"{key}_port" for key in EMULATION_KEYS)
        keys = ("rotctld_port", "pst_udp_port", *emulated)
        taken += [
            (f"rotators[{i}].{k}", getattr(r, k)) for i, r in enumerate(self.rotators) for k in keys
        ]
        for name, port in taken:
            clash = [other for other, p in taken if p == port and other != name]
            if port is not None and name.endswith(emulated) and clash:
                raise ValueError(f"{name} {port} is also {clash[0]}: give it another port")
        ptys = [
            (os.path.abspath(os.path.expanduser(path)), f"rotators[{i}].{k}")
            for i, r in enumerate(self.rotators)
            for k in (f"{key}_pty" for key in EMULATION_KEYS)
            if (path := getattr(r, k)) is not None
        ]
        for n, (path, name) in enumerate(ptys):  # one link, one pty
            clash = [other for p, other in ptys[:n] if p == path]
            if clash:
                raise ValueError(
                    f"{name} {shown_path(path)} is also {clash[0]}: give it another path"
                )
        pst = [r.pst_udp_port for r in self.rotators if r.pst_udp_port is not None]
        n1mm_ports = {r.n1mm_udp_port for r in self.rotators if r.n1mm_rotor_name is not None}
        n1mm_first: dict[int, str] = {}  # (rotators named on one N1MM port share it: below)
        for i, r in enumerate(self.rotators):
            if r.n1mm_rotor_name is not None:
                n1mm_first.setdefault(r.n1mm_udp_port, f"rotators[{i}].n1mm_udp_port")
        _one_each(
            [(f"rotators[{i}].pst_udp_port", r.pst_udp_port) for i, r in enumerate(self.rotators)]
            + [(name, port) for port, name in n1mm_first.items()]
        )
        if self.wsjtx.enabled and self.wsjtx.port in {*pst, *n1mm_ports}:  # (an attack pass)
            what = "a pst_udp_port" if self.wsjtx.port in pst else "an n1mm_udp_port"
            raise ValueError(
                f"wsjtx.port {self.wsjtx.port} is also {what}: one UDP port, one program"
            )
        named = [r for r in self.rotators if r.n1mm_rotor_name is not None]
        binds: dict[int, set[str]] = {}
        for r in named:  # interfaces/loggers/server.py rule 10: a port is one socket's alone
            binds.setdefault(r.n1mm_udp_port, set()).add(r.n1mm_udp_bind)
        for port, where in binds.items():
            if len(where) > 1:
                raise ValueError(
                    f"n1mm_udp_port {port} is bound to {' and '.join(sorted(where))} by "
                    "different rotators: give them one n1mm_udp_bind (every rotator named on "
                    "one N1MM port shares its address), or each its own port"
                )
        names = [(r.n1mm_udp_bind, r.n1mm_udp_port, r.n1mm_rotor_name) for r in named]
        for key in {n for n in names if names.count(n) > 1}:  # one name, chosen by band
            if any(n == key and not r.bands for n, r in zip(names, named, strict=True)):
                raise ValueError(
                    f"two rotators have n1mm_rotor_name {key[2]!r} on one N1MM port: give "
                    "each its own, or give each of them its bands to be chosen by"
                )
        owner: dict[str, str] = {}  # settings/bands.py rule 3
        for r in self.rotators:
            for band in r.bands:
                if band in owner:
                    raise ValueError(
                        f"rotators {owner[band]!r} and {r.id!r} both have {band!r} in bands: "
                        "a band turns one antenna"
                    )
                owner[band] = r.id
        topic_of: dict[str, str] = {}
        for r in self.rotators:
            topic = self.rotator_topic(r)
            if topic in topic_of:
                raise ValueError(
                    f"rotators {topic_of[topic]!r} and {r.id!r} share the topic {topic!r} "
                    "(a rotator's topic is its topic key, else mqtt.base_topic/<id>): "
                    "give one of them another topic"
                )
            topic_of[topic] = r.id
        prefix = self.homeassistant.discovery_prefix
        if self.homeassistant.enabled and self.base_under_discovery():
            raise ValueError("homeassistant.discovery_prefix must differ from mqtt.base_topic")
        # discovery's topics hold both (<prefix>/<platform>/rotorbridge_<base>_r_<id>/...)
        both = len(prefix.encode()) + len(self.mqtt.base_topic.encode())
        if self.homeassistant.enabled and both > MQTT_STRING_MAX - TOPIC_ROOM:
            raise ValueError(
                "mqtt.base_topic and homeassistant.discovery_prefix are together at most "
                f"{MQTT_STRING_MAX - TOPIC_ROOM} bytes in UTF-8 (discovery's topics hold both, "
                f"and MQTT's limit is {MQTT_STRING_MAX}); these are {both}"
            )
        return self

    @model_validator(mode="after")
    def _rotator_topics(self) -> Settings:
        """settings/groups.py rule 5: a rotator's topic under another's, or under the base
        topic, takes none of their topics' words (one topic would be a command of one and a
        reading of the other, or the bridge's own); none lies under Home Assistant's discovery
        prefix, nor Home Assistant's status topic under it (its R/status would be that)."""
        roots = [(r.id, self.rotator_topic(r)) for r in self.rotators]
        for i, (r, (_, root)) in enumerate(zip(self.rotators, roots, strict=True)):
            above = [
                (f"rotator {rid!r}", other, reserved()) for rid, other in roots if other != root
            ]
            for whose, prefix, words in [
                *above,
                ("the bridge", self.mqtt.base_topic, station_words()),
            ]:
                word = _word_under(root, prefix, words)
                if word is not None:
                    raise ValueError(
                        f"rotators[{i}].{'topic' if r.topic else 'id'}: its topic {root} lies "
                        f"under {prefix} (of {whose}), where {word!r} is a word of the bridge's "
                        "own topics: choose another"
                    )
            ha = self.homeassistant
            if ha.enabled and (root + "/").startswith(ha.discovery_prefix + "/"):
                raise ValueError(
                    f"rotators[{i}].{'topic' if r.topic else 'id'}: its topic {root} lies "
                    f"under homeassistant.discovery_prefix {ha.discovery_prefix}: choose another"
                )
            if ha.enabled and ha.status_topic.startswith(root + "/"):
                raise ValueError(
                    f"rotators[{i}].{'topic' if r.topic else 'id'}: homeassistant.status_topic "
                    f"{ha.status_topic} lies under its topic {root}: choose another"
                )
        return self

    @model_validator(mode="after")
    def _wind_topics(self) -> Settings:
        """settings/wind.py rule 3: a wind topic is none of the bridge's own topics (a
        rotator's, a group's, the bridge's ``B/bridge/...`` and the station features'), where
        no weather station publishes: such a topic would stay silent, or carry the bridge's own
        numbers (an attack pass: ``wind_topic = "rotor/bearing"`` was taken without a word).
        Under a rotator's or a group's topic only its words are its own, as for a rotator's
        topic under another's (``_rotator_topics``): a lone rotator's topic is the base topic,
        and a station's ``rotor/weather/wind`` beside it is no topic of the bridge's (a review:
        it was refused with one rotator, and taken with two)."""
        # (whose, its topic, the words under it that are its own, whether that topic is too)
        words = reserved()
        ours = [(f"rotator {r.id!r}", self.rotator_topic(r), words, True) for r in self.rotators]
        ours += [(f"group {g.id!r}", self.group_topic(g), words, True) for g in self.groups]
        ours.append(("the bridge", self.mqtt.base_topic, station_words(), False))
        for i, r in enumerate(self.rotators):
            topic = r.wind_topic
            if topic is None:
                continue
            for whose, root, own, itself in ours:
                word = _word_under(topic, root, own)
                if (itself and topic == root) or word is not None:
                    under = root if itself else f"{root}/{word}"
                    raise ValueError(
                        f"rotators[{i}].wind_topic: {topic} is one of the bridge's own topics "
                        f"(under {under}, {whose}'s): give the weather station's topic"
                    )
        return self

    @model_validator(mode="after")
    def _groups(self) -> Settings:
        """settings/groups.py rule 4: members are rotators, a group's topics no other's."""
        roots = {r.id: self.rotator_topic(r) for r in self.rotators}
        models = {r.id: r.model for r in self.rotators}
        specs = {r.id: r.spec for r in self.rotators}
        seen: set[str] = set()
        # Home Assistant's entity ids write each run of "-" and "_" as one "_", none at the end
        # (core/text.py entity_slug): two ids that differ only so would ask for the same
        # entities (an attack pass: one got "_2", in whichever order discovery came, and
        # dashboards pointed at the other antenna; "tower" and "tower-" the same, found later)
        slugs: dict[str, tuple[str, str]] = {}
        for kind, ident in [("rotator", r.id) for r in self.rotators] + [
            ("group", g.id) for g in self.groups
        ]:
            slug = entity_slug(ident)
            other = slugs.setdefault(slug, (kind, ident))
            if other[1] != ident:  # (one id twice: the checks below name it)
                raise ValueError(
                    f"{kind} id {ident!r} and {other[0]} {other[1]!r} are one name to Home "
                    f"Assistant ({slug}: it writes each run of '-' and '_' as one '_', none at "
                    "the end): give one of them another id"
                )
        for i, g in enumerate(self.groups):
            where = f"groups[{i}]"
            if g.id in seen:
                raise ValueError(f"{where}.id: group id {g.id!r} is used twice")
            seen.add(g.id)
            for rid in g.rotators:
                if rid not in roots:
                    raise ValueError(
                        f"{where}.rotators: {rid!r} is no rotator's id (the rotators are "
                        f"{', '.join(roots)})"
                    )
                model = models[rid]
                if bearing_is_elevation(specs[rid]):  # (an attack pass: G/target 80 tilted it)
                    raise ValueError(
                        f"{where}.rotators: {rid!r} is a {model} box, whose bearing is an "
                        "elevation: a group turns its members in azimuth; leave it out"
                    )
            if g.id in reserved():
                whose = topic_words().get(g.id)
                of = f" (the {whose} feature's)" if whose is not None else ""
                raise ValueError(
                    f"{where}.id: {g.id!r} is a word of the bridge's own topics{of}: choose another"
                )
            root = self.group_topic(g)
            for rid, r_root in roots.items():
                if root == r_root or r_root.startswith(root + "/"):
                    raise ValueError(
                        f"{where}.id: {g.id!r} would share its topic {root} with rotator {rid!r}"
                    )
        return self

    def group_topic(self, g: GroupSettings) -> str:
        """Where a group's topics are (``<base_topic>/<id>``)."""
        return f"{self.mqtt.base_topic}/{g.id}"

    @model_validator(mode="after")
    def _own_files(self) -> Settings:
        """Rule 6: the files the bridge writes are no file the settings name otherwise."""
        written = self.files_written()
        for n, (name, path) in enumerate(written):
            if name != "audit_file" and stream_fd(path) is not None:  # (audit.py rule 11)
                raise ValueError(
                    f"{name} {shown_path(path)} names one of the process's own descriptors, not "
                    f"a file: only audit_file may be the process's output; {_OWN}"
                )
            for other, given in [*written[n + 1 :], *self.files_read()]:
                if _written_at(name, path, other, given):
                    fix = "name that file otherwise" if name == _SECRET else _OWN
                    raise ValueError(
                        f"{name} {shown_path(path)} is also {other}: the bridge writes there, and "
                        f"would overwrite it; {fix}"
                    )
            for other, port in self.serial_ports():  # (a pty's at the port's device too)
                if _loop_back(name, other, port):
                    continue
                if _written_at(name, path, other, Path(port)):
                    raise ValueError(_on_a_port(name, path, other, port))
            mine = name.endswith(_PTY_KEYS) or stream_fd(path) is not None  # (judged by name)
            device = None if mine else _device_at(path)
            if device is not None:
                fix = "remove what is there" if name == _SECRET else _OWN  # (no key names it)
                raise ValueError(
                    f"{name} {shown_path(path)} is a {device}, not a file: the bridge writes "
                    f"there, and what it writes would go to the device; {fix}"
                )
        said = secret_read(self.files_secret(), self.files_read())  # rule 7
        if said is not None:
            raise ValueError(said)
        return self

    def files_secret(self) -> list[tuple[str, Path]]:
        """The files that hold a secret (rule 7), by key: the console's secret whether or not
        the console has a password now (a run that had one left it there)."""
        secret = [(name, path) for name, path in self.files_read() if name in _SECRET_KEYS]
        return [*secret, (_SECRET, self.console_secret())]

    def files_written(self) -> list[tuple[str, Path]]:
        """The files the bridge writes (rule 6), by key: a pty's link too (ptylines.py rule 1:
        it replaces a link there)."""
        written = [("state_file", self.state_file)]
        if self.audit_file is not None:
            written.append(("audit_file", self.audit_file))
        if self.web.password_file is not None:  # (app.py: a short one is made anew)
            written.append((_SECRET, self.console_secret()))
        written += [
            (f"rotators[{i}].{key}", Path(path))
            for i, r in enumerate(self.rotators)
            for key in _PTY_KEYS
            if (path := getattr(r, key)) is not None
        ]
        return written

    def serial_ports(self) -> list[tuple[str, str]]:
        """The rotators' serial ports (rule 6), by key (a composite's both)."""
        return [
            (f"rotators[{i}].{key}", port)
            for i, r in enumerate(self.rotators)
            for key, port in zip(
                ["azimuth.port", "elevation.port"] if r.axes else ["port"], r.ports, strict=True
            )
        ]

    def console_secret(self) -> Path:
        """Where the console's login secret is kept (interfaces/web/auth.py rule 2)."""
        return self.state_file.with_name("console-secret")

    def files_read(self) -> list[tuple[str, Path]]:
        """The files the settings name for the bridge to read (rule 6), by key."""
        tls, dx = self.mqtt.tls, self.dxcluster
        named = [
            ("mqtt.password_file", self.mqtt.password_file),
            ("mqtt.tls.ca_file", tls.ca_file),
            ("mqtt.tls.cert_file", tls.cert_file),
            ("mqtt.tls.key_file", tls.key_file),
            ("web.password_file", self.web.password_file),
            ("dxcluster.cty_file", dx.cty_file),
            ("tracking.tle_file", self.tracking.tle_file),
        ]
        return [(name, path) for name, path in named if path is not None]

    @model_validator(mode="after")
    def _installation(self) -> Settings:
        self.mqtt._state_file = str(self.state_file.expanduser().absolute())
        return self

    def base_under_discovery(self) -> bool:
        """The base topic is Home Assistant's discovery prefix or lies under it: refused with
        discovery on; with it off, nothing there is read as an earlier run's configs (app.py)."""
        prefix, base = self.homeassistant.discovery_prefix, self.mqtt.base_topic
        return prefix == base or base.startswith(prefix + "/")

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


def _one_each(ports: list[tuple[str, int | None]]) -> None:
    """ValueError naming the two keys that give one port (None: not given). An attack pass: a
    single rotator's pst_udp_port that was also its n1mm_udp_port was "two rotators share one
    pst_udp_port", naming neither key."""
    first: dict[int, str] = {}
    for key, port in ports:
        if port is None:
            continue
        if port in first:
            raise ValueError(f"{key} {port} is also {first[port]}: give it another port")
        first[port] = key


def _word_under(topic: str, prefix: str, words: frozenset[str]) -> str | None:
    """The word of ``words`` that ``topic`` has right under ``prefix``, if it has one (a topic
    of ``prefix``'s own: settings/groups.py rule 5, settings/wind.py rule 3)."""
    word = topic.removeprefix(prefix + "/").split("/")[0]
    return word if topic.startswith(prefix + "/") and word in words else None


def same_file(a: str | os.PathLike[str], b: str | os.PathLike[str]) -> bool:
    """Whether ``a`` and ``b`` are one file (rule 6): by the file itself where both are there
    (a link, a second name), else by the path they resolve to."""
    a, b = os.path.expanduser(a), os.path.expanduser(b)
    try:
        return os.path.samefile(a, b)
    except (OSError, ValueError):  # (one not there yet)
        return os.path.realpath(a) == os.path.realpath(b)


def _written_at(name: str, path: Path, other: str, given: Path) -> bool:
    """Rule 6: whether ``name``'s file at ``path`` is ``other``'s at ``given``. A pty's file is
    its link, not what a link there points at now (a crashed run's pty, replaced at the start;
    review 87: a leftover on the /dev/pts number a socat port had since was taken for the
    port): it is the other's if its place is the other's, or one the other's links go through
    or lead to."""
    if stream_fd(path) is not None or stream_fd(given) is not None:  # (by name: rule 6)
        return _place(path) == _place(given)
    ptys = [p for key, p in ((name, path), (other, given)) if key.endswith(_PTY_KEYS)]
    if not ptys:
        return same_file(path, given)
    if len(ptys) == 2:
        return _place(path) == _place(given)
    pty, file = (path, given) if name.endswith(_PTY_KEYS) else (given, path)
    return pty_takes(pty, file)


def pty_takes(pty: str | os.PathLike[str], file: str | os.PathLike[str]) -> bool:
    """Rule 6: whether a pty's link at ``pty`` would take over the name of the file at ``file``
    (the remote's ptys against the files it reads: remote/settings.py rule 6)."""
    if stream_fd(pty) is not None or stream_fd(file) is not None:
        return _place(Path(pty)) == _place(Path(file))
    return _place(Path(pty)) in _ways(Path(file))


def _place(path: Path) -> str:
    """Where ``path`` is, its folder's links followed and not its own (a pty's link)."""
    full = os.path.abspath(os.path.expanduser(path))
    return os.path.join(os.path.realpath(os.path.dirname(full)), os.path.basename(full))


def _ways(path: Path) -> set[str]:
    """Rule 6: the places of ``path``, of every link on its way to the file, and of the file: a
    pty's link at any of them would take that name over (a by-id link to a by-id link)."""
    ways = {_place(path), os.path.realpath(os.path.expanduser(path))}
    here = _place(path)
    for _ in range(40):  # (the kernel's own bound on a chain of links)
        try:
            target = os.readlink(here)
        except (OSError, ValueError):  # (no link: the file, or nothing there yet)
            break
        here = _place(Path(os.path.join(os.path.dirname(here), target)))
        ways.add(here)
    return ways


def _on_a_port(name: str, path: Path, port_key: str, port: str) -> str:
    """Rule 6: why a file the bridge writes may not be a rotator's serial port."""
    where = f"{name} {shown_path(path)} is also {port_key} ({shown_path(port)}), a serial port"
    if name.endswith(_PTY_KEYS):  # (ptylines.py rule 1: the port's link replaced by the pty's)
        return (
            f"{where}: the pty's link would replace the port's name, and the rotator would open "
            "the bridge's own pty, not the controller; give the pty another path"
        )
    return f"{where}: what the bridge writes there would go to the controller; {_OWN}"


# Linux's character majors of serial lines and terminals (Documentation/admin-guide/devices):
# 3 old ptys, 4 tty/ttyS, 5 tty/console/ptmx, 136-143 pts, 166 ttyACM, 188 ttyUSB, 204 more UARTs
_SERIAL_MAJORS = frozenset((3, 4, 5, *range(136, 144), 166, 188, 204))


def _device_at(path: Path) -> str | None:
    """Rule 6: what is at ``path`` (links followed) if it is a serial line or a disk, else
    None. Other devices are files to write to as far as the bridge cares (``/dev/null``, and
    ``/dev/full`` to try a full disk: the first CI run of attack 28's fix refused both)."""
    try:
        st = os.stat(os.path.expanduser(path))
    except (OSError, ValueError):  # (not there yet, or not to be looked at: the start says)
        return None
    if stat.S_ISCHR(st.st_mode) and os.major(st.st_rdev) in _SERIAL_MAJORS:
        return "serial line or terminal"
    return "block device" if stat.S_ISBLK(st.st_mode) else None


def _loop_back(name: str, port_key: str, port: str) -> bool:
    """Rule 6: whether ``name``, a rotator's pty, is another rotator's port that a link to a
    pty stands at or nothing does: the bridge driving its own emulated port (a Rotor-EZ
    rotator on a DCU-1 rotator's pty, as the integration tests run them). A pty on its own
    rotator's port, or on a port where a real serial line stands, is still refused (attack
    28: the by-id name pasted into both)."""
    if not name.endswith(_PTY_KEYS) or name.split(".")[0] == port_key.split(".")[0]:
        return False
    try:
        st = os.stat(os.path.expanduser(port))
    except (OSError, ValueError):
        return True  # (nothing there: the pty's link will be it)
    return stat.S_ISCHR(st.st_mode) and os.major(st.st_rdev) in range(136, 144)


def secret_read(secret: list[tuple[str, Path]], read: list[tuple[str, Path]]) -> str | None:
    """Rule 7: why a key of ``read`` that reads no secret names a file of ``secret`` (both by
    key), or None."""
    for name, path in read:
        if name in _SECRET_KEYS:
            continue
        for holder, held in secret:
            if (name, holder) not in _TOGETHER and same_file(path, held):
                return (
                    f"{name} {shown_path(path)} is also {holder}: a secret's file, which {name} "
                    f"would read as no secret (and could quote in the log); name the file {name} "
                    "wants"
                )
    return None


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
            data = f.read(CONFIG_FILE_MAX + 1)  # rule 5
        if len(data) > CONFIG_FILE_MAX:
            raise ConfigError(
                f"config file {shown_path(path)} is larger than {CONFIG_FILE_MAX >> 20} MiB: no "
                "configuration is (is it the right file?)"
            )
        # rule 5: a byte-order mark at the start is dropped (decoded whole first, so a byte an
        # error names is counted from the file's start)
        return tomllib.loads(data.decode().removeprefix("\ufeff"))
    except FileNotFoundError:
        raise ConfigError(f"config file {shown_path(path)} not found") from None
    except OSError as exc:
        raise ConfigError(f"config file {shown_path(path)}: {exc.strerror}") from None
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"config file {shown_path(path)} is not valid TOML: {exc}") from None
    except RecursionError:  # (arrays or tables nested past the parser's depth)
        raise ConfigError(
            f"config file {shown_path(path)} is not valid TOML: nested too deep"
        ) from None
    except UnicodeDecodeError as exc:
        raise ConfigError(
            f"config file {shown_path(path)} is not UTF-8 text (byte {exc.start}): save it as UTF-8"
        ) from None


def settings_from(
    data: dict[str, Any],
    environ: Any = None,
    path: str | os.PathLike[str] | None = None,
) -> Settings:
    """``data`` (a TOML document) with the environment's overrides, validated (ConfigError)."""
    env = os.environ if environ is None else environ
    links = service_links(env)  # rule 9
    ours = {k: v for k, v in env.items() if k not in links}
    _check_variables(ours)
    _one_variable_each(ours)
    _no_group_variables(env)
    _apply_rotator_env(data, env)
    unknown = [k for k in data if k not in Settings.model_fields]
    if (
        "rotators" not in data
        and not unknown  # a misspelt [[rotators]] is named as that (rule 1)
        and not any(k.upper().startswith("ROTOR_BRIDGE_ROTATORS") for k in env)
    ):
        if path:
            raise ConfigError(
                f"no rotators configured in {shown_path(path)}: add a [[rotators]] table with "
                "id, model and port (docs/configuration.md)"
            )
        raise ConfigError(
            "no configuration file given: pass --config FILE (see config/example.toml) "
            "or set ROTOR_BRIDGE_CONFIG"
        )
    try:
        settings = Settings(**data)
    except ValidationError as exc:
        raise ConfigError(format_validation_error(exc, data, env)) from None
    except SettingsError as exc:  # a variable pydantic-settings reads as JSON, and cannot
        raise ConfigError(_not_json(exc, env)) from None
    for name, written in settings.files_written():  # rule 6: nor the file itself
        if path and _written_at(name, written, "the configuration file", Path(path)):
            raise ConfigError(
                f"invalid configuration:\n  {name}: {shown_path(written)} is the configuration "
                "file itself: "
                f"the bridge writes there, and would overwrite it; {_OWN}"
            )
    said = path and secret_read([("the configuration file", Path(path))], settings.files_read())
    if said:  # rule 7: nor the file that may hold mqtt.password
        raise ConfigError(f"invalid configuration:\n  {said}")
    mqtt = data.get("mqtt")
    settings._password_in_file = isinstance(mqtt, dict) and "password" in mqtt
    settings._service_links = links
    return settings


def _not_json(exc: SettingsError, env: Any) -> str:
    """A list or a table set from the environment is JSON (an attack pass: a plain value there
    ended ``run`` in a traceback naming neither the variable nor the key)."""
    m = re.search(r'field "(\w+)"', str(exc))
    table = (m.group(1) if m else "").upper()
    names = sorted(
        k
        for k in env
        if table
        and k.upper().startswith(f"{ENV_PREFIX}{table}")
        and _complex(k.upper().removeprefix(ENV_PREFIX).lower().split("__"))
        and not _is_json(env[k])
    )
    where = ", ".join(names) or f"a {ENV_PREFIX}{table or '...'} variable"
    return (
        f"{where}: a list or a table is set from the environment in JSON "
        f"({ENV_PREFIX}WEB__HOST_NAMES='[\"shack.example.org\"]'), or in the configuration file"
    )


def _complex(path: list[str]) -> bool:
    """Whether the key at ``path`` (a table's, then its key's) is a list or a table: what
    pydantic-settings reads from the environment as JSON."""
    model: Any = Settings
    annotation: Any = None
    for name in path:
        fields = getattr(model, "model_fields", None)
        if not fields or name not in fields:
            return False
        annotation = fields[name].annotation
        model = next((a for a in (annotation, *get_args(annotation)) if isinstance(a, type)), None)
    kinds = (annotation, *get_args(annotation))
    return any(
        get_origin(a) in (list, dict, tuple, set)
        or (isinstance(a, type) and issubclass(a, (BaseModel, list, dict, tuple, set)))
        for a in kinds
    )


def _is_json(text: str) -> bool:
    try:
        json.loads(text)
    except ValueError:
        return False
    return True


# rule 9: the variables Kubernetes gives every pod for a Service named rotor-bridge (its
# "service links", enableServiceLinks on by default: the Service's own, then docker links')
_LINK_NAMES = re.compile(
    r"^ROTOR_BRIDGE_(?:SERVICE_HOST|SERVICE_PORT(?:_[A-Z0-9]+)*|PORT"
    r"|PORT_(?P<port>[0-9]+)_(?P<proto>TCP|UDP|SCTP)(?:_(?P<part>PROTO|PORT|ADDR))?)$"
)
_LINK_URL = re.compile(
    r"^(?P<proto>tcp|udp|sctp)://(?P<host>\[[0-9A-Fa-f:.]+\]|[0-9.]+):(?P<port>[0-9]+)$"
)


def _an_address(text: str) -> bool:
    try:
        ipaddress.ip_address(text.removeprefix("[").removesuffix("]"))
    except ValueError:
        return False
    return True


def _a_port(text: str) -> bool:
    return text.isascii() and text.isdigit() and 0 < int(text) < 65536


def _service_link(key: str, value: str) -> bool:
    """Rule 9: whether variable ``key`` is one Kubernetes sets for a Service named rotor-bridge,
    its name in the platform's spelling (capitals) and its value of the platform's form."""
    m = _LINK_NAMES.match(key)
    if m is None:
        return False
    if key == "ROTOR_BRIDGE_SERVICE_HOST" or m["part"] == "ADDR":
        return _an_address(value)
    if m["part"] == "PROTO":
        return value == m["proto"].lower()
    if m["part"] == "PORT":
        return value == m["port"] and _a_port(value)
    if key.startswith("ROTOR_BRIDGE_SERVICE_PORT"):
        return _a_port(value)
    url = _LINK_URL.match(value)  # ROTOR_BRIDGE_PORT, ROTOR_BRIDGE_PORT_<n>_<PROTO>
    return (
        url is not None
        and _an_address(url["host"])
        and _a_port(url["port"])
        and (m["port"] is None or (url["port"], url["proto"]) == (m["port"], m["proto"].lower()))
    )


def service_links(env: Any) -> list[str]:
    """Rule 9: the variables of ``env`` that Kubernetes set for a Service named rotor-bridge,
    which the bridge ignores (none of them names a key: ``port`` and ``service_*`` are no keys
    of the file's top)."""
    return sorted(k for k in env if _service_link(k, env[k]) and not _names_a_key(k))


def _names_a_key(key: str) -> bool:
    """Whether variable ``key`` could name a key of the file's top (the whole of it after the
    prefix, or its start up to a ``_``): then it is no service link, whatever its form."""
    name = key[len(ENV_PREFIX) :].lower()
    return any(name == f or name.startswith(f"{f}_") for f in Settings.model_fields)


def _check_variables(env: Any) -> None:
    """Rule 4: ConfigError naming the first variable of the bridge that names no key."""
    known = [*Settings.model_fields, "config"]
    for key in sorted(env):
        if not key.upper().startswith(ENV_PREFIX):
            continue
        name = key[len(ENV_PREFIX) :].lower()
        first = name.split("__")[0]
        if first == "config" and name != first:
            raise ConfigError(
                f"{key}: {ENV_PREFIX}CONFIG names the configuration file, and has no keys under "
                f"it: set {ENV_PREFIX}CONFIG itself, or a key as {ENV_PREFIX}<KEY>"
            )
        if name == "config" and key != f"{ENV_PREFIX}CONFIG":  # (read so spelt: cli.py too)
            raise ConfigError(
                f"{key}: the configuration file's variable is spelt {ENV_PREFIX}CONFIG, in capitals"
            )
        if first in known:
            if first not in ("rotators", "groups"):  # (theirs: _apply_rotator_env, below)
                _nothing_under_a_value(key, name.split("__"))
            continue
        table = next((t for t in known if first.startswith(f"{t}_")), None)
        if table is None:
            table = next(iter(difflib.get_close_matches(first, known, n=1, cutoff=0.6)), None)
            rest = name[len(first) :]
        else:
            rest = "__" + name[len(table) + 1 :]
        hint = f": did you mean {ENV_PREFIX}{(table + rest).upper()}?" if table else ""
        raise ConfigError(
            f"{key}: unknown key {first!r} (the keys at the top: "
            f"{', '.join(Settings.model_fields)}; a table's keys are joined with __){hint}"
        )


def _one_variable_each(env: Any) -> None:
    """Rule 4: ConfigError naming two variables that set one key: names that differ only by
    case (``ROTOR_BRIDGE_MQTT__HOST``, ``rotor_bridge_mqtt__host``; ``PRESETS__EU``,
    ``PRESETS__eu``), or one setting a table whole and the other a key in it where their
    order decides (``ROTOR_BRIDGE_MQTT__TLS``, ``ROTOR_BRIDGE_MQTT__TLS__CA_FILE``; not a table
    of the top: _laid_over). An attack pass: which one the bridge took was decided by their
    order in the environment, without a word."""
    ours = sorted(
        (k for k in env if k.upper().startswith(ENV_PREFIX)), key=lambda k: (k.upper(), k)
    )
    for i, a in enumerate(ours):
        for b in ours[i + 1 :]:
            wa, wb = a.upper().split("__"), b.upper().split("__")
            if wa == wb:
                raise ConfigError(
                    f"{a}, {b}: both set one key (a variable's name is read in any case), and "
                    "which the bridge took would depend on their order: set one"
                )
            if wa == wb[: len(wa)] and not _laid_over(wa):  # (sorted: the shorter is first)
                raise ConfigError(
                    f"{a}, {b}: the first sets a table whole and the second a key in it, and "
                    "which the bridge took would depend on their order: set one"
                )


def _laid_over(words: list[str]) -> bool:
    """Whether the variable of ``words`` (its name split at ``__``) sets a table of the top
    whole, in JSON, which pydantic-settings reads first and lays every variable of a key in it
    over, in whatever order they come (its env source: the table's JSON, then ``deep_update``
    with the rest): the key's variable is what the bridge takes for that key, the JSON for the
    others (a review: 2bfa58c0 refused ``ROTOR_BRIDGE_MQTT`` beside compose.yaml's
    ``ROTOR_BRIDGE_MQTT__HOST``, which had always worked). A table below the top is laid in
    the environment's order, and a rotator's keys (_apply_rotator_env) likewise: refused."""
    if len(words) != 1:
        return False
    field = Settings.model_fields.get(words[0].removeprefix(ENV_PREFIX).lower())
    if field is None:
        return False
    kinds = [field.annotation]
    if get_origin(field.annotation) in (Union, types.UnionType):  # (``... | None``)
        kinds = list(get_args(field.annotation))
    return all(get_origin(a) is not list for a in kinds) and any(
        get_origin(a) is dict or (isinstance(a, type) and issubclass(a, BaseModel)) for a in kinds
    )


def _nothing_under_a_value(key: str, path: list[str], rotator: str | None = None) -> None:
    """Rule 4: ConfigError if variable ``key``, setting the key at ``path``, goes through a key
    that is one value (text, a number, a list): nothing is under it (an attack pass:
    ``ROTOR_BRIDGE_LOG_LEVEL__X`` and ``ROTOR_BRIDGE_STATE_FILE__X`` were dropped without a
    word, ``ROTOR_BRIDGE_MQTT__HOST__X`` was "mqtt.host: Input should be a valid string",
    naming no variable). ``rotator``: the id of the rotator whose key ``path`` (``rotators``,
    then the key) is."""
    for i in range(1, len(path)):
        annotation = _annotation_at(path[:i])
        if annotation is None:
            return  # an unknown key: validation names it and the variable
        if not any(
            get_origin(a) is dict or (isinstance(a, type) and issubclass(a, BaseModel))
            for a in _kinds(annotation)
        ):
            over = key.rsplit("__", len(path) - i)[0]
            where = ".".join(path[:i])
            if rotator is not None:
                where = f"rotator {rotator!r}'s {'.'.join(path[1:i])}"
            raise ConfigError(
                f"{key}: {where} is one value, not a table: there is no key under it (set "
                f"{over} itself)"
            )


def _no_group_variables(env: Any) -> None:
    """Rule 4: ConfigError naming the first variable that would set a group."""
    for key in sorted(env):
        if key.upper() == f"{ENV_PREFIX}GROUPS" or key.upper().startswith(f"{ENV_PREFIX}GROUPS__"):
            raise ConfigError(
                f"{key}: groups are set in the configuration file only ([[groups]]), not from "
                f"the environment (a rotator's keys are: {ENV_PREFIX}ROTATORS__<ID>__<KEY>)"
            )


def _apply_rotator_env(data: dict[str, Any], env: Any) -> None:
    if not isinstance(data.get("rotators", []), list):
        # nothing to set a rotator's key in: validation names ``rotators`` (an attack pass:
        # ``rotators = 5`` with any rotator's variable was a TypeError traceback, exit code 1)
        return
    rotators = [r for r in data.get("rotators", []) if isinstance(r, dict)]
    for key, value in env.items():
        if not key.upper().startswith(f"{ENV_PREFIX}ROTATORS__"):
            continue
        # a key of a table in the rotator (its azimuth box's port) joined with "__" as elsewhere
        r, rid, words = _rotator_of(key, rotators, data)
        path = [w.lower() for w in words]
        _nothing_under_a_value(key, ["rotators", *path], rid)
        if _complex(["rotators", *path]):  # a list or a table: JSON, as for the other tables
            try:  # (a review: the text itself was handed on, and refused as no table)
                value = json.loads(value)
            except (ValueError, RecursionError):
                raise ConfigError(
                    f"{key}: a list or a table is set from the environment in JSON "
                    f"({ENV_PREFIX}ROTATORS__{rid.upper()}__PRESETS='{{\"EU\": 45}}'), or in the "
                    "configuration file"
                ) from None
        for i, name in enumerate(path[:-1]):
            if _user_keyed(["rotators", *path[:i]]):
                name = _file_key(key, r, words[i])
            if not isinstance(r.get(name), dict):
                r[name] = {}
            r = r[name]
        last = path[-1]
        if _user_keyed(["rotators", *path[:-1]]):
            last = _file_key(key, r, words[-1])
            value = _entry_value(key, ["rotators", *path[:-1]], value)
        r[last] = value


def _rotator_of(
    key: str, rotators: list[dict[str, Any]], data: dict[str, Any]
) -> tuple[dict[str, Any], str, list[str]]:
    """The rotator (its table in the file) whose key variable ``key`` sets, its id, and the
    key's words as the variable spells them. The file's ids are looked for whole, in any case,
    so an id with ``__`` in it or at its end (``a__b``, ``tower_``) is read as one; ConfigError
    (rule 4) where none is, or where two ids both fit. An id with ``-`` keeps it in the name
    (``ROTOR_BRIDGE_ROTATORS__TOWER-2__PORT``), which a shell's ``export`` and systemd's
    ``Environment=`` do not take: a review: ``TOWER_2`` for ``tower-2`` was only "no rotator
    with id 'tower_2'"; the refusal now says so."""
    rest = key[len(f"{ENV_PREFIX}ROTATORS__") :]
    found = []
    for r in rotators:
        rid = str(r.get("id", ""))
        if rid and rest.lower().startswith(f"{rid.lower()}__") and len(rest) > len(rid) + 2:
            found.append((r, rid, rest[len(rid) + 2 :].split("__")))
    if len(found) > 1:  # (``sky`` and ``sky__azimuth``): the one whose key is a rotator's
        found = [f for f in found if _annotation_at(["rotators", f[2][0].lower()]) is not None]
    if len(found) > 1:
        fits = " and ".join(f"rotator {rid!r}'s {'.'.join(w).lower()}" for _, rid, w in found)
        raise ConfigError(
            f"{key}: it may set {fits}: set the key in the configuration file, or give one "
            "rotator an id without '__'"
        )
    if found:
        r, rid, words = found[0]
        return r, rid.lower(), words
    m = _ROTATOR_ENV.match(key)
    if not m:
        raise ConfigError(_no_rotator_key(key, data))
    rid = m.group(1).lower()
    ids = [str(r.get("id", "")) for r in rotators if r.get("id")]
    dashed = [i for i in ids if "-" in i and i.lower().replace("-", "_") == rid]
    if dashed:
        named = f"{ENV_PREFIX}ROTATORS__{dashed[0].upper()}__{m.group(2)}"
        hint = (
            f"; rotator {dashed[0]!r}'s variable keeps the id's '-': {named} (a name that "
            "a shell's export and systemd's Environment= do not take; env(1) does: "
            f"env '{named}=...' rotor-bridge run ...), or set the key in the configuration file"
        )
    else:
        hint = f" (its rotators: {', '.join(ids)})" if ids else ""
    raise ConfigError(f"{key}: no rotator with id {rid!r} in the configuration{hint}")


def _annotation_at(path: list[str]) -> Any:
    """The type of the key at ``path`` (a table's, then its key's; any word in a table keyed by
    the user's names, a preset's), or None where no key is."""
    annotation: Any = Settings
    for name in path:
        kinds = _kinds(annotation)
        model = next(
            (
                a
                for a in kinds
                if isinstance(a, type) and issubclass(a, BaseModel) and name in a.model_fields
            ),
            None,
        )
        table = next((a for a in kinds if get_origin(a) is dict), None)
        if model is not None:
            annotation = model.model_fields[name].annotation
        elif table is not None:
            annotation = get_args(table)[1]
        else:
            return None
    return annotation


def _kinds(annotation: Any) -> tuple[Any, ...]:
    """What a key of type ``annotation`` may hold: a union's members, an Annotated's type, a
    list's items (``rotators``: its tables), each so unwrapped."""
    origin = get_origin(annotation)
    if origin in (Union, types.UnionType):
        return tuple(k for a in get_args(annotation) for k in _kinds(a))
    if origin in (Annotated, list):
        return _kinds(get_args(annotation)[0])
    return (annotation,)


def _user_keyed(path: list[str]) -> bool:
    """Whether the key at ``path`` is a table whose keys are the user's names (a rotator's
    ``presets``), not the bridge's."""
    return any(get_origin(a) is dict for a in _kinds(_annotation_at(path)))


def _file_key(key: str, table: dict[str, Any], word: str) -> str:
    """The key of ``table`` that ``word``, a name in variable ``key``, sets (rule 8): the
    file's own spelling, matched whatever its case, or ``word`` where the file lacks it."""
    same = sorted(k for k in table if isinstance(k, str) and k.lower() == word.lower())
    if len(same) > 1:
        raise ConfigError(
            f"{key}: {' and '.join(repr(k) for k in same)} differ only by case, and a variable's "
            "name is read in any case: it cannot say which it sets; rename one, or set it in "
            "the configuration file"
        )
    return same[0] if same else word


def _entry_value(key: str, path: list[str], value: str) -> Any:
    """``value`` for an entry of the user-keyed table at ``path``: JSON where the entry may be
    a list and ``value`` is one (a preset's ``[azimuth, elevation]``: ``PRESETS__SAT='[180,
    45]'``), else the text, which the table's type reads."""
    table = next(a for a in _kinds(_annotation_at(path)) if get_origin(a) is dict)
    entry = get_args(table)[1]  # dict[str, entry]
    if not value.lstrip().startswith("[") or not _admits_list(entry):
        return value
    try:
        return json.loads(value)
    except (ValueError, RecursionError):
        raise ConfigError(
            f"{key}: a list is set from the environment in JSON ('[180, 45]'), or in the "
            "configuration file"
        ) from None


def _admits_list(annotation: Any) -> bool:
    """Whether ``annotation`` (a union, an Annotated) takes a list."""
    return get_origin(annotation) is list or any(_admits_list(a) for a in get_args(annotation))


def _no_rotator_key(key: str, data: dict[str, Any]) -> str:
    """Rule 4: why ``key`` (``ROTOR_BRIDGE_ROTATORS__`` and no ``<ID>__<KEY>``) is refused."""
    rest = key[len(f"{ENV_PREFIX}ROTATORS__") :]
    ids = [str(r.get("id", "")) for r in data.get("rotators", []) if isinstance(r, dict)]
    hint = ""
    for rid in sorted((i for i in ids if i), key=len, reverse=True):
        if rest.lower().startswith(f"{rid.lower()}_") and len(rest) > len(rid) + 1:
            hint = f": did you mean {ENV_PREFIX}ROTATORS__{rid.upper()}__{rest[len(rid) + 1 :]}?"
            break
    return (
        f"{key}: unknown rotator key (a rotator's key is {ENV_PREFIX}ROTATORS__<ID>__<KEY>, "
        f"joined with __: {ENV_PREFIX}ROTATORS__TOWER__PORT){hint}"
    )


def format_validation_error(
    exc: ValidationError, data: dict[str, Any] | None = None, environ: Any = None
) -> str:
    """One line per problem, each naming the key as the file spells it (rule 2), and the
    environment variable where one set the value (settings/errors.py)."""
    return settings_errors.describe(exc, Settings, ENV_PREFIX, data, environ)
