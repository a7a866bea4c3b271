"""A silent controller's slew whose report does not come (SatEL): what the session does then.
Pure: ``overdue`` gets the slew and the time and returns what to do (``Overdue``); the session
carries it out.

Source: protocols/satel.md (no input but a stop while the controller slews; it reports once the
move is over, also after a stop). See slew.py for what a slew is and how long it may take.

Rules:
1. A report that does not come within the slew's bound (slew.py rule 2) was lost, or the rotor is
   slower than configured. Either way the bridge does not poll into a slew it cannot see: it
   sends the stop (the one input allowed during a slew), asks for the position once the stopped
   controller had its chance to report, and sends the slew's target again, so the rotor still
   ends where the last accepted command asked. An error says so, naming the speed setting.
2. If the second try's report does not come either (a jammed rotor, a mechanical stop short of
   the point), the target is given up with an error: a motor is not driven against a jam again
   and again.
3. Any stop written during a slew (rule 1, stop and redirect, the user's stop) is followed by
   the report within one reply time or it is written again, up to SLEW_STOP_TRIES: a stop byte
   lost on the line must not let the poll that follows into a slew. Only then is the controller
   asked where it is.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

from bridge.engine.actions import Report
from bridge.engine.config import WorkerConfig
from bridge.engine.slew import Slew
from bridge.model import ErrorKind, Target, describe_command

log = logging.getLogger(__name__)

SLEW_STOP_TRIES = 3  # stops written to a slewing controller before it is asked where it is
SLEW_ATTEMPTS = 2  # a target whose report did not come is sent once more, then given up


@dataclass(frozen=True)
class Overdue:
    """What the session does about a reply that did not come by its deadline."""

    stop: bool  # write a stop (rules 1 and 3); otherwise stop waiting for the reply
    error: Report | None = None
    retry: Target | None = None  # put back as the pending target, try ``attempt`` (rule 1)
    attempt: int = 1
    track_lost: bool = False  # the slew's readings are lost (motion.track_lost)


def travel_s(rig: WorkerConfig, slew: Slew) -> float:
    spec = rig.spec
    span_el_deg = spec.el_max_deg - spec.el_min_deg
    return slew.travel_s(
        rig.az_speed_deg_s, rig.el_speed_deg_s, rig.motion.az_span_deg, span_el_deg
    )


def overdue(rig: WorkerConfig, slew: Slew | None, reply_timeout_s: float, now: float) -> Overdue:
    """The owed reply (or a slew's report) did not come by its deadline."""
    if slew is not None and slew.stops == 0:  # rule 1
        late = (
            f"no report from the controller {now - slew.start_t:.0f} s after a move that "
            f"takes {travel_s(rig, slew):.0f} s at {rig.az_speed_deg_s:g}/"
            f"{rig.el_speed_deg_s:g} deg/s"
        )
        if slew.attempt >= SLEW_ATTEMPTS:  # rule 2
            given_up = (
                f"{late}, the second time for this target: stopping it and giving the target "
                "up (rotor jammed or held short of the point? if it is that slow, set "
                "az_speed_deg_s / el_speed_deg_s)"
            )
            command = describe_command(Target(slew.to_az_deg, slew.to_el_deg))
            return Overdue(stop=True, error=Report(ErrorKind.SERIAL, given_up, command))
        again = (
            f"{late}: stopping it to ask where it is, then going on to the target (if "
            "the rotor is that slow, set az_speed_deg_s / el_speed_deg_s)"
        )
        target = Target(slew.to_az_deg, slew.to_el_deg, slew.source)
        error = Report(ErrorKind.SERIAL, again)
        return Overdue(stop=True, error=error, retry=target, attempt=slew.attempt + 1)
    if slew is not None and slew.stops < SLEW_STOP_TRIES:  # rule 3
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
