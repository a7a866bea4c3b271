"""Exceptions that cross layers."""

from __future__ import annotations

import enum


class RefusalCode(enum.StrEnum):
    """Why a command was refused; front ends map it (rotctld: to a Hamlib RPRT number)."""

    LOCKED = "locked"  # the safety lock is ON
    LIMITS = "limits"  # outside the configured limits (or rounded past them)
    OFFLINE = "offline"  # serial link down or controller silent
    UNSUPPORTED = "unsupported"  # the model cannot do it (an option, an elevation axis)
    KEEP_OUT = "keep_out"  # the bearing lies in a configured keep-out sector
    INVALID = "invalid"  # not a command at all (a target without an axis)
    LEASED = "leased"  # another operator holds the control lease (runtime/lease.py)
    STALE = "stale"  # a stop or lock ON came first (session/mailbox.py rule 10)


class Refused(Exception):
    """A command judged and refused before it reached a controller; nothing moved."""

    def __init__(self, code: RefusalCode, message: str) -> None:
        super().__init__(message)
        self.code = RefusalCode(code)
        self.message = message
