"""The target waiting to go to the controller, the rules for streams of targets, and its way to
the wire: whether it goes now, waits, is already done, needs a stop or a fresh reading first.
Pure: the session asks with the motion, the link's line state and the time, and carries the
answer out.

Rules:
1. One target waits at a time; a newer one replaces it (a dragged slider sends dozens),
   keeping an axis it leaves out from the one it replaces (model.combine).
2. Targets that come as a stream (one replaces a still-pending one, or arrives within
   BURST_QUIET_S of the last target sent: a dragged slider, a flood) are sent when the stream
   pauses for BURST_QUIET_S, and at the latest STREAM_MAX_WAIT_S after the stream's first unsent
   target (longer for controllers that must stop to re-target), so a continuous stream is
   followed without flooding the line. A single command is never delayed.
3. A target put back after a silent controller's lost report (slew.py) carries its try
   number; any newer target replaces it and starts again at the first try. It stands for the
   target that was sent, waiting and once sent again (``waits_for``, ``stands_for``): on a
   rotator of two boxes, the other box's drop of that target drops it too (runtime/
   composite.py rule 8; a cold review: a SatEL elevation box's put back was a new target the
   drop did not know, and the elevation turned on alone).
4. A target goes to the controller only when ``motion.plan_target`` says so; a stop due goes
   first, and a held target (session rule 13) waits for its marker.
5. A target the rotor is already on its way to, or (not tracking's: its steps may be finer
   than the tolerance; nor a nudge's, ``Target.nudge``: an attack pass, a Rotor-EZ at rest
   with the tolerance of 3 degrees was nudged +2 five times, each said carried out, and
   nothing turned; a GS-232B took the first and none after it, as each counted from where
   the one before had left the rotor) already within tolerance of, is done without a frame;
   so is a tracking step the rotor, at rest, already reads exactly as the controller would
   hold it (an attack pass: a step finer than the controller's degree sent a GS-232B ``W192 000``
   three times over to a rotor reading 192 and 0, 132 set frames of 320 on a pass).
6. A stream of targets waits for its pause (rule 2); a half-duplex line with a reply in flight
   is free right after it.
7. A target for a controller that stops on re-target (Rotor-EZ) goes out only after a reading
   younger than one moving poll interval has shown the rotor idle: a front-panel move that
   began after the last poll must not be cut short. Otherwise the controller is asked first.
8. The target sent last goes once more when the controller asks it (controller.py rule 11:
   it did not move the rotor, or was refused before it did) only while the bridge still
   stands for it: no newer target, no stop, lock or link down since (``clear``), and the
   feature that sent it not ended (``clear_from``: an attack pass, tracking's first bearing
   lost, then tracking turned off, and the try more turned the rotor to the sun), nor a
   storm that refuses motion (session.py drops it, said: wind.py rule 1); its turn,
   which never began, is then over when the reading that would have sent it comes, if
   nothing waits (``forsaken``: controller.py ``forgo``, at rest; a stall was said 10 s
   later, blaming the brake, and counted in rotor health), or at once if that reading came
   already and its try more waited (``forgo_owed``). It is the same target, the same
   bearing (an axis it leaves out resolved as at its first try), and rule 5 does not take it
   for one on its way. The control lease held, when that reading comes, by another operator
   than its sender takes its try more too (``unstand``; session.py rule 23; a claim released
   before it takes nothing): its first try did not move the rotor, so it is as unsent, and
   so is its try more waiting (``unsent``, dropped at the claim itself).
9. An axis a target leaves out keeps its current target (a bare azimuth leaves the elevation
   turning on to where it was sent), except in a park (``Target.park``: the storm's, auto-park's,
   ``R/park``), which takes the place of the turn under way: there it holds where it reads (its
   position). A storm's park names no elevation where only ``wind_park_az_deg`` is set; it
   kept the elevation's current target, the half of a target the storm had just dropped, and
   a GS-232B elevation box of a composite, sent ``W000 040`` for it, turned on to 40 while the
   azimuth went to the park (a closing note: a storm begun late in a Rotor-EZ azimuth box's
   brake, the whole 300/40 dropped and said so). Nor does a park take such an axis from a
   target still waiting when it comes (rule 1's ``combine``, and the mailbox's: an attack
   pass, R/park after the same sender's 300/40 went out as ``W000 040``). An elevation held
   where it reads is held inside what the controller can be sent (its model's range): an
   Easycomm or RC2800 box reads a little below the horizon (-0.5) and cannot be sent it, and
   the storm's park never went out (the step failed at every try). Not inside the user's
   ``el_min_deg``..``el_max_deg``, which judge the targets asked for: a dish resting at 0
   below a limit of 10 was lifted to 10 by a storm's park and by every bare azimuth (an
   N1MM turn), an axis nobody asked to turn.
10. A target the rotor is already within tolerance of is said at INFO at most once per
   WITHIN_LOG_S, the rest at DEBUG (an attack pass: 16 TCP clients and a UDP flood sending
   the bearing the rotor was at wrote 650-800 lines a second, past journald's default limit,
   which then drops every line of the service, its safety warnings too).
"""

from __future__ import annotations

import enum
import logging
import math
from dataclasses import dataclass, replace

from bridge.core.model import Source, Target, combine
from bridge.pointing import Pointing
from bridge.protocols.base import HoldsOnGrid, NotReady
from bridge.session import motion as mo
from bridge.session.config import WorkerConfig
from bridge.session.link import Link

log = logging.getLogger(__name__)

BURST_QUIET_S = 0.5
SAME_DEG = 1e-6  # rule 5: a reading this near what would be sent is the same value
STREAM_MAX_WAIT_S = {"direct": 1.0, "stop_and_wait": 5.0}
WITHIN_LOG_S = 10.0  # rule 10


class Targets:
    def __init__(self, cfg: WorkerConfig) -> None:
        self._max_wait_s = STREAM_MAX_WAIT_S[cfg.spec.retarget.value]
        self.pending: Target | None = None
        self._pending_t = 0.0
        self._replaced = False  # part of a stream (rule 2)
        self._stream_t = 0.0
        self._last_sent_t = -1e18
        self._attempt = 1
        self._standing: Target | None = None  # rule 8: the target sent last, while it stands
        self.again_now = False  # rule 8: the waiting target is that one, once more
        self._forsaken: Target | None = None  # rule 8: the one sent last its feature's end took
        self._forgo_owed = False  # rule 8: ... or its try more waiting, dropped by that end
        self.within_said_t = -math.inf  # rule 10: "already within tolerance" said at INFO
        self._pending_of: Target | None = None  # rule 3: what the waiting put back stands for
        self._standing_of: Target | None = None  # ... and the one sent last

    def put(self, target: Target, now: float) -> None:
        recent = now - self._last_sent_t < BURST_QUIET_S
        if self.pending is None:
            self._stream_t = now
        self._replaced = self.pending is not None or recent
        self.pending, self._pending_t, self._attempt = combine(target, self.pending), now, 1
        self._pending_of = None
        self.again_now = False  # rule 8: a newer one waits (sent, it stands instead: ``sent``)

    @property
    def standing(self) -> Target | None:
        """Rule 8: the target sent last, while the bridge stands for it (none after a stop, a
        newer target or the end of its feature)."""
        return self._standing

    @property
    def unsent(self) -> Target | None:
        """The waiting target if it never moved the rotor: never sent, or its try more (rule
        8: its first try did not move it), else None (rule 3's, whose turn was under way:
        session.py rule 23)."""
        if self._attempt != 1 and not self.again_now:
            return None
        return self.pending

    def unstand(self) -> Target | None:
        """Rule 8: the target sent last goes no more (session.py rule 23: another operator
        claimed the lease); the one it was."""
        standing, self._standing, self._standing_of = self._standing, None, None
        return standing

    def put_back(self, target: Target, attempt: int, now: float, of: Target | None = None) -> None:
        """Rule 3: send ``target`` again (unless a newer one waits already), standing for
        ``of``, the target sent (or what that one stood for)."""
        if self.pending is None:
            self.pending, self._pending_t, self._stream_t = target, now, now
            self._replaced, self._attempt = False, attempt
            stood = self._standing_of if of is not None and of is self._standing else None
            self._pending_of = stood or of

    def waits_for(self, target: Target) -> bool:
        """Rule 3: ``target`` waits, or a put back that stands for it."""
        pending = self.pending
        return pending is not None and (pending is target or self._pending_of is target)

    def stands_for(self, target: Target) -> bool:
        """Rule 3: ``target`` is the one sent last (``standing``), or was put back as it."""
        standing = self._standing
        return standing is not None and (standing is target or self._standing_of is target)

    def clear(self) -> Target | None:
        """Drop the waiting target (a stop, the lock, the link down); the one dropped."""
        dropped, self.pending = self.pending, None
        self._standing, self.again_now, self._forsaken = None, False, None  # rule 8
        self._pending_of = self._standing_of = None  # rule 3
        self._forgo_owed = False
        return dropped

    def clear_from(self, source: Source) -> None:
        """Drop the waiting target if ``source`` put it (a feature that has ended: a target of
        its own must not go out after it, nor go once more: rule 8)."""
        standing, again = self._standing, self.again_now
        if self.pending is not None and self.pending.source is source:
            self.clear()
            self._forgo_owed = again  # (its first try never moved the rotor either)
        if standing is not None and standing.source is source:
            self._standing, self._forsaken, self._standing_of = None, standing, None

    def forsaken(self, target: Target) -> bool:
        """Rule 8: ``target`` is the one sent last whose try more its feature's end took
        (``clear_from``), and nothing waits since: the rotor never turned for it, and its turn
        is the session's to give up (controller.py ``forgo``)."""
        return target is self._forsaken and self.pending is None

    def forgo_owed(self) -> bool:
        """Rule 8: a try more waiting was dropped by its feature's end (``clear_from``), and
        nothing waits since: the turn its first try never began is the session's to give up
        now (controller.py ``forgo``). Told once."""
        owed, self._forgo_owed = self._forgo_owed, False
        return owed and self.pending is None

    def sent(self, now: float) -> int:
        """The waiting target went to the controller; which try it was."""
        attempt = self._attempt
        self._standing, self.again_now, self._forsaken = self.pending, False, None  # rule 8
        self._standing_of, self._pending_of = self._pending_of, None  # rule 3
        self._forgo_owed = False
        self.pending, self._attempt, self._last_sent_t = None, 1, now
        return attempt

    def done(self) -> Target | None:
        """Rule 5: the waiting target is the one on its way (said again): dropped, and the
        one sent last still stands (rule 8: its try more, a review: a lost target said again
        by a logger lost it); the one dropped."""
        dropped, self.pending, self.again_now = self.pending, None, False
        self._pending_of = None
        return dropped

    def again(self, target: Target, az_deg: float, el_deg: float | None, now: float) -> bool:
        """Rule 8: ``target`` waits once more, try 2, as its first try resolved it (``az_deg``,
        ``el_deg``: raw), if it is the one sent last and the bridge still stands for it; True
        if so."""
        if target is not self._standing or self.pending is not None:
            return False
        again = replace(target, az_deg=az_deg, el_deg=el_deg, true_az_deg=None)
        self.pending, self._pending_t, self._stream_t = again, now, now
        self._replaced, self._attempt, self.again_now = False, 2, True
        self._pending_of = self._standing_of or target  # (rule 3's: it stands for that one)
        return True

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


def resolve(
    target: Target,
    m: mo.Motion,
    aim: Pointing,
    codec: object = None,
    el_range: tuple[float, float] | None = None,
) -> tuple[float | None, float | None]:
    """The raw values to send now: a target whose side is free takes the side nearest to where
    the rotor is now (pointing.py rule 2); an axis left out keeps its current target (a park's
    holds where it reads: rule 9), else its position, as ``codec`` must be asked for it to stay
    on the step it read (a Rot2Prog at 0.25 degrees reads 44.25 as 44.2, and 44.2 asked for is
    44.0: protocols/base.py HoldsOnGrid), an elevation inside ``el_range`` (the model's: rule
    9; None: as it reads)."""
    az = target.az_deg
    if target.true_az_deg is not None and m.position_deg is not None:
        az = aim.raw_for(target.true_az_deg, m.position_deg, either_end=target.az_either_end)
    has_elevation = aim.has_elevation
    if az is None:
        az = m.target_deg if m.target_deg is not None and not target.park else None  # rule 9
        if az is None:
            az = _kept(codec, m.position_deg, "azimuth")
    el = target.el_deg
    if has_elevation and el is None:
        el = None if target.park else m.el_target_deg  # rule 9
        if el is None:
            el = _kept(codec, m.el_position_deg, "elevation")
            if el is None:
                return None, None
            if el_range is not None:  # rule 9: one it can be sent, not the user's limits
                el = min(max(el, el_range[0]), el_range[1])
    return az, el


def _kept(codec: object, deg: float | None, axis: str) -> float | None:
    """What to ask for to keep ``axis`` where it read ``deg`` (None: not read yet)."""
    if deg is None or not isinstance(codec, HoldsOnGrid):
        return deg
    return codec.held(deg, axis)


class Go(enum.Enum):
    WAIT = "wait"
    DONE = "done"  # rule 5: clear it, nothing to write
    STOP_FIRST = "stop first"
    ASK_FIRST = "ask first"  # rule 7: poll now, the target follows the answer
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
        return Sending(Go.WAIT)  # rule 4
    az, el = resolve(pending, m, rig.aim, link.codec, (rig.spec.el_min_deg, rig.spec.el_max_deg))
    if az is None:
        return Sending(Go.WAIT)  # no reading yet to keep the other axis where it is
    try:
        wire = link.codec.wire_target(az, el)
    except NotReady:  # the codec cannot count it yet (protocols/base.py): ask first
        return Sending(Go.ASK_FIRST) if link.free() else Sending(Go.WAIT)
    if m.target_deg is not None and (m.target_deg, m.el_target_deg) == wire:
        if not targets.again_now:  # (rule 8: that one once more is what it is for)
            return Sending(Go.DONE, wire=wire)  # already on its way there
    if pending.source is Source.TRACKING and _reads(m, rig, wire) and not targets.again_now:
        return Sending(Go.DONE, wire=wire)  # rule 5: nothing the controller would turn for
    small = pending.source is not Source.TRACKING and not pending.nudge  # (rule 5)
    if small and rig.spec.can_report_position and mo.within_tolerance(m, rig.motion, wire):
        loud = now - targets.within_said_t >= WITHIN_LOG_S  # rule 10
        if loud:
            targets.within_said_t = now
        log.log(
            logging.INFO if loud else logging.DEBUG,
            "%s: already within tolerance of %s",
            rig.rotator_id,
            wire,
        )
        return Sending(Go.DONE, wire=wire)
    plan = mo.plan_target(m, rig.motion, now)
    if plan is mo.Plan.STOP_FIRST:
        doing = "turning" if rig.spec.can_report_position else "may still be turning"
        log.info("%s: %s; stopping before the new target %s", rig.rotator_id, doing, wire)
        return Sending(Go.STOP_FIRST)
    if plan is not mo.Plan.SEND or not link.free() or targets.stream_wait(now):
        return Sending(Go.WAIT)  # rules 4 and 6
    if _needs_fresh_reading(rig, link, now):
        return Sending(Go.ASK_FIRST)
    return Sending(Go.SEND, az, el, wire)


def _reads(m: mo.Motion, rig: WorkerConfig, wire: tuple[float, float | None]) -> bool:
    """Rule 5: at rest, reading ``wire`` itself on each axis it names."""
    if not mo.at_rest(m) or m.position_deg is None:
        return False
    if mo.angle_error(m.position_deg, wire[0], rig.motion.az_wraps) > SAME_DEG:
        return False
    el = wire[1]
    return el is None or (m.el_position_deg is not None and abs(m.el_position_deg - el) <= SAME_DEG)


def _needs_fresh_reading(rig: WorkerConfig, link: Link, now: float) -> bool:
    """Rule 7."""
    if not rig.motion.can_report_position or rig.motion.direct_retarget:
        return False
    age = now - (link.last_reply_t if link.last_reply_t is not None else -1e18)
    return age > rig.moving_poll_interval_s
