"""Parking by itself after a quiet spell (``park_after_idle_s``; a windy remote site). Pure.

Rules:
1. The quiet spell counts from the last command (a target, a stop or the lock switched either
   way), from the last moment the rotor was seen turning (a hand on the front panel), from
   start-up and from the controller answering again: a rotor never parks the moment someone
   unlocks it or switches its controller back on.
2. Parking happens only when everything else would allow a target: the controller answering,
   the lock off, the rotor idle, no target waiting, and not already at the park position.
3. The park is an ordinary target (source ``auto-park``): any command meanwhile replaces or
   stops it, and it counts as activity itself, so a park that cannot finish (a stall) is
   tried again only after another quiet spell.
"""

from __future__ import annotations

import logging
import math
from typing import TYPE_CHECKING

from bridge.errors import Refused
from bridge.model import ErrorKind, MotionState, Source, Target

if TYPE_CHECKING:
    from bridge.engine.session import RotatorSession

log = logging.getLogger(__name__)


class AutoPark:
    def __init__(self, after_s: float, park: tuple[float, float | None] | None) -> None:
        self._after_s = after_s if park is not None else 0.0
        self._park = park
        self._since = -math.inf

    def activity(self, now: float) -> None:
        """Rule 1: the quiet spell starts again."""
        self._since = now

    def deadline(self) -> float | None:
        """When parking is due (None: never)."""
        if self._after_s <= 0.0 or not math.isfinite(self._since):
            return None
        return self._since + self._after_s

    def wakeup(self, now: float) -> float | None:
        """When the session must look again: the deadline while it lies ahead. Once it has
        passed without parking (not ready: locked, turning), the session's own polls and
        inputs bring it back; waking at a past time would spin."""
        deadline = self.deadline()
        return deadline if deadline is not None and deadline > now else None

    def due(self, now: float, ready: bool) -> Target | None:
        """The park target, if the spell is over and ``ready`` (rule 2); restarts the spell."""
        deadline = self.deadline()
        if deadline is None or now < deadline or not ready or self._park is None:
            return None
        self._since = now  # rule 3
        return Target(self._park[0], self._park[1], Source.AUTO_PARK, park=True)


def step(session: RotatorSession, now: float) -> None:
    """Run by the session with its other rules, while the controller answers."""
    m = session.motion
    if m.state is MotionState.MOVING:
        session.autopark.activity(now)  # rule 1: someone is turning it
        return
    free = m.state is MotionState.IDLE and session.targets.pending is None
    park = session.autopark.due(now, free and not session.locked and not session.status.parked)
    if park is None:
        return
    try:
        session.targets.put(session.cfg.aim.judge(park, m.position_deg), now)
    except Refused as exc:
        session.error(ErrorKind.REFUSED, f"auto-park refused: {exc.message}", "park")
        return
    log.info("%s: parking (no command for %g s)", session.name, session.cfg.park_after_idle_s)
