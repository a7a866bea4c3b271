"""The broker settings: ``[mqtt]``, ``[mqtt.tls]`` and ``[homeassistant]``.

Rules:
1. Every key carries its meaning (``description``) and, where its default says nothing, an
   example and the words for "left out" (``unset``); docs/configuration.md is generated from
   them (bridge/config_doc.py).
2. The files named here (TLS, password) are read once while loading (settings/files.py), so a
   file that will not do is a configuration error naming the key, not a traceback at start.
3. The client id left out is unique per installation and stable across restarts
   (effective_client_id).
4. A host (``mqtt.host``, ``dxcluster.host``: check_host; an address a port listens on:
   check_bind) is a name or an address alone; a
   refusal quotes it, but never one holding '@': a URL's login (``mqtt://rotor:pw@broker``)
   would put the password in the error, on the terminal and in the journal.
5. An empty ``username`` or ``password`` is an error, as an empty ``password_file`` is: what
   ``ROTOR_BRIDGE_MQTT__PASSWORD=${MQTT_PASSWORD}`` gives with the variable unset (an attack
   pass: check-config said "user rotor, a password", and the broker's "Not authorized" named
   neither key).
"""

from __future__ import annotations

import hashlib
import re
import socket
from pathlib import Path
from typing import Literal

from pydantic import (
    Field,
    PrivateAttr,
    SecretStr,
    ValidationInfo,
    field_validator,
    model_validator,
)

from bridge.core.text import NOT_TEXT, bad_char, shown_path
from bridge.settings.base import NOT_SHOWN, Strict
from bridge.settings.files import check_tls_files, read_password_file

_TOPIC_BAD = re.compile(r"[+#\x00]")
# MQTT's strings (a topic, the client id, the user name, the password) are at most this many
# bytes in UTF-8: a longer one ended every connection attempt in a traceback (an attack pass)
MQTT_STRING_MAX = 65535
# what the bridge adds under a topic of its own: a rotator's id and its words under the base
# topic (<base>/<id>/option/<name>/state), Home Assistant's node and object ids after the
# discovery prefix (<prefix>/<platform>/rotorbridge_<base>_r_<id>/<object>/config): a few
# hundred bytes at most, with room to spare
TOPIC_ROOM = 1024
# levels a topic of the bridge's own may have: it adds up to five under one (a group's or a
# rotator's words, a vouch read's <base>/bridge/info), and brokers drop or die of deeper
# subscriptions (mosquitto drops a client past some 200 levels; aedes, Node-RED's broker, dies
# past 100: review 102, a stamp naming a 250-level base topic)
TOPIC_LEVELS_MAX = 32
# what the stop lane and the stop express add to a client id set (interfaces/mqtt/lane.py)
CLIENT_ID_ROOM = len("-stop")


def check_topic(v: str, *, own: bool = True) -> str:
    """``v`` if it is a plain topic: no wildcards, no leading, trailing or double '/', nothing
    core/text.py refuses (mosquitto drops a client whose topic holds a control character, the
    will's among them, at every CONNECT: an attack pass), and short enough for MQTT. ``own``: a
    topic the bridge publishes under, which leaves room for the levels it adds (TOPIC_ROOM),
    has at most TOPIC_LEVELS_MAX levels, and does not start with '$' (the broker's own topics,
    $SYS: it would take no message there)."""
    if not v or v.startswith("/") or v.endswith("/") or _TOPIC_BAD.search(v) or "//" in v:
        raise ValueError(
            "must be a plain topic like 'rotor' (no wildcards, no leading/trailing '/')"
        )
    bad = bad_char(v)
    if bad is not None:
        raise ValueError(f"holds {bad}, {NOT_TEXT}")
    if own and v.startswith("$"):
        raise ValueError("must not start with '$': the broker keeps those topics for itself")
    if own:
        room = f"{TOPIC_ROOM} for the levels the bridge adds"
        check_length(v, MQTT_STRING_MAX - TOPIC_ROOM, "a topic", room)
        levels = v.count("/") + 1
        if levels > TOPIC_LEVELS_MAX:
            raise ValueError(
                f"has {levels} levels, at most {TOPIC_LEVELS_MAX} (brokers drop a client, or"
                " stop, for subscriptions much deeper than that)"
            )
    else:
        check_length(v, MQTT_STRING_MAX, "a topic")
    return v


def check_length(v: str, most: int, what: str, room: str = "") -> None:
    """ValueError if ``v`` is not UTF-8 text (a lone surrogate: what Python makes of a byte
    from the environment that is not UTF-8, which ended ``run`` in a traceback where paho
    encoded it) or is longer than ``most`` bytes in UTF-8 (``room``: what is kept from MQTT's
    limit, and why); the value is never quoted (a password may be one)."""
    try:
        size = len(v.encode())
    except UnicodeEncodeError:
        raise ValueError(f"{what} must be UTF-8 text: set it again, in UTF-8") from None
    if size > most:
        why = f"MQTT's limit is {MQTT_STRING_MAX}{', less ' + room if room else ''}"
        raise ValueError(f"{what} is at most {most} bytes in UTF-8 ({why}); this is {size}")


# rule 4: where a URL's login goes instead, by table
_LOGIN_KEYS = {
    "mqtt": "mqtt.username and mqtt.password_file",
    "dxcluster": "the call sign in dxcluster.login",
}


def check_host(v: str, table: str, port_key: str | None = None) -> str:
    """``v`` if it is a host name or address as getaddrinfo takes it (``table``'s ``host``, or
    an address to listen on: check_bind): no URL, no port (``port_key``'s, else the table's),
    no brackets, DNS's lengths. A value holding '@' is never quoted (rule 4)."""
    if "@" in v:  # (an attack pass: 'mqtt://rotor:pw@broker' was quoted, the password with it)
        login = _LOGIN_KEYS.get(table)
        raise ValueError(
            f"a host name or address, not a URL with a login: it holds '@' ({NOT_SHOWN})"
            + (f"; the login goes in {login}" if login else "")
        )
    if not v.strip() or any(c.isspace() or not c.isprintable() for c in v):
        raise ValueError(f"a host name or address, got {v!r}")
    if "://" in v or "/" in v:  # (an attack pass: check-config said "config OK")
        tls = ", TLS mqtt.tls" if table == "mqtt" else ""
        raise ValueError(
            f"a host name or address, not a URL: {v!r} (the port is {table}.port{tls})"
        )
    if v.startswith("["):  # (an address in brackets is a URL's: getaddrinfo takes none)
        raise ValueError(f"an IPv6 address is written without brackets here: {v!r}")
    if v.count(":") == 1:  # (IPv6 has two at least)
        port = port_key or f"{table}.port"
        raise ValueError(f"a host name or address, without its port: {v!r} ({port})")
    name = v.removesuffix(".")
    if ":" not in v and (  # a name or IPv4, as DNS takes them (an attack pass: a longer
        len(name) > 253 or any(not 0 < len(label) <= 63 for label in name.split("."))
    ):  # one logged a traceback at every retry)
        raise ValueError(f"{v!r} is no host name: at most 253 characters, 1 to 63 between dots")
    return v


def check_bind(v: str, port_key: str) -> str:
    """An address to listen on (a ``*_bind``, ``web.bind``): empty for every address, else a
    host name or address alone, as check_host takes them (an attack pass: check-config passed
    ``shack-pc.lan:pw@127.0.0.1`` and ``x y``, and ``run`` then stopped on a line that named no
    key and quoted the part before the '@')."""
    return v if v == "" else check_host(v, "bind", port_key)


class TlsSettings(Strict):
    """``[mqtt.tls]``: an encrypted connection to the broker, with a client certificate if the
    broker asks for one. Every file is checked while the configuration loads; a file given with
    ``enabled`` false is refused (the connection would not be encrypted)."""

    enabled: bool = Field(
        False,
        description="connect with TLS (the broker's TLS port, usually 8883); the files below "
        "are refused without it",
        examples=[True],
    )
    ca_file: Path | None = Field(
        None,
        description="the certificate authority that signed the broker's certificate (PEM)",
        examples=["/etc/ssl/certs/my-ca.pem"],
        json_schema_extra={"unset": "the system's trusted authorities"},
    )
    cert_file: Path | None = Field(
        None,
        description="a client certificate (PEM), for brokers that authenticate clients by "
        "certificate; goes with key_file",
        examples=["/etc/rotor-bridge/client.crt"],
        json_schema_extra={"unset": "no client certificate"},
    )
    key_file: Path | None = Field(
        None,
        description="the client certificate's private key (PEM, not encrypted); goes with "
        "cert_file",
        examples=["/etc/rotor-bridge/client.key"],
        json_schema_extra={"unset": "no client certificate"},
    )
    insecure: bool = Field(
        False,
        description="skip the check that the broker's certificate names its host (self-signed "
        "lab brokers only)",
        examples=[True],
    )

    @model_validator(mode="after")
    def _files(self) -> TlsSettings:
        # loaded here as the MQTT client will load them, so a bad file is a config error now and
        # not a traceback at start (paho's tls_set would raise it)
        check_tls_files(self.ca_file, self.cert_file, self.key_file)
        given = [n for n in ("ca_file", "cert_file", "key_file") if getattr(self, n) is not None]
        # (an attack pass: files given, enabled left out, the password went out in the clear;
        # enabled = false written out is a choice, a review: TLS switched off for a while)
        if given and "enabled" not in self.model_fields_set:
            raise ValueError(
                f"{', '.join(given)} given but enabled left out: the bridge would connect "
                "without TLS (and send a password in the clear); set enabled = true (or false, "
                "to connect without TLS all the same)"
            )
        return self


class MqttSettings(Strict):
    """``[mqtt]``: the broker the bridge connects to, and the topics it uses there."""

    host: str = Field(
        "127.0.0.1", description="the broker's host name or address", examples=["broker.lan"]
    )
    port: int = Field(
        1883, ge=1, le=65535, description="the broker's port (TLS: usually 8883)", examples=[8883]
    )
    username: str | None = Field(
        None,
        description="the user name to log in to the broker with; needed with a password",
        examples=["rotor"],
        json_schema_extra={"unset": "no login"},
    )
    password: SecretStr | None = Field(
        None,
        description="the password, with username; better in password_file (this file then "
        "holds a secret: check-config warns). Never printed. An empty one is refused, as an "
        "empty username is (what a variable left unset in ${...} gives)",
        examples=["s3cret"],
        json_schema_extra={"unset": "no password"},
    )
    password_file: Path | None = Field(
        None,
        description="a file holding the password (one line), readable by the service user and "
        "not by every user (chown root:rotor-bridge, chmod 640); with username, not together "
        "with password",
        examples=["/etc/rotor-bridge/mqtt-password"],
        json_schema_extra={"unset": "no password file"},
    )
    tls: TlsSettings = Field(
        default_factory=TlsSettings, description="the [mqtt.tls] table (below)"
    )
    client_id: str | None = Field(
        None,
        description="the MQTT client id. Left out, it is 'rotor-', up to 10 characters of the "
        "host name, '-' and 6 hex digits of a hash of the host name, base_topic and state_file: "
        "unique per installation, stable across restarts, at most 23 characters. Set it only "
        "if the broker's access rules need a fixed id.",
        examples=["rotor-shack"],
        json_schema_extra={"unset": "rotor-<host>-<6 hex digits>"},
    )
    keepalive_s: int = Field(
        30,
        ge=5,
        le=3600,
        description="seconds between keep-alive pings of the main connection; the broker "
        "declares the bridge offline after 1.5 times this without a word (the connections that "
        "carry stops ping every 2 s, so that a dead network path under them is found within 7 s)",
        examples=[60],
    )
    error_events_per_s: float = Field(
        10.0,
        gt=0,
        le=10000,
        description="R/error events per rotator: at most this many a second after a burst of "
        "five times as many (a controller spewing junk cannot flood the broker)",
        examples=[2],
    )
    base_topic: str = Field(
        "rotor",
        description="the first level of every topic: one rotator uses <base_topic>/target ..., "
        "several <base_topic>/<id>/target ...",
        examples=["shack/rotor"],
    )
    protocol: Literal["auto", "5", "3.1.1"] = Field(
        "auto",
        description='the MQTT version: "auto" tries MQTT 5 and falls back to 3.1.1 when the '
        'broker answers "Unsupported protocol version", or closes MQTT 5 connections and '
        "accepts an MQTT 3.1.1 one (RabbitMQ 3, amqtt); said once, as a warning, and in "
        'B/bridge/info. "5" or "3.1.1" forces one. '
        "Under 3.1.1 retained commands are recognised only when the broker replays them "
        "(docs/brokers.md)",
        examples=["3.1.1"],
    )

    stop_express: bool = Field(
        True,
        description="a STOP's frame written by a small process of its own, on a connection "
        "of its own to the broker (client id 'rfast-...' beside 'rotor-...', the stop lane's "
        "'rstop-...' and the lock lane's 'rlock-...'), so that nothing the bridge's process "
        "is busy with delays it; "
        "only for controllers that take a stop frame at any moment (Rotor-EZ, RotorCard, "
        "GS-232, Easycomm). Off: stops take the stop lane in the bridge's process",
        examples=[False],
    )

    @field_validator("protocol", mode="before")
    @classmethod
    def _protocol(cls, v: object) -> object:
        return str(v) if isinstance(v, int | float) and not isinstance(v, bool) else v

    @field_validator("base_topic")
    @classmethod
    def _topic(cls, v: str) -> str:
        return check_topic(v)

    @field_validator("client_id")
    @classmethod
    def _client_id(cls, v: str | None) -> str | None:
        if v is not None:
            _mqtt_text(v, "a client id")
            room = f"{CLIENT_ID_ROOM} for the stop lane's '-stop'"
            check_length(v, MQTT_STRING_MAX - CLIENT_ID_ROOM, "a client id", room)
        return v

    @field_validator("username")
    @classmethod
    def _username(cls, v: str | None) -> str | None:
        if v is not None:
            if not v.strip():  # rule 5
                raise ValueError(
                    "empty: the broker would be asked for a user with no name; leave "
                    "mqtt.username out to connect without a login"
                )
            _mqtt_text(v, "a user name")
            check_length(v, MQTT_STRING_MAX, "a user name")
        return v

    @field_validator("password")
    @classmethod
    def _password(cls, v: SecretStr | None, info: ValidationInfo) -> SecretStr | None:
        if v is not None:
            _needs_username(info)
            if not v.get_secret_value():  # rule 5
                raise ValueError(
                    "empty: the bridge would log in with no password; leave mqtt.password out "
                    "to log in with the user name alone"
                )
            check_length(v.get_secret_value(), MQTT_STRING_MAX, "a password")
        return v

    @field_validator("password_file")
    @classmethod
    def _password_file_user(cls, v: Path | None, info: ValidationInfo) -> Path | None:
        if v is not None:
            _needs_username(info)
        return v

    @field_validator("host")
    @classmethod
    def _host(cls, v: str) -> str:
        return check_host(v, "mqtt")

    @model_validator(mode="after")
    def _password_file(self) -> MqttSettings:
        if self.password_file is None:
            return self
        if self.password is not None:
            raise ValueError("set password or password_file, not both")
        password = read_password_file(self.password_file)
        if not password or "\n" in password or "\r" in password:  # (an attack pass)
            raise ValueError(
                f"password_file {shown_path(self.password_file)} must hold the password on one "
                f"line (it holds {'nothing' if not password else 'several lines'})"
            )
        try:
            check_length(password, MQTT_STRING_MAX, "a password")
        except ValueError as exc:
            raise ValueError(f"password_file {shown_path(self.password_file)}: {exc}") from None
        self.password = SecretStr(password)
        return self

    # the state file of the installation these settings belong to (Settings fills it in)
    _state_file: str = PrivateAttr(default="")

    def effective_client_id(self, state_file: str | None = None) -> str:
        """``client_id``, or a default that is unique per installation and stable across restarts.

        The default is "rotor-", up to 10 characters of the host name, "-" and 6 hex digits of a
        hash of the full host name, the base topic and the state file path: at most 23
        characters, the length every MQTT 3.1.1 broker must accept, from the characters every
        broker takes (plus "-"). Two bridges on one host (a second installation, the demo beside
        the real one) differ in state file or base topic, so they do not take each other's
        session over; one installation keeps its id. Two hosts sharing one configuration with
        an explicit client_id still collide: the client reports that (interfaces/mqtt/client.py rule
        7). ``state_file``: the default another state file would give (settings/report.py rule 6).
        """
        if self.client_id:
            return self.client_id
        host = socket.gethostname()
        # (a state file's path need not be UTF-8: only hashed)
        path = self._state_file if state_file is None else state_file
        key = f"{host}\n{self.base_topic}\n{path}".encode(errors="surrogatepass")
        digest = hashlib.sha256(key).hexdigest()[:6]
        short = re.sub(r"[^a-z0-9-]", "", host.split(".")[0].lower())[:10].strip("-")
        return f"rotor-{short}-{digest}" if short else f"rotor-{digest}"


def _mqtt_text(v: str, what: str) -> None:
    """A client id or a user name holds nothing core/text.py refuses: mosquitto closes such a
    CONNECT, and the bridge blamed the broker's access rules (a review). (Not the password:
    MQTT carries it as bytes.)"""
    bad = bad_char(v)
    if bad is not None:
        raise ValueError(f"{what} holds {bad}, {NOT_TEXT}")


def _needs_username(info: ValidationInfo) -> None:
    """A password goes with a user name (an attack pass: without one the MQTT client logged in
    with neither, and check-config said "no login" of a configuration holding a password).
    A user name that did not validate is said already, and not here."""
    if "username" in info.data and info.data["username"] is None:
        raise ValueError(
            "needs mqtt.username: the bridge logs in with a user name and its password, and "
            "would leave a password without one unused"
        )


class HomeAssistantSettings(Strict):
    """``[homeassistant]``: MQTT discovery, so every rotator appears in Home Assistant as a
    device with its controls, by itself."""

    enabled: bool = Field(
        True,
        description="publish Home Assistant's discovery messages (off: those an earlier run "
        "left are cleared, and Home Assistant drops the bridge's devices)",
        examples=[False],
    )
    discovery_prefix: str = Field(
        "homeassistant",
        description="the discovery prefix set in Home Assistant's MQTT options; must differ "
        "from mqtt.base_topic",
        examples=["ha"],
    )
    status_topic: str = Field(
        "homeassistant/status",
        description="where Home Assistant announces its start (its birth message); the bridge "
        "then publishes its state again",
        examples=["ha/status"],
    )
    birth_delay_s: float = Field(
        10.0,
        ge=0,
        le=300,
        description="wait this long after Home Assistant's birth message before publishing the "
        "state again (state that arrives before Home Assistant has read discovery is ignored)",
        examples=[5],
    )

    @field_validator("discovery_prefix")
    @classmethod
    def _topic(cls, v: str) -> str:
        return check_topic(v)

    @field_validator("status_topic")
    @classmethod
    def _status_topic(cls, v: str) -> str:
        return check_topic(v, own=False)  # Home Assistant's: the bridge only listens there
