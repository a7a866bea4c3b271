"""Exceptions that cross layers."""

from __future__ import annotations


class Refused(Exception):
    """A command judged and refused before it reached a controller; nothing moved."""

    def __init__(self, code: str, message: str) -> None:
        super().__init__(message)
        self.code = code  # locked | limits | offline | unsupported | invalid
        self.message = message
