"""The target waiting to go to the controller, and the rules for streams of targets. Pure.

Rules:
1. One target waits at a time; a newer one replaces it (a dragged slider sends dozens),
   keeping an axis it leaves out from the one it replaces (model.combine).
2. Targets that come as a stream (one replaces a still-pending one, or arrives within
   BURST_QUIET_S of the last target sent: a dragged slider, a flood) are sent when the stream
   pauses for BURST_QUIET_S, and at the latest STREAM_MAX_WAIT_S after the stream's first unsent
   target (longer for controllers that must stop to re-target), so a continuous stream is
   followed without flooding the line. A single command is never delayed.
3. A target put back after a silent controller's lost report (slew.py) carries its try
   number; any newer target replaces it and starts again at the first try.
"""

from __future__ import annotations

from bridge.engine import motion as mo
from bridge.engine.config import WorkerConfig
from bridge.model import Source, Target, combine
from bridge.pointing import Pointing

BURST_QUIET_S = 0.5
STREAM_MAX_WAIT_S = {"direct": 1.0, "stop_and_wait": 5.0}


class Targets:
    def __init__(self, cfg: WorkerConfig) -> None:
        self._max_wait_s = STREAM_MAX_WAIT_S[cfg.spec.retarget.value]
        self.pending: Target | None = None
        self._pending_t = 0.0
        self._replaced = False  # part of a stream (rule 2)
        self._stream_t = 0.0
        self._last_sent_t = -1e18
        self._attempt = 1

    def put(self, target: Target, now: float) -> None:
        recent = now - self._last_sent_t < BURST_QUIET_S
        if self.pending is None:
            self._stream_t = now
        self._replaced = self.pending is not None or recent
        self.pending, self._pending_t, self._attempt = combine(target, self.pending), now, 1

    def put_back(self, target: Target, attempt: int, now: float) -> None:
        """Rule 3: send ``target`` again (unless a newer one waits already)."""
        if self.pending is None:
            self.pending, self._pending_t, self._stream_t = target, now, now
            self._replaced, self._attempt = False, attempt

    def clear(self) -> Target | None:
        """Drop the waiting target (a stop, the lock, the link down); the one dropped."""
        dropped, self.pending = self.pending, None
        return dropped

    def clear_from(self, source: Source) -> None:
        """Drop the waiting target if ``source`` put it (a feature that has ended: a target of
        its own must not go out after it)."""
        if self.pending is not None and self.pending.source is source:
            self.clear()

    def sent(self, now: float) -> int:
        """The waiting target went to the controller; which try it was."""
        attempt = self._attempt
        self.pending, self._attempt, self._last_sent_t = None, 1, now
        return attempt

    def stream_wait(self, now: float) -> bool:
        if not self._replaced:
            return False
        # the same sums as stream_deadline: a wake-up at that time must end the wait
        return now < self._pending_t + BURST_QUIET_S and now < self._stream_t + self._max_wait_s

    def stream_deadline(self, now: float) -> float | None:
        """When a waiting stream's target goes out at the latest (None: not waiting)."""
        if self.pending is None or not self.stream_wait(now):
            return None
        return min(self._pending_t + BURST_QUIET_S, self._stream_t + self._max_wait_s)


def resolve(target: Target, m: mo.Motion, aim: Pointing) -> tuple[float | None, float | None]:
    """The raw values to send now: a target whose side is free takes the side nearest to where
    the rotor is now (pointing.py rule 2); an axis left out keeps its current target, else its
    position."""
    az = target.az_deg
    if target.true_az_deg is not None and m.position_deg is not None:
        az = aim.raw_for(target.true_az_deg, m.position_deg)
    has_elevation = aim.has_elevation
    if az is None:
        az = m.target_deg if m.target_deg is not None else m.position_deg
    el = target.el_deg
    if has_elevation and el is None:
        el = m.el_target_deg if m.el_target_deg is not None else m.el_position_deg
        if el is None:
            return None, None
    return az, el
