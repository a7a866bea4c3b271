"""The remote's file (``rotor-bridge remote -c remote.toml``): who operates, the station's broker
and which local endpoints to offer.

Rules:
1. ``[mqtt]`` is the bridge's own table (MqttSettings: TLS, password_file, ...); ``base_topic``
   is the station's. MQTT 5 only: every command carries an expiry (interfaces/mqtt/remote.py rule
   1).
2. An endpoint may leave ``rotator`` out only when it is the only endpoint; no two endpoints
   take one address: a TCP port (whatever its bind), a UDP port or the one beside it (a PST
   client hears its replies on port + 1), a pty's path; nor the console's web.port.
3. A problem is a ConfigError naming the key as the file spells it, one line each; a table is
   settings/base.py's ``Strict`` (no unknown key, no boolean where a number goes).
4. An endpoint offers one thing at least (rotctld, GS-232, Easycomm or DCU-1 on TCP or a pty,
   PstRotator UDP); every bind is loopback unless set.
5. ``[web]`` is the bridge's own table (WebSettings), with its refusal of a console beyond
   loopback without a password.
6. A pty's path is a file the remote writes (ptylines.py rule 1 replaces a link there), as the
   bridge's settings rule 6 says of the station's: it is not the remote's file itself nor a
   file another key names (``mqtt.password_file``, ``mqtt.tls``'s files,
   ``web.password_file``), by any name its links go through (``pty_takes``), nor one of the
   process's own descriptors (``/dev/stdout``). A review (87): ``gs232_pty`` naming the
   symlinked password or configuration file (a dotfiles folder's link) passed, and the start
   replaced that link with the pty's: the next start could not read its file.
"""

from __future__ import annotations

import hashlib
import os
import re
import socket
from pathlib import Path
from typing import Any, Literal, NamedTuple

from pydantic import Field, ValidationError, field_validator, model_validator

from bridge.core.model import OPERATOR_CHARS, operator_name, valid_operator
from bridge.core.readfile import stream_fd
from bridge.core.text import NOT_TEXT, bad_char, shown_path
from bridge.settings import ConfigError, pty_takes, read_toml
from bridge.settings.base import Strict
from bridge.settings.errors import describe
from bridge.settings.mqtt import MqttSettings
from bridge.settings.web import WebSettings

ENV_PREFIX = "ROTOR_REMOTE_"  # no variables are read; describe() wants a prefix to name


_BIND = "127.0.0.1"
# an endpoint's offers: (the key, its bind key or None for a path, the transport)
OFFERS = (
    ("rotctld_port", "rotctld_bind", "tcp"),
    ("gs232_port", "gs232_bind", "tcp"),
    ("easycomm_port", "easycomm_bind", "tcp"),
    ("pst_udp_port", "pst_udp_bind", "udp"),
    ("dcu1_port", "dcu1_bind", "tcp"),
    ("gs232_pty", None, "pty"),
    ("easycomm_pty", None, "pty"),
    ("dcu1_pty", None, "pty"),
)


class RemoteMqtt(MqttSettings):
    """The bridge's ``[mqtt]`` table, MQTT 5 only (rule 1); a refusal names ``mqtt.protocol``
    (rule 3)."""

    @field_validator("protocol")
    @classmethod
    def _mqtt5(cls, v: str) -> str:
        if v == "3.1.1":
            raise ValueError('must be "5" here: the remote\'s commands carry a message expiry')
        return v


class Offer(NamedTuple):
    key: str  # rotctld_port, gs232_pty, ...
    transport: str  # tcp, udp, pty
    where: int | str  # the port, or the pty's path
    bind: str  # "" for a pty


def _port(what: str) -> Any:
    return Field(None, ge=1, le=65535, description=what)


def _bind(what: str) -> Any:
    return Field(_BIND, description=f"the address the {what} listens on")


def _pty(what: str) -> Any:
    return Field(
        None,  # (no min_length: settings/base.py rule 4 refuses an empty one)
        description=f"{what} on a pseudo-terminal: the path of a link to it, made at start and "
        "removed at the end (anything but a link already there is refused)",
    )


class Endpoint(Strict):
    """``[[endpoints]]``: local ports onto one of the station's rotators (rule 4: one at least)."""

    rotator: str | None = Field(
        None,
        min_length=1,
        description="the station's rotator id; may be left out when the station has one",
    )
    rotctld_port: int | None = _port("a Hamlib rotctld port (rotctl -m 2)")
    rotctld_bind: str = _bind("rotctld port")
    gs232_port: int | None = _port("a Yaesu GS-232B TCP port (rotctl -m 603 -r 127.0.0.1:PORT)")
    gs232_bind: str = _bind("GS-232 port")
    gs232_pty: str | None = _pty("Yaesu GS-232B (rotctl -m 603 -r PATH)")
    easycomm_port: int | None = _port("an Easycomm II TCP port (rotctl -m 202)")
    easycomm_bind: str = _bind("Easycomm port")
    easycomm_pty: str | None = _pty("Easycomm II")
    gs232_replies: Literal["A", "B"] = Field(
        "B",
        description="the GS-232 endpoints' readings: B as a GS-232B (AZ=120  EL=000), A as a "
        "GS-232A (+0120+0000: ARSVCOM, PstRotatorAz, rotctl -m 601)",
    )
    dcu1_port: int | None = _port(
        "a Hy-Gain DCU-1 / Rotor-EZ TCP port (DXView, DXbase, WriteLog, Win-EQF; rotctl -m 401)"
    )
    dcu1_bind: str = _bind("DCU-1 port")
    dcu1_pty: str | None = _pty("DCU-1 / Rotor-EZ (rotctl -m 401 -r PATH)")
    pst_udp_port: int | None = _port(
        "a PstRotator-style UDP port (replies go to the sender's port + 1)"
    )
    pst_udp_bind: str = _bind("PstRotator UDP port")

    def offers(self) -> list[Offer]:
        """What it offers, in OFFERS' order."""
        out = []
        for key, bind_key, transport in OFFERS:
            value = getattr(self, key)
            if value is not None:
                out.append(
                    Offer(key, transport, value, getattr(self, bind_key) if bind_key else "")
                )
        return out


class RemoteSettings(Strict):
    operator: str = Field(
        min_length=1,
        max_length=OPERATOR_CHARS,
        pattern=r"^\S(.*\S)?$",
        description="who operates (a call sign): carried with every command",
    )
    mqtt: RemoteMqtt = Field(default_factory=RemoteMqtt)
    command_expiry_s: int = Field(
        5, ge=1, le=60, description="a command not delivered within this many seconds is dropped"
    )
    ack_wait_s: float = Field(
        1.0,
        gt=0,
        le=30,
        description="how long a command waits for the station's broker to acknowledge it before "
        "it is refused and the link reset (a stalled link); raise it for a link whose round trip "
        "is longer (satellite, a congested mobile network); at most command_expiry_s",
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

    @field_validator("operator")
    @classmethod
    def _operator(cls, v: str) -> str:
        """As the station reads it (core/model.py ``valid_operator``): a control character
        in it got every command's connection dropped by mosquitto (an MQTT 5 user property),
        and a name longer than the station takes was ignored there (a review)."""
        bad = bad_char(v)
        if bad is not None:
            raise ValueError(f"holds {bad}, {NOT_TEXT}")
        name = valid_operator(v)  # (its compatibility form: the station's, the lease's)
        if name is None:
            raise ValueError(
                f"1 to {OPERATOR_CHARS} characters, none of them invisible or a direction override"
            )
        if operator_name(name) is None:  # the station would ignore it (lease.py rule 1)
            raise ValueError(f"{name!r} is how the bridge names an interface: use your call sign")
        return name

    @model_validator(mode="after")
    def _check(self) -> RemoteSettings:
        self.mqtt.protocol = "5"  # "auto" never falls back here: the remote needs MQTT 5
        if self.ack_wait_s > self.command_expiry_s:
            raise ValueError(
                f"ack_wait_s ({self.ack_wait_s:g}) must not be more than command_expiry_s "
                f"({self.command_expiry_s}): a command acknowledged that late would be answered "
                "as sent while the station refuses it as old"
            )
        if len(self.endpoints) > 1 and any(e.rotator is None for e in self.endpoints):
            raise ValueError("with several [[endpoints]], each names its rotator")
        taken: dict[tuple[str, str | int], str] = {}  # (transport, port or path) -> its key
        for i, e in enumerate(self.endpoints):
            offers = e.offers()
            if not offers:
                who = f" (rotator {e.rotator!r})" if e.rotator else ""
                keys = ", ".join(key for key, _, _ in OFFERS)
                raise ValueError(f"endpoints[{i}]{who} offers nothing: give it one of {keys}")
            for key, transport, where, _ in offers:
                name = f"endpoints[{i}].{key}"
                if transport == "pty":
                    where = os.path.abspath(os.path.expanduser(str(where)))
                claims = [(transport, where)]
                if transport == "udp":  # a PST client listens on port + 1 for the replies
                    claims += [(transport, int(where) + 1), (transport, int(where) - 1)]
                for claim in claims:
                    if claim in taken:
                        what = "path" if transport == "pty" else "port"
                        raise ValueError(
                            f"{name} {shown_path(str(where))} clashes with {taken[claim]}: "
                            f"give it another {what}"
                        )
                taken[(transport, where)] = name
                if transport == "pty":
                    self._own_pty(name, str(where))
        if self.web.enabled and ("tcp", self.web.port) in taken:  # rule 2: the console too
            clash = taken[("tcp", self.web.port)]
            raise ValueError(f"web.port {self.web.port} clashes with {clash}: give it another port")
        return self

    def files_read(self) -> list[tuple[str, Path]]:
        """The files the remote's keys name for it to read (rule 6), by key."""
        tls = self.mqtt.tls
        named = [
            ("mqtt.password_file", self.mqtt.password_file),
            ("mqtt.tls.ca_file", tls.ca_file),
            ("mqtt.tls.cert_file", tls.cert_file),
            ("mqtt.tls.key_file", tls.key_file),
            ("web.password_file", self.web.password_file),
        ]
        return [(key, path) for key, path in named if path is not None]

    def _own_pty(self, name: str, path: str) -> None:
        """Rule 6: ValueError when the pty's link at ``path`` would take another file's name."""
        if stream_fd(path) is not None:
            raise ValueError(
                f"{name} {shown_path(path)} names one of the process's own descriptors, not a "
                "path for a pty's link: give the pty another path"
            )
        for key, file in self.files_read():
            if pty_takes(path, file):
                raise ValueError(
                    f"{name} {shown_path(path)} is also {key}: the pty's link would replace that "
                    "file's name; give the pty another path"
                )

    def client_id(self) -> str:
        """``mqtt.client_id``, or one per operator, host and what the file serves, that no
        bridge uses ("remote-"): two remotes of one operator on one host (one per rotator, a
        console beside a rotctld port) would otherwise take each other's connection over for
        ever (interfaces/mqtt/connection.py rule 7); one file keeps its id across restarts."""
        if self.mqtt.client_id:
            return self.mqtt.client_id
        served = [(e.rotator, e.offers()) for e in self.endpoints]
        web = self.web.port if self.web.enabled else None
        key = f"{socket.gethostname()}\n{self.mqtt.base_topic}\n{self.operator}\n{served}\n{web}"
        short = re.sub(r"[^a-z0-9]", "", self.operator.lower())[:8]
        return f"remote-{short}-{hashlib.sha256(key.encode()).hexdigest()[:6]}"


def load_remote_settings(path: str) -> RemoteSettings:
    """The file validated; ConfigError with one line per problem."""
    data: dict[str, Any] = read_toml(path)
    try:
        settings = RemoteSettings(**data)
    except ValidationError as exc:
        raise ConfigError(describe(exc, RemoteSettings, ENV_PREFIX, data, {})) from None
    for i, e in enumerate(settings.endpoints):  # rule 6: nor the file itself
        for key, transport, where, _ in e.offers():
            if transport == "pty" and pty_takes(str(where), path):
                raise ConfigError(
                    f"endpoints[{i}].{key}: {shown_path(str(where))} is the configuration file "
                    "itself: the pty's link would replace it; give the pty another path"
                )
    return settings
