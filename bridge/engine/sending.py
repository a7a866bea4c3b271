"""The pending target's way to the wire: whether it goes now, waits, is already done, needs a
stop or a fresh reading first. Pure: the session asks with the motion, the link's line state
and the time, and carries the answer out.

Rules:
1. A target goes to the controller only when ``motion.plan_target`` says so; a stop due goes
   first, and a held target (session rule 13) waits for its marker.
2. A target the rotor is already on its way to, or (not tracking's: its steps may be finer
   than the tolerance) already within tolerance of, is done without a frame.
3. A stream of targets waits for its pause (targets.py rule 2); a half-duplex line with a
   reply in flight is free right after it.
4. A target for a controller that stops on re-target (Rotor-EZ) goes out only after a reading
   younger than one moving poll interval has shown the rotor idle: a front-panel move that
   began after the last poll must not be cut short. Otherwise the controller is asked first.
"""

from __future__ import annotations

import enum
import logging
from dataclasses import dataclass

from bridge.engine import motion as mo
from bridge.engine.config import WorkerConfig
from bridge.engine.link import Link
from bridge.engine.targets import Targets, resolve
from bridge.model import Source

log = logging.getLogger(__name__)


class Go(enum.Enum):
    WAIT = "wait"
    DONE = "done"  # rule 2: clear it, nothing to write
    STOP_FIRST = "stop first"
    ASK_FIRST = "ask first"  # rule 4: poll now, the target follows the answer
    SEND = "send"


@dataclass(frozen=True)
class Sending:
    go: Go
    az_deg: float = 0.0  # the raw values to encode (SEND)
    el_deg: float | None = None
    wire: tuple[float, float | None] = (0.0, None)  # as the controller will hold them


def decide(
    rig: WorkerConfig, link: Link, m: mo.Motion, targets: Targets, held: bool, now: float
) -> Sending:
    """What the pending target of ``targets`` does now (``held``: session rule 13)."""
    pending = targets.pending
    assert pending is not None
    if link.stop_due or held:
        return Sending(Go.WAIT)  # rule 1
    az, el = resolve(pending, m, rig.aim)
    if az is None:
        return Sending(Go.WAIT)  # no reading yet to keep the other axis where it is
    wire = link.codec.wire_target(az, el)
    if m.target_deg is not None and (m.target_deg, m.el_target_deg) == wire:
        return Sending(Go.DONE, wire=wire)  # already on its way there
    small = pending.source is not Source.TRACKING
    if small and rig.spec.can_report_position and mo.within_tolerance(m, rig.motion, wire):
        log.info("%s: already within tolerance of %s", rig.rotator_id, wire)
        return Sending(Go.DONE, wire=wire)
    plan = mo.plan_target(m, rig.motion, now)
    if plan is mo.Plan.STOP_FIRST:
        doing = "turning" if rig.spec.can_report_position else "may still be turning"
        log.info("%s: %s; stopping before the new target %s", rig.rotator_id, doing, wire)
        return Sending(Go.STOP_FIRST)
    if plan is not mo.Plan.SEND or not link.free() or targets.stream_wait(now):
        return Sending(Go.WAIT)  # rules 1 and 3
    if _needs_fresh_reading(rig, link, now):
        return Sending(Go.ASK_FIRST)
    return Sending(Go.SEND, az, el, wire)


def _needs_fresh_reading(rig: WorkerConfig, link: Link, now: float) -> bool:
    """Rule 4."""
    if not rig.motion.can_report_position or rig.motion.direct_retarget:
        return False
    age = now - (link.last_reply_t if link.last_reply_t is not None else -1e18)
    return age > rig.moving_poll_interval_s
