"""The WSJT-X (and JTDX) listener's settings: ``[wsjtx]`` (the listener is
bridge/interfaces/wsjtx/).

Rules:
1. Off unless enabled: WSJT-X's UDP port is a shared resource (GridTracker, JTAlert and
   loggers listen there too), so the bridge takes it only when asked.
2. ``multicast_group`` is an IPv4 multicast address (224.0.0.0/4) or absent: WSJT-X sends
   its messages to one address, and a multicast group is how several programs hear them.
3. Every key carries its meaning (``description``) for docs/configuration.md.
"""

from __future__ import annotations

import ipaddress

from pydantic import Field, field_validator

from bridge.settings.base import Strict

DEFAULT_PORT = 2237  # WSJT-X's own default UDP server port


class WsjtxSettings(Strict):
    """``[wsjtx]``: WSJT-X's or JTDX's UDP messages, so that a rotator can follow the QSO
    partner (``R/follow``)."""

    enabled: bool = Field(
        False,
        description="listen for WSJT-X's (or JTDX's) UDP messages, so that a rotator can "
        "follow the station being worked (R/follow)",
        examples=[True],
    )
    port: int = Field(
        DEFAULT_PORT,
        ge=1,
        le=65535,
        description="the UDP port WSJT-X sends to (Settings, Reporting, UDP Server port number)",
        examples=[2238],
    )
    bind: str = Field(
        "127.0.0.1",
        description="the address to listen on: WSJT-X on this machine sends to 127.0.0.1; "
        "with multicast_group, the address of the interface to join it on (0.0.0.0: any); "
        "the protocol has no authentication (check-config warns off loopback)",
        examples=["0.0.0.0"],
    )
    multicast_group: str | None = Field(
        None,
        description="a multicast group WSJT-X sends to (its UDP Server set to e.g. "
        "239.255.0.1), so that GridTracker, JTAlert and the bridge all hear it",
        examples=["239.255.0.1"],
        json_schema_extra={"unset": "no group: WSJT-X sends to this program's address alone"},
    )

    @field_validator("bind")
    @classmethod
    def _bind(cls, v: str) -> str:
        try:
            ipaddress.IPv4Address(v)
        except ValueError:
            raise ValueError("must be an IPv4 address (127.0.0.1, 0.0.0.0, ...)") from None
        return v

    @field_validator("multicast_group")
    @classmethod
    def _group(cls, v: str | None) -> str | None:
        if v is None:
            return v
        try:
            group = ipaddress.IPv4Address(v)
        except ValueError:
            raise ValueError("must be an IPv4 multicast address, e.g. 239.255.0.1") from None
        if not group.is_multicast:
            raise ValueError(f"{v} is not a multicast address (224.0.0.0 to 239.255.255.255)")
        return v
