"""Parking by itself after a quiet spell (``park_after_idle_s``; a windy remote site). Pure: it
owns the quiet spell; each step gets a read-only ``Scene`` (parts.py) and returns a ``Proposal``
(the park target, or the error of a park the judge refuses) that the session applies.

Rules:
1. The quiet spell counts from the last command (a target, a stop or the lock switched either
   way), from the last moment the rotor was seen turning (a hand on the front panel), from
   start-up, from the controller answering again, from the end of a storm (session.py
   ``_storm``) and from the lock becoming known (runtime/kept.py rule 10: the broker's first
   look said no lock ON, after a start whose state file did not say it): a rotor never parks
   the moment someone unlocks it, switches its controller back on, a calm reading ends a
   storm (wind.py rule 2; an attack pass: the spell, long over in the storm, parked the rotor
   the instant the storm ended, moved by a reading) or a broker back from a long absence
   says there is no lock (attack 14: the spell ran out while the lock was not known, and the
   rotor turned the instant the look came).
2. Parking happens only when everything else would allow a target: the controller answering,
   the lock off and known (``Scene.locked`` is set while it is not known yet: runtime/kept.py
   rule 10), the rotor idle, no target waiting, and not already at the park position.
3. The park is an ordinary target (source ``auto-park``): any command meanwhile replaces or
   stops it, and it counts as activity itself, so a park that cannot finish (a stall) is
   tried again only after another quiet spell. A park still waiting to go out when the rotor
   is seen turning (a hand on the front panel that the readings had not shown yet) is dropped
   (``Proposal.drop``), never sent: the bridge does not stop a hand to park (a Rotor-EZ's
   target goes only to a rotor at rest, so the park's stop-first wrote a stop to the hand's
   turn, told nowhere: a loaded CI run, and a hand that began between an idle poll and the
   spell's end). The next spell counts from the hand's last move (rule 1).
4. A rotator of two boxes (runtime/composite.py rule 7) has one quiet spell: each box's
   auto-park is told of the other's activity (``since``, ``told``), but not of its park nor
   of its park's turn (rule 3's, kept apart), so both axes park together once the rotator
   was left alone. Told of the other's activity after its own park was proposed (a hand on
   the other box's panel, seen only by the reading asked for that box's park), its park is
   dropped if still waiting, else its turn is halted (``Scene.parking``: the last target sent
   was the park): a GS-232B sends its park at once, and the elevation went on to its stow
   under a hand on the azimuth, which parked a whole spell later (one axis at a time).
5. On a rotator of two boxes each box's park is judged as the rotator's whole park first
   (``Scene.whole``: the rotator's judge, as ``R/park``'s, and each box's own, runtime/
   composite.py rule 7): all axes or none. Judged by each box alone, the azimuth box refused a
   park whose turn passed north while the elevation box took it and lowered the dish to its
   stow, under an R/error that said the park was refused (an attack pass). Both boxes then say
   the same refusal, said once (composite.py rule 9). While the azimuth box has no reading of
   its own since it answers again (``Unjudged``) it does not park yet, and that is no park
   tried (rule 3): the next step judges it again (review 63: it counted as one, and the next
   try came a whole quiet spell later).
"""

from __future__ import annotations

import logging
import math

from bridge.core.errors import Refused
from bridge.core.model import ErrorKind, MotionState, Source, Target
from bridge.session import motion as mo
from bridge.session.actions import Report
from bridge.session.config import WorkerConfig
from bridge.session.parts import NOTHING, Proposal, Scene, Unjudged

log = logging.getLogger(__name__)


class AutoPark:
    def __init__(self, rig: WorkerConfig) -> None:
        park = rig.aim.park
        self._rig = rig
        self._after_s = rig.park_after_idle_s if park is not None else 0.0
        self._park = park
        self._since = -math.inf  # rule 1: the last activity
        self._shared = -math.inf  # rule 4: the last activity but its own park's turn
        self._told = -math.inf  # rule 4: the other box's last activity it was told of
        self._parked_t = -math.inf  # rule 3: its own last park (rule 4: not shared)

    @property
    def on(self) -> bool:
        """Whether it ever parks (a park position and a quiet time configured): off, its step
        changes nothing and the session does not run it (parts.py rule 3)."""
        return self._after_s > 0.0

    @property
    def since(self) -> float:
        """Rule 4: when the last activity was (not its own park, nor its turn)."""
        return self._shared

    def activity(self, now: float) -> None:
        """Rule 1: the quiet spell starts again."""
        self._since = self._shared = now

    def told(self, t: float) -> None:
        """Rule 4: the other box's latest activity (a command, its rotor seen turning)."""
        self._told = self._shared = t
        self._since = max(self._since, t)  # (its own park's turn may be newer)

    def deadline(self) -> float | None:
        """When parking is due (None: never)."""
        if self._after_s <= 0.0 or not math.isfinite(self._since):
            return None
        return max(self._since, self._parked_t) + self._after_s

    def wakeup(self, now: float) -> float | None:
        """When the session must look again: the deadline while it lies ahead. Once it has
        passed without parking (not ready: locked, turning), the session's own polls and
        inputs bring it back; waking at a past time would spin."""
        deadline = self.deadline()
        return deadline if deadline is not None and deadline > now else None

    def step(self, scene: Scene) -> Proposal:
        """Run by the session with its other rules, while the controller answers."""
        m, now, parking = scene.motion, scene.now, scene.parking
        pending = scene.pending
        mine = pending is not None and pending.source is Source.AUTO_PARK
        if self._told > self._parked_t and (mine or parking and _aiming(m)):  # rule 4
            log.info(
                "%s: the other box was busy before the park ended: park stopped",
                self._rig.rotator_id,
            )
            return Proposal(halt=not mine, drop=Source.AUTO_PARK)
        if m.state is MotionState.MOVING:
            if parking and _aiming(m):  # rule 3: its own park's turn, activity here alone
                self._since = now
                return NOTHING
            self.activity(now)  # rule 1: someone is turning it
            if mine:  # rule 3
                log.info(
                    "%s: turned by hand before the park went: park dropped", self._rig.rotator_id
                )
                return Proposal(drop=Source.AUTO_PARK)
            return NOTHING
        deadline = self.deadline()
        if deadline is None or now < deadline or self._park is None:
            return NOTHING
        ready = mo.at_rest(m) and scene.pending is None  # rule 2 (no brake: motion rule 4)
        if not ready or scene.locked or scene.parked:
            return NOTHING
        before, self._parked_t = self._parked_t, now  # rule 3
        park = Target(self._park[0], self._park[1], Source.AUTO_PARK, park=True)
        try:
            if scene.whole is not None:  # rule 5: all axes or none
                scene.whole(park)
            judged = self._rig.aim.judge(park, m.position_deg)
        except Unjudged:  # rule 5: the azimuth box's reading not fresh yet: not now, and no
            self._parked_t = before  # park tried (the next step judges it again, not the
            return NOTHING  # next quiet spell: review 63)
        except Refused as exc:
            return Proposal(
                error=Report(ErrorKind.REFUSED, f"auto-park refused: {exc.message}", "park")
            )
        log.info("%s: parking (no command for %g s)", self._rig.rotator_id, self._after_s)
        return Proposal(target=judged)


def _aiming(m: mo.Motion) -> bool:
    """A target of the bridge's is still being turned to (a stop or its arrival ends it)."""
    return m.target_deg is not None or m.el_target_deg is not None
