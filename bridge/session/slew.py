"""A slew: a move on a controller that is silent until it ends (SatEL), as far as it can be known,
and what the session does when its report does not come. Pure: ``overdue`` gets the slew and the
time and returns what to do (``Overdue``); the session carries it out.

Source: protocols/satel.md (the controller answers nothing while it moves, takes no input but a
stop, and reports its position once the move is over, also after a stop). What is known: where it
started (the last reading, if any), where it goes, when, at which speeds the rotor turns; so how
long it should take, and where the rotor should be meanwhile (an estimate, marked as one in the
status).

Rules:
1. Travel time is the slower axis's; an unknown start costs the whole span; the azimuth travels
   linearly between its stops (no wrap through north).
2. Its report is owed until SLEW_TIME_FACTOR times the travel time plus SLEW_MARGIN_S.
3. The estimate moves from the start at the configured speeds in whole degrees and never passes
   the target.
4. A report that does not come within the slew's bound (rule 2) was lost, or the rotor is
   slower than configured. Either way the bridge does not poll into a slew it cannot see: it
   sends the stop (the one input allowed during a slew), asks for the position once the stopped
   controller had its chance to report, and sends the slew's target again, so the rotor still
   ends where the last accepted command asked, as its sender's (an axis alone that sender
   sends meanwhile is taken with it: core/model.py ``combine``; a cold review, put back as
   nobody's, it was not, and the rotor went to an elevation short of the azimuth asked).
   What is put back stands for the target sent (``Overdue.retry_of``): on a rotator of two
   boxes, a drop of the other box's half drops it too (runtime/composite.py rule 8; a cold
   review: a SatEL elevation box's 40, put back as a new target, was not known for the
   rotator's half, and went out after a claim dropped the azimuth's).
   An error says so, naming the speed setting. In a storm that refuses motion (session/
   wind.py rule 1) the target is not put back (a storm's own park is): the error says the
   stop, and that the target is not sent again, with the storm's words (the session words it:
   ``Overdue.late``).
   A controller restarted mid-slew sends no report either: the first reading after the stop
   (rule 6's too) tells it by its clock gone back, and the target waiting is dropped, not sent
   (controller.py rule 14); the error says the target goes on unless its clock says so.
5. If the second try's report does not come either (a jammed rotor, a mechanical stop short of
   the point), the target is given up with an error: a motor is not driven against a jam again
   and again.
6. Any stop written during a slew (rule 4, stop and redirect, the user's stop) is followed by
   the report within one reply time or it is written again, up to SLEW_STOP_TRIES: a stop byte
   lost on the line must not let the poll that follows into a slew. Only then is the controller
   asked where it is.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

from bridge.core.model import ErrorKind, Origin, Source, Target, describe_command
from bridge.session.actions import Report
from bridge.session.config import WorkerConfig

log = logging.getLogger(__name__)

SLEW_TIME_FACTOR = 2.0  # a slew's report is waited for twice the travel time at the set speeds...
SLEW_MARGIN_S = 5.0  # ...plus this (relays, start-up, the report itself at 9600 baud)
SLEW_STOP_TRIES = 3  # stops written to a slewing controller before it is asked where it is
SLEW_ATTEMPTS = 2  # a target whose report did not come is sent once more, then given up


@dataclass(frozen=True)
class Slew:
    """A move on a controller that is silent until it ends: what we know to estimate it."""

    start_t: float
    from_az_deg: float | None
    from_el_deg: float | None
    to_az_deg: float
    to_el_deg: float | None
    source: Source = Source.MQTT
    stops: int = 0  # stops written during the slew
    attempt: int = 1  # 2: the same target sent again after its report did not come
    origin: Origin | None = None  # who sent it (rule 4: put back as its sender's own)
    sent: Target | None = None  # the target sent (rule 4: the one its put back stands for)

    def travel_s(
        self, az_speed_deg_s: float, el_speed_deg_s: float, az_span_deg: float, el_span_deg: float
    ) -> float:
        """How long the slew takes at these speeds: the slower axis decides. Where the start is
        unknown, the whole span; the azimuth travels linearly between its stops."""
        az_travel = _travel(self.from_az_deg, self.to_az_deg, az_span_deg)
        el_travel = _travel(self.from_el_deg, self.to_el_deg, el_span_deg)
        return max(az_travel / az_speed_deg_s, el_travel / el_speed_deg_s)

    def estimate(
        self, now: float, az_speed_deg_s: float, el_speed_deg_s: float
    ) -> tuple[float | None, float | None]:
        """Where the rotor should be, in whole degrees, moving at the nominal speeds."""
        dt = now - self.start_t
        return (
            _toward(self.from_az_deg, self.to_az_deg, az_speed_deg_s * dt),
            _toward(self.from_el_deg, self.to_el_deg, el_speed_deg_s * dt),
        )


def _travel(start: float | None, end: float | None, span: float) -> float:
    if end is None:
        return 0.0
    return span if start is None else abs(end - start)


def _toward(start: float | None, end: float | None, step: float) -> float | None:
    if start is None or end is None:
        return end
    if abs(end - start) <= step:
        return end
    return float(round(start + step * (1 if end > start else -1)))


@dataclass(frozen=True)
class Overdue:
    """What the session does about a reply that did not come by its deadline."""

    stop: bool  # write a stop (rules 4 and 6); otherwise stop waiting for the reply
    error: Report | None = None
    retry: Target | None = None  # put back as the pending target, try ``attempt`` (rule 4)
    retry_of: Target | None = None  # ... standing for this one, the target the slew was sent
    attempt: int = 1
    track_lost: bool = False  # the slew's readings are lost (motion.track_lost)
    late: str = ""  # rule 4: how late its report is, said alone when ``retry`` may not go


def travel_s(rig: WorkerConfig, slew: Slew) -> float:
    spec = rig.spec
    span_el_deg = spec.el_max_deg - spec.el_min_deg
    return slew.travel_s(
        rig.az_speed_deg_s, rig.el_speed_deg_s, rig.motion.az_span_deg, span_el_deg
    )


def overdue(rig: WorkerConfig, slew: Slew | None, reply_timeout_s: float, now: float) -> Overdue:
    """The owed reply (or a slew's report) did not come by its deadline."""
    if slew is not None and slew.stops == 0:  # rule 4
        late = (
            f"no report from the controller {now - slew.start_t:.0f} s after a move that "
            f"takes {travel_s(rig, slew):.0f} s at {rig.az_speed_deg_s:g}/"
            f"{rig.el_speed_deg_s:g} deg/s"
        )
        if slew.attempt >= SLEW_ATTEMPTS:  # rule 5
            given_up = (
                f"{late}, the second time for this target: stopping it and giving the target "
                "up (rotor jammed or held short of the point? if it is that slow, set "
                "az_speed_deg_s / el_speed_deg_s)"
            )
            command = describe_command(Target(slew.to_az_deg, slew.to_el_deg))
            return Overdue(stop=True, error=Report(ErrorKind.SERIAL, given_up, command))
        again = (
            f"{late}: stopping it to ask where it is, then going on to the target unless "
            "its clock shows it restarted (if the rotor is that slow, set az_speed_deg_s / "
            "el_speed_deg_s)"
        )
        target = Target(slew.to_az_deg, slew.to_el_deg, slew.source, origin=slew.origin)
        error = Report(ErrorKind.SERIAL, again)
        return Overdue(
            stop=True,
            error=error,
            retry=target,
            retry_of=slew.sent,
            attempt=slew.attempt + 1,
            late=late,
        )
    if slew is not None and slew.stops < SLEW_STOP_TRIES:  # rule 6
        log.warning(
            "%s: no report %g s after a stop during a slew; stopping again before asking",
            rig.rotator_id,
            reply_timeout_s,
        )
        return Overdue(stop=True)
    if slew is None:
        return Overdue(stop=False)
    lost = "no report after the stopped slew; asking the controller"
    return Overdue(stop=False, error=Report(ErrorKind.SERIAL, lost), track_lost=True)
