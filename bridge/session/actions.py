"""What a rotator session asks its worker to do: the session's only outputs besides its
``next_wakeup`` (session.py)."""

from __future__ import annotations

from dataclasses import dataclass

from bridge.core.model import ErrorKind, Origin, RotatorStatus
from bridge.sky.worker import Question

__all__ = ["Action", "Ask", "Audit", "Publish", "Report", "Write"]


@dataclass(frozen=True)
class Write:
    """Put these bytes on the serial line, now, in order."""

    data: bytes


@dataclass(frozen=True)
class Publish:
    """Hand this status to the listeners (MQTT, rotctld, Home Assistant)."""

    status: RotatorStatus


@dataclass(frozen=True)
class Report:
    """Hand an error event to the listeners (the worker stamps it with the wall time);
    ``origin``: the sender of a command the session dropped, for the audit trail."""

    kind: ErrorKind
    message: str
    command: str | None = None
    origin: Origin | None = None


@dataclass(frozen=True)
class Audit:
    """A move of the bridge's own taken (auto-park's, the storm's park: session.py rule 25):
    its line in the audit trail, ``command`` executed, ``origin`` naming the feature."""

    origin: Origin
    command: str


@dataclass(frozen=True)
class Ask:
    """Hand ``question`` to the sky worker; its answer goes back to the session with
    ``generation`` (``RotatorSession.sky_answer``, tracking.py rule 8)."""

    generation: int
    question: Question


Action = Write | Publish | Report | Audit | Ask
