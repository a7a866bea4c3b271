"""The operator console's settings: ``[web]`` (the server is bridge/interfaces/web/).

Rules:
1. Off unless enabled; on loopback unless told otherwise. A console reachable from other
   machines without a password is a configuration error naming the risk: anyone who can reach
   it could turn the antenna.
2. The password is never written in the configuration (nor in the environment): only in the
   file password_file names, read once while loading as the MQTT password file is
   (settings/files.py), so a file that will not do is an error naming the key. What was read
   is ``password`` (a SecretStr, not a field: no dump, report or document shows it).
3. frame_ancestors are origins and nothing else: the server writes them into its
   Content-Security-Policy header, so a path, a space or a ';' there is refused here.
   host_names are names alone (no scheme, port or path), compared in lower case.
4. Every key carries its meaning (``description``) for docs/configuration.md.
5. A refused origin or host name is quoted in the error, but never one holding '@': a URL's
   login (``https://admin:pw@ha.local``) would put a password on the terminal and in the
   journal (an attack pass; settings/mqtt.py rule 4 for the broker's host).
"""

from __future__ import annotations

import ipaddress
import re
from pathlib import Path
from typing import Any

from pydantic import (
    Field,
    PrivateAttr,
    SecretStr,
    field_validator,
    model_validator,
)

from bridge.core.text import shown_path
from bridge.settings.base import NOT_SHOWN, Strict
from bridge.settings.files import read_password_file
from bridge.settings.loggers import is_loopback
from bridge.settings.mqtt import check_bind

PASSWORD_MIN_CHARS = 8
# scheme://host[:port]: a DNS name or an IPv4 address, or an IPv6 address in brackets
_ORIGIN = re.compile(
    r"(?P<scheme>https?)://"
    r"(?P<host>[A-Za-z0-9](?:[A-Za-z0-9-]*[A-Za-z0-9])?(?:\.[A-Za-z0-9](?:[A-Za-z0-9-]*[A-Za-z0-9])?)*"
    r"|\[[0-9A-Fa-f:.]+\])"
    r"(?::(?P<port>[0-9]{1,5}))?",
    re.ASCII,
)

_NAME = re.compile(
    r"[A-Za-z0-9](?:[A-Za-z0-9-]*[A-Za-z0-9])?(?:\.[A-Za-z0-9](?:[A-Za-z0-9-]*[A-Za-z0-9])?)*"
)


class WebSettings(Strict):
    """``[web]``: the operator console, the beam on a map in any browser, served by the bridge
    itself over HTTP."""

    enabled: bool = Field(
        False,
        description="serve the operator console (the beam on a map, the rotators' controls) "
        "over HTTP",
        examples=[True],
    )
    bind: str = Field(
        "127.0.0.1",
        description="the address the console listens on. Beyond loopback (another address, "
        "0.0.0.0, ::) it needs password_file; better: keep 127.0.0.1 behind a reverse proxy "
        "that asks for a password and speaks HTTPS",
        examples=["0.0.0.0"],
    )
    port: int = Field(
        8754,
        ge=1,
        le=65535,
        description="the console's TCP port: open `http://<bind>:<port>/` (not a rotctld_port)",
        examples=[8080],
    )
    password_file: Path | None = Field(
        None,
        description="a file holding the console's password (one line, at least "
        f"{PASSWORD_MIN_CHARS} characters), readable by the service user and not by every "
        "user (chown root:rotor-bridge, chmod 640). The password is never written in this "
        "configuration.",
        examples=["/etc/rotor-bridge/web-password"],
        json_schema_extra={"unset": "no password: only on a loopback bind"},
    )
    frame_ancestors: list[str] = Field(
        default_factory=list,
        description="origins (scheme://host[:port], no path) allowed to show the console in a "
        "frame, such as Home Assistant's Webpage card; the console's own origin always may",
        examples=[["http://homeassistant.local:8123"]],
        json_schema_extra={"unset": "only the console's own pages"},
    )
    host_names: list[str] = Field(
        default_factory=list,
        description="without a password the console answers only to requests addressed to an "
        "IP address or localhost (a web page whose own name was pointed at this machine must "
        "not drive it); behind a reverse proxy that passes its own host name on (Caddy does), "
        "name it here",
        examples=[["shack.example.org"]],
        json_schema_extra={"unset": "IP addresses and localhost only"},
    )
    trusted_proxies: list[str] = Field(
        default_factory=list,
        description="addresses (or networks) of your reverse proxies, whose X-Forwarded-For "
        "header names the browser's address: failed logins are then limited, and commands "
        "audited, per browser rather than per proxy. Only the proxies you run: anyone can "
        "write that header",
        examples=[["127.0.0.1"]],
        json_schema_extra={"unset": "the connection's address: no X-Forwarded-For is believed"},
    )
    _password: SecretStr | None = PrivateAttr(default=None)

    @field_validator("bind")
    @classmethod
    def _bind(cls, v: str) -> str:
        return check_bind(v, "web.port")

    @field_validator("trusted_proxies")
    @classmethod
    def _proxies(cls, values: list[str]) -> list[str]:
        for value in values:
            try:
                ipaddress.ip_network(value, strict=False)
            except ValueError:
                raise ValueError(
                    f"{_shown(value)} is no address or network (127.0.0.1, ::1, 10.0.0.0/8)"
                ) from None
        return values

    @property
    def password(self) -> SecretStr | None:
        """The password read from password_file (``.get_secret_value()``), or None: no
        password asked (rule 2)."""
        return self._password

    @model_validator(mode="before")
    @classmethod
    def _no_password_here(cls, data: Any) -> Any:
        if isinstance(data, dict) and "password" in data:  # rule 2: say where it goes
            raise ValueError(
                "the console's password is never written in the configuration: put it in a "
                "file of its own, readable only by the service user, and name that file in "
                "web.password_file"
            )
        return data

    @field_validator("frame_ancestors")
    @classmethod
    def _origins(cls, values: list[str]) -> list[str]:
        out = []
        for value in values:
            # a bare trailing '/' is how a browser's address bar shows an origin: the same one
            origin = value[:-1] if value.endswith("/") and value.count("/") == 3 else value
            m = _ORIGIN.fullmatch(origin)
            if m is None or (m["port"] is not None and not 1 <= int(m["port"]) <= 65535):
                raise ValueError(
                    f"{_shown(value)} is not an origin: write scheme://host[:port] with http "
                    "or https, no login and no path, e.g. 'http://homeassistant.local:8123'"
                )
            out.append(origin)
        return out

    @field_validator("host_names")
    @classmethod
    def _names(cls, values: list[str]) -> list[str]:
        for value in values:
            if _NAME.fullmatch(value) is None:
                raise ValueError(
                    f"{_shown(value)} is not a host name: write the name alone, without "
                    "scheme, login, port or path, e.g. 'shack.example.org'"
                )
        return [v.casefold() for v in values]

    @model_validator(mode="after")
    def _password_and_reach(self) -> WebSettings:
        if self.password_file is not None:
            password = read_password_file(self.password_file)
            where = f"password_file {shown_path(self.password_file)}"
            if not password:
                raise ValueError(f"{where} is empty: write the console's password in it")
            if "\n" in password or "\r" in password:
                raise ValueError(f"{where} holds more than one line: write the password on one")
            if len(password) < PASSWORD_MIN_CHARS:  # rule 3 of settings_files: never quoted
                raise ValueError(
                    f"{where}: the password is shorter than {PASSWORD_MIN_CHARS} characters"
                )
            self._password = SecretStr(password)
        if self.enabled and self.password_file is None and not is_loopback(self.bind):
            shown = f"{self.bind!r}" if self.bind else "every address"
            raise ValueError(
                f"the console would listen on {shown} (web.bind), beyond this machine, without "
                "a password (web.password_file): anyone who can reach that address could turn "
                "the antenna. Set web.password_file, or keep web.bind = '127.0.0.1' behind a "
                "reverse proxy that asks for a password"
            )
        return self


def _shown(value: str) -> str:
    """Rule 5: ``value`` quoted, unless it holds '@'."""
    if "@" in value:
        return f"an entry holding '@' ({NOT_SHOWN})"
    return repr(value)


def web_warnings(web: WebSettings) -> list[str]:
    """What check-config warns of a ``[web]`` table (settings/report.py rule 3), the bridge's or
    the remote's (whose file has no check-config: it logs these as it starts). Here, not in
    report.py: the remote runs on Windows too, and report.py needs POSIX modules."""
    found: list[str] = []
    if web.enabled and not is_loopback(web.bind):
        found.append(
            f"web.bind: {web.bind or '(every address)'} is not a loopback address: the console "
            "speaks plain HTTP, so its password and every command cross the network "
            "unencrypted; keep it on 127.0.0.1 behind a reverse proxy that speaks HTTPS"
        )
    for proxy in web.trusted_proxies if web.enabled else ():
        net = ipaddress.ip_network(proxy, strict=False)  # (valid: settings/web.py)
        if net.num_addresses > 1:
            found.append(
                f"web.trusted_proxies: {proxy} is a network of {net.num_addresses:,} "
                "addresses: any host in it can name itself another browser in X-Forwarded-For "
                "(its failed logins then limited as another's, its commands audited as "
                "another's); list only your reverse proxies' own addresses"
            )
    if web.enabled and web.trusted_proxies and not web.host_names and web.password_file:
        found.append(
            "web.host_names: none listed, with trusted_proxies: if the proxy is reached by a "
            "name, list it, or a hostile page of another name pointed at the proxy (DNS "
            "rebinding) counts its wrong passwords with yours, and holds your login back"
        )
    return found
