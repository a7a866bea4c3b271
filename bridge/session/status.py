"""What a rotator's status says, and when a new one is worth emitting. Pure, no clock: the
session hands ``current`` what it knows (``Seen``, a read-only view) and publishes what it
returns.

Rules:
1. The published bearing follows readings with hysteresis (``publishable_bearing``): analog
   jitter of a still rotor never reaches a dashboard, but for a step on the way it turned at
   the reading that finds it still and in its brake window (the last degrees of a turn). The
   first reading after readings were lost (the port closed, the controller offline, a SatEL's
   report lost) while the rotor turned or had a target out is shown as it is: it may be
   anywhere near (controller.py ``_lose_motion``). One at rest forgets the way of its last
   turn then.
2. During a silent slew (SatEL) the bearing is the slew's estimate, marked ``estimated``.
3. Without position feedback (DCU-1) a commanded move is shown as ``moving`` with
   ``estimated`` set, the target and the time it should be over; after that the state is
   ``unknown`` and the target is cleared. The bridge never shows more than it knows.
4. Bearings and targets are shown as true bearings (pointing.py), with the controller's raw
   value beside them (``raw_bearing``, ``overlap``). ``parked`` holds while the rotor is still
   within tolerance of the park position it was last sent to. A target shown while it waits
   to go out (asked first, a brake) is shown with its own source and operator (``sent_by``; a
   contract check: a rotctld target was shown beside ``last_command_source: mqtt``).
5. A status is emitted when something a user would notice changed. The controller's own clock
   (SatEL) ticks every second: it rides along in the next status but never causes one.
6. ``current`` gives every field of ``RotatorStatus`` a value, and makes it as the dataclass's
   own ``__init__`` would, without its ``object.__setattr__`` for each of the 30 fields (a
   frozen dataclass's: most of the cost of a status, made at every reading that moves the
   bearing). tests/engine/test_status_build.py holds it to the dataclass.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import NamedTuple

from bridge.core.model import (
    Control,
    FollowingInfo,
    MotionState,
    Order,
    RotatorHealth,
    RotatorStatus,
    SettingValue,
    Source,
    Target,
    TargetInfo,
    TrackingInfo,
    WindInfo,
)
from bridge.session import motion as mo
from bridge.session.config import WorkerConfig
from bridge.session.slew import Slew


@dataclass
class Hysteresis:
    """One axis's published value (rule 1)."""

    value: float | None = None
    direction: int = 0

    def feed(
        self,
        reading: float,
        moving: bool,
        deadband_deg: float,
        wraps: bool,
        coasting: bool,
        toward: float | None = None,
    ) -> None:
        new, self.direction = publishable_bearing(
            self.value, self.direction, reading, moving, deadband_deg, wraps, coasting, toward
        )
        if new is not None:
            self.value = new


@dataclass
class View:
    """Everything the status shows besides what the motion machine and the link know."""

    last_error: str | None = None
    last_source: str | None = None
    target_info: TargetInfo | None = None  # of the last target sent (locator, coordinates);
    # a target still waiting (a brake delay) shows its own: it is the current one for ``long``
    park_raw: tuple[float, float | None] | None = None  # the park target last sent (rule 4)
    last_operator: str | None = None  # who sent the command of last_source (model.Origin)
    control: Control | None = None  # the control lease's holder (runtime/lease.py)


class Features(NamedTuple):
    """What the session's parts show (tracking.py, follow.py, wind.py, health.py)."""

    tracking: TrackingInfo | None = None
    tracking_ended: str | None = None
    following: FollowingInfo | None = None
    following_ended: str | None = None
    wind: WindInfo | None = None
    health: RotatorHealth | None = None  # health.py: a new one after each move
    parts: dict[str, object] | None = None  # what the handed parts show (parts.py rule 6)


class Seen(NamedTuple):
    """What the session knows at one moment, as the status needs it (a tuple: read-only, and
    cheap to build at every step)."""

    previous: RotatorStatus
    view: View
    version: str | None  # the controller's, as it says
    controller_time: str | None  # its own clock (SatEL)
    motion: mo.Motion
    connected: bool
    answering: bool  # connected, and the controller answers (or cannot: DCU-1)
    locked: bool
    options: dict[str, SettingValue]
    bearing_deg: float | None  # the published readings (rule 1), raw
    elevation_deg: float | None
    slew: Slew | None
    pending: Target | None  # the target waiting to go out...
    pending_wire: tuple[float | None, float | None] | None  # ...and its raw values, if known
    wall_offset_s: float
    features: Features
    stop_owed: bool  # stops.py rule 3
    short_of_deg: float | None  # controller.py rule 10 (``short_of``)


def sent_by(target: Target, operator: str | None) -> tuple[str, str | None]:
    """Rule 4: the source and operator the status names for ``target``; ``operator`` the one
    named before (a track's stays: who started it)."""
    if target.origin is not None:  # following's: wsjtx (follow.py rule 7)
        return target.source.value, target.origin.who
    if target.source is Source.TRACKING:
        return target.source.value, operator
    return target.source.value, None  # the bridge's own (auto-park, the wind)


def current(rig: WorkerConfig, seen: Seen, now: float, order: Order | None = None) -> RotatorStatus:
    """The status as of ``now``."""
    m, spec, view = seen.motion, rig.spec, seen.view
    answering = seen.answering
    target: tuple[float | None, float | None] = (m.target_deg, m.el_target_deg)
    if seen.pending_wire is not None:
        target = seen.pending_wire
    state = m.state if answering else MotionState.OFFLINE
    bearing, elevation = seen.bearing_deg, seen.elevation_deg
    estimated = False
    if seen.slew is not None:  # rule 2
        bearing, elevation = seen.slew.estimate(now, rig.az_speed_deg_s, rig.el_speed_deg_s)
        estimated = True
    expected_end: float | None = None
    if not spec.can_report_position and answering:  # rule 3
        moving = m.target_deg is not None and m.stop_sent_t is None
        if moving and m.busy_until_t is not None and now < m.busy_until_t:
            state, estimated = MotionState.MOVING, True
            expected_end = m.busy_until_t + seen.wall_offset_s
        else:
            state, target = MotionState.UNKNOWN, (None, None)
    aim = rig.aim
    raw = bearing if spec.can_report_position else None
    pending = seen.pending
    source, operator = view.last_source, view.last_operator
    if seen.pending_wire is not None and pending is not None:  # rule 4: the target shown
        source, operator = sent_by(pending, operator)  # waiting, with who sent it
    status = _new(RotatorStatus)  # rule 6 (its fields in their order)
    status.__dict__.update(
        rotator_id=seen.previous.rotator_id,
        state=state,
        bearing_deg=None if raw is None else aim.true_of(raw),
        elevation_deg=elevation if spec.has_elevation else None,
        target_az_deg=None if target[0] is None else aim.true_of(target[0]),
        target_el_deg=target[1] if spec.has_elevation else None,
        connected=seen.connected,
        available=answering,
        locked=seen.locked,
        lock_unknown=False,  # (the session says it: runtime/kept.py rule 10)
        version=seen.version,
        options=dict(seen.options),
        last_error=view.last_error,
        last_command_source=source,
        estimated=estimated,
        controller_time=seen.controller_time,
        expected_end_unix=expected_end,
        raw_bearing_deg=raw,
        raw_target_az_deg=target[0],
        overlap=aim.overlap(raw),
        target_info=pending.info if pending is not None else view.target_info,
        parked=_parked(rig, seen, state),
        tracking=seen.features.tracking,
        tracking_ended=seen.features.tracking_ended,
        following=seen.features.following,
        following_ended=seen.features.following_ended,
        wind=seen.features.wind,
        health=seen.features.health,
        last_operator=operator,
        control=view.control,
        features=dict(seen.features.parts) if seen.features.parts else {},
        stop_owed=seen.stop_owed,
        short_of_deg=seen.short_of_deg,
        turn_kept=not spec.can_report_position and mo.turn_kept(m, now),
        turn_kept_until=None if spec.can_report_position else mo.turn_kept_until(m, now),
        relayed=None,  # (a remote's reading alone: remote/readings.py rule 3)
        order=order,
    )
    return status


_new = object.__new__  # rule 6


def _parked(rig: WorkerConfig, seen: Seen, state: MotionState) -> bool:
    park = seen.view.park_raw
    if park is None or state in (MotionState.MOVING, MotionState.OFFLINE):
        return False
    if not rig.spec.can_report_position:
        return True  # the estimated move is over
    return mo.within_tolerance(seen.motion, rig.motion, park)


def worth_emitting(new: RotatorStatus, old: RotatorStatus) -> bool:
    """Rule 5: the controller's clock alone is no change."""
    bearing = new.bearing_deg
    if bearing is not old.bearing_deg and bearing != old.bearing_deg:
        return True  # (a turning rotor's every reading: no need to compare the other 30 fields)
    if new.controller_time == old.controller_time:
        return new != old
    return replace(new, controller_time=None) != replace(old, controller_time=None)


def signed_delta(to_deg: float, from_deg: float, wraps: bool) -> float:
    d = to_deg - from_deg
    if wraps and abs(d) > 180.0:
        d -= 360.0 if d > 0 else -360.0
    return d


# publishable_bearing's direction of travel when it is not known (neither way, nor at rest:
# a step within the deadband is then jitter, whether the rotor is called moving or not)
WAY_UNKNOWN = 2


def publishable_bearing(
    published_deg: float | None,
    direction: int,
    reading_deg: float,
    moving: bool,
    deadband_deg: float,
    wraps: bool,
    coasting: bool = False,
    toward: float | None = None,
) -> tuple[float | None, int]:
    """Hysteresis on the published bearing: (bearing to publish or None, direction of travel).

    At rest only a change beyond the deadband is published. While moving, every step in the
    direction of travel is published (dashboards stay fresh), but a step back inside the
    deadband is analog jitter and is not. While the rotor comes to rest after a turn
    (``coasting``: the reading that found it still, then its brake window), a step on in the
    direction of travel is published too, however small: the last degrees of a turn are the
    bearing it ends at, not jitter (a CI run: a rotor called arrived 2 degrees short, at the
    reading that found it still, was shown there for good).

    The direction a step beyond the deadband sets is the shorter way round on a wrapping
    scale, but for a step of more than half a turn on the scale of a rotor whose travel ends
    at north (``toward``: its raw target; it turns only along the scale): the way along the
    scale, unless the bearing shown or the reading is at the end that reads 000 (its 0 and its
    360 read alike): then the way on from the reading to the target, or, once there,
    WAY_UNKNOWN (a review: the way on to the target alone took an overshoot read late, 301 on
    the way from 10 to 300, for down, and its last degree, 302, for jitter; a busy machine: a
    RotorCard parked
    from 290 was read at 290 then at its park, 0, the shorter way called +70, and its jitter
    at rest, 1, was then shown as the turn's last degree for good; the way from the bearing
    shown before cannot be told, its 360 end reading 000 as its 0 does: a review, a turn down
    from 360 to 200 was taken for up, and its jitter, 201, shown for good).
    """
    if published_deg is None:
        return reading_deg, 0
    delta = signed_delta(reading_deg, published_deg, wraps)
    if delta == 0:
        return None, direction
    step = 1 if delta > 0 else -1
    jump = abs(delta) > deadband_deg
    if jump and toward is not None and wraps and abs(reading_deg - published_deg) > 180.0:
        if published_deg % 360.0 and reading_deg % 360.0:  # (neither at the end 000 reads)
            return reading_deg, 1 if reading_deg > published_deg else -1  # along the scale
        way = toward - reading_deg  # (the scale's way on to the target: the rotor's; not
        return reading_deg, (way > 0) - (way < 0) if way else WAY_UNKNOWN  # known once there)
    if jump or ((moving or coasting) and step == direction):
        return reading_deg, step
    if moving and direction == 0:
        return reading_deg, step
    return None, direction
