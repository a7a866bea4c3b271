"""The DX cluster client's settings: ``[dxcluster]`` (the client is bridge/interfaces/dxcluster/).

Rules:
1. Off unless enabled. Enabled, ``host``, ``login`` and ``cty_file`` are needed: a node asks
   for a call sign, and a spot without a cty file has no position unless its comment holds a
   locator. Each missing one is an error naming it.
2. The cty file is read from disk at start-up (interfaces/dxcluster/cty.py): one that is missing or
   unreadable stops the start with one line naming it. The bridge never downloads it.
3. ``bands`` names bands of core/bands.py's table (empty: every spot), the one a rotator's
   ``bands`` names: a name not there is an error that lists the known ones.
4. Every key carries its meaning (``description``) for docs/configuration.md.
5. ``host`` is a host name or an address alone, as ``mqtt.host`` (settings/mqtt.py
   check_host): a URL, a port or a login written there is an error naming the key (an attack
   pass: ``telnet://call:pw@node:7300`` passed check-config, which printed it whole, and the
   client retried it for ever).
"""

from __future__ import annotations

import re
from pathlib import Path

from pydantic import Field, field_validator, model_validator

from bridge.core.bands import NAMES, UnknownBand, band_of_hz, canonical
from bridge.settings.base import Strict
from bridge.settings.mqtt import check_host

DEFAULT_PORT = 7300  # DX Spider's usual telnet port (many nodes also take 23 or 8000)

_CALL = re.compile(r"[A-Z0-9/-]{3,20}", re.ASCII)


def band_of(freq_khz: float) -> str | None:
    """The band a spot's frequency (kHz) is in, or None: core/bands.py's table, the one a
    rotator's ``bands``, the loggers and following read."""
    return band_of_hz(freq_khz * 1000)


class DxClusterSettings(Strict):
    """``[dxcluster]``: spots from a DX cluster node (telnet), on ``B/spots``, and turning a
    rotator to a spotted call (``R/target`` ``{"call": ...}``)."""

    enabled: bool = Field(
        False,
        description="connect to a DX cluster node and publish its spots (B/spots)",
        examples=[True],
    )
    host: str | None = Field(
        None,
        description="the cluster node's host name or address (a DX Spider node, for example)",
        examples=["dxc.example.org"],
        json_schema_extra={"unset": "needed when enabled"},
    )
    port: int = Field(
        DEFAULT_PORT, ge=1, le=65535, description="the node's telnet port", examples=[8000]
    )
    login: str | None = Field(
        None,
        description="your call sign, sent when the node asks for it",
        examples=["G4ABC"],
        json_schema_extra={"unset": "needed when enabled"},
    )
    cty_file: Path | None = Field(
        None,
        description="AD1C's cty.dat or cty.csv (country-files.com), downloaded by you: the "
        "entity, and so the bearing, of a spotted call without a locator. A regular file of "
        "16 MiB at most, with an entity in it (the start and check-config judge it alike); a "
        "secret's file (a password file, the TLS key, the console's secret) or the "
        "configuration file is refused",
        examples=["/etc/rotor-bridge/cty.dat"],
        json_schema_extra={"unset": "needed when enabled"},
    )
    max_spots: int = Field(
        50, ge=1, le=200, description="the newest spots kept on B/spots, at most", examples=[20]
    )
    max_age_min: float = Field(
        30.0,
        gt=0,
        le=1440,
        description="a spot older than this (by the spot's own time) leaves B/spots, and "
        "one the node sends older than this is not taken",
        examples=[15],
    )
    bands: list[str] = Field(
        default_factory=list,
        description="only spots on these bands (" + ", ".join(NAMES) + "); empty: all",
        examples=[["20m", "15m", "10m"]],
        json_schema_extra={"unset": "every band"},
    )

    @field_validator("host")
    @classmethod
    def _host(cls, v: str | None) -> str | None:
        return v if v is None else check_host(v, "dxcluster")  # rule 5

    @field_validator("login")
    @classmethod
    def _login(cls, v: str | None) -> str | None:
        if v is None:
            return v
        call = v.strip().upper()
        if not _CALL.fullmatch(call):
            raise ValueError("must be a call sign: 3 to 20 letters, digits, / or -")
        return call

    @field_validator("bands")
    @classmethod
    def _bands(cls, v: list[str]) -> list[str]:
        try:
            return [canonical(b) for b in v]
        except UnknownBand as exc:
            raise ValueError(str(exc)) from None

    @model_validator(mode="after")
    def _needed(self) -> DxClusterSettings:
        if self.enabled:
            for name in ("host", "login", "cty_file"):
                if getattr(self, name) is None:
                    raise ValueError(f"{name}: needed when [dxcluster] is enabled")
        return self
