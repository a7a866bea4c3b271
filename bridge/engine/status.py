"""What a rotator's status says, and when a new one is worth emitting. Pure, no clock.

Rules:
1. The published bearing follows readings with hysteresis (motion.publishable_bearing): analog
   jitter of a still rotor never reaches a dashboard.
2. During a silent slew (SatEL) the bearing is the slew's estimate, marked ``estimated``.
3. Without position feedback (DCU-1) a commanded move is shown as ``moving`` with
   ``estimated`` set, the target and the time it should be over; after that the state is
   ``unknown`` and the target is cleared. The bridge never shows more than it knows.
4. Bearings and targets are shown as true bearings (pointing.py), with the controller's raw
   value beside them (``raw_bearing``, ``overlap``). ``parked`` holds while the rotor is still
   within tolerance of the park position it was last sent to.
5. A status is emitted when something a user would notice changed. The controller's own clock
   (SatEL) ticks every second: it rides along in the next status but never causes one.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

from bridge.engine import motion as mo
from bridge.model import MotionState, RotatorStatus, TargetInfo

if TYPE_CHECKING:
    from bridge.engine.session import RotatorSession


@dataclass
class Hysteresis:
    """One axis's published value (rule 1)."""

    value: float | None = None
    direction: int = 0

    def feed(self, reading: float, moving: bool, deadband_deg: float, wraps: bool) -> None:
        new, self.direction = mo.publishable_bearing(
            self.value, self.direction, reading, moving, deadband_deg, wraps
        )
        if new is not None:
            self.value = new


@dataclass
class View:
    """Everything the status shows besides what the motion machine and the link know."""

    version: str | None = None
    controller_time: str | None = None
    last_error: str | None = None
    last_source: str | None = None
    target_info: TargetInfo | None = None  # of the last target sent (locator, coordinates);
    # a target still waiting (a brake delay) shows its own: it is the current one for ``long``
    park_raw: tuple[float, float | None] | None = None  # the park target last sent (rule 4)


def current(session: RotatorSession, now: float) -> RotatorStatus:
    """The status of ``session`` as of ``now``."""
    link, m, spec, view = session.link, session.motion, session.cfg.spec, session.view
    answering = link is not None and session.answering
    target: tuple[float | None, float | None] = (m.target_deg, m.el_target_deg)
    pending = session.targets.pending
    if pending is not None and link is not None:
        az, el = session.resolve(pending)
        target = link.codec.wire_target(az, el) if az is not None else target
    state = m.state if answering else MotionState.OFFLINE
    bearing, elevation = session.az_shown.value, session.el_shown.value
    estimated = False
    if link is not None and link.slew is not None:  # rule 2
        cfg = session.cfg
        bearing, elevation = link.slew.estimate(now, cfg.az_speed_deg_s, cfg.el_speed_deg_s)
        estimated = True
    expected_end: float | None = None
    if not spec.can_report_position and answering:  # rule 3
        moving = m.target_deg is not None and m.stop_sent_t is None
        if moving and m.busy_until_t is not None and now < m.busy_until_t:
            state, estimated = MotionState.MOVING, True
            expected_end = m.busy_until_t + session.wall_offset_s
        else:
            state, target = MotionState.UNKNOWN, (None, None)
    aim = session.cfg.aim
    raw = bearing if spec.can_report_position else None
    return replace(
        session.status,
        state=state,
        bearing_deg=None if raw is None else aim.true_of(raw),
        raw_bearing_deg=raw,
        overlap=aim.overlap(raw),
        target_info=pending.info if pending is not None else view.target_info,
        parked=_parked(session, state),
        tracking=session.tracker.info,
        tracking_ended=session.tracker.ended,
        elevation_deg=elevation if spec.has_elevation else None,
        estimated=estimated,
        expected_end_unix=expected_end,
        controller_time=view.controller_time,
        target_az_deg=None if target[0] is None else aim.true_of(target[0]),
        raw_target_az_deg=target[0],
        target_el_deg=target[1] if spec.has_elevation else None,
        connected=link is not None,
        available=answering,
        locked=session.locked,
        version=view.version,
        options=dict(session.options),
        last_error=view.last_error,
        last_command_source=view.last_source,
    )


def _parked(session: RotatorSession, state: MotionState) -> bool:
    park = session.view.park_raw
    if park is None or state in (MotionState.MOVING, MotionState.OFFLINE):
        return False
    if not session.cfg.spec.can_report_position:
        return True  # the estimated move is over
    return mo.within_tolerance(session.motion, session.cfg.motion, park)


def worth_emitting(new: RotatorStatus, old: RotatorStatus) -> bool:
    """Rule 5: the controller's clock alone is no change."""
    if new.controller_time == old.controller_time:
        return new != old
    return replace(new, controller_time=None) != replace(old, controller_time=None)
