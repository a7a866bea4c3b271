"""What the session's parts (tracking.py, autopark.py) see and what they hand back
(docs/architecture.md, "parts decide and return"). Frozen data, nothing else.

Rules:
1. A part never holds the session: it gets a ``Scene`` (a read-only view of the moment) and
   returns a ``Proposal``; the session applies proposals in one order it shows in its step.
2. A proposal's target is already judged (pointing.py): the session only queues it.
3. A part says what wakes it (``Wake``): a step that brings none of that does not run it, and
   a part that is off (nothing tracked, no wind configured, no auto-park) is not run at all.
   A part that reads the time itself, or whose side effects count its steps, asks for every
   step while it is on.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Flag, auto
from typing import NamedTuple

from bridge.core.model import Target
from bridge.session import motion as mo
from bridge.session.actions import Report


class Wake(Flag):
    """What makes a part worth running in a step (rule 3)."""

    STEP = auto()  # every step while it is on: it reads the time (the sky, a quiet spell)
    MOTION = auto()  # the motion changed: a reading taken, the motion machine's clock, a write


class Scene(NamedTuple):
    """The session as a part may see it at ``now`` (a tuple: read-only, cheap at every step)."""

    now: float
    motion: mo.Motion
    pending: Target | None  # the target waiting to go to the controller (targets.py)
    locked: bool
    parked: bool  # the last status said so (status.py rule 4)
    slewing: bool  # a silent controller's slew is under way (slew.py)
    wall_offset_s: float  # wall clock (unix seconds) = now + this


@dataclass(frozen=True)
class Proposal:
    """What a part wants done; every field is optional."""

    target: Target | None = None  # put it as the pending target
    error: Report | None = None  # hand this error event out
    ended: str | None = None  # tracking ended for this reason: drop a target of its own
    busy: bool = False  # activity: auto-park's quiet spell starts again (autopark.py rule 1)
    halt: bool = False  # stop the turn under way (following: a transmission began, follow.py)


NOTHING = Proposal()
