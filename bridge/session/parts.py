"""What the session's parts (tracking.py, autopark.py) see and what they hand back
(docs/architecture.md, "parts decide and return"), and how the session's step runs one
(``Part``: each feature's package declares its part's, bridge/features/). Frozen data, and one
reading of a scene two parts share (rule 8).

Rules:
1. A part never holds the session: it gets a ``Scene`` (a read-only view of the moment) and
   returns a ``Proposal``; the session applies proposals in one order it shows in its step.
2. A proposal's target is already judged (pointing.py): the session only queues it.
3. A part says what wakes it (``Wake``): a step that brings none of that does not run it, and
   a part that is off (nothing tracked, no wind configured, no auto-park) is not run at all.
   A part that reads the time itself, or whose side effects count its steps, asks for every
   step while it is on.
4. The session's step runs the parts it is handed (session.py rule 17), in their order, and
   knows them by nothing but their ``Part``: what wakes one, whether it is on, its step, its
   wake-up and its reset after a bug. ``H`` is the session (session.py, above this module):
   a part's callables reach its own state there: the session's attribute for the parts it
   was written with (tracking's, the wind's...), or what the part's ``state`` made for it
   when the session was made (``RotatorSession.own[name]``), so that a new feature's part
   keeps its state without a line in the session.
5. A feature's own command (core/model.py ``FeatureCommand``, judged by runtime/rotator.py)
   reaches its part by the feature's name through ``command``, in the session's ``commands``,
   after any stop or lock of its batch, whether the part is on or not (a command may turn it
   on; one that moves is refused first while a user's target would be: rule 7); what it
   returns is applied like a step's proposal,
   except that its target is refused (on R/error, nothing queued) while the session would
   refuse a user's target (locked, offline, a storm) or the controller may not be sent it
   (the limits, a keep-out sector: pointing.py rule 8), and always when the command said it
   does not move the rotor (the judge judged it as no motion). A part that has no
   ``command``, or a name no part has, is a refusal too.
6. ``status`` gives what the part shows in ``R/status`` (a JSON-able value, None: nothing),
   read at every status the session builds and compared with the last: the part hands a new
   value when it changes (never one it changes afterwards). One that raises shows nothing and
   is reported once per kind of failure (session.py rule 19), not at every status. The
   status keeps it by the part's name (``RotatorStatus.features``), where the feature's
   StatusBlock reads it.
7. Whatever ends tracking and following ends a part's own motion too, through its ``end``
   (a stop, a lock ON, a release that clears, the link lost, a user's target, a track or
   follow start, a feature's command that moves, its own too, before its part is handed
   it, a storm that begins), and so does the lock's release: a part a command turned on never
   turns the rotor after a later stop or lock, nor over the user's later word, nor once the
   lock it was turned on under is released (a command that does not move the rotor is taken
   while locked, and may have turned on a part that moves). A command that moves reaches no
   part while the session would refuse a user's target (locked, offline, a storm). And no
   part's step target goes to a locked rotor, nor to one whose lock is not known yet
   (``lock_unknown``: runtime/kept.py rule 10; the wind's park neither, and the parts see
   ``Scene.locked`` then), nor in a storm, nor once the bridge's end began (session.py rule
   21), but the wind's own park: the session drops it, whatever the part says.
8. A hand on the front panel is a command too: tracking and following each end on one
   (``turned_by_hand``): the rotor turning with no target and no stop of the bridge's out, and
   already further from the part's last target than the part allows for (its tolerance, and
   tracking's step): not jitter, coasting or a late start. Nor the turn its start found under
   way that the readings came back to (``before``: the part's first step saw it ``carried``
   over a lost link, motion.py rule 4, and it has gone on since with no target and no stop
   out; judged at the first step the readings tell whether the rotor turns: a bridge just
   started waits for them, motion.py ``found_unjudged``): the controller finishing a turn by
   itself, its target dropped with the port (a replug mid-turn) or the bridge restarted under
   it, is nobody's hand; a turn the bridge saw begin from rest with the link up
   is a hand as ever. The start's first target stops the carried turn or re-targets it as an
   ``R/target`` would (review 50: ``track sun`` right after a replug ended at once as "turned
   by hand", and the rotor turned on to the old target; review 52: a hand already at the panel
   when tracking started was taken for such a turn, stopped and overridden).
9. A part times a turn by the speeds in effect (``Scene.speeds``: the configured ones times the
   factor of the speed setting the controller was last sent, controller.py rule 7), never by
   the configuration it was made with, which keeps the configured speeds (attack 19: a GS-232B
   set to speed 1, a quarter of full speed, left for the next pass when full speed would have
   made it, and stood 99 degrees off, still turning, when the pass rose).
10. A start's first target stops the turn it found under way (or re-targets it) as any newest
    target does; a first target the judge refuses (the limits, a keep-out sector) holds the
    rotor where it is all the same: tracking's and following's starts each propose one halt
    (``Proposal.halt``) of a turn or slew under way then (``StartHalt``), once per start, never
    for a later target's refusal (their own turn to the target before goes on). Once: the stop
    then takes its course (review 52: a SatEL's slew, stopped and waited out silently, was
    halted again at every step). Review 50 (tracking), attack 19 (a tracking start whose wait
    for the pass was refused, and a following start whose first grid was: each said so on
    R/error while a Rotor-EZ turned on some 100 degrees to the older target).
    Right after a replug mid-turn the turn carried over the lost link (motion.py rule 4) is
    not seen yet at the start's refusal: the first reading back shows where the rotor is, not
    whether it moves, and the refusals are not judged again (following's grid, tracking's
    wait). So the halt is owed (``StartHalt.owed``) and proposed at the step the next reading
    shows that turn move; readings that show the rotor still instead drop it, each axis judged
    by its own speed (``Motion.lost_still``, motion.py rule 4: every axis still for its own
    time, the turn came to rest while the port was out; or a move only on axes already shown
    still, a turn begun since, once a later reading confirms it, reading on from it the way it
    moved or that move lasting the axis's own time: one garbled reading is none, review 93,
    nor the same garble read twice, review 95; the session tells the motion the halt is
    owed while the part is on: feature_commands.py rule 7), so a hand at the panel after
    that is never halted for it
    (review 73: d609655e owed the halt until rule 2's rest, a second or more, and stopped a
    hand begun in that time; review 89: so did the slowest axis's time for every axis, a hand
    at a GS-232B's azimuth a second after a replug). A bridge just started
    does not know whether the box is turning either (a restart mid-turn: the controller
    finishing the turn the bridge before it sent): a start refused before its readings have
    told (motion.py rule 4, ``found_unjudged``: a move, or none on each axis for its own
    time, not rule 2's ``settle_s``, asked at the moving rate) owes the halt the same way,
    proposed if they show a move, dropped if they show none (review 89: dropped at rule 2's
    rest, a slow elevation turned on 60 degrees), so a hand begun after that is never halted
    for it (review 73's hand on a
    Rot2Prog, whose second reading came a whole 6 s idle poll on, stays a hand). Review 84:
    after a restart mid-turn a refused follow or track start halted nothing, and the Rotor-EZ
    turned on some 100 degrees to the old target. On a controller with no readings (a
    DCU-1) nothing ever shows the turn: the one under way when the port went, the bridge's
    own, or one the run before kept in flight in the state file (a restart mid-turn; review
    89: the DCU-1 turned on 95 degrees under "refused"; runtime/kept.py rule 13), is taken as
    going on for the time assumed from the connect (motion.py rule 6, ``may_finish_blind``)
    and halted at the refusal itself, as it would be without the replug. Not a start with
    none kept: nothing tells the old bridge's turn from a hand's at the panel, and review 93
    found the operator's own turn stopped by a refused start after every bridge start.
    Review 70: a start right after a replug mid-turn, refused, halted nothing, and the rotor
    turned on some 95 degrees to the target from before the unplug (review 73: a DCU-1's, 90
    degrees, no stop frame).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from enum import Flag, auto
from typing import Generic, NamedTuple, TypeVar

from bridge.core.errors import Refused
from bridge.core.model import FeatureCommand, Source, Target
from bridge.pointing import Pointing, angle_between
from bridge.session import motion as mo
from bridge.session.actions import Report

H = TypeVar("H")  # the session a part is run by (rule 4)


class Wake(Flag):
    """What makes a part worth running in a step (rule 3)."""

    STEP = auto()  # every step while it is on: it reads the time (the sky, a quiet spell)
    MOTION = auto()  # the motion changed: a reading taken, the motion machine's clock, a write


class Speeds(NamedTuple):
    """The rotor's speeds in effect, degrees a second (rule 9)."""

    az_deg_s: float
    el_deg_s: float


class Scene(NamedTuple):
    """The session as a part may see it at ``now`` (a tuple: read-only, cheap at every step)."""

    now: float
    motion: mo.Motion
    pending: Target | None  # the target waiting to go to the controller (targets.py)
    locked: bool  # or its lock not known yet (rule 7: runtime/kept.py rule 10)
    parked: bool  # the last status said so (status.py rule 4)
    slewing: bool  # a silent controller's slew is under way (slew.py)
    wall_offset_s: float  # wall clock (unix seconds) = now + this
    speeds: Speeds  # rule 9: the configuration in effect's (controller.py ``cfg``)
    parking: bool = False  # the last target sent was auto-park's (autopark.py rule 4)
    # a rotator of two boxes' judge of a park of the bridge's own as the rotator's whole park
    # (runtime/composite.py rule 7: Refused if any axis's would be, Unjudged while it cannot be
    # judged yet); None: one controller
    whole: Callable[[Target], None] | None = None


class Unjudged(Exception):
    """``Scene.whole``: the rotator's whole park cannot be judged yet (runtime/composite.py
    rule 7: its azimuth box does not answer, or has taken no reading since it answers again):
    neither taken nor refused, it waits."""


class RefusedHere(Refused):
    """``Scene.whole``: the rotator's whole storm park refused on this box while the other box
    has its own axis parked already (runtime/composite.py rule 7: parked alone while this box
    did not answer): this box's axis stands where the storm found it, the other's at its park
    (review 65: the azimuth's refusal said 'nothing parked' beside a dish at its stow)."""


@dataclass(frozen=True)
class Proposal:
    """What a part wants done; every field is optional."""

    target: Target | None = None  # put it as the pending target
    error: Report | None = None  # hand this error event out
    ended: str | None = None  # end tracking and following for this reason (their targets dropped)
    busy: bool = False  # activity: auto-park's quiet spell starts again (autopark.py rule 1)
    halt: bool = False  # stop the turn under way (following: a transmission began, follow.py;
    # the wind: its storm's park refused, wind.py rule 5)
    drop: Source | None = None  # drop the waiting target if this source put it (autopark.py
    # rule 3: a hand on the panel before the park went)


NOTHING = Proposal()


def turning_alone(m: mo.Motion) -> bool:
    """Rule 8: turning with no target and no stop of the bridge's out."""
    return m.state is mo.MOVING and m.target_deg is None and m.stop_sent_t is None


class Before:
    """Rule 8: whether the turn with no target a part's start found under way, carried over a
    lost link (motion.py rule 4), goes on (not a hand): judged at the part's first step after
    its start, and kept while that turn does."""

    def __init__(self) -> None:
        self._seen: bool | None = None  # None: no step since the start

    def start(self) -> None:
        self._seen = None

    def look(self, scene: Scene) -> bool:
        """The turn under way is the one the start found (at every step, before judging)."""
        m = scene.motion
        if self._seen is None and mo.found_unjudged(m):  # a restart's readings not yet told
            return False  # whether the rotor turns: judged at the first step they do
        alone = turning_alone(m) and m.carried  # (not a turn seen begin with the link up)
        self._seen = alone if self._seen is None else self._seen and alone
        return self._seen


def turning(scene: Scene) -> bool:
    """Rule 10: a turn or a slew under way with no stop of the bridge's out (one whose port was
    out, not yet seen to move, may have come to rest: motion.py rule 4, no stop to it); on a
    controller with no readings (a DCU-1), its own target out with no stop since, or a turn
    under way when its port was lost that it may be finishing by itself, within the assumed
    travel time (motion.py rule 6: it may be turning)."""
    m = scene.motion
    moving = m.state is mo.MOVING and m.stop_sent_t is None and not m.lost_turning
    now = scene.now
    return moving or scene.slewing or mo.may_turn_blind(m, now) or mo.may_finish_blind(m, now)


def _unseen(m: mo.Motion) -> bool:
    """Rule 10: a turn carried over a lost link (motion.py rule 4), or one a bridge just
    started may have found (a restart mid-turn), that no reading back has shown moving nor
    still yet, nothing of the bridge's sent into it."""
    return (
        _not_seen_yet(m)
        and m.carried
        and not m.lost_still
        and m.target_deg is None
        and m.stop_sent_t is None
    )


def _not_seen_yet(m: mo.Motion) -> bool:
    """Rule 10: the readings back have not shown yet whether the rotor turns: a lost turn not
    seen move (``lost_turning``), or a restart's first readings (``found_unjudged``)."""
    return (m.state is mo.MOVING and m.lost_turning) or mo.found_unjudged(m)


class StartHalt:
    """Rule 10: the one halt a start proposes when its first target is refused; and, while
    that refusal stands, the one owed to a turn carried over a lost link (or found by a bridge
    just started) that no reading back has shown yet, proposed if the next readings show it
    move (``owed``)."""

    def __init__(self) -> None:
        self._done = False
        self._owed = False  # the first refused with a carried turn not yet seen

    def start(self) -> None:
        self._done = self._owed = False

    @property
    def owing(self) -> bool:
        """The halt is owed (feature_commands.py rule 7: motion.py rule 4 judges that turn by
        a move only on axes decided still once a later reading confirms it, not by one)."""
        return self._owed

    def wanted(self, scene: Scene, first: bool) -> bool:
        """Whether the refusal of a target (``first``: the start's first) halts the turn under
        way: the first's, once per start, while a turn or slew goes on. A turn carried over a
        lost link not yet seen is owed the halt instead (``owed``)."""
        halt = first and not self._done and turning(scene)
        self._done = self._done or halt
        self._owed = first and not self._done and _unseen(scene.motion)
        return halt

    def owed(self, scene: Scene, first: bool) -> bool:
        """At every step after the refusal (the part's own refusals are not judged again:
        following's grid, tracking's wait): whether the carried turn is seen now, moving with
        no stop of the bridge's out, before any reading back showed the rotor still, and is
        halted, once; ``first``: no target of the part's taken since (one that is stops or
        re-targets it). Dropped at the first reading that shows the rotor still, or once the
        turn is known to be none, so a hand's turn begun later is never halted for it."""
        if not self._owed:
            return False
        m = scene.motion
        if not first or self._done or m.lost_still or not m.carried or m.target_deg is not None:
            self._owed = False
            return False
        if m.lost_turning or mo.found_unjudged(m):
            return False  # (not seen yet: the next reading says)
        self._owed, self._done = False, True
        return turning(scene)


def turned_by_hand(
    scene: Scene, aim: Pointing, last_deg: float | None, far_deg: float, before: bool = False
) -> bool:
    """Rule 8: turning with no target and no stop of the bridge's out, and more than
    ``far_deg`` from ``last_deg`` (the part's last target, a true bearing): a hand on the front
    panel. With nothing to measure by (no last target, no reading), any such turn; but never
    the turn the part's start found under way (``before``: ``Before.look``)."""
    m = scene.motion
    if before or not turning_alone(m):
        return False
    if last_deg is None or m.position_deg is None:
        return True
    return angle_between(aim.true_of(m.position_deg), last_deg) > far_deg


@dataclass(frozen=True)
class Part(Generic[H]):
    """One of the session's parts as its step runs it (rule 4; session.py rules 14 and 17):
    looked up on the session at every step (a reset part is a new object)."""

    name: str  # as the error event of its failure names it (session.py rule 14)
    wakes: Wake  # rule 3
    deciding: bool  # True: runs while the controller answers, before the pending target goes;
    # False: after the poll, whatever the link (what it measures rides along in the status)
    on: Callable[[H], bool]  # off: not run, and no wake-up of its own
    step: Callable[[H, Scene], Proposal | None]
    reset: Callable[[H, float], None]  # after a bug: its state made again (session.py rule 14)
    wakeup: Callable[[H, float], float | None] | None = None  # when it wants to be woken
    state: Callable[[H], object] | None = None  # rule 4: its own state, made with the session
    command: Callable[[H, FeatureCommand, float], Proposal | None] | None = None  # rule 5
    status: Callable[[H], object] | None = None  # rule 6: its block's value, None: none
    end: Callable[[H, str], None] | None = None  # rule 7: its motion ends, for this reason
