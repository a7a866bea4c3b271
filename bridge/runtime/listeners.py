"""Listeners (MQTT, rotctld, Home Assistant) as the engine calls them: never raising into it.

A listener that raises is logged once per kind of failure and otherwise ignored: a display
problem never closes or reopens the line to the controller (worker.py rule 3).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import TypeVar

__all__ = ["contained"]

log = logging.getLogger(__name__)
T = TypeVar("T")


def contained(listener: Callable[[T], None], what: str) -> Callable[[T], None]:
    """``listener`` with its failures logged (once per exception type) and never raised."""
    seen: set[type[BaseException]] = set()

    def call(value: T) -> None:
        try:
            listener(value)
        except Exception as exc:
            if type(exc) not in seen:
                seen.add(type(exc))
                log.exception("%s failed (logged once; the rotator goes on)", what)

    return call
