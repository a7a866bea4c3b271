"""The motion state machine: pure, clock passed in, no I/O.

What it models: an analog rotator seen through periodic bearing readings (Rotor-EZ family), or
not seen at all (DCU-1). Source: the Idiom Press FAQ ("if the bearing is changing, the rotator is
probably turning; close to the target and steady for several seconds: arrived; not changing but
not close: cancelled from the front panel or a hardware failure") and its brake-delay answers.

Rules:
1. Movement is a reading more than ``noise_deg`` away from the anchor (the reading where the last
   movement was seen). Analog jitter of a still rotor stays inside that band and moves nothing.
2. Still = no movement for ``settle_s`` (counted from the later of the last movement and the
   last command, so a rotor that has not started yet is not "still"), as a reading shows it: the
   clock alone never says a rotor stopped (a CI run: the lines starved for 0.35 s, the rotor 2
   degrees short of its target and still turning was called arrived, and the status showed it 2
   degrees short for good). While a setting slows the rotor (controller.py rule 7: a GS-232 at
   X1), never shorter than it takes at its slower axis's speed to go a step of its readings
   beyond ``noise_deg``, plus a moving poll (``settle_for``: a review found a GS-232 at X1, 1.5
   degrees a second, called arrived at 128.9 on its way to 130). Speeds the user configures are
   the user's to pair with ``settle_s``. A turn the controller finishes by itself (``carried``,
   rule 4: over a lost link, or found by a bridge just started, and a turn begun since, no stop
   sent into it) is still once each axis is, by its own time (``carried_rest_from``): no
   movement of that axis's own (more than ``noise_deg`` from where that axis itself last moved:
   ``az_moved_deg``, ``el_moved_deg``; from the first reading back for an axis not seen move
   since, but not at all, till it is seen move, for an axis the lost target left out or leaves
   where it stands, within ``tolerance_deg``: ``lost_aim``, ``_nothing_to_do``), nor a reading
   of it further from there than any since (it creeps inside ``noise_deg``: ``az_crept_deg``,
   ``el_crept_deg``; jitter back and forth does not) at CREEP_SHARE of the speed that axis turns
   at its slowest (``slowest_deg_s``) or faster, timed from its last creep (its first since a
   move, from the reading before), for the longer of ``settle_s`` and its ``axis_seen_s`` (rule
   4: what a reading's step and ``noise_deg`` take at that axis's speed, as slow as rule 6
   allows for), a user's ``settle_s`` never shortening it. A creep slower than any turn is no
   turn: review 110, every creep counted, a jammed RC2800 (noise_deg 0.5, read in tenths) whose
   pot drifted a tenth every 1.2 s (0.08 deg/s; its slowest turn 4 deg/s) was shown moving for
   ever and never got controller.py rule 13's stop. Nor is an axis with nothing to do waited on:
   review 110, an azimuth-only turn on a GS-232B with its elevation set slow (1.0 deg/s), jammed
   a second after a replug, was stopped 3.9 s after the jam (8.5 s at 0.5 deg/s), by the
   elevation's own time counted from the first reading back, not the azimuth's 1.7 s. Review 95:
   a GS-232B's elevation at 1.8 deg/s, read in whole degrees with 2 degrees of noise, shows a
   move every 1.7 s; its turn carried over a replug was called at rest at rule 2's 1.5 s and
   stopped short by controller.py rule 13, R/error blaming a jam. Not the slowest axis's time
   for every axis (31a878ae, reverted: review 101, a carried azimuth turn jammed while a slow
   elevation had been shown still for 6 s was stopped 4.9 s after the jam, not 1.5 s; and a
   ``settle_s`` of the user's a little above the default brought review 95 back): a jam of a
   fast axis is told by its own short time, the slow axis shown still by its own. The creep:
   review 95, a hand at a GS-232B's azimuth begun as that rest came, its first readings 63 and
   64 inside ``noise_deg`` of 62, was shown moving, 'idle' at 64, then moving: one hand's turn
   told as two moves (before, a hand 1.3 s after the port answered; with each axis's own time,
   1.9 s). A target for a controller that must be stopped first, come while the rotor stands at
   its target still by the clock with that reading late, waits for it: no stop to a rotor at
   rest (``plan_target``; an attack pass).
3. Still and within ``tolerance_deg`` of the target: arrived. Off target with no movement for
   ``stall_timeout_s``: stalled (and the target is dropped). Still with no target: stopped.
   A stall is told by a reading, or by time while the controller is asked and does not
   answer (``tick``'s ``asking_since``), never by time in which the bridge asked nothing:
   its process held mid-turn (SIGSTOP, a host that stalls) longer than the timeout, the rotor
   turning on meanwhile, was called stalled and stopped short (docs/architecture.md rule 15;
   review 102). At the stall's time with nothing asked, the controller is asked at once
   (``stall_due``, controller.py ``tick``): its reading decides a reply time later, not a
   moving poll later (a review: the motor drove on against a jam for one more moving poll).
   (Movement, not a shrinking error, is progress: a rotor that must go the long way round its
   end stop first moves away from a target across the stop.) On an az/el rotor each axis is
   judged on its own (``stalling``): an axis off its target whose own movement (more than
   ``noise_deg`` from where that axis last moved since the target went out: rule 5's
   ``az_from_deg``, ``el_from_deg``; not rule 1's shared anchor, which moves with either axis)
   stopped ``stall_timeout_s`` ago is stalled while the other still turns; an axis within
   ``tolerance_deg`` of its target, or one the target leaves out, is not judged (attack 25:
   the azimuth's turn counted as a jammed elevation's progress, its motor drove against the
   jam 30 s longer on a 180 degree GS-232B move, and the stall was said at the azimuth, which
   had arrived). The stall names its axis (``Motion.stalled``). An axis whose frame of a
   target sent mid-turn was lost rests at the old target off the new one: controller.py
   rule 11 finds it left behind by the same per-axis time (``axis_progress_t``) and sends the
   target again before its stall is due, the stall counting from that try (review 78). Every
   family here turns both axes at once (their fact sheets and emulators: SPID, SatEL's slew,
   GS-232's ``W``, Easycomm, an RC2800's two frames 200 ms apart, a Combi-Track's two units;
   a composite's two boxes each judge their own axis); a box that turned them one after the other
   (``ModelSpec.axes_in_turn``) would show its waiting axis not moving: there movement of
   either axis counts for both, as before. So it does for an axis whose own frame of the
   target the controller refused (``undriven``: an RC2800's ``E ERR``, a Combi-Track's unit
   B error, the target a frame per axis): the controller does not drive it, and the other
   axis's turn goes on to its target (a review: an RC2800's refused elevation was taken for
   the whole target's refusal while the azimuth turned 190 degrees to it; judged per axis, it
   was stopped 10 s into that turn). A reading tells a stall only when the question it
   answers went out at the stall's time or later (``reading``'s
   ``asked_t``): the reply to one asked before it shows the rotor as it was when answered,
   any time from the question on, and a reply read late (the bridge's process held with a
   poll out, SIGSTOP, a host that stalls, a starved thread) was taken for no progress in all
   that time: the turn was called stalled and stopped short (review 102 left it open; seen
   under load in a broker-restart test). That reading decides nothing; the controller is
   asked at once (``stall_due``, from the reading itself: controller.py ``_reading``; review
   36: left to the tick, it waited a moving poll) and its answer does.
4. Every stop starts the brake window: ``braking`` for ``brake_delay_s`` counted from when the
   rotor stopped: the last reading that changed at all (a move smaller than ``noise_deg`` is
   still a move: the rotor creeps up to its stop) plus one poll interval (``poll_margin_s``:
   it stopped somewhere before the next reading), never before a stop or target went out, plus
   BRAKE_GUARD_S for the controller's own timer. Not from when the stillness was detected: that
   is ``settle_s`` later and would make every new target after an arrival wait for nothing. A
   stall counts from its detection (safe side).
   At start-up the machine assumes a brake window may be running, and that the rotor may be
   turning: no target goes out before ``settle_s`` of stillness after the first reading. Without
   a brake (``brake_delay_s`` 0: SPID, SatEL, RotorCard) the rotor is never ``braking``: it is
   ``idle`` from the first still reading (a turning one shows ``moving`` at the next), and that
   wait is kept apart (``settling``). Where its readings were lost while it turned or had a
   target out (``link_down``: a port replugged, a controller silent mid-turn), the first
   reading back is ``moving`` instead, from that reading: it stops as any turn does, when
   readings show it still (rule 2), never by the clock alone (an attack pass: replies lost
   for a moment after the first reading back, the clock settled it, the status showed it idle
   while it turned, and an Easycomm's turn was then stopped as one nobody asked for). Until a
   reading shows it move, a target for a controller stopped first waits (no stop to a rotor
   that came to rest while its port was out: a review), and that reading is no change of
   bearing (rotor health counts no move from it). That turn is ``carried`` until it comes to
   rest: the controller finishing a turn by itself, no hand on the panel (parts.py rule 8);
   so is a turn the readings of a bridge just started find (a restart mid-turn: the
   controller finishing the turn the bridge before it sent), until the rotor comes to rest;
   readings that show each axis no move for its own ``axis_seen_s`` from the first (as a
   lost turn's, below; not rule 2's ``settle_s``, shorter than a slow axis needs to show its
   move: review 89, a GS-232's elevation at 2 deg/s and an azimuth set to 2 deg/s, dropped
   at rule 2's rest after a restart mid-turn, turned on 60 and 100 degrees past a refused
   start, and following ended "turned by hand"; only a ``settle_s`` the user set, rule 2's
   to pair with the speeds, ends the wait at rest sooner, ``settle_own``: one other than the
   default, since the default written out in the file is no choice of the user's; review 93:
   ``settle_s = 1.5`` written out brought review 89's slow elevation back) say a turn after
   them is seen to begin, and till they do the controller is asked
   at the moving rate (``found_unjudged``; not the clock alone, nor one reading a whole idle
   poll on: review 54, a Rot2Prog polled every 9 s at rest had settled before its second
   reading, and a hand in a Rotor-EZ's first brake window was taken for the old turn; review
   84: the restart's turn is judged as a replug's, so a refused start owes it a halt, parts.py
   rule 10, and a GS-232 read 0.2 s on shows no move of a turn under way); not a
   hand's turn the bridge saw begin before the link went (``lost_hand``), nor once the
   bridge sends a target of its own into it (review 53). The lost turn is judged per axis, as
   rule 3's stall is (``_judged``): readings back for an axis's own ``axis_seen_s`` (the time
   that axis turning at its nominal speed, as slow as rule 6 allows for, needs to move more
   than ``noise_deg`` and a reading's step, plus a poll) that show it no move decide it still
   (``still_axes``); a move on an axis not yet decided is the lost turn, seen; a move only on
   axes decided still is a turn begun since, not known to be the lost one; every axis decided
   (by ``carried_seen_s``, the slowest axis's time) says the lost turn came to rest while the
   port was out. Either way ``lost_still``, though rule 2 waits each axis's own time (the
   longer of ``settle_s`` and ``axis_seen_s``; none for an axis the lost target gave nothing
   to do, till it is seen move) to call the rotor still (a turn begun since too: the lost one
   may go on on an axis not yet decided), and a refused start's halt owed
   to the lost turn is dropped (parts.py rule 10; review 73, a hand a second after a
   replug). Review 84: the lost turn may be an elevation's alone (a GS-232's 2.5 deg/s
   elevation, read in whole degrees with 2 degrees of noise, timed at the azimuth's 6 deg/s,
   was taken for at rest and turned on 60 degrees past a refused start); review 89: the
   slowest axis's time for every axis (2.1 s on an az/el GS-232B) took a hand at the azimuth
   a second after a replug at rest for the lost turn, and the owed halt stopped it a few
   degrees in.
   While a refused start's halt is owed to the turn under judgement (``owes_halt``, told by
   the session at every step while the start's feature is on and owes it, parts.py rule 10,
   feature_commands.py rule 7, so it ends however tracking or following end; ``owed_halt``:
   no target nor stop sent since), a move only on decided axes
   is a turn begun since only once a later reading confirms it (``_confirms``: an axis that
   moved in it reads on from it the way it moved, a whole degree where the readings are in
   whole degrees, or that move has lasted the axis's own ``axis_seen_s``; a move on an
   undecided axis meanwhile is the lost turn, seen). The reading that showed it is held back
   (``begun_t``, ``begun_deg``, ``held_back``), and so is every reading after it that still
   shows the move unconfirmed (``held_t``): no move, no rest told by them, nothing of them
   shown in the status (controller.py feeds no bearing from them); one that shows those axes
   back where they stood ends the hold and is judged as any. So one garbled reading keeps the
   halt owed and never shows, nor does the same garble read twice, and a hand is followed
   and shown moving a reading or two later (review 93: "AZ=066" read for 062 a second after
   a replug mid slow elevation turn was taken for a hand's turn, the owed halt dropped, and
   the elevation turned on 25 -> 85; review 95: "EL=014" read for 010 in two readings in a
   row confirmed itself, being as far from where the elevation stood as the first, and a
   slow azimuth turned on 85 -> 250). Only then: with no halt owed a hand is told at once, as it
   was, for 03af385a, which asked the second reading everywhere and showed the first at
   rest, published one 'idle' status with a hand's new bearing before 'moving' (a hand at a
   slowed GS-232's panel just after a bridge started), and was reverted.
5. Movement without a command (front panel) is ``moving`` too. So is movement away from the
   target on a controller whose scale does not wrap (SPID: it always heads straight for the raw
   target): two readings in a row, each further from it than the one before and both more
   than ``tolerance_deg + noise_deg`` + AWAY_MARGIN_DEG further than the closest one so far,
   are someone else's hand on the front panel, or a controller driving the wrong way (not one
   stray reading, an overshoot or the coasting of a reversal): ``turned away``, the target is
   dropped; the session reports it and stops the rotor once it is at rest. On a wrapping scale
   the way round the stop may lead away first (rule 3), so going away tells nothing by itself.
   Turning back does: once two movements of the azimuth in a row have closed in on the
   target (it heads for it; one corrupt reading closes in once, and the true one after it goes
   away again: an attack pass, a tens digit flipped stopped a long way round), two movements
   away in a row, the second further than the first, both more than ``tolerance_deg +
   noise_deg`` + AWAY_MARGIN_DEG beyond the closest it came, are a turn back: ``turned back``,
   the target dropped and the rotor stopped at once, as a pass is (a poll garbled into a jog,
   Easycomm's ``ML``, ran the other way to the end stop; a hand at the panel). A movement away
   before it heads for the target starts the count again. A target sent while the rotor turns
   is watched so only after twice ``settle_s`` (``back_from_t``): until then a reply on its
   way and the coast show the way it was going (an attack pass: an RC2800 at 12 degrees a
   second sent across its stop mid-turn; a review: a rotor that ramps down over 3 s; one that
   coasts longer needs a longer ``settle_s``). On either axis, each judged on its own: once a
   movement on it (more than ``noise_deg`` from where that axis last moved since the target
   went out: rule 1's anchor moves with either axis) closed in on its target to within
   ``tolerance_deg``, or went over it (the target between that axis's last movement and this
   one), or the axis was within ``noise_deg`` of it along the rotor's travel when the target
   went out (the axis an elevation-only move leaves where it is; ``along_travel``: where the
   stop is not known to be at north, both ways, so 179 and 181 on a Hy-Gain rotor are a whole
   turn apart), and the next movement on it went on the same way (one that turns back says
   the arrival was none: a corrupt reading close to the last, or a hand turning the rotor
   back), two movements away on that axis, the second further than the first, both more than
   ``tolerance_deg + noise_deg`` + AWAY_MARGIN_DEG further than the closest it came, say the
   rotor ``passed`` its target, on either scale. A reading further from the one before than
   three times the larger of the two nominal speeds (``nominal_speed_deg_s``, the model's
   elevation's) over the time since the later of the last reading that changed and the
   target, plus that sum, is corrupt: no arrival, and no reading away.
   That is most likely a controller heading elsewhere: the target never reached it (the line
   lost the frame; a review: a STOP and the target after it eaten by one noise burst, and the
   rotor turned on through the new bearing to the one the operator had stopped). The target
   is dropped and the rotor stopped at once (stops.py rule 4: a hand at the panel in the
   settle time after a move reached its target looks the same). An axis that came stays
   judged while the other still turns (an elevation that arrives first does not make an
   azimuth going the long way round its stop a pass). A target behind the rotor is never
   come to: that turn runs on until a stall tells (a protocol limit: no controller of these
   says which target it heads for).
6. Without position feedback (DCU-1) the state is ``unknown``; a commanded move is assumed to
   last the travel time at the nominal speed (the whole range when the start is unknown), its
   way measured as rule 5's ``along_travel``: 170 to 190 on a DCU-1's Hy-Gain rotor is 340
   degrees round its stop at south, not 20 (a review: taken as over in 7 s, the next target went
   into the turn, which the box ignores, stopping the rotor 105 degrees off, unsaid). Assumed
   generously (``blind_busy_s``): BLIND_SLOW_FACTOR times the nominal travel time plus
   BLIND_START_S to get going. A connect (a replug, the bridge started) cannot know whether a
   turn is still under way: the end assumed before the port was lost is kept, and at least the
   whole range's generous time from the connect is assumed (attack 22: the connect put the
   whole range at the nominal speed alone, no margin, in place of what it knew; a rotor a quarter
   slower was still turning when the next target went, and the box stopped there, unsaid).
   Whether a turn of the bridge's was under way when the port went (``lost_turning``) is kept
   over the connect till that time is over or a stop or target goes: the controller may be
   finishing it by itself (``may_finish_blind``; parts.py rule 10, review 73: a DCU-1's refused
   start right after a replug halted nothing, and it turned on 90 degrees). So is one the
   run of the bridge before may have left in flight (review 89: a refused start right after
   a restart mid-turn halted nothing, and the DCU-1 turned on 95 degrees), as the state file
   keeps it (runtime/kept.py rule 13): a session started with a turn kept (``turn_kept``
   said so in the run before, or the file could not say) takes the first connect as a
   replug mid-turn. Not every first connect: a DCU-1 reports nothing, so a turn taken for the
   old bridge's is also a hand's at the panel, and a refused start stopped that (review 93:
   for some 90 s after every start, none of any bridge's ever sent, the operator's turn cut
   short at 74 of 182). ``turn_kept`` is true from a turn of the bridge's sent (a target out,
   or one taken as carried over a connect) till TURN_KEPT_S past its end (``kept_end_t``, or
   the stop that ended it, the first of a new target's stop-first too). That end is not the
   one assumed from the last bearing sent (``busy_until_t``): a DCU-1 reports nothing, so a
   hand at its panel since may have left the rotor anywhere, and the next target, a few
   degrees from the last, then runs the whole range (review 97: the hold ran out mid-turn,
   and after a restart a refused follow start let it turn on 29 degrees). It is the end of a
   turn over the whole range at the slowest this rule allows (``blind_busy_s`` of
   ``az_span_deg``: BLIND_SLOW_FACTOR past nominal, and BLIND_START_S) counted from when the
   turn was sent, whatever its length; a turn slower still outlasts it (then as before). The
   status says when the hold runs out (``turn_kept_until``), which the state file keeps on
   the kernel's boot clock (runtime/kept.py rule 13, state_store.py rule 15: a bridge ended
   within the hold leaves none kept once it is past, on the same boot; review 97). The
   state file is written when it changes, so at a turn begun from rest and a minute after it
   is over, never per target (a tracker's or a logger's targets in a row, each a stop and a
   turn on a DCU-1, are one turn kept, not two writes each; the end written runs ten minutes
   ahead, rewritten when a target's passes it). What stays: a bridge that dies
   between writing a turn's frame and the state writer's save of it (the status, then an
   fsync: tens of milliseconds), or whose save failed (said, kind ``state``), starts with no
   turn kept, and a refused start then does not halt that turn (review 89's case, in that
   window alone: the unsafe side, a turn on to the old target under "refused"); one
   restarted on the same boot before the end the file keeps (TURN_KEPT_S past a turn's end,
   and up to kept.py's TURN_FILED_AHEAD_S more), on another boot after a turn kept, or after
   a file it could not read, stops a box at rest or a hand's turn at a start refused in the
   range's time, as every start did (the safe side).
7. ``plan_target`` is the one place that decides whether a target may go to the controller now.
8. A controller that answers with its refusal (GS-232's ``?>``) while a target is out that has
   not moved the rotor refused that target: it is dropped at once (``refused``), at rest as
   after a stop, instead of waiting ``stall_timeout_s`` for a stall that blames the brake.
   Movement since the target went out means the refusal was of something else; so does
   any command written after the target (a setting, a query: the controller asks,
   controller.py). A new bearing refused while the rotor still turns to the one before: the
   target is dropped and the rotor stays ``moving`` (stops.py then stops it). So is, at rest
   alike, a target whose frame never moved the rotor and that the bridge no longer sends
   once more (``forgone``: controller.py rule 11; session.py rule 23, a claim; targets.py
   rule 8, its feature ended): its turn never began,
   and ``stall_timeout_s`` later a stall would blame the brake and count in rotor health.
9. Every time ``tick`` (with no reading: rule 2) or ``plan_target`` compares the clock with is
   one ``next_deadline`` looks at: a motion that ``tick`` left as it was at ``t0`` (one it made,
   ``reading``'s, which ends with ``tick``, or one a stop or a target made since at ``t0``)
   stays as it is at every time before ``next_deadline(m, cfg, t0)``, so the controller does not
   tick it before then (controller.py ``tick``).
10. Limits hold on the way too (pointing.py rule 4 holds them for targets): while a target is
   out, two readings in a row more than ``tolerance_deg + noise_deg`` beyond a limit an axis is
   held to (``az_limits_deg``, ``el_limits_deg``: the judge's raw ones), the second further out
   than the first and more than ``noise_deg`` from where that axis last moved since the target
   went out (rule 5's), are ``past limit`` (``Motion.past`` says which): the target dropped and
   the rotor stopped at once, as a pass is. Not one reading (a review: one digit flipped, 86
   read as 96, stopped a rotor short of its target at 89 and ended tracking), and not the coast
   of a turn to a target at its limit (arrival allows ``tolerance_deg``; a review: a SPID's
   elevation read -0.1 at 0). The controller is heading elsewhere: a GS-232 target frame is one
   flipped bit from a jog (``W`` to ``U``, up until stopped: an attack pass ran an elevation
   held to 90 degrees to 103, and a pass 10 degrees beyond the target told it only there). The
   elevation always; the azimuth on a scale that does not wrap (a wrapping controller picks its
   own way round, which may sweep past a limit); neither on a box that does not turn it (a
   composite's elevation box's azimuth). A rotor outside a limit (set narrower since, or turned
   there by hand) that a target brings back moves inward; its jitter is no movement (rule 1).
11. A controller that says it restarted (controller.py rule 12: a power-on byte) while a target
   is out and the rotor is taken for turning has forgotten it: ``restarted`` drops the target
   (so no stall can come of it: rule 3) and leaves the rotor ``moving`` until readings show it
   still (rule 2), as after any stop.
12. A controller that says it drives no motor (controller.py rule 12: Prosistel's ``B``, an
   RC2800's ``ST``) at a reading that finds the rotor still (rule 2) off its target (further
   than ``tolerance_deg``) with a target out has given that turn up: ``halted`` drops the
   target at once, no stall (rule 3) waited for, and leaves the rotor ``moving`` until readings
   show it still after the stop that follows, as rule 11's restart (rotor health then counts
   the turn a stopped one: no arrival error of a turn that arrived nowhere).
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, replace
from typing import Any

from bridge.core.geo import apart_deg, travel_deg
from bridge.core.model import MotionState
from bridge.protocols.base import ModelSpec, RetargetPolicy

# the states by module names: a member looked up on its enum costs some 70 ns in Python 3.11, a
# module's name a tenth of that (reading, tick and next_deadline run at every step of every
# rotator, and compare its state several times)
OFFLINE, UNKNOWN, MOVING = MotionState.OFFLINE, MotionState.UNKNOWN, MotionState.MOVING
BRAKING, STALLED, IDLE = MotionState.BRAKING, MotionState.STALLED, MotionState.IDLE
AWAY_MARGIN_DEG = 5.0  # rule 5
REACH_FACTOR = 3.0  # rule 5: a rotor may turn up to this much faster than nominal
BRAKE_GUARD_S = 0.3  # rule 4: the controller's brake timer is its own; do not cut it fine
BLIND_SLOW_FACTOR = 1.5  # rule 6: a rotor without feedback may be this much slower than nominal
#: rule 2: a carried axis's creep inside ``noise_deg`` is a move only at this share of the speed
#: it turns at its slowest (``slowest_deg_s``) or faster: a turn's first degrees, not a drift
CREEP_SHARE = 0.25
BLIND_START_S = 2.0  # rule 6: ...and take this long to get going
TURN_KEPT_S = 60.0  # rule 6: a turn is kept in the state file this long past its end (the margin)
COAST_S = 1.0  # ``coast_end``: a rotor's run-on after its motor is cut


@dataclass(frozen=True)
class MotionConfig:
    spec: ModelSpec  # the model's capabilities: read from here, never copied (the one place)
    tolerance_deg: float = 3.0
    stall_timeout_s: float = 10.0
    brake_delay_s: float = 5.0
    settle_s: float = 1.5
    # rule 4: ``settle_s`` is the user's own (set in the settings to other than the default,
    # rule 2's to pair with the speeds): the rotor at rest by it ends a found turn's wait; the
    # default's never does, written out in the file or not (review 93)
    settle_own: bool = False
    noise_deg: float = 2.0
    az_span_deg: float = 360.0
    nominal_speed_deg_s: float = 6.0
    # the elevation's nominal speed (the settings' el_speed_deg_s, else the model's); None: the
    # model's (``spec.nominal_el_speed_deg_s``); read where an axis is timed on its own (rule 4)
    el_speed_deg_s: float | None = None
    stop_resend_s: float = 2.0  # a stop that did not take is sent again after this long
    poll_margin_s: float = 0.2  # readings while moving come this often (rule 4)
    # rule 10: the raw limits each axis is held to (pointing.py rule 4's, the judge's)
    az_limits_deg: tuple[float, float] = (-math.inf, math.inf)
    el_limits_deg: tuple[float, float] = (-math.inf, math.inf)

    @property
    def can_report_position(self) -> bool:
        return self.spec.can_report_position

    @property
    def az_wraps(self) -> bool:
        return self.spec.az_wraps

    @property
    def away_deg(self) -> float:
        """Rule 5: how far beyond the closest it came a reading is "away" (tolerance, noise and
        AWAY_MARGIN_DEG): a turn away, a pass, a turn back; a reading's least reach."""
        return self.tolerance_deg + self.noise_deg + AWAY_MARGIN_DEG

    @property
    def direct_retarget(self) -> bool:
        """The controller takes a new target while turning (SPID)."""
        return self.spec.retarget is RetargetPolicy.DIRECT


#: rule 5, one axis's watch once it came to its target: its closest error since, the error
#: of a first reading away (or None), and the way it was turning when it came (1 or -1) until
#: a movement after it turned on that way (0: sure)
Watch = tuple[float, float | None, int]
#: rule 5, a wrapping azimuth's watch on its way to the target: its movements in a row that
#: closed in on it (two at most: two, it heads for it), its closest error since the first of
#: them, and the error of a first movement back (or None)
Back = tuple[int, float, float | None]
#: rule 10: the axis that turned on past its limit ("azimuth" or "elevation"), its reading
#: and that limit (the controller's values), and the limit's setting
Past = tuple[str, float, float, str]


@dataclass(frozen=True)
class Motion:
    state: MotionState = MotionState.OFFLINE
    position_deg: float | None = None
    anchor_deg: float | None = None
    last_move_t: float | None = None
    changed_t: float | None = None  # last reading that differed at all from the one before
    still_since_t: float | None = None
    target_deg: float | None = None
    target_t: float | None = None
    progress_t: float | None = None  # last movement while a target is active (either axis)
    # rule 3: each axis's last movement (from its own ``az_from_deg``/``el_from_deg``) while a
    # target is active
    az_progress_t: float | None = None
    el_progress_t: float | None = None
    stalled: str | None = None  # rule 3: the axis the last stall was of ("azimuth", "elevation")
    undriven: str | None = None  # rule 3: the axis whose frame of the target was refused
    idle_not_before_t: float | None = None
    stop_sent_t: float | None = None
    stop_read_t: float | None = None  # the first reading after the last stop (``stop_again``)
    busy_until_t: float | None = None  # no feedback: when the last move is assumed done
    assumed_deg: float | None = None  # no feedback: where the last move should have ended
    # elevation, for az/el controllers; movement on either axis is movement
    el_position_deg: float | None = None
    el_anchor_deg: float | None = None
    el_target_deg: float | None = None
    closest_err: float | None = None  # rule 5: the least error seen since the target went out
    away_err: float | None = None  # rule 5: the last reading's error, if already turned away
    # rule 5, each axis: since a reading showed it come to its target, its closest error
    # since and the error of a first reading away (None: not come to it)
    az_pass: Watch | None = None
    el_pass: Watch | None = None
    az_back: Back | None = None  # rule 5: a wrapping azimuth on its way, until it came
    back_from_t: float | None = None  # rule 5: its watch starts then (a target mid-turn)
    # rule 5, each axis: where it last moved (more than noise_deg from its own last movement)
    # since the target went out: the shared anchor of rule 1 moves with either axis
    az_from_deg: float | None = None
    el_from_deg: float | None = None
    past: Past | None = None  # rule 10: the limit the last target's turn went past, if it did
    lost_turning: bool = False  # rule 4: its readings were lost while it turned (link_down)
    # rule 4: the turn under way is the one taken for turning when the readings came back (the
    # controller finishing a turn by itself, its target dropped with the port), till it rests
    carried: bool = False
    lost_hand: bool = False  # rule 4: the turn lost was a hand's, seen begin with the link up
    # rule 4: readings back for ``carried_seen_s`` and none showed the lost turn move: it came
    # to rest meanwhile, and a turn seen after that is not known to be that one
    lost_still: bool = False
    # rule 4: when the first reading since the link came up was taken (a restart's found turn
    # is judged from it, as a lost one is)
    first_read_t: float | None = None
    # rule 4: the axes ("azimuth", "elevation") a reading since the first has shown still for
    # their own ``axis_seen_s``: a lost (or found) turn is not theirs, a move of theirs after
    # that is a turn begun since
    still_axes: frozenset[str] = frozenset()
    # rule 4: a start refused while that turn was not yet seen owes it a halt (parts.py rule
    # 10, kept by the session at every step: ``halt_owed``); meanwhile a move only on axes in
    # ``still_axes`` is a turn begun since only once a later reading confirms it
    owes_halt: bool = False
    # rule 4: when a reading showed such a move, not yet confirmed (a hand's turn, or a
    # garbled reading): that reading was held back, neither a move nor a rest, nor shown
    begun_t: float | None = None
    # rule 6 (no feedback): the end of the last turn of the bridge's, assumed or stopped
    # (``turn_kept``)
    kept_end_t: float | None = None
    # rule 4: that reading's azimuth and elevation: a hand's turn moves on from them the way
    # they moved (a garble read again stays where it was)
    begun_deg: tuple[float, float | None] | None = None
    # rule 4: the last reading held back (``held_back``): the first, or one after it that
    # neither confirmed the move nor showed the axes where they stood
    held_t: float | None = None
    # rule 2: while ``carried``, each axis's own last movement (more than ``noise_deg`` from
    # where that axis itself last moved; rule 1's anchor moves with either axis), the
    # farthest its readings crept from there since, inside ``noise_deg``, and when the last
    # move or creep as fast as a turn was, from the first reading back (None: an axis with
    # nothing to do in the lost turn, not seen move): the carried turn rests by each axis's
    # own time
    az_moved_deg: float | None = None
    az_moved_t: float | None = None
    el_moved_deg: float | None = None
    el_moved_t: float | None = None
    az_crept_deg: float = 0.0
    el_crept_deg: float = 0.0
    # rule 2: each axis's last creep (or, not crept since it moved, its last reading): the
    # next creep's speed is measured from it
    az_crept_t: float | None = None
    el_crept_t: float | None = None
    # rule 2: the target out when the readings were lost (``link_down``; its azimuth and
    # elevation), kept till the first reading back: an axis it leaves where it stands has
    # nothing to do in the turn carried, and that turn's rest waits no time of its own
    lost_aim: tuple[float, float | None] | None = None


class Event(enum.StrEnum):
    ARRIVED = "arrived"
    STALLED = "stalled"
    STOPPED = "stopped"
    REFUSED = "refused"  # rule 8
    TURNED_AWAY = "turned away"
    PASSED = "passed"  # rule 5: turned on past its target
    TURNED_BACK = "turned back"  # rule 5: a wrapping azimuth turned back on its way
    PAST_LIMIT = "past limit"  # rule 10: turned on beyond a limit while a target was out
    RESTARTED = "restarted"  # rule 11: the controller said it restarted while a turn was out
    HALTED = "halted"  # rule 12: the controller says it drives no motor, the rotor still short


class Plan(enum.StrEnum):
    SEND = "send"  # write the target now
    STOP_FIRST = "stop_first"  # the rotor turns: stop it, then wait
    WAIT = "wait"  # brake delay or a stop in progress: keep the target pending


angle_error = apart_deg  # (core/geo.py: a reading past 360 on a wrapping box on the circle)


def settle_for(
    settle_s: float, noise_deg: float, step_deg: float, slowest_deg_s: float, poll_s: float
) -> float:
    """Rule 2: the settle time a rotor whose readings move in ``step_deg`` steps needs at
    ``slowest_deg_s`` (its slower axis), at least ``settle_s``."""
    if slowest_deg_s <= 0:
        return settle_s
    return max(settle_s, (noise_deg + step_deg) / slowest_deg_s + poll_s)


def stop_checked(m: Motion) -> Motion:
    """stops.py rule 2: the last stop was had (a reading showed the rotor still after it):
    nothing more to check of it (controller.py ``lock_released``)."""
    return replace(m, stop_sent_t=None)


def found_unjudged(m: Motion) -> bool:
    """Rule 4: a bridge just started, its first reading taken, and its readings have not yet
    shown whether the rotor turns (a move; none on each axis for its own ``axis_seen_s``, or
    at rest sooner by a ``settle_s`` of the user's, ``tick``): it is asked at the moving rate
    meanwhile (controller.py), so that a
    turn found is told from a hand's later one at once on every controller (a Rot2Prog's idle
    poll is 6 s)."""
    return m.carried and m.state is not MOVING and m.state is not OFFLINE


def axis_seen_s(cfg: MotionConfig) -> dict[str, float]:
    """Rule 4: how long after the first reading back a turn lost with the link on each axis the
    controller turns, were it still on, shows a move (more than ``noise_deg`` and a reading's
    step, at that axis's nominal speed as slow as rule 6 allows for) at a reading: none by
    then, that axis came to rest while its port was out, though rule 2 calls it still only
    ``settle_s`` on. Each axis by its own speed (rule 3's way; review 84: a GS-232's
    elevation-only turn, timed at the azimuth's speed, taken for none; review 89: an azimuth
    timed at the elevation's, a hand at it a second after a replug taken for the lost turn)."""
    step = cfg.noise_deg + cfg.spec.reading_step_deg
    seen = {axis: step / speed + cfg.poll_margin_s for axis, speed in slowest_deg_s(cfg).items()}
    return seen or {
        "azimuth": BLIND_SLOW_FACTOR * step / cfg.nominal_speed_deg_s + cfg.poll_margin_s
    }


def slowest_deg_s(cfg: MotionConfig) -> dict[str, float]:
    """Rules 2 and 4: the speed each axis the controller turns turns at its slowest: its
    nominal speed (the elevation's as configured) as slow as rule 6 allows for."""
    spec, speeds = cfg.spec, {}
    if spec.turns_azimuth:
        speeds["azimuth"] = cfg.nominal_speed_deg_s
    if spec.has_elevation:
        el = cfg.el_speed_deg_s
        speeds["elevation"] = spec.nominal_el_speed_deg_s if el is None else el
    return {axis: speed / BLIND_SLOW_FACTOR for axis, speed in speeds.items() if speed > 0}


def carried_seen_s(cfg: MotionConfig) -> float:
    """Rule 4: by when the readings back have shown a lost (or found) turn on every axis, were
    it on: the slowest axis's ``axis_seen_s``."""
    return max(axis_seen_s(cfg).values())


def _judged(
    m: Motion,
    cfg: MotionConfig,
    now: float,
    moved: tuple[bool, bool],
    where: tuple[float, float | None],
) -> dict[str, Any]:
    """Rule 4: what a reading at ``now`` (``where``: its azimuth and elevation; ``moved``:
    which of them moved) tells of a turn lost with the link (``lost_turning``, the rotor taken
    for turning) or found by a bridge just started (``found_unjudged``): a move on an axis not
    yet shown still for its own ``axis_seen_s`` is that turn, seen; a move only on axes that
    were is a turn begun since (not the lost one: ``lost_still``; not the found one: no
    longer ``carried``), while a refused start's halt is owed only once a later reading
    confirms it (``_confirms``; ``begun_t``: held back till then, reviews 93 and 95); a
    reading with no move shows each axis still whose own time is over, and the turn over (or
    none) once every axis is (review 89: the slowest axis's time for every axis stopped a
    hand at a GS-232B's azimuth a second after a replug)."""
    lost = m.state is MOVING
    az_moved, el_moved = moved
    held: dict[str, Any] = (  # (told now)
        {} if m.begun_t is None else {"begun_t": None, "begun_deg": None, "held_t": None}
    )
    if az_moved or el_moved:
        if (az_moved and "azimuth" not in m.still_axes) or (
            el_moved and "elevation" not in m.still_axes
        ):
            return held  # (the turn seen, as it was taken for)
        if owed_halt(m):  # (a halt owed: a reading that only jumps is no hand's)
            if m.begun_t is None:
                return {"begun_t": now, "begun_deg": where, "held_t": now}
            if not _confirms(m, cfg, now, where):
                return {"held_t": now}  # (held back too: a garble read again, or a slow hand)
        return {**held, "lost_still": True} if lost else {**held, "carried": False}
    first = m.first_read_t if m.first_read_t is not None else now
    seen = axis_seen_s(cfg)
    still = m.still_axes | {axis for axis, s in seen.items() if now - first >= s}
    if still == m.still_axes:
        return held
    if not still.issuperset(seen):
        return {**held, "still_axes": still}
    done = {**held, "still_axes": still}
    return {**done, "lost_still": True} if lost else {**done, "carried": False}


def _confirms(m: Motion, cfg: MotionConfig, now: float, where: tuple[float, float | None]) -> bool:
    """Rule 4: whether a reading at ``now`` (``where``), still showing a move only on decided
    axes from where they stood, confirms the one held back since ``begun_t`` as a hand's turn:
    an axis that moved in it reads on from it the way it moved by more than ``noise_deg`` (a
    hand turns on; the same garble read again stays within the axis's noise: review 95,
    "EL=014" for 010 in two readings in a row dropped the owed halt, and review 101, "EL=015"
    for 011 on a still elevation wandering a degree between them did so again), or
    the move has lasted that axis's own ``axis_seen_s`` (a hand slower than a degree a
    reading, or one that stopped: the move is the rotor's)."""
    if m.begun_t is None or m.begun_deg is None:
        return True
    wraps, noise, seen = cfg.spec.az_wraps, cfg.noise_deg, axis_seen_s(cfg)
    (az0, el0), (az, el) = m.begun_deg, where
    axes: list[tuple[str, float, float, float, bool]] = []
    if m.anchor_deg is not None:
        axes.append(("azimuth", m.anchor_deg, az0, az, wraps))
    if m.el_anchor_deg is not None and el0 is not None and el is not None:
        axes.append(("elevation", m.el_anchor_deg, el0, el, False))
    for axis, stood, then, read, wrap in axes:
        way = then - stood
        if wrap:
            way = (way + 180.0) % 360.0 - 180.0
        if abs(way) <= noise:
            continue  # (this axis did not move in the reading held back)
        if now - m.begun_t >= seen.get(axis, 0.0):
            return True
        on = read - then
        if wrap:
            on = (on + 180.0) % 360.0 - 180.0
        if on * way > 0 and abs(on) > noise:
            return True
    return False


def owed_halt(m: Motion) -> bool:
    """Rule 4: a refused start's halt is owed to the turn under judgement (``owes_halt``, as
    parts.py rule 10's ``StartHalt.owed`` keeps it: no target, no stop sent since)."""
    return m.owes_halt and m.target_deg is None and m.stop_sent_t is None


def halt_owed(m: Motion, owed: bool) -> Motion:
    """Rule 4: the session says a refused start's halt is owed to the turn under judgement
    (parts.py rule 10), or no longer (the start's part ended)."""
    if m.owes_halt is owed:
        return m
    if owed:
        return replace(m, owes_halt=True)
    return replace(m, owes_halt=False, begun_t=None, begun_deg=None, held_t=None)


def held_back(m: Motion, now: float) -> bool:
    """Rule 4: the reading just taken at ``now`` was held back (a move only on axes decided
    still while a halt is owed, a later reading to confirm it): nothing of it is shown."""
    return m.held_t == now


# -- observations ----------------------------------------------------------------------------
def blind_busy_s(travel_deg: float, cfg: MotionConfig) -> float:
    """Rule 6: how long a turn of ``travel_deg`` is assumed to last without feedback."""
    return BLIND_SLOW_FACTOR * travel_deg / cfg.nominal_speed_deg_s + BLIND_START_S


def link_up(m: Motion, cfg: MotionConfig, now: float) -> Motion:
    if not cfg.can_report_position:
        # rule 6: we cannot know whether it is still turning or braking: assume the worst once,
        # as generously as a turn sent, and never sooner than the end assumed before
        worst = now + blind_busy_s(cfg.az_span_deg, cfg)
        kept = m.busy_until_t
        busy = worst if kept is None else max(kept, worst)
        # (a turn lost with the port, or one the run before kept in flight, controller.py
        # ``keep_turn``: review 89; not every first connect, review 93)
        lost, end = m.lost_turning, m.kept_end_t
        if lost:
            end = busy if end is None else max(end, busy)  # (turn_kept: from its time)
        return Motion(state=UNKNOWN, busy_until_t=busy, lost_turning=lost, kept_end_t=end)
    return Motion(
        state=OFFLINE,
        position_deg=m.position_deg,
        el_position_deg=m.el_position_deg,
        lost_turning=m.lost_turning,
        lost_hand=m.lost_hand,
        lost_aim=m.lost_aim,
    )


def link_down(m: Motion) -> Motion:
    """The readings lost (the port closed, the controller silent): whether it was turning, or
    had a target out, is kept for the first reading back (rule 4)."""
    turning = m.state is MOVING or m.target_deg is not None or m.el_target_deg is not None
    hand = m.state is MOVING and m.target_deg is None and m.stop_sent_t is None and not m.carried
    aim = m.lost_aim if m.anchor_deg is None else None  # (rule 2: lost before, nothing read)
    if m.target_deg is not None:
        aim = (m.target_deg, m.el_target_deg)
    return Motion(
        state=OFFLINE,
        position_deg=m.position_deg,
        el_position_deg=m.el_position_deg,
        lost_turning=turning or m.lost_turning,
        lost_hand=hand or (m.lost_hand and m.state is OFFLINE),
        busy_until_t=m.busy_until_t,  # rule 6: no feedback: the turn's assumed end is kept
        kept_end_t=m.kept_end_t,  # (rule 6: turn_kept)
        lost_aim=aim,
    )


def track_lost(m: Motion, cfg: MotionConfig) -> Motion:
    """Readings were missed (a silent controller's after-move report was lost): whether and
    where the rotor moved since is unknown, so the next reading is taken like the first one
    after a connect (rule 4). Until it comes the rotor is braking (it was just stopped), or,
    without a brake, in a state the bridge cannot tell."""
    state = BRAKING if cfg.brake_delay_s > 0 else UNKNOWN
    return Motion(state=state, position_deg=m.position_deg, el_position_deg=m.el_position_deg)


def slew_ended(m: Motion, now: float) -> Motion:
    """A slew the controller was silent through ended without a readable report: the rotor was
    turning all along where no reading could show it, so the stall clock and the settling
    count start now. The reading asked for at once decides arrival (or a real stall)."""
    if m.state is not MOVING:
        return m
    t = now if m.target_deg is not None else None
    return replace(m, last_move_t=now, progress_t=t, az_progress_t=t, el_progress_t=t)


def at_target(m: Motion, cfg: MotionConfig) -> bool:
    """Within ``tolerance_deg`` of the target by the last reading: no stall can come (rule 3);
    the reading that finds it still says it arrived."""
    err = target_error(m, cfg)
    return err is not None and err <= cfg.tolerance_deg


def target_error(m: Motion, cfg: MotionConfig) -> float | None:
    """How far the rotor is from its target (the worse axis), or None if unknown."""
    if m.target_deg is None or m.position_deg is None:
        return None
    err = angle_error(m.position_deg, m.target_deg, cfg.az_wraps)
    if m.el_target_deg is not None and m.el_position_deg is not None:
        err = max(err, abs(m.el_position_deg - m.el_target_deg))
    return err


def reading(
    m: Motion,
    cfg: MotionConfig,
    az_deg: float,
    now: float,
    el_deg: float | None = None,
    asked_t: float | None = None,
) -> tuple[Motion, list[Event]]:
    """A reading taken at ``now``, answering a question that went out at ``asked_t`` (None:
    at ``now``; rule 3)."""
    asked = now if asked_t is None else asked_t
    if m.anchor_deg is None:
        # first reading since the link came up: the brake window may still be running; where
        # the rotor turned when its readings were lost, it turns from this reading until
        # readings show it still (rule 2), not still by the clock (rule 4)
        turning = m.lost_turning  # (kept till a reading shows it move, or rest: plan_target)
        # (a turn found going on with nothing known of before it, the bridge restarted, is the
        # controller's too, until the rotor is seen at rest; a hand's turn lost is a hand's)
        fresh = m.position_deg is None
        # (rule 2: an axis the lost target leaves where it stands waits no time of its own)
        az_idle, el_idle = _nothing_to_do(m, cfg, az_deg, el_deg)
        m = replace(
            m,
            state=MOVING if turning else BRAKING if cfg.brake_delay_s > 0 else IDLE,
            position_deg=az_deg,
            anchor_deg=az_deg,
            el_position_deg=el_deg,
            el_anchor_deg=el_deg,
            last_move_t=now if turning else m.last_move_t,
            carried=(turning and not m.lost_hand) or fresh,
            lost_hand=False,
            first_read_t=now,
            still_axes=frozenset(),
            begun_t=None,
            begun_deg=None,
            held_t=None,
            az_moved_deg=az_deg,  # (rule 2: each axis's own rest counts from here)
            az_moved_t=None if az_idle else now,
            el_moved_deg=el_deg,
            el_moved_t=None if el_deg is None or el_idle else now,
            lost_aim=None,
            az_crept_deg=0.0,
            el_crept_deg=0.0,
            az_crept_t=now,
            el_crept_t=None if el_deg is None else now,
            still_since_t=None if turning else now,
            idle_not_before_t=None if turning else now + cfg.settle_s,
            stop_read_t=now if m.stop_sent_t is not None else m.stop_read_t,  # (an owed stop's)
        )
        return tick(m, cfg, now, read=True, asking_since=None, asked_t=asked)
    anchor_deg = m.anchor_deg  # (not None: the first reading returned above)
    before = m  # (rule 5 compares this reading with the one before)
    # one replace() per reading: this runs at every poll (its changes as literals, no update)
    changes: dict[str, Any] = (
        {"changed_t": now, "position_deg": az_deg, "el_position_deg": el_deg}
        if az_deg != m.position_deg or el_deg != m.el_position_deg
        else {}
    )
    wraps = cfg.spec.az_wraps  # (asked twice: no property call)
    az_moved = angle_error(az_deg, anchor_deg, wraps) > cfg.noise_deg
    el_moved = (
        el_deg is not None
        and m.el_anchor_deg is not None
        and abs(el_deg - m.el_anchor_deg) > cfg.noise_deg
    )
    moved = az_moved or el_moved
    if (m.lost_turning and not m.lost_still and m.state is MOVING) or found_unjudged(m):
        # rule 4: each axis its own
        judged = _judged(m, cfg, now, (az_moved, el_moved), (az_deg, el_deg))
        if judged.get("held_t") == now:  # (held back till a later reading confirms it: no
            m = replace(m, **judged)  # move, no rest told by it, nothing shown of it)
            return tick(m, cfg, now, asking_since=None)
        changes.update(judged)
    if m.carried:  # rule 2: each axis's own movement and creep, for the carried turn's rest
        ref = m.az_moved_deg
        off = cfg.noise_deg + 1.0 if ref is None else angle_error(az_deg, ref, wraps)
        _own_move(changes, cfg, now, "az", off, az_deg, m.az_crept_deg, m.az_crept_t)
        ref = m.el_moved_deg
        if el_deg is not None:
            off = cfg.noise_deg + 1.0 if ref is None else abs(el_deg - ref)
            _own_move(changes, cfg, now, "el", off, el_deg, m.el_crept_deg, m.el_crept_t)
    sent_t, read_t = m.stop_sent_t, m.stop_read_t
    if sent_t is not None and (read_t is None or read_t <= sent_t):
        changes["stop_read_t"] = now  # (stop_again: it shows where the rotor was at the stop)
    if moved:
        changes["anchor_deg"], changes["el_anchor_deg"] = az_deg, el_deg
        changes["last_move_t"], changes["still_since_t"] = now, None
        changes["state"] = MOVING
        if m.lost_turning:  # (rule 4: a reading shows it turning, as it was taken for)
            changes["lost_turning"] = False
        if m.target_deg is not None:
            changes["progress_t"] = now
    if m.target_deg is not None:  # rule 3: each axis's own progress, from where it last moved
        ref = m.az_from_deg if m.az_from_deg is not None else m.position_deg
        if ref is not None:  # (measured as ``_passing`` moves ``az_from_deg``: the same float)
            step = az_deg - ref
            if wraps:
                step = (step + 180.0) % 360.0 - 180.0
            if abs(step) > cfg.noise_deg:
                changes["az_progress_t"] = now
        ref = m.el_from_deg if m.el_from_deg is not None else m.el_position_deg
        if el_deg is not None and ref is not None and abs(el_deg - ref) > cfg.noise_deg:
            changes["el_progress_t"] = now
    if changes:
        m = _with(m, changes)
    if moved and m.target_deg is not None:  # rule 10
        past = _past_limit(before, m, cfg)
        if past is not None:
            m, events = tick(
                _dropped(replace(m, past=past)),
                cfg,
                now,
                read=True,
                asking_since=None,
                asked_t=asked,
            )
            return m, [Event.PAST_LIMIT, *events]
    if m.target_deg is not None:
        m, passed = _passing(before, m, cfg, now)
        if passed is not None:  # rule 5
            m, events = tick(_dropped(m), cfg, now, read=True, asking_since=None, asked_t=asked)
            return m, [passed, *events]
    if m.target_deg is not None and not wraps:
        err = target_error(m, cfg)
        if err is not None:
            away = m.closest_err is not None and err > m.closest_err + cfg.away_deg
            if m.closest_err is None or err < m.closest_err:
                m = replace(m, closest_err=err, away_err=None)
            elif not away or not moved:
                if m.away_err is not None and not away:
                    m = replace(m, away_err=None)
            elif m.away_err is None or err <= m.away_err:
                m = replace(m, away_err=err)  # the first reading away: one more must follow
            else:
                m, events = tick(_dropped(m), cfg, now, read=True, asking_since=None, asked_t=asked)
                return m, [Event.TURNED_AWAY, *events]
    return tick(m, cfg, now, read=True, asking_since=None, asked_t=asked)


def _nothing_to_do(
    m: Motion, cfg: MotionConfig, az_deg: float, el_deg: float | None
) -> tuple[bool, bool]:
    """Rule 2: whether the first reading back (``az_deg``, ``el_deg``) shows the azimuth and
    the elevation with nothing to do in the turn the controller carries on by itself (a turn
    of the bridge's lost with the link, ``lost_aim``, not a hand's): the target left that axis
    out, or it stands within ``tolerance_deg`` of it. Such an axis is not waited on at the
    carried turn's rest till it is seen move (review 110: an azimuth-only turn jammed a second
    after a replug waited a slow elevation's own time, 3.9 s, not the azimuth's 1.7 s)."""
    aim = m.lost_aim
    if aim is None or not m.lost_turning or m.lost_hand:
        return False, False
    az, el = aim
    tol = cfg.tolerance_deg
    az_idle = along_travel(az_deg, az, cfg) <= tol  # (179 and 181 on a Hy-Gain: a turn apart)
    el_idle = el is None or (el_deg is not None and abs(el_deg - el) <= tol)
    return az_idle, el_idle


def _own_move(
    changes: dict[str, Any],
    cfg: MotionConfig,
    now: float,
    axis: str,
    off: float,
    deg: float,
    crept: float,
    crept_t: float | None,
) -> None:
    """Rule 2: what a reading of a carried turn's axis (``axis``: "az" or "el"; ``off``: how
    far it is from where that axis last moved, ``deg``) tells of that axis's own movement: more
    than ``noise_deg``, a move (its own time starts again from here); further than any reading
    since inside ``noise_deg`` (it creeps), a move only if it crept at least CREEP_SHARE of
    what the axis turns at its slowest (``slowest_deg_s``) since its last creep (the first
    creep since a move: since the reading before). A creep slower than any turn is no turn
    (review 110: a jammed RC2800's pot drifting a tenth every 1.2 s kept the turn 'moving' for
    ever, no stop). Jitter back and forth counts once at most."""
    if off > cfg.noise_deg:
        changes[f"{axis}_moved_deg"], changes[f"{axis}_moved_t"] = deg, now
        changes[f"{axis}_crept_deg"], changes[f"{axis}_crept_t"] = 0.0, now
        return
    if off <= crept:
        if crept == 0.0:  # (not crept since it moved: a first creep is timed from here)
            changes[f"{axis}_crept_t"] = now
        return
    changes[f"{axis}_crept_deg"], changes[f"{axis}_crept_t"] = off, now
    slowest = slowest_deg_s(cfg).get("azimuth" if axis == "az" else "elevation")
    dt = None if crept_t is None else now - crept_t
    if slowest is None or not dt or off - crept >= CREEP_SHARE * slowest * dt:
        changes[f"{axis}_moved_t"] = now  # (a creep as fast as a turn: its first degrees)


def _past_limit(before: Motion, m: Motion, cfg: MotionConfig) -> Past | None:
    """Rule 10: the axis ``m``'s reading shows turned on outward beyond a limit (the
    elevation's first), or None: this reading and the one before both more than ``margin``
    past the limit, this one further out and more than ``noise_deg`` from where the axis last
    moved."""
    spec, margin, noise = cfg.spec, cfg.tolerance_deg + cfg.noise_deg, cfg.noise_deg
    axes = []
    if spec.has_elevation:
        el = before.el_position_deg, m.el_position_deg, m.el_from_deg, cfg.el_limits_deg
        axes.append(("elevation", "el", *el))
    if spec.turns_azimuth and not spec.az_wraps:
        az = before.position_deg, m.position_deg, m.az_from_deg, cfg.az_limits_deg
        axes.append(("azimuth", "az", *az))
    for axis, key, last, pos, since, (low, high) in axes:
        if last is None or pos is None or since is None:
            continue
        if pos > last > high + margin and pos - since > noise:
            return axis, pos, high, f"{key}_max_deg"
        if pos < last < low - margin and since - pos > noise:
            return axis, pos, low, f"{key}_min_deg"
    return None


def _dropped(m: Motion) -> Motion:
    """Rule 5: the target dropped, the rotor still turning (someone else's move now)."""
    return replace(
        m,
        target_deg=None,
        el_target_deg=None,
        target_t=None,
        progress_t=None,
        az_progress_t=None,
        el_progress_t=None,
        closest_err=None,
        away_err=None,
        az_pass=None,
        el_pass=None,
        az_back=None,
    )


def _passing(
    before: Motion, m: Motion, cfg: MotionConfig, now: float
) -> tuple[Motion, Event | None]:
    """Rule 5, each axis on its own: whether the reading just taken (``m``'s; ``before``, the
    motion as it was) shows the rotor come to that axis's target, and whether an axis that
    came has turned on past it (two readings in a row further than its closest since, by
    more than ``tolerance_deg + noise_deg`` + AWAY_MARGIN_DEG, each a movement: PASSED), or a
    wrapping azimuth that headed for it has turned back on its way (``_back``: TURNED_BACK)."""
    tol, noise, far = cfg.tolerance_deg, cfg.noise_deg, cfg.away_deg
    reach = reach_deg(before, cfg, now)
    wraps = cfg.spec.az_wraps
    axes = (
        (m.az_from_deg, before.position_deg, m.position_deg, m.target_deg, wraps, m.az_pass),
        (
            m.el_from_deg,
            before.el_position_deg,
            m.el_position_deg,
            m.el_target_deg,
            False,
            m.el_pass,
        ),
    )
    watched: list[Watch | None] = []
    froms: list[float | None] = []
    back = m.az_back
    for anchor, last, pos, target, wrap, watch in axes:
        if last is None or pos is None or target is None:
            watched.append(watch)
            froms.append(anchor)
            continue
        if anchor is None:
            anchor = last  # (the target went out with no reading of this axis)
        if apart_deg(last, pos, wrap) > reach:  # a corrupt reading: nothing to judge by
            return m, None
        step = pos - anchor  # (since this axis last moved, signed)
        if wrap:
            step = (step + 180.0) % 360.0 - 180.0
        moved = abs(step) > noise
        heading = 1 if step > 0 else -1
        froms.append(pos if moved else anchor)
        if watch is not None and watch[2] and moved and heading != watch[2]:
            watch = None  # it came, then turned back: that reading was none to judge by
        a, err = apart_deg(anchor, target, wrap), apart_deg(pos, target, wrap)
        if watch is None:
            came = moved and (
                (err <= tol and err < a)  # closing in on it
                or (a > 0.0 and err > 0.0 and abs(step) >= a + err - 1e-9)
            )  # (or gone over it: it lies between the last movement and this one)
            watched.append((err, None, heading) if came else None)
            if wrap and (m.back_from_t is None or now >= m.back_from_t):  # (only the azimuth)
                back = None if came else _back(back, moved, a, err, far)
                if back is not None and back[2] is not None and err > back[2]:
                    return m, Event.TURNED_BACK
            continue
        closest, away, pending = watch[0], watch[1], watch[2] if not moved else 0
        if err < closest:
            watched.append((err, None, pending))
        elif err <= closest + far:
            watched.append((closest, None, pending))
        elif not moved:  # (then pending is the watch's: a reading away counts once it moves)
            watched.append(watch)
        elif away is None or err <= away:
            watched.append((closest, err, 0))  # the first reading away: one more must follow
        else:
            return m, Event.PASSED
        if wrap:
            back = None  # (it came: the watch above judges it)
    az_pass, el_pass = watched
    az_from, el_from = froms
    if (az_pass, el_pass, az_from, el_from, back) != (
        m.az_pass,
        m.el_pass,
        m.az_from_deg,
        m.el_from_deg,
        m.az_back,
    ):
        m = replace(
            m,
            az_pass=az_pass,
            el_pass=el_pass,
            az_from_deg=az_from,
            el_from_deg=el_from,
            az_back=back,
        )
    return m, None


def reach_deg(m: Motion, cfg: MotionConfig, now: float, since_t: float | None = None) -> float:
    """Rule 5: how far a reading at ``now`` can be from ``m``'s last on either axis: three
    times the larger of the two nominal speeds over the time since the later of the last
    reading that changed and the target (``since_t`` if given: controller.py rule 9 measures
    from the reading it compares with), plus ``tolerance_deg + noise_deg`` + AWAY_MARGIN_DEG;
    one further is corrupt."""
    t0 = max(m.changed_t or -math.inf, m.target_t or -math.inf) if since_t is None else since_t
    dt = now - t0 if t0 > -math.inf else 0.0
    return top_speed_deg_s(cfg) * dt + cfg.away_deg


def top_speed_deg_s(cfg: MotionConfig) -> float:
    """Rule 5: the fastest a rotor is taken to turn on either axis, its speed-up bound over the
    nominal speeds (REACH_FACTOR times the larger of the two): what it can have turned between
    two readings (``reach_deg``; controller.py rule 9's first readings on one line, ``_steady``)."""
    return REACH_FACTOR * max(cfg.nominal_speed_deg_s, cfg.spec.nominal_el_speed_deg_s)


def _back(back: Back | None, moved: bool, a: float, err: float, far: float) -> Back | None:
    """Rule 5, a wrapping azimuth on its way to its target (``a``: its error where it last
    moved, ``err``: now; ``moved``: more than ``noise_deg`` since). Two movements in a row
    that close in on the target say it heads for it (a way round a stop that leads away first
    heads for it later, or never: nothing to judge by; one corrupt reading closes in once, and
    the true one after it goes away again); then a movement away by more than ``far`` beyond
    the closest it came is a first one back, and a second further still is the turn back (the
    caller's). A movement away before it heads for the target starts the count again."""
    if not moved or err == a:
        return back
    closings, closest, away = back if back is not None else (0, a, None)
    if err < a:  # closing in
        return (min(closings + 1, 2), min(closest, err) if closings else err, None)
    if closings < 2:
        return None  # (not heading for it yet)
    if err <= closest + far:
        return (closings, closest, None)
    return (closings, closest, err if away is None or err <= away else away)


def _with(m: Motion, changes: dict[str, Any]) -> Motion:
    """``replace(m, **changes)``, less its checks and its frozen ``__init__`` (an
    ``object.__setattr__`` per field, 20 of them), at every reading that changed something:
    Motion has no slots, no ``__post_init__`` and every field is one of its ``__init__``'s,
    so its ``__dict__`` is all of them, in their order (tests/engine/test_motion.py)."""
    new = _new(Motion)
    fields = new.__dict__
    fields.update(m.__dict__)
    fields.update(changes)
    return new


_new = object.__new__


def commanded(
    m: Motion, cfg: MotionConfig, target_deg: float, now: float, el_target_deg: float | None = None
) -> Motion:
    if not cfg.can_report_position:
        start = m.assumed_deg
        # (no wrap past the stop; the farther way where the stop is not known to be at north)
        travel = cfg.az_span_deg if start is None else along_travel(start, target_deg, cfg)
        busy = blind_busy_s(travel, cfg)  # rule 6: generous
        return replace(
            m,
            target_deg=target_deg,
            target_t=now,
            busy_until_t=now + busy,
            assumed_deg=target_deg,
            stop_sent_t=None,
            lost_turning=False,  # (rule 6: a turn of its own now)
            # (rule 6: turn_kept, for a turn over the whole range at the slowest, from now: a
            # hand at the panel since may have left it anywhere; review 97)
            kept_end_t=now + blind_busy_s(cfg.az_span_deg, cfg),
        )
    return replace(
        m,
        state=MOVING,
        target_deg=target_deg,
        el_target_deg=el_target_deg,
        target_t=now,
        progress_t=now,
        az_progress_t=now,
        el_progress_t=now,
        stalled=None,
        undriven=None,
        stop_sent_t=None,
        still_since_t=None,
        carried=False,  # (the bridge's own turn now: a review)
        closest_err=None,
        az_pass=_there(m.position_deg, target_deg, cfg, azimuth=True),
        el_pass=_there(m.el_position_deg, el_target_deg, cfg),
        az_from_deg=m.position_deg,
        el_from_deg=m.el_position_deg,
        past=None,
        away_err=None,
        az_back=None,
        # rule 5: sent while it turns, the readings of twice the settle time may be of the way
        # it was going (a reply on its way, a coast): the watch starts after them
        back_from_t=now + 2 * cfg.settle_s if m.state is MOVING else None,
    )


def _there(
    pos: float | None, target: float | None, cfg: MotionConfig, *, azimuth: bool = False
) -> Watch | None:
    """Rule 5: an axis already at its target when it goes out (within ``noise_deg``: the axis a
    target leaves as it is, an elevation-only move's azimuth) has come to it. Measured along
    the rotor's travel, not round the circle: 359 sent 0 may go the long way round a stop at
    north (a review: that turn was stopped as a pass), and 179 sent 181 goes the long way round
    a Hy-Gain rotor's stop at south (``along_travel``). (Not the straight way within
    ``noise_deg`` of it either: a reading there that may be past the stop makes a blind spot in
    which a turn away from a near target, a garbled one, goes unseen until it stalls: a review.)"""
    if pos is None or target is None:
        return None
    err = along_travel(pos, target, cfg) if azimuth else abs(pos - target)
    return (err, None, 0) if err <= cfg.noise_deg else None


def along_travel(a_deg: float, b_deg: float, cfg: MotionConfig) -> float:
    """Rules 5-6: how far apart two raw azimuths are along the rotor's travel. On the scale, where
    its 0 and 360 are the travel's ends; where they are not known to be (``az_ends_at_north``
    False: a Hy-Gain rotor's stop is at south, an RT-21 turns its own way), the farther of that
    and the way along a travel whose ends are at south (raw 180: either end, counted as the
    farther one). Two readings close on the scale may be a whole turn apart: 179 and 181 on a
    Hy-Gain rotor (an investigation: a sun tracked across south was sent 181 at 179, the rotor
    went the long way round, as it must, and its turn was stopped as a pass)."""
    return travel_deg(a_deg, b_deg, cfg.az_wraps, cfg.spec.az_ends_at_north)


def stop_sent(m: Motion, cfg: MotionConfig, now: float) -> Motion:
    if not cfg.can_report_position:
        # it may have been turning; from now on it is stopping, then braking
        return replace(
            m,
            target_deg=None,
            stop_sent_t=now,
            busy_until_t=now,
            assumed_deg=None,
            lost_turning=False,
            kept_end_t=now if turn_kept(m, now) else m.kept_end_t,  # (rule 6: it ended it)
        )
    return replace(
        m,
        target_deg=None,
        el_target_deg=None,
        progress_t=None,
        az_progress_t=None,
        el_progress_t=None,
        stop_sent_t=now,
        closest_err=None,
        away_err=None,
        az_pass=None,
        el_pass=None,
        az_back=None,
    )


def refused(m: Motion, cfg: MotionConfig, now: float) -> tuple[Motion, list[Event]]:
    """Rule 8: the controller refused a command; whether it was the target that is out."""
    if not cfg.can_report_position or m.target_deg is None or m.state is not MOVING:
        return m, []
    if m.last_move_t is not None and m.target_t is not None and m.last_move_t > m.target_t:
        return m, []  # it moved since: the refusal was of something else
    if m.last_move_t is not None and m.target_t is not None:
        if m.target_t - m.last_move_t <= cfg.settle_s:  # a new bearing refused mid-turn: the
            # rotor still turns to the one before, which nobody wants now (stops.py stops it)
            dropped = replace(
                m,
                target_deg=None,
                el_target_deg=None,
                progress_t=None,
                az_progress_t=None,
                el_progress_t=None,
                closest_err=None,
                away_err=None,
                az_pass=None,
                el_pass=None,
                az_back=None,
            )
            return dropped, [Event.REFUSED]
    return _at_rest(m, cfg, now, BRAKING), [Event.REFUSED]


def forgone(m: Motion, cfg: MotionConfig, now: float) -> Motion:
    """Rule 8: the target out, whose frame did not move the rotor, is given up: at rest as
    after a refusal (nothing if no target is out)."""
    if m.state is not MOVING or (m.target_deg is None and m.el_target_deg is None):
        return m
    return _at_rest(m, cfg, now, BRAKING)


def restarted(m: Motion, cfg: MotionConfig) -> tuple[Motion, list[Event]]:
    """Rule 11: the controller said it restarted; a turn it had is dropped."""
    if not cfg.can_report_position or m.state is not MOVING:
        return m, []
    if m.target_deg is None and m.el_target_deg is None:
        return m, []  # (no turn of the bridge's: the readings say whether it turns)
    return _dropped(m), [Event.RESTARTED]


def halted(m: Motion, cfg: MotionConfig, now: float) -> tuple[Motion, list[Event]]:
    """Rule 12: a reading at ``now`` says the controller drives no motor; a turn it left short,
    the rotor still, is over (its target dropped)."""
    if m.state is not MOVING or now < still_from(m, cfg):
        return m, []
    err = target_error(m, cfg)
    if err is None or err <= cfg.tolerance_deg:
        return m, []  # (at its target: the arrival its reading tells)
    return _dropped(m), [Event.HALTED]


def tick(
    m: Motion,
    cfg: MotionConfig,
    now: float,
    read: bool = False,
    asking_since: float | None = -math.inf,
    asked_t: float = -math.inf,
) -> tuple[Motion, list[Event]]:
    """Time-driven transitions: settling, stall, end of the brake window; the rotor found
    arrived or stopped (``Event.ARRIVED``, ``Event.STOPPED``) only at a reading (``read``:
    rule 2); a stall (rule 3) only at a reading whose question went out at the stall's time
    or later (``asked_t``), or by time while the controller is asked and does not answer:
    ``asking_since`` the first question since its last reply (link.py), at the stall's time
    at the latest; None: nothing asked since (controller.py rule 2)."""
    events: list[Event] = []
    if not cfg.spec.can_report_position:  # (the spec's: no property call at every step)
        done_t = m.busy_until_t if m.stop_sent_t is None else m.stop_sent_t
        if m.target_deg is not None and done_t is not None and now >= done_t + cfg.brake_delay_s:
            m = replace(m, target_deg=None, target_t=None)
        busy = m.busy_until_t  # (None: a turn kept, the port not open yet: its time from
        if m.lost_turning and busy is not None and now >= busy:  # the connect, link_up)
            m = replace(m, lost_turning=False)  # rule 6: the carried turn's time is over
        return m, events
    if m.state is OFFLINE:
        return m, events
    if m.state is MOVING:
        still = read and now >= still_from(m, cfg)  # rule 2
        judged = stalling(m, cfg)
        stall_t = (now if judged is None else judged[1]) + cfg.stall_timeout_s
        if m.target_deg is not None:
            err = target_error(m, cfg)
            if still and err is not None and err <= cfg.tolerance_deg:
                events.append(Event.ARRIVED)
                m = _at_rest(m, cfg, now, BRAKING)
            elif (  # (off target: one at it waits for the reading that shows it still)
                (  # (rule 3)
                    (read and asked_t >= stall_t)
                    or (asking_since is not None and asking_since <= stall_t)
                )
                and err is not None
                and err > cfg.tolerance_deg
                and now >= stall_t
            ):
                events.append(Event.STALLED)
                axis = None if judged is None else judged[0]
                m = replace(_at_rest(m, cfg, now, STALLED), stalled=axis)
        elif still:
            events.append(Event.STOPPED)
            m = _at_rest(m, cfg, now, BRAKING)
    if m.state is BRAKING and m.still_since_t is not None:
        if now >= m.still_since_t + cfg.brake_delay_s and now >= (m.idle_not_before_t or now):
            m = replace(m, state=IDLE, idle_not_before_t=None)
    elif m.state is IDLE and m.idle_not_before_t is not None:
        if now >= m.idle_not_before_t:
            m = replace(m, idle_not_before_t=None)  # rule 4: settled
    if m.carried and cfg.settle_own and at_rest(m):  # rule 4: a restart's first readings at
        m = replace(m, carried=False)  # rest by a settle time of the user's: no turn found
    return m, events


def settling(m: Motion) -> bool:
    """Idle with no brake, but not yet still for ``settle_s`` since the first reading (rule 4):
    no target goes out yet."""
    return m.state is IDLE and m.idle_not_before_t is not None


def at_rest(m: Motion) -> bool:
    """Idle and settled (rule 4): ready for a target, an option, a park."""
    return m.state is IDLE and m.idle_not_before_t is None


def _at_rest(m: Motion, cfg: MotionConfig, now: float, state: MotionState) -> Motion:
    if state is BRAKING and cfg.brake_delay_s <= 0:
        state = IDLE  # rule 4: no brake, never braking (``settling`` may still hold)
    stopped_t = now  # rule 4
    if state is BRAKING and m.last_move_t is not None:
        after = [t for t in (m.stop_sent_t, m.target_t) if t is not None]
        last = max(m.last_move_t, m.changed_t or m.last_move_t)
        stopped_t = min(now, max([last + cfg.poll_margin_s, *after]) + BRAKE_GUARD_S)
    return replace(
        m,
        state=state,
        still_since_t=stopped_t,
        lost_turning=False,
        carried=False,
        target_deg=None,
        el_target_deg=None,
        target_t=None,
        progress_t=None,
        az_progress_t=None,
        el_progress_t=None,
        stop_sent_t=None,
        closest_err=None,
        away_err=None,
        az_pass=None,
        el_pass=None,
        az_back=None,
    )


# -- decisions -------------------------------------------------------------------------------
def within_tolerance(m: Motion, cfg: MotionConfig, wire: tuple[float, float | None]) -> bool:
    """Idle and already within tolerance of ``wire`` on both axes: nothing to send."""
    if not at_rest(m) or m.position_deg is None:
        return False
    if angle_error(m.position_deg, wire[0], cfg.az_wraps) > cfg.tolerance_deg:
        return False
    el = wire[1]
    return (
        el is None or m.el_position_deg is None or abs(m.el_position_deg - el) <= cfg.tolerance_deg
    )


def plan_target(m: Motion, cfg: MotionConfig, now: float) -> Plan:
    """May a new target be written to the controller now?"""
    if not cfg.can_report_position:
        if m.stop_sent_t is not None:
            # the brake timer starts when the stop has arrived: not a hair before (rule 4)
            brake_over = now >= m.stop_sent_t + cfg.brake_delay_s + BRAKE_GUARD_S
            return Plan.SEND if brake_over else Plan.WAIT
        if m.busy_until_t is not None and now < m.busy_until_t:
            return Plan.STOP_FIRST
        if m.busy_until_t is not None and now < m.busy_until_t + cfg.brake_delay_s:
            return Plan.WAIT
        return Plan.SEND
    if cfg.direct_retarget:
        return Plan.SEND
    if m.state is IDLE:
        return Plan.SEND if at_rest(m) else Plan.WAIT
    if m.state is STALLED:
        rested = m.still_since_t is not None and now >= m.still_since_t + cfg.brake_delay_s
        return Plan.SEND if rested else Plan.WAIT
    if m.state is MOVING:
        if m.stop_sent_t is None and m.lost_turning:  # rule 4: taken for turning, not seen
            return Plan.WAIT  # to (a review: a stop to a rotor that came to rest while its
            # port was out); the next reading says which
        if m.stop_sent_t is None:  # (at its target and still by the clock, the reading that
            came = at_target(m, cfg) and now >= still_from(m, cfg)  # says so late: no stop,
            return Plan.WAIT if came else Plan.STOP_FIRST  # the target waits for it: rule 2)
        # a stop went out: send another only if a reading since shows it did not take
        return Plan.STOP_FIRST if stop_again(m, cfg, now) else Plan.WAIT
    return Plan.WAIT  # braking (or no reading yet)


def may_turn_blind(m: Motion, now: float) -> bool:
    """Rule 6: no feedback, and its own target out with no stop since, within the time its turn
    is assumed to take: it may be turning (``plan_target`` stops it first then)."""
    busy = m.busy_until_t
    return (
        m.state is UNKNOWN
        and m.target_deg is not None
        and m.stop_sent_t is None
        and busy is not None
        and now < busy
    )


def may_finish_blind(m: Motion, now: float) -> bool:
    """Rule 6: no feedback, and a turn under way when the link was lost (its target out) that
    the controller may still be finishing by itself, within the time assumed from the connect,
    nothing of the bridge's sent since (parts.py rule 10: a refused start halts it)."""
    busy = m.busy_until_t
    return (
        m.state is UNKNOWN
        and m.lost_turning
        and m.target_deg is None
        and m.stop_sent_t is None
        and busy is not None
        and now < busy
    )


def turn_kept(m: Motion, now: float) -> bool:
    """Rule 6 (no feedback): whether a turn of the bridge's may be in flight, as the state file
    keeps it (runtime/kept.py rule 13): one taken as carried over a connect (``lost_turning``;
    before the connect, with no end assumed yet, as kept), or TURN_KEPT_S not past the end of
    the last one sent (``kept_end_t``)."""
    if m.lost_turning:
        return True  # (till its time from the connect is over: ``tick``)
    end = m.kept_end_t
    return end is not None and now < end + TURN_KEPT_S


def turn_kept_until(m: Motion, now: float) -> float | None:
    """Rule 6: when ``turn_kept`` runs out, on the session's clock: TURN_KEPT_S past
    ``kept_end_t``; None while none is kept, or while one is kept with no end yet (carried
    to a connect not made: its time counts from the connect, ``link_up``)."""
    end = m.kept_end_t
    if end is None or not turn_kept(m, now):
        return None
    return end + TURN_KEPT_S


def stall_due(m: Motion, cfg: MotionConfig, now: float) -> bool:
    """Rule 3: turning off target with no movement for ``stall_timeout_s``, the stall not
    called for want of a reading since (``tick``'s): the controller is to be asked at once,
    not at the next moving poll (a review: the motor drove against a jam a moving poll longer,
    2 s for a GS-232B polled every 2 s while turning)."""
    if m.state is not MOVING:
        return False
    judged = stalling(m, cfg)
    return judged is not None and now >= judged[1] + cfg.stall_timeout_s


def undriven(m: Motion, axis: str) -> Motion:
    """Rule 3: the controller refused ``axis``'s own frame of the target out (a target of a
    frame per axis: an RC2800's az/el box, a Combi-Track); not driven to it, that axis is
    judged by either axis's movement, as before, not stalled while the other turns. Nothing
    if no target is out, or the axis moved since it went (the refusal was of something
    else)."""
    if m.state is not MOVING or m.target_deg is None or m.target_t is None:
        return m
    moved_t = m.az_progress_t if axis == "azimuth" else m.el_progress_t
    if moved_t is not None and moved_t > m.target_t:
        return m
    return replace(m, undriven=axis)


def stall_from(m: Motion, cfg: MotionConfig) -> float | None:
    """Rule 3: from when the turn under way may be called stalled ``stall_timeout_s`` later
    (``stalling``'s time), or None: no stall can come (no target, or at it)."""
    judged = stalling(m, cfg)
    return None if judged is None else judged[1]


def stalling(m: Motion, cfg: MotionConfig) -> tuple[str, float] | None:
    """Rule 3: the axis off its target (beyond ``tolerance_deg``) whose own last movement since
    the target went out is the oldest, and that time ("azimuth" or "elevation"); None with no
    target, no reading, or every axis at its target. On a box that turns its axes one after the
    other (``axes_in_turn``) either axis's movement is both axes' progress."""
    shared = m.progress_t
    if shared is None or m.target_deg is None or m.position_deg is None:
        return None
    judged: tuple[str, float] | None = None
    if angle_error(m.position_deg, m.target_deg, cfg.spec.az_wraps) > cfg.tolerance_deg:
        t = axis_progress_t(m, cfg, "azimuth")
        judged = ("azimuth", shared if t is None else t)
    el, el_target = m.el_position_deg, m.el_target_deg
    if el is not None and el_target is not None and abs(el - el_target) > cfg.tolerance_deg:
        t = axis_progress_t(m, cfg, "elevation")
        t = shared if t is None else t
        if judged is None or t < judged[1]:
            judged = ("elevation", t)
    return judged


def axis_progress_t(m: Motion, cfg: MotionConfig, axis: str) -> float | None:
    """Rule 3: ``axis``'s last movement while the target is out, as its stall is judged (and
    controller.py rule 11 judges it left behind): its own (``az_progress_t``,
    ``el_progress_t``), or either axis's (``progress_t``) on a box that turns its axes in turn
    or for an axis whose frame of the target was refused (``undriven``); None with no target."""
    own = m.az_progress_t if axis == "azimuth" else m.el_progress_t
    if cfg.spec.axes_in_turn or own is None or m.undriven == axis:
        return m.progress_t
    return own


def next_deadline(m: Motion, cfg: MotionConfig, now: float) -> float | None:
    """The next time after ``now`` that ``tick`` or ``plan_target`` could change its answer
    (the soonest kept as it goes, no list: this runs at every step of every rotator)."""
    soonest: float | None = None
    state = m.state
    if state is MOVING:  # (the rotor found still comes with a reading: rule 2)
        judged = None if m.progress_t is None else stalling(m, cfg)
        if judged is not None:  # (rule 3: the axis judged first)
            t = judged[1] + cfg.stall_timeout_s
            if t > now and (soonest is None or t < soonest):
                soonest = t
        if m.stop_sent_t is not None:  # (stop_again's window)
            t = m.stop_sent_t + cfg.stop_resend_s
            if t > now and (soonest is None or t < soonest):
                soonest = t
        if m.stop_sent_t is not None or at_target(m, cfg):  # (plan_target's at its target)
            t = still_from(m, cfg)
            if t > now and (soonest is None or t < soonest):
                soonest = t
    elif (state is BRAKING or state is STALLED) and m.still_since_t is not None:
        t = m.still_since_t + cfg.brake_delay_s
        if t > now and (soonest is None or t < soonest):
            soonest = t
    t_idle = m.idle_not_before_t
    if t_idle is not None and t_idle > now and (soonest is None or t_idle < soonest):
        soonest = t_idle
    if not cfg.spec.can_report_position:
        busy, stop = m.busy_until_t, m.stop_sent_t
        for t_or_none in (
            busy,
            None if busy is None else busy + cfg.brake_delay_s,
            None if stop is None else stop + cfg.brake_delay_s,
            None if stop is None else stop + cfg.brake_delay_s + BRAKE_GUARD_S,  # (plan_target)
            None if m.kept_end_t is None else m.kept_end_t + TURN_KEPT_S,  # (turn_kept)
        ):
            if t_or_none is not None and t_or_none > now:
                if soonest is None or t_or_none < soonest:
                    soonest = t_or_none
    return soonest


def still_from(m: Motion, cfg: MotionConfig) -> float:
    """Rule 2: from when a reading may find the rotor still (no movement for ``settle_s``; a
    carried turn's, each axis still for its own time too: ``carried_rest_from``)."""
    if m.carried and m.stop_sent_t is None and m.state is MOVING:
        return max(_moved_ref(m) + cfg.settle_s, carried_rest_from(m, cfg))  # (rule 4: rare)
    return _moved_ref(m) + cfg.settle_s


def carried_rest_from(m: Motion, cfg: MotionConfig) -> float:
    """Rule 2: from when a turn the controller finishes by itself (``carried``) may be found
    at rest: every axis still for its own time (``axis_seen_s``, never under ``settle_s``)
    since its own last movement or creep as fast as a turn (``az_moved_t``, ``el_moved_t``:
    the first reading back, for an axis not seen move since; none, for one the lost target
    gave nothing to do, ``_nothing_to_do``, till it is seen move). A fast axis's jam is told by
    its own short time, a slow axis's turn is not called over while it shows a move only
    every few readings."""
    ref = -1e18
    for axis, seen in axis_seen_s(cfg).items():
        moved_t = m.az_moved_t if axis == "azimuth" else m.el_moved_t
        if moved_t is not None:
            ref = max(ref, moved_t + max(cfg.settle_s, seen))
    return ref


def stop_again(m: Motion, cfg: MotionConfig, now: float) -> bool:
    """Whether a stop that went out is to go again (stops.py rule 2): from ``stop_resend_s`` on,
    a movement seen after the first reading after the stop and after its coast (``coast_end``),
    less than ``settle_s`` old. The first reading shows where the rotor was when the stop came,
    not that it turned on since (an attack pass: replies lost across a stop that took, the
    first after them moved the rotor by the way it came, and a second stop went to a rotor at
    rest); past ``settle_s``, the next reading may find it still (rule 2), and none is owed."""
    sent_t, read_t, moved_t = m.stop_sent_t, m.stop_read_t, m.last_move_t
    if m.state is not MOVING or sent_t is None or read_t is None or moved_t is None:
        return False
    if read_t <= sent_t or moved_t <= read_t:  # (no reading since it, or no movement after)
        return False
    if moved_t < coast_end(cfg, sent_t):  # (its run-on: the motor is off)
        return False
    return sent_t + cfg.stop_resend_s <= now < still_from(m, cfg)


def coast_end(cfg: MotionConfig, stop_t: float) -> float:
    """Until when a movement read after a stop written at ``stop_t`` may be the rotor running
    on with its motor off (momentum, a controller's soft stop: a SPID's "often off by a degree
    or two"): COAST_S and a moving poll for the reading that shows it, never past
    ``stop_resend_s`` (a stop lost on the line is sent again when it always was: a rotor
    turning on at speed is read moving after the coast too). Before, a SPID that coasted a
    second had every ordinary stop sent twice, with a warning in the log each time."""
    return stop_t + min(COAST_S + cfg.poll_margin_s, cfg.stop_resend_s)


def _moved_ref(m: Motion) -> float:
    """Rule 2: the later of the last movement, the last command and the last stop."""
    ref = -1e18  # (each by its name, no tuple: tick and next_deadline ask at every step)
    t = m.last_move_t
    if t is not None and t > ref:
        ref = t
    t = m.target_t
    if t is not None and t > ref:
        ref = t
    t = m.stop_sent_t
    if t is not None and t > ref:
        ref = t
    return ref
