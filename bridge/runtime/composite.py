"""A composite rotator: its azimuth turned by one controller, its elevation by another, on two
serial lines (settings/rotator.py rule 4, protocols/axes.py). One judge, one mailbox, one
status, one stop for both.

The rotator's judge (rotator.py) is the one every rotator has: the lock, the wind, the lease,
the limits and the link are judged once, against the merged status, and what it accepts goes
into the rotator's one mailbox. Each box is then driven by a session of its own (session.py,
every rule of a single controller: the stop re-sent, the stop owed while a port is closed, the
polls, the motion machine), served by a worker of its own (worker.py: its port, its back-off).
``Composition`` (sans-IO) splits each batch the mailbox hands out between the two sessions and
merges their statuses into the rotator's; ``CompositeWorker`` is the serial-lines thread's one
worker for the rotator, serving both boxes' workers.

Rules:
1. A stop, a lock word, a hold and its release, options, notes, the lease, the wind, WSJT-X's
   news, the bridge's end and track and follow commands go to both sessions, in one batch
   each (a feature's own command goes to one: rule 6), in the same serve: one STOP writes a
   stop frame on both lines before either status goes to the listeners, and each session
   keeps its own stop rules (a stop owed to an unplugged box is its first frame on replug).
   Both sessions are told the wall clock (worker.py ``tell_wall``) before either is handed
   its batch (review 109: told only by its box's own serve, after the batch, a session judged
   the first wind reading after a suspend by the clock from before it, session/wind.py rule 2,
   and a two-box rotator's storm ended with ten minutes of calm never heard).
2. A target is split: its azimuth to the azimuth box, its elevation to the elevation box; an
   axis it leaves out is no target for that box (but a park's: it goes to both boxes, the
   elevation box holding its axis where it reads, session/targets.py rule 9, as in a storm;
   an attack pass: R/park with no ``park_el_deg`` left the elevation box turning on from 10 to
   the 40 of the 100/40 it interrupted, and the rotator never said parked), but ends there
   what a target ends (tracking, following, a part's motion: ``Batch.ends``), as in the box
   it goes to: the operator's
   bearing is the last word on the whole rotator (an attack pass: an azimuth after a track
   command ended tracking in the azimuth box alone, and the elevation box went on tracking
   by itself, the status saying nothing was tracked).
3. The status is the azimuth box's, with the elevation box's elevation and elevation target:
   connected and available only when both are (the judge then refuses targets and track
   commands: the safe side), moving when either is read turning, else offline when either
   is; the last error is the newer of the two. (An attack pass: the azimuth box read turning
   on while the elevation box was unplugged was shown offline and not moving, and a group
   with that rotator said idle.) Its wind is the azimuth box's, whose storm's park is seen
   reached (session/wind.py rule 7, kept over a restart by runtime/kept.py rule 4) only when
   both boxes' parks were: otherwise a restart in the storm parks both again; refused, or
   waiting, or off the park sent, when either box's park is, in that box's words
   (session/wind.py rules 5, 9 and 10: a park waiting in one box, or one box's rotor off its
   park, is no park said done for the rotator). Its version is
   its boxes' joined, azimuth first (``1.4S / SatEL``), each box whose model reports one
   (protocols/axes.py rule 4), and none until every such box has said its own, the rotator
   saying meanwhile the pair kept from the last run, if any (runtime/kept.py rule 11). One
   box's alone was read as the pair's (``SatEL``, the elevation box's, shown as if it were
   the azimuth's), and at each restart the kept pair gave way to the first box's alone and
   came back when the other answered, each time a round of Home Assistant discovery and a
   state-file write (a review).
4. Tracking and following run in both sessions (each aims its own axis, never flipped:
   session/tracking.py rule 4); when one ends (an
   unplugged box, a stop, the horizon) the other is ended too, and the status says why the
   first one ended. One that runs in a box while the other does not answer (begun there
   after the judge took the command while the other box went offline, which refused it) is
   ended at once ("rotator offline"): no axis tracks or follows alone.
5. Each box's worker is guarded on its own: a bug in serving one closes and reopens that line
   only, and the other line goes on.
6. A feature's own command (core/model.py ``FeatureCommand``, session/parts.py rule 5) is one
   word to the rotator: it goes to the azimuth box's session alone, whose status (the
   feature's block in it) is the rotator's, and its part acts once. Given to both, its part
   acted twice (its state, its errors on R/error) and aimed the elevation box at an azimuth
   it never turns. What it proposes is that box's to carry: a target with an elevation is
   refused there on R/error (the box turns no elevation) and neither box turns, never the
   elevation box alone. A halt that part proposes in the azimuth box (as it takes the
   command, or in any later step) is the elevation box's too, in the same serve (``Followed``):
   the turn under way stopped, nothing ended, as the part's halt does in its own box.
   Tracking's and following's parts run in both boxes (rule 4) and halt each on their own.
7. Auto-park's quiet spell is the rotator's (session/autopark.py rule 4): a target to one axis
   is activity in the other box's session too (``Batch.activity``), and before each box is
   served it is told of the other's latest activity (its rotor seen turning, a hand on its
   front panel: ``share_quiet``; a park under way stopped for it: autopark.py rule 4), and a
   box that does not answer is activity at every serve
   (the rotator is offline: no box parks its axis alone, and the spell starts again when both
   answer, as autopark.py rule 1 has it for one controller); each box then parks its own axis,
   the azimuth box the park's azimuth alone (app.py ``axis_configs``, as the wind's park),
   together once the rotator was left alone that long. That park, and the storm's (each box
   parks its own axis too), is judged as the rotator's whole park (``judged_whole``, the
   parts' ``Scene.whole``: the rotator's judge against the azimuth box's reading, as
   ``R/park`` is judged, then each box's own), all axes or none: judged by each box alone, the
   azimuth box (a Rotor-EZ, its stop at south) refused a park whose turn passed north while
   the elevation box (a GS-232B, its azimuth never turned) took it and lowered the dish from
   40 to its stow, under an R/error saying the park was refused (an attack pass). Both boxes
   then refuse it in the same words, said once (rule 9). All axes or none holds while both
   boxes answer. While the azimuth box does not answer, its reading is the one from before
   its offline, which judges nothing (review 60: the elevation box refused the whole storm
   park from the azimuth box's bearing before its offline, for the whole storm, the azimuth
   rotor turned by hand meanwhile to where the park was allowed): the storm's park is then
   the elevation box's own axis's, judged by that box alone, and it lowers the dish (the safe
   side, as a storm begun with the elevation box out parks the azimuth alone; review 63:
   judged ``Unjudged``, the dish stayed raised for the whole storm), while the azimuth box's
   park stays owed until it answers (session/wind.py rule 7); auto-park's waits (no box parks
   its axis alone while the rotator is offline: ``share_quiet``). While the azimuth box
   answers again but has taken no reading since (the first back doubted), the whole park is
   not judged at all (``Unjudged``), neither taken nor refused: it stays owed in each box
   (session/wind.py rule 5), and is judged whole at the first reading.
8. No axis turns alone to a target while the rotator is offline: when a box stops answering, a
   target still waiting in the other (held back by a Rotor-EZ's brake delay, a stop first) is
   dropped there, as a single controller's is when its line goes (said on R/error), and a target
   handed out while either box does not answer is refused in both (a review: the azimuth box's
   target, held back by its brake delay, went out after the elevation box was unplugged, and the
   azimuth turned alone under an ``offline`` status). A turn to a target already on its way in
   the box that answers is stopped there: the rotator's turn is no longer watched whole, and a
   single controller gone silent mid-turn is stopped on both axes (session/controller.py rule 2;
   a review: the azimuth box ran on alone to the target the bridge had dropped, under an
   ``offline`` status). The box whose port went mid-turn (a turn or a target out when it closed)
   owes its stop, its first frame when it is back: a single controller's turn goes on after a
   replug (session/controller.py rule 13), but here the other axis was stopped (an attack pass:
   the elevation box, replugged, turned on alone to its target, 60/80 where 300/80 was asked);
   both boxes whose ports went together (one USB hub) owe theirs, and the turn is sent again by
   hand. The box's port error is its port's words alone (``WorkerConfig.box``): a single
   controller's says its turn is left to it (session/controller.py rule 13), which here is
   stopped. A box that says it restarted mid-turn (session/controller.py rule 12: a power-on
   byte; rule 14: a SatEL's clock gone back), or gave its turn up (rule 12: a Prosistel or
   RC2800 that says its motor is off short of the target), abandons the rotator's turn as a
   whole: the other box's turn under way is stopped and its target waiting dropped (session.py
   ``abandon``), unsaid, the restart's one error saying it was not resumed (a review: the
   azimuth box's turn was said abandoned while the elevation box turned on to the user's
   elevation, the antenna left half moved). So does a box that drops its turn with an error of
   its own (controller.py ``dropped_turns``: a stall, which is all an RT-21's restart shows, a
   limit passed, a turn away or back, a pass, a refusal; an attack pass: the elevation turned on
   alone to the 80 of a target said dropped), as soon as the other box's rotor moves: one that
   stands (not moved since its target went out, or for ``settle_s``: session.py ``stands``) is
   left to say its own stall or refusal, so that two iced rotors say two stalls, and is
   abandoned if it moves after all (a SatEL in its slew, which reports nothing, never stands: a
   review); motion sent to it meanwhile (a target's half, a track, a follow) is newer than the
   turn dropped, and ends the wait, and nothing else does (``Siblings``; a review: a wind
   reading ended it). The storm's park goes on there, under way or still waiting (session.py
   ``_storm_park``, ``_storm_park_waiting``; an attack pass: a Rotor-EZ azimuth box's park, held
   back by its brake delay, was dropped and never sent again): each box parks its own axis, as
   one does alone in a storm begun while the other did not answer, and nobody can send it again
   in the storm (a review of 83a398d: the azimuth box's park, stopped when the elevation box
   fell silent for 4 s, was never tried again, the antenna left 140 degrees short of it for the
   whole storm). A STOP still reaches the box that answers. A target one box drops before it
   went out or moved the rotor (session.py rule 23: a lease claimed by someone else; wind.py
   rule 1: a storm begun, or one that refuses the try more of a frame lost on the line,
   controller.py rule 11: a cold review, the elevation turned on to 40 for a 300/40 whose
   azimuth the storm did not send again) is the rotator's whole target dropped: the other box
   drops its half too (session.py ``forsake``, unsaid), if it is that sender's (``sibling``: a
   half another sender sent since, the lease holder's own, goes on; a cold review, DL1ABC's
   elevation 10, sent before their claim, was dropped with G4XYZ's azimuth 300 and the elevation
   turned on to G4XYZ's 40), and an axis a sender's target leaves out is that sender's half
   before while its box waits for it or turns to it, as one controller takes one sender's two
   halves for one target (``aimed``, core/model.py ``combine``; a cold review: G4XYZ's 310 sent
   alone after 300/40, dropped by a claim, left the elevation turning on to 40). A half a SatEL
   box put back after its slew's late report (session/ slew.py rule 4, session/targets.py rule
   3) is that half still (a cold review: the put back was a new target the drop did not know,
   and went out: the elevation turned on to 40 for the claim's dropped 300/40): waiting, it is
   cleared; sent already (a Rotor-EZ azimuth box waits out its brake, a GS-232B elevation box
   sends its half at once), its turn is stopped, unless a newer target there names its axis (a
   storm's park with an elevation; one without holds that axis where it reads,
   session/targets.py rule 9: it kept that axis's target, the dropped half's, when the storm
   began late in the azimuth box's brake, and the elevation turned on to 40). A claim dropped
   the azimuth's half and the elevation turned on to the other's, and so did a storm whose park
   named no elevation: the antenna left half moved for a target nobody stood for (a closing
   note). The elevation box's half sent before the drop has moved it meanwhile; the stop ends
   that. A stamped sender's two halves so expire as one: a half waiting in its box when a hold
   ends there (session.py rule 13) is judged by the whole target's expiry, the sooner of its
   two halves' (``expires_as``, each session told by ``joined``), so both boxes drop it at
   that hold's end, in the same serve, before either sends its half, and say it once (rule
   9); a cold review: each half kept its own, the azimuth box dropped its half at the hold's
   end past its expiry, and the elevation box turned alone to the 40 of a target one
   controller drops whole.
9. An event both boxes hand out, word for word (the same kind, message and command, within
   TWIN_S of each other), is the rotator's one event: said once, by the box that said it
   first. Both sessions take the same commands, the wind and the TLE file's answers (rule 1),
   so each refused the same track command and said the same silence of the wind topic (an
   attack pass: ``R/track NOSUCH`` was refused twice on R/error). What names its box (a
   port's fault) or its axis (a stall, a refusal: session/stops.py rule 4) is no twin, and one box's
   word is matched once: the same refusal again later (a command sent again) is said again.
   A box's word that it dropped its half of the rotator's last target (``target dropped...``,
   or that a try more of it is not sent, ``target not sent again...``, ``target did not move
   the rotor...``: session.py ``DROPS``, with that half as its command) names the whole
   target, as it was sent (``target az 300 el 40``, ``whole``): the two boxes' drops of one
   target are then twins, said once (a claim or a storm that found both halves waiting said
   the drop twice, ``target az 300`` then ``target el 40``), and one box's drop names what
   the user lost (a cold review: a claim's or a storm's drop of the azimuth's try more, the
   elevation stopped for it, named ``target az 300`` alone). So are the two boxes' audit
   lines of one park of the bridge's own (auto-park's, the storm's: session.py rule 25).
10. A turn of the bridge's own (auto-park's park, the storm's: session.py ``Order``) takes its
   place in the order of commands from the rotator's mailbox, whose counter the rotator's
   commands advance (mailbox.py rule 10a), not from the box's own mailbox, which no command
   reaches (review 86: each box's park took place 1 from it however many commands came
   before, and a remote's old held STOP, read as asked against the park, went again and
   stopped it short: a storm's park so left the antenna up in the wind; remote.py rule 10).
   Both boxes' parks of one turn are the rotator's one turn and take one place (mailbox.py
   rule 10b's ``own_place``, the turn named by the session: the storm's park by the newest
   storm either box saw begin, ``rotators_turn``; auto-park's by its moment, the quiet spell
   shared: rule 7): each drawing its own, the status showed one box's place, then the
   other's, one park at two places (review 86), and so did one storm's park whose second box
   began it in a later serve, plugged back mid-storm, or a box's park owed again once the
   box answers (wind.py rule 7; review 91: places 2 and 3, no command between). A motion
   command or a halt put since, or a new storm, makes a park begun after it a turn of its
   own, at a later place. A storm's park a start sends again keeps the place the run before
   gave it (``storm_place``, kept with the storm: runtime/kept.py rule 4), both boxes' halves
   at that one place (review 96). The merged order is the newest of each (rule 3), so it
   never goes back.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable, Iterator
from dataclasses import replace
from functools import partial
from typing import Any

from bridge.core.errors import Refused
from bridge.core.model import (
    ErrorEvent,
    ErrorKind,
    FeatureCommand,
    MotionState,
    Order,
    RotatorStatus,
    Source,
    Target,
    combine,
    describe_command,
    kept_if_same,
)
from bridge.protocols.axes import Axis
from bridge.runtime.port import PortOpener, open_port
from bridge.runtime.worker import Worker
from bridge.session import status as st
from bridge.session.actions import Action, Audit, Write
from bridge.session.config import WorkerConfig
from bridge.session.follow import Follow
from bridge.session.mailbox import Batch, Mailbox
from bridge.session.parts import RefusedHere, Unjudged
from bridge.session.session import DROPS, OwnTurn, RotatorSession
from bridge.session.tracking import Track
from bridge.sky.worker import SkyWorker

__all__ = [
    "CompositeWorker",
    "Composition",
    "joined",
    "judged_whole",
    "merge",
    "rotators_turn",
    "share_quiet",
    "split",
]

log = logging.getLogger(__name__)
AXES = (Axis.AZIMUTH, Axis.ELEVATION)
TWIN_S = 5.0  # rule 9: two boxes' same event this close is one
TWINS_KEPT = 16  # rule 9: a box's events awaiting their twin, at most
OFFLINE = "rotator offline"  # rule 4: why tracking begun in one box alone ended there


def split(batch: Batch) -> dict[Axis, Batch]:
    """Rules 1, 2 and 6: the batch each box's session gets."""
    target = batch.target
    az = el = None
    if target is not None and target.az_deg is not None:
        az = replace(target, el_deg=None)
    if target is not None and target.el_deg is not None:
        el = replace(target, az_deg=None, true_az_deg=None, within_deg=None)
    elif target is not None and target.park:  # rule 2: a park's is one (targets.py rule 9)
        el = target  # (the shape of the storm's park in that box: app.py ``axis_configs``)
    # rule 6: a feature's own commands (and the halts marked among them) to the azimuth box
    moved = target is not None  # rule 7: the quiet spell starts again in both
    # rule 2: a target leaving an axis out ends in that box what it ends in the other
    ends = None if target is None else f"{target.source.value} target"
    alone = replace(
        batch, target=el, feature_commands=[], activity=moved, ends=None if el else ends
    )
    return {
        Axis.AZIMUTH: replace(batch, target=az, activity=moved, ends=None if az else ends),
        Axis.ELEVATION: alone,
    }


def joined(composition: Composition, sessions: dict[Axis, RotatorSession]) -> None:
    """Rule 8: each box's session told what a half waiting there expires as (session.py rule
    13: ``Composition.expires_as``)."""
    for axis, session in sessions.items():
        session.expires_as = partial(composition.expires_as, axis)


def judged_whole(cfg: WorkerConfig, sessions: dict[Axis, RotatorSession]) -> None:
    """Rule 7: each box's session told how a park of the bridge's own (auto-park's, the
    storm's) is judged whole: Refused if the rotator's judge (``cfg``'s, as ``R/park``'s,
    against the azimuth box's reading) or either box's own refuses that park; Unjudged while
    the azimuth box has taken no reading since it answers again, and while it does not answer
    (auto-park's); the storm's park with the azimuth box offline is the elevation box's alone,
    judged there by its own judge (the part's, after this)."""
    azimuth = sessions[Axis.AZIMUTH]

    def whole(park: Target) -> None:
        ctl = azimuth.controller
        if ctl.link is None or not ctl.answering:  # the azimuth box offline:
            if park.source is Source.WIND:  # the storm's park is the elevation box's own,
                return  # judged by that box alone (review 63: the dish stayed up all storm)
            raise Unjudged(park)  # (auto-park's waits for the rotator: ``share_quiet``)
        if ctl.motion.state is MotionState.OFFLINE:  # back, no reading of its own since:
            raise Unjudged(park)  # the one it has is from before its offline, a stale one
        rotator = _park_as(cfg, park)
        if rotator is not None:
            cfg.aim.judge(rotator, azimuth.controller.motion.position_deg)
        for session in sessions.values():
            own = _park_as(session.cfg, park)
            if own is not None:
                session.cfg.aim.judge(own, session.controller.motion.position_deg)

    def judge(mine: RotatorSession, park: Target) -> None:
        try:
            whole(park)
        except Refused as exc:  # (RefusedHere: the other box's axis parked alone already)
            others = [s for s in sessions.values() if s is not mine]
            if park.source is Source.WIND and any(s.wind.parked for s in others):
                raise RefusedHere(exc.code, exc.message) from exc
            raise

    for session in sessions.values():
        session.judge_whole = partial(judge, session)


def _park_as(cfg: WorkerConfig, park: Target) -> Target | None:
    """``park`` (a box's auto-park or storm's park) as ``cfg``'s park of the same kind."""
    if park.source is Source.WIND:
        where = None if cfg.wind is None else cfg.wind.park
    else:
        where = cfg.aim.park
    return None if where is None else replace(park, az_deg=where[0], el_deg=where[1])


def share_quiet(sessions: list[RotatorSession], now: float) -> None:
    """Rule 7: each box's auto-park told of the latest activity of either (a box that does not
    answer: now)."""
    latest = max(s.autopark.since for s in sessions)
    if not all(s.controller.link is not None and s.controller.answering for s in sessions):
        latest = now
    for s in sessions:
        if s.autopark.since < latest:
            s.autopark.told(latest)


def rotators_turn(turn: OwnTurn, sessions: list[RotatorSession]) -> OwnTurn:
    """Rule 10: a box's own turn as the rotator's: a storm's park is the park of the newest
    storm either box saw begin. Both boxes take every reading and judge a storm's begin and
    end at it, answering or not (session/wind.py rule 2, review 96: a box silent through a
    calm kept the storm it had, f96b859a named its park by the other's storm for its place
    only), so they count the same storms; the newest names the park should they ever differ,
    so a box plugged back parks at the rotator's park's place, never a place of its own."""
    if turn.source is not Source.WIND:
        return turn
    newest = max(s.wind.storms for s in sessions)
    if newest == turn.of:
        return turn
    return turn._replace(of=newest, kept=0)  # (a storm of this run: no place kept for it)


def _order(az: Order | None, el: Order | None) -> Order | None:
    """Rule 3: the rotator's place in the order of its commands: both boxes take the same
    places (one mailbox, its batches split), each box's turn and lock word its own; the newest
    of each, named by the azimuth box's run (both start together)."""
    if az is None or el is None:
        return az or el
    return Order(
        az.run,
        max(az.taken, el.taken),
        max(az.turn, el.turn),
        max(az.lock, el.lock),
        az.since,  # (both boxes': the rotator's, kept.py rule 12)
    )


def merge(
    rotator_id: str,
    az: RotatorStatus,
    el: RotatorStatus,
    *,
    error: str | None = None,
    versioned: tuple[bool, bool] = (True, True),
    before: RotatorStatus | None = None,
) -> RotatorStatus:
    """Rule 3: the rotator's status from its two boxes' (``error``: the newer last error;
    ``versioned``: whether the azimuth's and the elevation's box report a version). What it
    makes of the two (the order, the joined version, the wind) is ``before``'s, the rotator's
    last merged status, while it says the same: R/status's text keeps what a reading leaves by
    its very objects (interfaces/mqtt/payloads.py StatusText), and those made anew at every
    merge made the rest of that text again at every reading of either box (issue 39)."""
    states = {az.state, el.state}
    if MotionState.MOVING in states:  # (a box read turning while the other is out: turning)
        state = MotionState.MOVING
    elif MotionState.OFFLINE in states:
        state = MotionState.OFFLINE
    else:
        order = (MotionState.STALLED, MotionState.BRAKING, MotionState.UNKNOWN)
        state = next((s for s in order if s in states), az.state)
    said = [box.version for box, has in zip((az, el), versioned, strict=True) if has]
    version = " / ".join(v for v in said if v) if said and all(said) else None
    if before is not None and version is not None and version == before.version:
        version = before.version  # (text: equal is the same text)
    wind = az.wind  # (its park seen reached only if both boxes' parks were; waiting if either's;
    # refused if either's, in the words of the box that refused it, else waiting in the words
    # of the box whose park waits, else off the park in those of the box off it:
    # session/wind.py rules 9 and 10)
    if wind is not None and el.wind is not None:
        refusal = wind.refusal
        if el.wind.refused and not wind.refused:
            refusal = el.wind.refusal
        elif el.wind.waiting and not (wind.refused or wind.waiting):
            refusal = el.wind.refusal
        elif el.wind.off_park and not (wind.refused or wind.waiting or wind.off_park):
            refusal = el.wind.refusal  # (session/wind.py rule 10: the box off its park)
        wind = replace(
            wind,
            arrived=wind.arrived and el.wind.arrived,
            waiting=wind.waiting or el.wind.waiting,
            refused=wind.refused or el.wind.refused,
            off_park=wind.off_park or el.wind.off_park,
            refusal=refusal,
        )
        wind = kept_if_same(wind, None if before is None else before.wind)
    place = _order(az.order, el.order)
    if before is not None and place is not az.order:
        place = kept_if_same(place, before.order)
    return replace(
        az,
        rotator_id=rotator_id,
        state=state,
        elevation_deg=el.elevation_deg,
        target_el_deg=el.target_el_deg,
        connected=az.connected and el.connected,
        available=az.available and el.available,
        locked=az.locked or el.locked,
        lock_unknown=az.lock_unknown or el.lock_unknown,
        version=version,
        last_error=error,
        estimated=az.estimated or el.estimated,
        controller_time=az.controller_time or el.controller_time,
        parked=az.parked and el.parked,
        stop_owed=az.stop_owed or el.stop_owed,
        turn_kept=az.turn_kept or el.turn_kept,
        turn_kept_until=az.turn_kept_until if az.turn_kept else el.turn_kept_until,
        order=place,
        wind=wind,
    )


class Composition:
    """Sans-IO: the two boxes' statuses in, the rotator's out (rule 3), what rule 4 asks of
    the other session when one ends tracking or following, and the events said (rule 9)."""

    def __init__(self, rotator_id: str, versioned: tuple[bool, bool] = (True, True)) -> None:
        self.rotator_id = rotator_id
        self.versioned = versioned  # rule 3: whether each box's model reports a version
        self.boxes: dict[Axis, RotatorStatus] = {a: RotatorStatus(rotator_id) for a in AXES}
        self.status = RotatorStatus(rotator_id)
        self._error: str | None = None
        self._ended: str | None = None  # rule 4: why the first one ended
        self._owed: dict[Axis, tuple[bool, bool]] = {}  # (tracking, following) to end
        self._dropped: set[Axis] = set()  # rule 8: a waiting target to drop there
        self._first = True
        self._unmatched: dict[Axis, list[ErrorEvent]] = {a: [] for a in AXES}  # rule 9
        # rule 8: the halves of the rotator's last target, as handed to each box, and rule 9:
        # each half's words, and the whole target's
        self.halves: dict[Axis, Target | None] = dict.fromkeys(AXES)
        self._halves_said: dict[Axis, str | None] = dict.fromkeys(AXES)
        self._whole_said = ""
        self._whole: Target | None = None  # rules 8 and 9: the rotator's target, its halves'

    def aimed(
        self, batch: Batch, batches: dict[Axis, Batch], held: Callable[[Axis, Target], bool]
    ) -> None:
        """Rules 8 and 9: the rotator's target (``batch``'s), split into ``batches``; an axis
        it leaves out keeps the half its sender sent before while that box still ``held`` it
        (waiting, or turning to it: session.py ``holds``), as one controller takes one
        sender's two halves for one target (core/model.py ``combine``); none where the batch
        stops the rotor first (a stop or lock ON in it ends that turn: review 36, its whole
        target's sooner expiry dropped a fresh elevation half)."""
        target = batch.target
        assert target is not None
        stops = batch.stop is not None or batch.lock_on
        whole, self._whole = combine(target, self._whole), target
        for axis in AXES:
            half, before = batches[axis].target, self.halves[axis]
            kept = before is not None and not stops and held(axis, before)
            if half is None and whole is not target and kept:
                self._whole = whole  # (kept: taken with the new half)
                continue
            self.halves[axis] = half
            self._halves_said[axis] = None if half is None else describe_command(half)
        self._whole_said = describe_command(self._whole)

    def expires_as(self, axis: Axis, waiting: Target) -> Target:
        """Rule 8 (session.py rule 13): what ``waiting``, the target waiting in ``axis``'s box
        when a hold ends there, expires as: the rotator's whole target where it is that box's
        half of it (``aimed``: one sender's two halves expire with the sooner of the two, as
        one controller keeps them, core/model.py ``combine``), else itself."""
        if self._whole is not None and waiting is self.halves[axis]:
            return self._whole
        return waiting

    def sibling(self, other: Axis, dropped: Target | None) -> Target | None:
        """Rule 8: ``other``'s box's half of the rotator's last target, to drop with the target
        the other box ``dropped``, if one sender sent both (a half another sender sent since,
        the lease holder's own, is not the dropped target's: it goes on)."""
        half = self.halves[other]
        if half is None or dropped is None:
            return None
        if half.source is not dropped.source or half.origin != dropped.origin:
            return None
        return half

    def whole(self, axis: Axis, event: ErrorEvent) -> ErrorEvent:
        """Rule 9: ``event`` naming the rotator's whole target where it says ``axis``'s box
        dropped its half of it."""
        dropped = event.kind is ErrorKind.REFUSED and event.message.startswith(DROPS)
        if dropped and event.command is not None and event.command == self._halves_said[axis]:
            return replace(event, command=self._whole_said)
        return event

    def said(self, axis: Axis, event: ErrorEvent) -> bool:
        """Rule 9: whether ``axis``'s box's event (``whole``'s) is to be said (not the twin of
        one the other box said)."""

        def near(e: ErrorEvent) -> bool:
            return abs(e.time_unix - event.time_unix) < TWIN_S

        word = (event.kind, event.message, event.command)
        other = self._unmatched[AXES[1] if axis is AXES[0] else AXES[0]]
        other[:] = [e for e in other if near(e)]
        for i, e in enumerate(other):
            if (e.kind, e.message, e.command) == word:
                del other[i]
                return False
        mine = self._unmatched[axis]
        mine[:] = [e for e in mine if near(e)][-TWINS_KEPT + 1 :]
        mine.append(event)
        return True

    def seen(self, axis: Axis, status: RotatorStatus) -> RotatorStatus | None:
        """A box's new status; the rotator's, when it is worth publishing."""
        before = self.boxes[axis]
        if status.last_error != before.last_error:
            self._error = status.last_error  # rule 3: the newer of the two
        if status.tracking is not None:
            self._ended = None
        # rule 4, on the edge: this box has just ended it (a look-up under way in one box
        # while the other already has its answer is no end)
        track = before.tracking is not None and status.tracking is None
        follow = before.following is not None and status.following is None
        if track or follow:
            self._owe(Axis.ELEVATION if axis is Axis.AZIMUTH else Axis.AZIMUTH, track, follow)
            if track and self._ended is None:
                self._ended = status.tracking_ended
        if before.available and not status.available:  # rule 8, on the edge: both boxes
            self._dropped.update(AXES)  # (the one gone too: its turn, cut, owes a stop)
        self.boxes[axis] = status
        for mine, theirs in ((Axis.AZIMUTH, Axis.ELEVATION), (Axis.ELEVATION, Axis.AZIMUTH)):
            box = self.boxes[mine]  # rule 4: one that tracks while the other does not answer
            if not self.boxes[theirs].available and (box.tracking or box.following):
                self._owe(mine, box.tracking is not None, box.following is not None)
                if box.tracking is not None and self._ended is None:
                    self._ended = OFFLINE
        az, el = self.boxes[Axis.AZIMUTH], self.boxes[Axis.ELEVATION]
        merged = merge(
            self.rotator_id, az, el, error=self._error, versioned=self.versioned, before=self.status
        )
        if self._ended is not None and merged.tracking is None:
            merged = replace(merged, tracking_ended=self._ended)
        worth = self._first or st.worth_emitting(merged, self.status)
        self._first = False  # the first status goes out whatever it says (session.py start)
        self.status = merged
        return merged if worth else None

    def _owe(self, axis: Axis, track: bool, follow: bool) -> None:
        """Rule 4: tracking (``track``) or following to be ended in ``axis``'s box."""
        owed = self._owed.get(axis, (False, False))
        self._owed[axis] = (owed[0] or track, owed[1] or follow)

    def ends(self) -> dict[Axis, Batch]:
        """Rule 4: a batch ending tracking or following in the box that still has it; rule 8:
        dropping a target waiting in the box whose other stopped answering."""
        out: dict[Axis, Batch] = {}
        for axis in AXES:
            track, follow = self._owed.get(axis, (False, False))
            mine = self.boxes[axis]
            track = track and mine.tracking is not None
            follow = follow and mine.following is not None
            offline = OFFLINE if axis in self._dropped else None
            if track or follow or offline:
                out[axis] = Batch(
                    track=Track(None, Source.TRACKING) if track else None,
                    follow=Follow(False) if follow else None,
                    offline=offline,
                )
        self._owed, self._dropped = {}, set()
        return out

    def offline(self, batches: dict[Axis, Batch]) -> dict[Axis, Batch]:
        """Rule 8: a target handed to a box whose other does not answer is refused there."""
        for axis, other in ((Axis.AZIMUTH, Axis.ELEVATION), (Axis.ELEVATION, Axis.AZIMUTH)):
            batch = batches[axis]
            if batch.target is not None and not self.boxes[other].available:
                batches[axis] = replace(batch, offline=OFFLINE)
        return batches


class Followed:
    """Sans-IO: a count a box keeps, followed from the other box: True once for each time it
    grew. Rule 6's (the azimuth box's ``part_halts``: the elevation box halts too) and rule
    8's (a box's controller's ``restarts``: the other box abandons its turn)."""

    def __init__(self) -> None:
        self._seen = 0

    def follow(self, halts: int) -> bool:
        if halts == self._seen:
            return False
        self._seen = halts
        return True


class Siblings:
    """Sans-IO: what one box's session did that the other box follows, in order: rule 6's
    halt (the azimuth box's ``part_halts``), rule 8's abandoned turn (a box's controller's
    ``restarts``; its ``dropped_turns``, once the other box's rotor moves or its turn is
    over: one that stands is left to its own stall), and rule 8's dropped half (``drops``)."""

    def __init__(self) -> None:
        self._halted = Followed()
        self._restarted = {axis: Followed() for axis in AXES}
        self._dropped = {axis: Followed() for axis in AXES}
        self._drops = {axis: Followed() for axis in AXES}
        self._forsaken: set[Axis] = set()  # to abandon once their rotor does not stand

    def newer(self, batches: dict[Axis, Batch]) -> None:
        """Commands came: a box sent motion of its own since (a target's half, a track, a
        follow, a feature's command) abandons nothing for a turn dropped before it; anything
        else (a wind reading, a program's status, a lease) leaves the abandon due (a review:
        a wind reading let the elevation turn on to the target said dropped)."""
        for axis, batch in batches.items():
            if (
                batch.target is not None
                or (batch.track is not None and (batch.track.body or batch.track.lookup))
                or (batch.follow is not None and batch.follow.on)
                or any(isinstance(c, FeatureCommand) and c.moves for c in batch.feature_commands)
            ):  # (a track or follow off, a feature's setting, moves nothing: a review)
                self._forsaken.discard(axis)

    def follow(
        self, sessions: dict[Axis, RotatorSession], composition: Composition, now: float
    ) -> Iterator[tuple[Axis, Callable[[float], list[Action]]]]:
        """Each step due, for the box it is for: carry each out before asking for the next."""
        if self._halted.follow(sessions[Axis.AZIMUTH].part_halts):  # rule 6
            yield Axis.ELEVATION, sessions[Axis.ELEVATION].halt
        for axis, other in ((Axis.AZIMUTH, Axis.ELEVATION), (Axis.ELEVATION, Axis.AZIMUTH)):
            session = sessions[axis]
            if self._restarted[axis].follow(session.controller.restarts):
                yield other, sessions[other].abandon  # rule 8: a restart mid-turn abandons it
            if self._dropped[axis].follow(session.controller.dropped_turns):
                self._forsaken.add(other)  # rule 8: so does a turn dropped (a stall), said
            if self._drops[axis].follow(session.drops):
                half = composition.sibling(other, session.dropped)  # rule 8: the same half
                yield other, partial(sessions[other].forsake, half)
        for axis in tuple(self._forsaken):
            if axis not in self._forsaken or sessions[axis].stands(now):
                continue  # (both rotors iced: its own stall is said and counted)
            self._forsaken.discard(axis)
            yield axis, sessions[axis].abandon


class CompositeWorker:
    """The serial-lines thread's worker for a composite rotator (lines.py): the rotator's
    mailbox, and the two boxes' workers, each with its port, back-off and session."""

    def __init__(
        self,
        cfg: WorkerConfig,
        axes: tuple[WorkerConfig, WorkerConfig],
        mailbox: Mailbox,
        on_status: Callable[[RotatorStatus], None],
        on_event: Callable[[ErrorEvent], None],
        *,
        locked: bool = False,
        health: dict[str, object] | None = None,
        storm: bool = False,
        storm_halted: bool = False,
        storm_arrived: bool = False,  # (both boxes were seen at their parks: ``merge``)
        storm_place: int = 0,  # kept.py rule 4: the place the kept storm's park took
        stop_owed: bool = False,
        short_of: float | None = None,
        turn_kept: bool = False,  # kept.py rule 13 (an azimuth box's with no feedback)
        order: tuple[int, int, int] = (0, 0, 0),  # kept.py rule 12
        wall: Callable[[], float] = time.time,
        port_opener: PortOpener = open_port,
        sky: SkyWorker | None = None,
        on_audit: Callable[[Audit], None] | None = None,
    ) -> None:
        self.cfg = cfg
        self._mailbox = mailbox
        self._box = mailbox.fileno()
        self._urgent = frozenset({self._box})
        self._on_status = on_status
        self._on_event = on_event
        self._on_audit = on_audit
        self._wall = wall
        self._audited: dict[Axis, tuple[Audit, float] | None] = dict.fromkeys(AXES)  # rule 9
        self._halts_applied = 0
        self._newest_applied = 0
        self._winds_applied = 0
        self.composition = Composition(
            cfg.rotator_id, (axes[0].spec.has_version, axes[1].spec.has_version)
        )
        self._siblings = Siblings()  # rules 6 and 8
        self.boxes: dict[Axis, Worker] = {}
        self._own = [Mailbox(), Mailbox()]  # each box's own: only sky answers wake them
        for axis, box, own in zip(AXES, axes, self._own, strict=True):
            self.boxes[axis] = Worker(
                box,
                own,
                partial(self._seen, axis),
                partial(self._event, axis),
                locked=locked,
                health=health if axis is Axis.AZIMUTH else None,  # the azimuth's is shown
                storm=storm,
                storm_halted=storm_halted,
                storm_arrived=storm_arrived,
                storm_place=storm_place,  # (the rotator's park's: rule 10)
                stop_owed=stop_owed,  # (each box: the rotator's, kept whole)
                short_of=short_of if axis is Axis.AZIMUTH else None,  # (the status's)
                turn_kept=turn_kept and axis is Axis.AZIMUTH,  # (the elevation box reports)
                order=order,  # (kept.py rule 12: the rotator's, kept whole)
                wall=wall,
                port_opener=port_opener,
                sky=sky,
                on_audit=partial(self._audit, axis),
                place=self._place,  # rule 10: the rotator's places, not the box's own
            )
        sessions = {axis: box.session for axis, box in self.boxes.items()}
        joined(self.composition, sessions)
        judged_whole(cfg, sessions)  # rule 7

    @property
    def status(self) -> RotatorStatus:
        return self.composition.status

    @property
    def halts_applied(self) -> int:
        """mailbox.py rule 10, as a worker's: the merged status shows every stop and lock ON
        up to it (set once both boxes' statuses were handed on: ``serve``)."""
        return self._halts_applied

    @property
    def stop_due(self) -> bool:
        """Either box's stop waits for its line (worker.py ``stop_due``)."""
        return any(box.stop_due for box in self.boxes.values())

    @property
    def newest_applied(self) -> int:
        """mailbox.py rule 10a, as a worker's (set with ``halts_applied``; none while a box's
        status cannot show the target waiting there: session.py ``newest_applied``)."""
        applied = self._newest_applied  # (first, as session.py reads its own)
        if any(box.session.target_unshown for box in self.boxes.values()):
            return 0
        return applied

    @property
    def winds_applied(self) -> int:
        """mailbox.py rule 9, as a worker's (set with ``halts_applied``)."""
        return self._winds_applied

    @property
    def features_on(self) -> tuple[bool, bool]:
        """What a tracking OFF and a following OFF would end now, in either box (rule 4: one
        box may track or follow while the merged status, the azimuth box's, shows nothing)."""
        ons = [box.session.features_on for box in self.boxes.values()]
        return any(t for t, _ in ons), any(f for _, f in ons)

    def _event(self, axis: Axis, event: ErrorEvent) -> None:
        event = self.composition.whole(axis, event)  # rule 9
        if self.composition.said(axis, event):
            self._on_event(event)

    def _audit(self, axis: Axis, audit: Audit) -> None:
        """Rule 9: the two boxes' audit lines of one move of the bridge's own (each box parks
        its axis: session.py rule 25) are the rotator's one line."""
        now = self._wall()
        other = AXES[1] if axis is AXES[0] else AXES[0]
        twin = self._audited[other]
        if twin is not None and twin[0] == audit and abs(now - twin[1]) < TWIN_S:
            self._audited[other] = None
            return
        self._audited[axis] = (audit, now)
        if self._on_audit is not None:
            self._on_audit(audit)

    def _place(self, turn: OwnTurn) -> int:
        """Rule 10: the place of a turn of the bridge's own a box begins: the rotator's."""
        sessions = [box.session for box in self.boxes.values()]
        return self._mailbox.own_place(rotators_turn(turn, sessions))

    def _seen(self, axis: Axis, status: RotatorStatus) -> None:
        merged = self.composition.seen(axis, status)
        if merged is not None:
            self._on_status(merged)

    # -- what the serial-lines thread asks of a worker (lines.py) -------------------------------
    def begin(self, now: float, wake: Callable[[], None]) -> None:
        for box in self.boxes.values():
            box.guarded(box.begin, now, wake)

    def end(self, now: float) -> None:
        """For good (lines.py rule 4): nothing serves the boxes after this, so their own
        mailboxes are closed too (a late sky answer's wake-up then does nothing)."""
        for box, mailbox in zip(self.boxes.values(), self._own, strict=True):
            box.guarded(box.end, now)
            mailbox.close()

    def wait_closed(self, timeout_s: float) -> bool:
        deadline = time.monotonic() + timeout_s
        closed = [b.wait_closed(max(0.0, deadline - time.monotonic())) for b in self.boxes.values()]
        return all(closed)

    def has_commands(self, ready: set[int]) -> bool:
        return self._box in ready

    def urgent(self) -> frozenset[int]:
        return self._urgent if self._mailbox.urgent else frozenset()

    def wants(self, now: float) -> tuple[list[int], float, float]:
        fds, until, latest = [self._box], math.inf, math.inf
        for box in self.boxes.values():
            more, when, by = box.wants(now)
            fds += more
            until = min(until, when)
            latest = min(latest, by)
        return fds, until, latest

    def guarded(self, step: Callable[..., None], now: float, *args: Any) -> None:
        """``step`` (begin, end, serve): each box is guarded on its own inside it (rule 5)."""
        try:
            step(now, *args)
        except Exception:
            log.exception("%s: unexpected error in the composite worker", self.cfg.rotator_id)

    def serve(self, now: float, ready: set[int]) -> None:
        # both sessions told the wall clock before either is handed its batch (rule 1): only
        # a box's own serve told its own, after the batch, and the first wind reading after a
        # suspend was judged by the clock from before it (review 109; session/wind.py rule 2)
        for box in self.boxes.values():
            box.guarded(box.tell_wall, now)
        if self._box in ready:
            batch = self._mailbox.take()
            if batch:
                batches = self.composition.offline(split(batch))  # rule 8
                if batch.target is not None:  # (rules 8 and 9: its halves)
                    self.composition.aimed(batch, batches, self._holds)
                self._siblings.newer(batches)  # rule 8: newer than a turn dropped
                self._hand(batches, now)  # rule 1: both boxes in this one serve
                self._halts_applied = batch.epoch
                self._newest_applied = batch.newest
                self._winds_applied = batch.winds
        for box in self.boxes.values():
            fds, until, _ = box.wants(now)
            if now >= until or not ready.isdisjoint(fds):
                share_quiet([b.session for b in self.boxes.values()], now)  # rule 7
                box.guarded(box.serve, now, ready)
        ends = self.composition.ends()  # rule 4
        if ends:
            self._hand(ends, now)
        sessions = {axis: box.session for axis, box in self.boxes.items()}
        for axis, step in self._siblings.follow(sessions, self.composition, now):
            box = self.boxes[axis]
            box.guarded(lambda t, b=box, s=step: b.carry_out(t, s(t)), now)

    def _holds(self, axis: Axis, half: Target) -> bool:
        """Rule 8: whether ``axis``'s box still waits for ``half`` or turns to it."""
        return self.boxes[axis].session.holds(half)

    def _hand(self, batches: dict[Axis, Batch], now: float) -> None:
        """Each box's session decides on its batch; then the frames go out on both lines
        (a stop on each) before any status or event is handed to the listeners (rule 1)."""
        decided: dict[Axis, list[Action]] = {}
        for axis, batch in batches.items():
            session = self.boxes[axis].session
            self.boxes[axis].guarded(
                lambda t, s=session, b=batch, a=axis: decided.__setitem__(a, s.commands(b, t)),
                now,
            )
        for wire in (True, False):
            for axis, actions in decided.items():
                box = self.boxes[axis]
                todo = [a for a in actions if isinstance(a, Write) is wire]
                if todo:
                    box.guarded(box.carry_out, now, todo)
