"""The loggers' UDP endpoints in ``[[rotators]]`` (loggers/): PstRotator's and N1MM's.

Rules:
1. Off unless a port (PstRotator) or a rotor name (N1MM) is given; on loopback unless told
   otherwise: neither protocol has authentication (check-config warns off loopback).
2. An endpoint that could never work is a configuration error naming the key: a PstRotator port
   whose reply port (+ 1) does not exist, N1MM reports to another machine from a socket bound
   to loopback.
3. Every key carries its meaning (``description``) for docs/configuration.md.
"""

from __future__ import annotations

import ipaddress

from pydantic import Field, ValidationInfo, field_validator, model_validator

from bridge.settings.base import Strict
from bridge.settings.mqtt import check_bind


class LoggerFields(Strict):
    pst_udp_port: int | None = Field(
        None,
        ge=1,
        le=65534,
        description="PstRotator's UDP interface for this rotator (Log4OM, DXLog, QLog, Hamlib "
        "4.6): commands come to this port; replies go to the sender's host at this port + 1 "
        "(12001 for 12000), whichever port the sender sent from",
        examples=[12000],
        json_schema_extra={"unset": "off"},
    )
    pst_udp_bind: str = Field(
        "127.0.0.1",
        description="the address pst_udp_port listens on; the protocol has no authentication "
        "(check-config warns off loopback)",
        examples=["0.0.0.0"],
    )
    n1mm_rotor_name: str | None = Field(
        None,
        min_length=1,
        max_length=64,
        description="N1MM Logger+'s Rotor Description of this rotator's antenna: turns N1MM's "
        "rotor commands on for it",
        examples=["Tower"],
        json_schema_extra={"unset": "off"},
    )
    n1mm_udp_port: int = Field(
        12040,
        ge=1,
        le=65535,
        description="the UDP port N1MM sends rotor commands to; rotators share it by name",
        examples=[12041],
    )
    n1mm_udp_bind: str = Field(
        "127.0.0.1",
        description="the address n1mm_udp_port listens on (and position reports leave from); "
        "no authentication (check-config warns off loopback)",
        examples=["0.0.0.0"],
    )
    n1mm_report_to: str = Field(
        "127.0.0.1:13010",
        description="where position reports for N1MM go, host:port; another machine needs an "
        "n1mm_udp_bind that can reach it; a host name is looked up on a thread of its own, again "
        "every minute, and reports go to the last address found (none until one is)",
        examples=["192.168.1.20:13010"],
    )

    @field_validator("pst_udp_bind", "n1mm_udp_bind")
    @classmethod
    def _logger_bind(cls, v: str, info: ValidationInfo) -> str:
        return check_bind(v, str(info.field_name).replace("_bind", "_port"))

    @field_validator("n1mm_rotor_name")
    @classmethod
    def _printable(cls, name: str | None) -> str | None:
        if name is not None and (not name.isprintable() or name != name.strip() or "<" in name):
            raise ValueError("printable, no leading or trailing blanks, no '<'")
        if name is not None and not name.isascii():
            # the loggers' datagrams are ASCII (interfaces/loggers/datagrams.py rule 1): N1MM's
            # every word naming it, its STOP too, was dropped unread, and each position
            # report failed to encode (an attack pass)
            raise ValueError(f"{name!r} is not ASCII: N1MM's datagrams naming it are dropped")
        return name

    @field_validator("n1mm_report_to")
    @classmethod
    def _host_port(cls, text: str) -> str:
        host, sep, port = text.rpartition(":")
        if not sep or not host or not port.isdigit() or not 1 <= int(port) <= 65535:
            raise ValueError(f"{text!r} must be host:port, e.g. 127.0.0.1:13010")
        return text

    @model_validator(mode="after")
    def _reports_can_leave(self) -> LoggerFields:
        """Reports go out from the N1MM port's own socket (interfaces/loggers/server.py rule 6): one
        bound to loopback cannot reach another machine, and N1MM's rotor display would never
        move."""
        host = self.n1mm_report_address[0]
        if (
            self.n1mm_rotor_name is not None
            and is_loopback(self.n1mm_udp_bind)
            and not is_loopback(host)
        ):
            raise ValueError(
                f"n1mm_report_to {self.n1mm_report_to!r} is another machine, but n1mm_udp_bind "
                f"{self.n1mm_udp_bind!r} is loopback: position reports leave from the N1MM "
                "port's address and could not reach it; set n1mm_udp_bind to this machine's "
                "address on that network (or 0.0.0.0)"
            )
        return self

    @property
    def n1mm_report_address(self) -> tuple[str, int]:
        host, _, port = self.n1mm_report_to.rpartition(":")
        return host, int(port)


def is_loopback(host: str) -> bool:
    """Only this machine can reach ``host`` ("" = every address, a name: another machine as far
    as can be told here)."""
    if host.strip("[]").casefold() == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False  # a host name: another machine, as far as can be told here
