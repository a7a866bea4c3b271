"""Every decision about one rotator, sans-IO (in the shape of h11's Connection): events in,
actions out. No port, no thread, no select, no clock: time comes in with every input.

Inputs: ``start``, ``link_up`` / ``link_down`` / ``open_failed``, ``commands`` (a mailbox batch),
``bytes_received`` (whatever the port had), ``sky_answer`` (the sky worker's answer to an ``Ask``),
``tick`` (nothing happened, but time passed).
Outputs: a list of actions (``Write`` bytes, ``Publish`` a status, ``Report`` an error event,
``Ask`` the sky worker) and ``next_wakeup``, the time by which ``tick`` must be called if nothing
else happens first.

The session owns the commands' state (the lock, the hold, the last error) and its parts, each
with its own state (docs/architecture.md, "parts decide and return"): the controller as seen
through its line (controller.py, with link.py, motion.py, stops.py, options.py, slew.py),
tracking (tracking.py) and following (follow.py) as their commands start and end them
(feature_commands.py), the wind park (wind.py), auto-park (autopark.py), the pending target
(targets.py, targets.py), rotor health (health.py) and the status view (status.py). They see
what they need (a read-only ``parts.Scene``, ``status.Seen``, the motion, the time) and hand
back what they propose (a ``parts.Proposal``, the controller's notes, a health report, what a
command did); the session applies it. None of them imports this module. ``_step`` runs them in
one order after every input: the line's own work (an overdue reply, a due stop), the motion
machine's clock, the stop check, the parts handed in that decide (the registered features':
tracking, following, the wind, auto-park), the pending target, options, the poll, the parts
that measure (health), the status (a tick with nothing due but the poll runs the poll alone:
rule 20). Stops and the lock come before all of it, in ``commands``, in a fixed written order.

Rules:
1.-3. The controller's state (answering, options owed, motion to re-enable), whether it is
   available, and its polls: controller.py rules 1-3.
4. Targets go to the controller only when targets.py says so (targets.py keeps the pending
   one and the stream rules); a target waiting for a brake delay is replaced by newer ones
   and dropped by a stop, the lock, or the link going down.
5. Stops: written at once, merged, checked and sent again as stops.py rules 1-2 say.
6.-7. Options: options.py. A controller that stops on re-target (Rotor-EZ): targets.py rule 7.
8. A controller silent while it moves (SatEL) is sent nothing but a stop until its after-move
   report (controller.py rule 4, slew.py); a new target stops the slew and is sent once the
   rotor is still (stop and redirect).
9. Bytes that complete no reply change nothing: the rest of the rules run only when a reply
   (or junk) came, a command came, or ``next_wakeup`` passed.
10. Tracking (tracking.py) proposes its own targets, judged like any; a stop, the lock, a track
   command or any other target ends it. What it needs of the sky goes out as ``Ask`` actions
   and comes back through ``sky_answer``.
11. A stop is never lost (stops.py rule 3): one owed is the first frame once the port is open.
    A session that starts locked (a lock the state file kept) owes one: the lock ON may have
    come while the port was out, and its stop was owed in the process that ended (an attack
    pass: restarted before the adapter came back, the rotor turned on to its target, locked).
    So does one that starts with a stop owed (the status says one is, ``stop_owed``, and the
    state file keeps it: kept.py rule 8): a STOP taken while the adapter was out was lost to a
    restart before it came back, and the rotor turned on to its old target (an attack pass).
12. ``last_error`` is the last thing refused or gone wrong since the last batch of commands
   that was taken: a command after it that is carried out clears it. A port lost mid-turn
   that fails to open again (the adapter still out) says, after that failure's own words,
   what the lost port's error said of the turn (controller.py rule 13), until the port is
   open: the try's error is the newest, and its words alone ("... does not exist") took the
   last error's place, so a user who looked at it later (Home Assistant's last-error sensor),
   the rotor at rest where the controller took it by itself, never read that the turn had been
   dropped (a closing note).
13. The last word (interfaces/mqtt/lastword.py): a stop or lock ON from the stop lane holds the
    rotator:
   no target (the user's, tracking's, auto-park's) goes to the controller until the batch
   that releases it, put by the main connection when it has caught up. A release that clears
   drops whatever target or tracking waits, but the storm's park (wind.py rule 8), which
   goes then as at any release. A stamped target (``Target.not_after_s``: its
   expiry, interfaces/mqtt/service.py rule 9) whose expiry has passed when a hold it waited
   under ends, or when it is taken from the mailbox (a move the stop lane's marker kept behind
   a lock OFF, lastword.py rule 13, or a slow link's), is dropped, said (EXPIRED, and
   EXPIRED_TAKEN for one taken past it, which names no STOP: none may have come; review 34):
   the order of a STOP held it up as a slow link would (review 25, R25-3). Not once it is
   taken and waits for the controller's own rules (a brake delay, a stop first): the bridge
   took it in time. So is a stamped start (``not_after_s`` on a track or follow start, a
   feature's command that moves: core/model.py ``Move``): taken past its expiry it is
   refused ("tracking not started", ...: EXPIRED_TAKEN); taken under a hold that then ends
   past it, what it began (tracking, a look-up, following, its part's motion and the target
   that part proposed) ends, said once (review 34: a track start read after a lane STOP's
   copy began to turn the rotor at the marker's return, 14 s after it was sent). The newest
   start taken under the hold is the one judged: it ended what the one before it began, and
   so does anything that ends tracking (a stop, a target); one that ended already is not
   said. A target a stamped feature command's part proposes carries that command's expiry,
   so a later command that ends in no target leaves it to be judged as any target (attack 8:
   it went at the marker past its expiry). A satellite's look-up ends no tracking or
   following until its answer, so it takes no start's place: the two are judged as one, by
   the sooner expiry (review 37; the safe side: a late look-up also ends following begun in
   time under that hold, a known failure); once its answer begins tracking under the hold,
   it is judged alone (review 38: an earlier late start's expiry ended the tracking of a
   satellite asked for in time). (A look-up taken ends each part's motion at once, as any
   track start does; tracking and following wait for its answer.)
14. A part that raises (tracking, following, the wind, auto-park, health) is a bug contained
   here: its Part resets it (tracking ends, "internal error"; the wind keeps its storm;
   health starts again from its last memory, or stops measuring), an error event of kind
   internal names it, and the link, the stops and every other rule go on (a feature's
   failure never takes a link down, and never costs a stop).
15. Following (follow.py) is like tracking (rule 10), and a track command ends it too; what
   WSJT-X says comes in with the commands, and is no command itself (rule 12), nor is a wind
   reading (wind.py): a storm ends tracking and following, parks, and refuses motion.
   Following may also stop its own turn (a transmission began: follow.py rule 3). The
   wind's park, like auto-park, is the bridge's own move: the control lease never judges it.
16. Bytes that complete a reading the link holds for its quiet time (link.py rule 9), and do
   nothing else, run no step either: the held reading changes nothing the rules read until it
   is taken, and the session asks to be woken when the quiet time is over (the step then takes
   it). Only when nothing waits on such a step: no stop due (a half-duplex line takes one as
   soon as the reply is whole: that step writes it), no target waiting, nothing noted, and
   ``next_wakeup`` not yet come (what is due by then runs as before). Bytes after it that
   complete nothing (a CR LF's LF, noise still arriving) hold it longer (link.py rule 9), and
   the wake-up moves with the quiet time: the last step's own wake-up or the link's,
   whichever comes first; no step runs at the quiet time's old end.
17. The step runs the parts it is handed (``WorkerConfig.parts``: the registered features'
   ``Part``, parts.py rule 4, from the app; a session made without them takes the registry's,
   bridge/feature.py ``session_parts``), in their order, which is the registry's
   (bridge/features/ ``FEATURES``, bridge/feature.py rule 2); each says what wakes it (parts.py
   rule 3), whether it is on, when it wants to be woken and how it is reset (rule 14). A part
   that is off costs nothing, and is asked for no wake-up; one woken by the motion (health)
   runs only in a step where the motion is not the one it last saw. The step, the wake-ups and
   the resets name no feature: what still does is the commands' routing (a track, a follow, a
   wind reading, a health reset), the status, the refusal in a storm and auto-park's
   activity, each in a method of its own. A feature's own command (``FeatureCommand``) goes
   to its part by its name (parts.py rule 5), after the batch's stop, lock and fence and
   before its target; one that moves ends tracking, following and every part's own motion
   first, as a target does, and is refused while a target would be. Whatever ends tracking
   ends a part's own motion too (``Part.end``, parts.py rule 7: a storm that begins too, and
   the lock's release), and again after the feature commands put before a stop, a lock ON
   or OFF or a clearing release of the same batch (where mailbox.py rule 12 marks it); no
   part's step gets a target through while the rotator is locked or its lock is not known
   yet (runtime/kept.py rule 10: the wind's park neither), nor in a storm, nor once the
   bridge's end began (rule 21), but the wind's own park.
   What a part shows in the status is asked of it by its ``Part`` alone (parts.py rule 6).
18. The status is built again only when something it shows may have changed (the values it is
   built from, compared as one tuple; a slew's estimate and a DCU-1's estimated move read the
   time, and are built at every step): a poll that changed nothing builds no status.
19. A part's ``status`` is asked at every status built (several a second while the rotor
   turns): one that raises shows nothing in that status, the rest of which goes out, and is
   reported, logged and reset as rule 14 says once per kind of failure (its exception's type,
   as runtime/listeners.py does for a listener), not at every status.
20. A ``tick`` with nothing due but the poll (the query of every exchange) runs the poll alone
   and asks for the next wake-up: no line work, motion clock, stop check, parts, options or
   status, when every one of them would change nothing. Whether so is judged at the end of
   each whole step, as a time before which it holds if nothing but time passes, with the
   step's wake-up (``_next_wakeup``): no target waiting, a status built, the storm as last
   seen, every deciding part off, every measuring part off or woken by the motion alone and
   that motion seen, no part that shows a status block (``_poll_alone``), and the
   controller's own part (controller.py ``wakeups``, with the same look at the line as its
   wake-up: no stop due, owed or to check, no count of stops to start again, nothing on the
   line but the poll, no note, until the motion's next deadline, silence's timeout or an
   option owed). Bytes read and the poll step itself end it; every other input
   runs the whole step, which judges it anew; so the tick after a poll step, or after bytes
   that ran no step, runs the whole step. Nothing the status is built from changes in the poll
   step (rule 18: the poll changes only the link's own state).
21. Once told the bridge's end began (``Batch.ending``, app.py rule 6), no part's step gets a
   target through but the storm's park (a storm's park goes on: wind.py), as while the rotator
   is locked (rule 17): the end stops the rotors that may turn, and what started after its
   looks turned on unwatched (a review: auto-park's quiet spell ended while a front end took
   its time to close, and its park turned the rotor until the second look; or, after that
   look, on to the park with the port closed). Stops, the lock and the rest of the step go on.
22. A part's error (a grid following refuses, a body tracking cannot reach) is published as
   any (R/error, its own limit: interfaces/mqtt/service.py rule 4, and ``last_error``), and
   logged at warning level at most once per PART_ERROR_LOG_S for each part, the line then
   saying how many of that part's came since the last one; the rest at debug level. Whoever
   reaches WSJT-X's port chooses how often following refuses (an attack pass: a status a few
   milliseconds apart, each with a new grid in a keep-out sector, was a warning line each,
   some 190 a second, while R/error let through 79 in three seconds).
23. A change of the control lease (``Batch.control``: a claim, a renewal, a release, its end)
   drops a target that waits and never went to the controller (targets.py ``unsent``: a
   Rotor-EZ's, waiting out the brake delay after the stop its new target needed) or that
   comes in the same batch, when the lease now has a holder who did not send it: it was
   judged before the claim, and the claimant took control to keep others off (an attack
   pass: G4XYZ's target 300, waiting for the brake, went out after DL1ABC claimed the lease
   and turned the rotor for someone the lease refused). Said on R/error (kind ``refused``,
   naming the holder and the lease's end, its minutes on the lease's clock as the judge's
   refusal counts them, runtime/operators.py rule 5: a cold review, on the raw wall clock set
   back 10 minutes they were 10 more; the target as ``command``) and, with its sender, in the
   audit trail (runtime/rotator.py). So is a target sent whose frame the rotor never
   turned for (lost or refused on the line; its try more waiting is as unsent): when the
   reading that would send it once more comes (targets.py rule 8) and the lease is then
   another operator's, its try more is taken (``unstand``), it is said, "target not sent
   again", alone (the controller's refusal of its first try is not said too, as a storm's
   drop of it says one word: wind.py rule 1; a cold review: R/error got both), and its
   turn, which never began, is over (controller.py ``forgo``: no stall called; an attack
   pass: G4XYZ's 200, lost on a GS-232B's line, went once more 2 s after DL1ABC's claim
   and turned the rotor to 200). It is judged against the lease at that reading, not at
   the claim: a claim released before it takes nothing, and the try more of
   a target judged while the lease was free goes while it is free again (before, it was
   not sent, and R/error named a holder whose lease had ended). So is a satellite's name
   looked up (tracking by name: the sky worker answers it, tracking.py rule 8) at its answer:
   when the lease is then another operator's than its sender's, tracking does not start,
   "tracking not started", said and audited as the drop is (a review: G4XYZ's track by name,
   asked while the lease was free and answered after DL1ABC's claim, started tracking, and
   the rotor turned to wait for the pass for someone the lease refused). A track or follow
   start that comes in the claim's own batch (put before it) is judged as a target there is:
   "tracking not started" ("following not started"), said and audited (a review: G4XYZ's
   track sun taken with DL1ABC's claim turned the rotor to the sun under DL1ABC's lease). The
   holder's own target stays (so does every target after the holder's renewal: nobody
   else's can wait then), and so do the bridge's own moves (``OWN_MOVES``: tracking's,
   following's, auto-park's, the wind's, never judged by the lease) and a turn under way, or
   a SatEL's put back after its slew's lost report (targets.py rule 3: that slew turned the
   rotor): a claim is no stop, the holder may STOP. Commands judged after the claim are
   the judge's to refuse (runtime/lease.py rule 5), and a target judged before it but put
   after it the mailbox's (mailbox.py rule 14): none of them reaches the session; the lease
   takes no place in the order of commands (mailbox.py rule 10a). On a rotator of two boxes
   a drop here (``drops``, so does a storm's: ``_storm``, and its refusal of a try more,
   ``_heed``) drops the other box's half of that target too, its turn stopped if it went
   (``forsake``; a SatEL's put back stands for the half it was: targets.py rule 3), and the
   two are said once, naming the whole target (runtime/composite.py
   rules 8 and 9).
24. Every drop of a command taken (judged ``executed`` in the audit trail) before it moved the
   rotor is a refusal of its sender's command, said on R/error and in the audit trail by one
   path (``_refuse_dropped``; a start's end by its expiry, ``_waited``, names its sender too):
   a lease's (rule 23), a storm's (``_storm``, wind.py rule 1, and its try more), a hold's that
   ends clearing (``_fence``, rule 13), an expiry's (rule 13), a lost link's, a box gone
   offline, a restarted express's. The report carries the target's ``origin`` (its interface
   when it has none: ``auto-park`` for the bridge's own park); runtime/rotator.py audits it
   (an attack pass: a target the storm dropped, waiting for a Rotor-EZ's brake, stayed
   ``executed`` in the trail, while a lease's drop was audited).
25. A move of the bridge's own that no command started (``UNASKED``: auto-park's park, the
   storm's park) is a line in the audit trail when its frame goes out (``Audit``: command
   ``park``, executed, its interface and operator the feature's: ``auto-park``, ``wind``), as
   every operator's command is; tracking's and following's targets are not (their start was
   an operator's command, audited then), nor a try more (attack 25: an auto-park
   turned the rotor 110 degrees and the trail's last word on it was the operator's target).
   Not when the part proposes it (review 80: a storm's park kept by a STOP's hold and dropped
   unsaid by the storm's end, wind.py rule 8, stayed ``executed`` with the rotor unmoved).
   On a rotator of two boxes the two boxes' lines are one (runtime/composite.py rule 9).
"""

from __future__ import annotations

import logging
import math
import secrets
from collections.abc import Callable
from dataclasses import replace
from functools import partial
from typing import NamedTuple, TypeVar

from bridge.core.errors import Refused
from bridge.core.model import (
    Control,
    ErrorKind,
    FeatureCommand,
    MotionState,
    Order,
    Origin,
    RotatorStatus,
    SettingValue,
    Source,
    Target,
    describe_command,
    same_operator,
    sender,
)
from bridge.feature import session_parts
from bridge.session import status as st
from bridge.session.actions import Action, Ask, Audit, Publish, Report, Write
from bridge.session.autopark import AutoPark
from bridge.session.config import WorkerConfig
from bridge.session.controller import Again, Controller, Drop, Ends, Fed, Forgot, Retry
from bridge.session.feature_commands import Done, FeatureCommands
from bridge.session.follow import Follow
from bridge.session.health import Health
from bridge.session.link import Link
from bridge.session.mailbox import Batch, Halt, OwnTurn, PartsEnd
from bridge.session.motion import Motion
from bridge.session.parts import Part, Proposal, Scene, Wake
from bridge.session.stops import EXPRESS_LOST, SEND_AGAIN, Fence
from bridge.session.targets import Go, Targets, decide
from bridge.session.tracking import Track
from bridge.session.wind import WindPark
from bridge.sky.worker import Answer

__all__ = ["DROPS", "Action", "OwnTurn", "Publish", "Report", "RotatorSession", "Write"]

log = logging.getLogger(__name__)

T = TypeVar("T")


IDLE_WAKEUP_S = 1.0  # a session with nothing due still looks at the clock this often
DROPPED = "target dropped"  # how a target dropped before it went out is said (rules 4, 23)
PART_ERROR_LOG_S = 10.0  # rule 22: a part's error in the log at most this often (a count)
# controller.py rule 11: a try more a storm refuses (wind.py rule 1), said
TRY_DROPPED = (
    "target did not move the rotor, or was refused before it did (lost or garbled on the "
    "line?), and is not sent again"
)
# rule 23: the bridge's own moves, never judged by the lease (rules 10, 15; autopark.py)
OWN_MOVES = frozenset({Source.TRACKING, Source.WSJTX, Source.AUTO_PARK, Source.WIND})
# rule 25: the bridge's own moves that nobody's command started, each one line in the audit
# trail (tracking's and following's targets follow a start an operator sent, audited then)
UNASKED = frozenset({Source.AUTO_PARK, Source.WIND})
# rule 13: a stamped target whose expiry passed while the last word's order held it up...
EXPIRED = "its expiry passed while it waited for the order of a STOP or lock; send it again"
# ... or before it was taken at all (a slow link, a busy machine; or kept behind a lock OFF)
EXPIRED_TAKEN = "its expiry passed before the bridge could carry it out; send it again"
WAITING_DROPPED = "target dropped before it went out"  # rule 23's words: a target waiting...
AGAIN_DROPPED = "target not sent again"  # ... and one whose first try never moved the rotor
TRACK_REFUSED = "tracking not started"  # ... a track start (or its look-up's answer) so judged
FOLLOW_REFUSED = "following not started"  # ... and a follow start
# slew.py rule 4: a late slew's target put back, in a storm that refuses it (wind.py rule 1)
SLEW_STOPPED = "stopping it to ask where it is; its target is not sent again"
# wind.py rule 10: how a motion event's error ends for the storm's park, for SEND_AGAIN
PARK_NOT_AGAIN = "the storm's park is not sent again in this storm (motion refused for it)"
# ... and for a known restart's (the power-on byte, a SatEL's clock gone back): it goes again
PARK_AGAIN = "the storm's park is sent again"
# how every target dropped before it moved the rotor begins (runtime/composite.py rule 9 names
# the whole target in each: a storm's or a claim's drop of a try more named one box's half)
DROPS = (DROPPED, AGAIN_DROPPED, TRY_DROPPED)
# enum members the step and the reads compare with, by module names (a member looked up on its
# enum costs some 70 ns in Python 3.11: motion.py's states)
_BY_MOTION = Wake.MOTION
_FED_NOTHING, _FED_HELD = Fed.NOTHING, Fed.HELD
_SHOWN = len(st.Features._fields)  # rule 18: the status key ends with what the parts show


class RotatorSession:
    def __init__(
        self,
        cfg: WorkerConfig,
        *,
        options: dict[str, SettingValue] | None = None,
        locked: bool = False,
        health: dict[str, object] | None = None,  # what the state file kept (health.py)
        storm: bool = False,  # parked for a storm when last stopped (kept.py rule 4)
        storm_halted: bool = False,  # ... and its park stopped (wind.py rule 3)
        storm_arrived: bool = False,  # ... or seen reached (wind.py rule 7)
        storm_place: int = 0,  # ... the place its park took (0: none known; kept.py rule 4)
        stop_owed: bool = False,  # a stop owed when last stopped (kept.py rule 8)
        short_of: float | None = None,  # the target it rested short of then (kept.py rule 9)
        turn_kept: bool = False,  # a turn possibly in flight then (kept.py rule 13)
        place: Callable[[OwnTurn], int] | None = None,  # mailbox.py rule 10b's
        # ``own_place``: the place in the order of commands of a turn the bridge begins itself
        # (``Order``), named (``_own_turn``), from the counter the rotator's commands advance
        # (a composite's box: the rotator's mailbox's, not the box's own: runtime/composite.py
        # rule 10, review 86)
        order: tuple[int, int, int] = (0, 0, 0),  # runtime/kept.py rule 12: the places
        # earlier runs reserved (``since``), and the turn's and the lock word's kept
    ) -> None:
        self.cfg = cfg
        self._place = place
        self.locked = locked
        self.lock_shown = locked  # the lock saved last (runtime/kept.py rule 2)
        self.lock_unknown = False  # runtime/kept.py rule 10: the status says it is not known
        self.ending = False  # rule 21: the bridge's end began
        self.fence = Fence()  # rule 13
        self.wall_offset_s = 0.0
        self._lease_offset_s: float | None = None  # rule 23: the lease's clock = now + this
        self.controller = Controller(cfg, options)
        # rule 11: a lock kept from before (the state file) owes a stop: the lock ON that set
        # it may have come while the port was closed, its stop owed in a process now ended
        # (and so does a stop owed then: taken while the port was out, say)
        if locked or stop_owed:
            self.controller.owe_stop()
        if short_of is not None:  # (controller.py rule 10)
            self.controller.keep_short_of(short_of)
        if turn_kept:  # (motion.py rule 6: a box with no feedback may be finishing it)
            self.controller.keep_turn()
        self.targets = Targets(cfg)
        self.features = FeatureCommands(cfg, self.targets)  # tracking and following
        self.tracker, self.follower = self.features.tracker, self.features.follower
        self.autopark = AutoPark(cfg)
        self.wind = WindPark(
            cfg,
            storm=storm and cfg.wind is not None,
            halted=storm_halted,
            arrived=storm_arrived and cfg.spec.can_report_position,  # (never a DCU-1's)
        )
        self.health = Health(cfg, health)
        self.view = st.View()
        # the status's ``order`` (core/model.py Order; interfaces/mqtt/remote.py rule 10): this
        # run's name, the newest place taken, the place of the turn shown and of the lock word,
        # on from the places earlier runs took (runtime/kept.py rule 12: a turn and a lock word
        # kept across the restart at their own places)
        self._run = secrets.token_hex(4)
        self._since, self._turn_place, self._lock_place = order
        # mailbox.py rule 10b: the kept storm's park, sent again by this start (wind.py rule
        # 7), is the turn it was, at the place it took (review 96)
        owed = storm and not storm_halted and not storm_arrived
        self._storm_place = storm_place if owed and 0 < storm_place <= self._since else 0
        self._taking = self._since
        self.status = RotatorStatus(
            cfg.rotator_id,
            locked=locked,
            health=self.health.report,
            stop_owed=self.controller.stops.owed,
            short_of_deg=self.controller.short_of_deg,  # (kept: the first status says so too)
            turn_kept=not cfg.spec.can_report_position and turn_kept,  # (likewise)
            # (likewise the storm kept: a first status with no wind said the wind off, and
            # runtime/kept.py rule 4 took it for the storm over: review 104, its park's place
            # lost at a second restart; None is the wind off, and only that)
            wind=self.wind.info if self.wind.on else None,
            order=Order(  # (the first status's too: no change to say)
                self._run, self._since, self._turn_place, self._lock_place, self._since
            ),
        )
        # rule 17: the parts handed in (the features', from the app), in the order they run
        parts: tuple[Part[RotatorSession], ...] = (
            session_parts() if cfg.parts is None else cfg.parts
        )
        self._deciding = tuple(p for p in parts if p.deciding)
        self._measuring = tuple(p for p in parts if not p.deciding)
        self._waking = tuple(p for p in parts if p.wakeup is not None)
        self._waking_measuring = tuple(p for p in self._waking if not p.deciding)  # rule 20
        self._ending = tuple(p for p in parts if p.end is not None)
        # parts.py rule 7: a storm kept was seen; the storms begun with it (wind.py rule 2: one
        # may end and the next begin between two looks, both judged at readings)
        self._storm_seen = self._storm_look()
        self._answered = False  # wind.py rule 7: the controller answered at the last step
        self._parts_named = {p.name: p for p in parts}
        self._showing = tuple((p.name, p.status) for p in parts if p.status is not None)
        # parts.py rule 4: the state of the parts the session knows by their Part alone
        self.own: dict[str, object] = {p.name: p.state(self) for p in parts if p.state}
        self._actions: list[Action] = []
        self._wakeup = 0.0
        self._step_wakeup = 0.0  # rule 16: the last step's own wake-up
        self._seen_motion: dict[str, Motion] = {}  # rule 17: what each MOTION part has seen
        self._part_said: dict[str, tuple[float, int]] = {}  # rule 22: logged when, unsaid since
        self._status_key: tuple[object, ...] | None = None  # rule 18
        self._poll_until = -math.inf  # rule 20: a tick before it runs the poll alone
        self._status_failed: dict[str, set[type[BaseException]]] = {}  # rule 19
        # the halts proposed by parts that take their feature's own commands: on a rotator of
        # two boxes those run in the azimuth box alone (runtime/composite.py rule 6 reads it)
        self.part_halts = 0
        # targets dropped here before they went out by a lease's change (rule 23) or a storm's
        # start (wind.py rule 1), or their try more by either: on a rotator of two boxes the
        # other box drops the other half of that target too (runtime/composite.py rule 8 reads
        # it: ``forsake``, of the same sender's target: ``dropped``, the last one)
        self.drops = 0
        self.dropped: Target | None = None
        # rule 13: the target a waiting one expires as when a hold ends (on a rotator of two
        # boxes, the whole one it is a half of: runtime/composite.py rule 8 sets it)
        self.expires_as: Callable[[Target], Target] = lambda target: target
        # a park of the bridge's own (auto-park's, the storm's) judged as the whole rotator's
        # park: on a rotator of two boxes, all axes or none (runtime/composite.py rule 7 sets
        # it; the parts see it as ``Scene.whole``)
        self.judge_whole: Callable[[Target], None] | None = None
        # mailbox.py rule 10: the halt count of the last batch applied; ``status`` shows every
        # stop and lock ON up to it (set once the step built the status: a thread that reads
        # this count and then the status sees a status at least that new)
        self.halts_applied = 0
        self._newest_taken = 0  # mailbox.py rule 10a: the newest place of the batches applied
        self.winds_applied = 0  # mailbox.py rule 9: the live wind readings of those (likewise)
        self.target_unshown = False  # ... and whether ``status`` cannot show the target waiting
        self._lost_turn = ""  # rule 12: what the port error said of the turn it dropped
        self._waiting: _Waiting | None = None  # rule 13: a stamped start taken under a hold
        # rule 13: a look-up taken under a hold, and its own start (None: unstamped), which is
        # the one judged once its answer begins tracking
        self._lookup_held = False
        self._lookup_waiting: _Waiting | None = None

    @property
    def newest_applied(self) -> int:
        """mailbox.py rule 10a: the newest place the status shows every command up to; none
        (0) while a target waits that it cannot show (its raw value not known yet: a SPID
        before its resolution is learned; an attack pass: target 100 then a nudge +10 just
        after a connect went to the bearing plus 10), so a nudge is refused meanwhile."""
        taken = self._newest_taken  # (first: read in the order the lines thread writes the
        return 0 if self.target_unshown else taken  # status, then this, then the place)

    @property
    def features_on(self) -> tuple[bool, bool]:
        """Whether a tracking OFF and a following OFF would end anything here now: a body
        tracked or a look-up under way (tracking.py rule 8: not in the status), following on.
        Read from another thread (runtime/rotator.py: a halt that changed nothing, audit.py
        rule 10), attribute reads, after ``newest_applied`` (the batch applied before it)."""
        tracker = self.tracker
        return tracker.body is not None or tracker.lookup is not None, self.follower.on

    @property
    def name(self) -> str:
        return self.cfg.rotator_id

    # -- inputs -------------------------------------------------------------------------------
    def start(self, now: float) -> list[Action]:
        """The first status, whatever it says (nothing has been published for this rotator)."""
        self._actions.append(Publish(self.status))
        self._activity(now)
        return self._step(now)

    def open_failed(self, reason: str, now: float) -> list[Action]:
        self.controller.open_failed(reason + self._lost_turn)  # (rule 12: the turn still said)
        return self._step(now)

    def link_up(self, now: float, wall_s: float) -> list[Action]:
        self.wall_offset_s = wall_s - now
        self._lost_turn = ""  # (rule 12: what its port error said is the last error's now)
        self._activity(now)  # never park the moment a controller comes back
        self.controller.connect(now, wall_s)
        return self._step(now)

    def link_down(
        self, reason: str | None, now: float, kind: ErrorKind = ErrorKind.SERIAL
    ) -> list[Action]:
        """The port is closed (``reason`` says why; None on shutdown)."""
        if reason is not None:  # (a turn out: what becomes of it, controller.py rule 13)
            self._lost_turn = self.controller.lost_turn()
            self._error(kind, reason + self._lost_turn)
        self.controller.disconnect(reason is not None, now)  # rule 11: a stop may be owed
        # tracking after a reconnect needs a new command (reason None: the bridge is stopping)
        why = "serial link down" if reason is not None else "bridge stopped"
        self._end(why, now)  # (what waits is reported dropped: next line)
        self._drop_pending("serial link down")
        if reason is not None:
            self.wind.lost()  # wind.py rule 7: the park owed again, once it answers
        return self._step(now)

    def commands(self, batch: Batch, now: float) -> list[Action]:
        ctl = self.controller
        self._taking = max(self._taking, batch.newest)  # (the status made below shows it)
        commanded = batch.stop or batch.target or batch.options or batch.track or batch.follow
        if commanded or batch.feature_commands or batch.lock is not None:
            self.view.last_error = None  # rule 12: until this batch refuses something again
        for note in batch.notes:
            self.view.last_error = note
        for heard in batch.heard:  # each program's newest, in the order put
            self.follower.heard(heard, now)  # rule 15
        wall = self.wall_offset_s  # (wind.py rule 2: a gap across a suspend is a gap)
        if batch.wind_replayed is not None:  # wind.py rule 6: before a fresh one
            self.wind.reading(batch.wind_replayed, now, wall_offset_s=wall, replayed=True)
        if batch.wind_halted is not None:  # (mailbox.py rule 9: put before the halt)
            self.wind.reading(batch.wind_halted, now, wall_offset_s=wall)  # no command either
        if batch.stop is not None or batch.lock_on:
            self.wind.halted()  # wind.py rule 3: the park stops, and is not tried again
        if batch.wind is not None:  # (mailbox.py rule 9: put after any halt of the batch)
            self.wind.reading(batch.wind, now, wall_offset_s=wall)
        if batch.control_set:
            self.view.control = batch.control
            if batch.control_unix is not None:  # rule 23: the lease's clock (operators.py 5)
                self._lease_offset_s = batch.control_unix - now
        if batch.ending:
            self.ending = True  # rule 21
        unlocked = batch.lock is False and (self.locked or batch.lock_on)
        if batch.lock is not None:
            self.locked = batch.lock
            self._lock_place = batch.newest  # (Order: the lock word's place)
        if batch.lock_saved is not None:  # (the status says what a restart would find)
            self.lock_shown = batch.lock_saved
        if batch.lock_unknown is not None:
            if self.lock_unknown and not batch.lock_unknown:  # autopark.py rule 1: known at
                self._activity(now)  # last, a refusal ended: a new quiet spell
            self.lock_unknown = batch.lock_unknown
        if unlocked:  # parts.py rule 7: nothing turned on while locked turns it once unlocked
            self._end_parts("lock released", now)
            if not batch.lock_on:  # (an ON then OFF in one batch: its stop is checked)
                ctl.lock_released()  # stops.py rule 2
        if batch.lock_on:  # mailbox.py rule 7: even when an OFF followed it in the batch
            self._end("lock", now)
            self._drop_pending(None)
            self.view.target_info, self.view.park_raw = None, None  # (as a stop's ``_taken``: an
            # attack pass, "long path" after a lock turned to the target the lock had dropped)
            ctl.stop(now)  # whatever we believe: the lock is for tower work
        if batch.stop is not None or batch.target is not None or batch.lock is not None:
            self._activity(now)  # (unlocking starts a new spell)
        elif batch.activity:  # (a target to a composite's other box)
            self._activity(now)
        elif batch.feature_commands:
            self._activity(now)
        if batch.stop is not None:
            self._end("stop", now)
            self.targets.clear()
            self._taken(batch.stop.source.value, batch.stop.origin)
            ctl.stop(now, merge=True)
        if batch.control_set:  # rule 23: a waiting target the new holder did not send
            self._lease_taken(now)
        held = self.fence.held
        cleared = self._fence(batch, now)
        if held and not self.fence.held and not cleared:  # rule 13: what waited for it
            pending = self.targets.pending
            if pending is not None and _expired(self.expires_as(pending), now):
                if not self._part_waited(pending, now):  # (else said once, as its command)
                    self._drop_pending(EXPIRED)
            self._waited(now)
        if batch.lost_target is not None:  # (stops.py rule 5: dropped in the mailbox, said)
            self._refuse_dropped(batch.lost_target, f"{DROPPED}: {EXPRESS_LOST}")
        if batch.offline is not None:  # (runtime/composite.py rule 8)
            if not self._storm_park_waiting():  # (the storm's park, this box's own axis,
                self._drop_pending(batch.offline)  # waits on: nobody could send it again)
            if ctl.turning() and not self._storm_park():  # (its turn is the rotator's, which
                ctl.stop(now)  # no reading watches whole: stopped, as one controller gone
                # silent mid-turn is; but the storm's park, this box's own axis, goes on)
            elif ctl.cut_mid_turn() and not self._storm_park():  # (the box whose port went
                ctl.stop(now)  # mid-turn: its stop owed, its first frame when it is back;
                # else it turned on alone, its other axis stopped above: an attack pass)
        if batch.health_reset:
            self._guarded("health", lambda: self.health.reset(), now)
        for opt in batch.options:
            ctl.options.set(opt.name, opt.value, ctl.link is not None)
        if (track := batch.track) is not None:
            leased = None
            if start := track.body is not None or track.lookup is not None:
                self._end_parts("track command", now)  # parts.py rule 7
                if batch.control_set:  # rule 23: judged before the claim it came with
                    leased = self._start_leased(track, now, TRACK_REFUSED)
            late = _late(track.not_after_s, now, TRACK_REFUSED)  # rule 13
            done = self.features.track(track, self._refused() or late, leased)
            self._apply(done)
            if start and done.error is None:
                self._turn_place = batch.newest  # (Order: the turn's place)
                began = track.body is not None  # (a look-up: no tracking until its answer)
                what = track.described or "track"
                by = track.origin or Origin(track.source)
                self._wait(track.not_after_s, what, "tracking ended", by, ends=began)
        if (follow := batch.follow) is not None:
            leased = None
            if follow.on:
                self._end_parts("follow command", now)
                if batch.control_set:  # rule 23: as a track start
                    leased = self._start_leased(follow, now, FOLLOW_REFUSED)
            late = _late(follow.not_after_s, now, FOLLOW_REFUSED)
            done = self.features.follow(follow, self._refused() or late, now, leased)
            self._apply(done)
            if follow.on and done.error is None:
                self._turn_place = batch.newest  # (Order: the turn's place)
                what, by = follow.described or "follow", follow.origin or Origin(follow.source)
                self._wait(follow.not_after_s, what, "following ended", by)
        ends: dict[Halt, str | None] = {  # parts.py rule 7 where the mailbox marks them
            "stop": "stop",
            "lock": "lock",
            "unlock": "lock released" if unlocked else None,
            "clear": "a stop or lock came first" if cleared else None,
        }
        for command in batch.feature_commands:  # rule 17, in the order they were put
            if not isinstance(command, PartsEnd):
                self._feature_command(command, now)
            elif (why := ends[command.what]) is not None:
                self._end_parts(why, now)
        leased = self._leased(batch.target, now) if batch.control_set else None
        if batch.target is not None and leased is not None:  # rule 23: judged before it
            self._refuse_leased(batch.target, leased)
        elif batch.target is not None:
            what = describe_command(batch.target)
            self._end(f"{batch.target.source.value} target", now)  # never combined
            refused = batch.offline or self._refused()
            if refused is None and _expired(batch.target, now):  # rule 13
                refused = f"{DROPPED}: {EXPIRED_TAKEN}"
            if refused is not None:
                self._error(ErrorKind.REFUSED, refused, command=what)
            else:
                self.targets.put(batch.target, now)
                self._turn_place = batch.newest  # (Order: the turn's place)
        elif batch.ends is not None:  # (a target to a composite's other box: ended here too)
            self._end(batch.ends, now)
        actions = self._step(now)
        self.halts_applied = batch.epoch  # (after the status: see __init__)
        self._newest_taken = batch.newest
        self.winds_applied = batch.winds
        return actions

    def bytes_received(self, data: bytes, now: float) -> list[Action]:
        self._poll_until = -math.inf  # rule 20: the next tick runs the whole step
        ctl = self.controller
        was_answering = ctl.answering
        fed = ctl.feed(data, now)
        if fed is _FED_NOTHING:
            if ctl.link is not None:  # rule 16: a held reading's quiet time may be longer
                self._wakeup = min([self._step_wakeup, *ctl.link.wakeups()])
            return []  # rule 9
        if fed is _FED_HELD and self._quiet_hold(now):
            return []  # rule 16
        if self.controller.answering and not was_answering:
            self._activity(now)
        self._heed(now)
        return self._step(now)

    def nothing_read(self, now: float) -> None:
        """The port had nothing when the hold on a poll's reply ended: the reply is late
        (link.py rule 7 learns by how much). Nothing else changes: no step."""
        link = self.controller.link
        if link is not None:
            link.got_bytes(0, now)

    def sky_answer(self, generation: int, answer: Answer, now: float) -> list[Action]:
        """The sky worker's answer to an ``Ask`` of ``generation`` (tracking.py rule 8); a
        satellite's name looked up is judged against the lease as it is now (rule 23)."""
        if generation == self.tracker.generation:
            refused, lookup, body = self._refused(), self.tracker.lookup, self.tracker.body
            leased = self._start_leased(lookup, now, TRACK_REFUSED) if lookup else None
            answered = self._guarded(
                "tracking", lambda: self.features.answered(answer, refused, leased), now
            )
            if answered is not None:
                self._apply(answered)
                if lookup is not None and self.tracker.lookup is None:  # (its answer)
                    began = self.tracker.body not in (None, body)  # (tracking it began)
                    if began and self._lookup_held and self.fence.held:  # rule 13: what
                        self._waiting = self._lookup_waiting  # waits is what it began
                    self._lookup_held, self._lookup_waiting = False, None
        return self._step(now)

    def set_wall(self, now: float, wall_s: float) -> None:
        """The wall clock (unix seconds) at ``now``: tracking reads the sky by it."""
        self.wall_offset_s = wall_s - now

    def _quiet_hold(self, now: float) -> bool:
        """Rule 16: whether a reading just held, and nothing else, needs no step now; if so,
        the session is woken when its quiet time is over."""
        ctl, link = self.controller, self.controller.link
        if link is None or link.stop_due or ctl.notes or self._actions:
            return False
        if now >= self._wakeup or self.targets.pending is not None:
            return False
        self._wakeup = min([self._step_wakeup, *link.wakeups()])
        return True

    def tick(self, now: float) -> list[Action]:
        if now < self._poll_until:  # rule 20
            return self._poll_step(now)
        return self._step(now)

    def _deciding_off(self) -> bool:
        """Whether every deciding part is off."""
        for part in self._deciding:
            if part.on(self):
                return False
        return True

    def _poll_alone(self) -> bool:
        """Rule 20, at the end of a step whose deciding parts are all off: whether the
        session's own part of it holds (the controller's own: ``Controller.wakeups``)."""
        if self.targets.pending is not None or self._showing or self._status_key is None:
            return False
        if self._storm_look() != self._storm_seen:
            return False
        motion = self.controller.motion
        for part in self._measuring:
            if part.on(self) and (
                part.wakes is not _BY_MOTION or self._seen_motion.get(part.name) is not motion
            ):
                return False
        return True

    def _poll_step(self, now: float) -> list[Action]:
        """Rule 20: the step when only the poll is due: the poll, its frame, the next wake-up
        (the deciding parts are off and ask for none). The next tick runs the whole step."""
        self._poll_until = -math.inf
        ctl = self.controller
        ctl.poll(now, False)
        link = ctl.link
        assert link is not None
        actions: list[Action] = [Write(frame) for frame in link.output()]
        wakeup = ctl.wakeups(now, now + IDLE_WAKEUP_S, False)[0]  # (no target waits: no stream)
        self._wakeup = self._step_wakeup = self._parts_wakeup(now, wakeup, self._waking_measuring)
        return actions

    def halt(self, now: float) -> list[Action]:
        """A halt a part proposed in the other box of this rotator (runtime/composite.py rule
        6): as that part's halt here, the turn under way stopped and nothing ended."""
        self._halt(now)
        return self._step(now)

    def abandon(self, now: float) -> list[Action]:
        """The other box of this rotator restarted mid-turn and abandoned its turn (runtime/
        composite.py rule 8): the rotator's turn is abandoned here too, a target waiting
        dropped and a turn under way stopped, unsaid (the other box said it); the storm's
        park, this box's own axis, goes on, as when the other box stops answering."""
        ctl = self.controller
        if not self._storm_park_waiting():
            self._drop_pending(None)
        if (ctl.turning() or ctl.cut_mid_turn()) and not self._storm_park():
            ctl.stop(now)
        return self._step(now)

    def stands(self, now: float) -> bool:
        """A turn under way whose rotor has not moved since its target went out, or for
        ``settle_s`` (in which one turning at its speed shows movement): jammed too, or
        refusing it, its own stall or refusal comes (motion.py rules 3 and 8), said and
        counted, not abandoned unsaid (runtime/composite.py rule 8: abandoned once it moves).
        Never a box in a slew (a SatEL reports nothing while it slews) nor one offline."""
        ctl = self.controller
        m, link = ctl.motion, ctl.link
        progress_t, target_t = m.progress_t, m.target_t
        return (
            link is not None
            and link.slew is None  # (a SatEL says nothing while it slews: a review)
            and m.state is MotionState.MOVING
            and m.target_deg is not None
            and m.stop_sent_t is None
            and progress_t is not None
            and target_t is not None
            and (progress_t <= target_t or now - progress_t >= ctl.cfg.motion.settle_s)
        )

    def forsake(self, half: Target | None, now: float) -> list[Action]:
        """The other box of this rotator dropped a target before it went out (rule 23's lease,
        a storm's start: runtime/composite.py rule 8): ``half``, this box's half of the same
        target (None: none, or another sender's since), is dropped here too, unsaid (the
        other box said it): waiting, it is cleared; sent already and under way, its turn is
        stopped, unless a newer target waits that names this box's axis (a storm's park with
        an elevation): one that leaves it out would keep turning it to the dropped half (the
        antenna is never left half moved for a target the lease or the storm refused)."""
        ctl, targets = self.controller, self.targets
        pending = targets.pending
        if half is not None and targets.waits_for(half):
            targets.clear()
        elif half is not None and targets.stands_for(half):
            if (pending is None or _leaves_out(pending, half)) and (
                ctl.turning() or ctl.cut_mid_turn()
            ):
                ctl.stop(now)
        return self._step(now)

    def holds(self, half: Target) -> bool:
        """Whether ``half`` (a target handed to this box of a rotator of two) still waits here
        or is the one its turn under way goes to (runtime/composite.py rule 8)."""
        ctl, targets = self.controller, self.targets
        if targets.waits_for(half):
            return True
        return targets.stands_for(half) and (ctl.turning() or ctl.cut_mid_turn())

    def _halt(self, now: float) -> None:
        """A part's halt: the turn under way stopped, a WSJT-X target waiting dropped."""
        self.targets.clear_from(Source.WSJTX)
        self.controller.stop(now)

    def next_wakeup(self) -> float:
        return self._wakeup

    def hold_reads_until(self) -> float:
        """Bytes arriving before this time can wait in the port (link.py rule 7)."""
        link = self.controller.link
        return link.hold_reads_until() if link is not None else 0.0

    def hold_reads_latest(self) -> float:
        """How late the end of that hold may be met (link.py rule 7)."""
        link = self.controller.link
        return link.hold_reads_latest() if link is not None else 0.0

    # -- commands, applied ----------------------------------------------------------------------
    def _refused(self) -> str | None:
        """Why a target or a track command cannot be taken now, if it cannot."""
        if self.locked:
            return "rotator is locked"
        if self.controller.link is None or not self.controller.answering:
            return "rotator offline"
        return self.wind.refusal()  # wind.py rule 1

    def _fence(self, batch: Batch, now: float) -> bool:
        """Rule 13 (stops.Fence); a hold that ends with clearing drops what waited (True),
        but the storm's park (wind.py rule 8: the bridge's own move, which nobody could send
        again in the storm), which goes now, unsaid."""
        if not self.fence.apply(batch):
            return False
        waiting = self._waiting  # a start taken under the hold: its sender's refusal (rule 24;
        if waiting is not None and not self._began(waiting):  # review 80: 'executed' in the
            waiting = None  # trail)
        if not self._storm_park_waiting():
            pending = self.targets.pending  # (its part's target: said once, as its command)
            of_part = pending is not None and waiting is not None and _proposed(pending, waiting)
            self._drop_pending(None if of_part else self.fence.cleared_why)
        if waiting is not None:
            said = f"{waiting.said}: {self.fence.cleared_why}"
            self._error(ErrorKind.REFUSED, said, command=waiting.what, origin=waiting.origin)
        self._end("a stop or lock came first; send the {} command again", now)
        return True

    def _end(self, why: str, now: float) -> None:
        """Tracking and following end (feature_commands.py), and every part's motion
        (parts.py rule 7): whatever a start that waits under a hold began (rule 13)."""
        self._waiting = None
        self._lookup_held, self._lookup_waiting = False, None
        self.features.end(why)
        self._end_parts(why, now)

    def _end_parts(self, why: str, now: float) -> None:
        """parts.py rule 7: each part's own motion ends (one that raises is reset: rule 14)."""
        for part in self._ending:
            end = part.end
            assert end is not None
            self._guarded(part.name, partial(end, self, why), now)

    def _apply(self, done: Done) -> None:
        """What a tracking or following command did (feature_commands.py), shown."""
        if done.error is not None:  # (a sender named: rule 23's audit)
            error = done.error
            self._error(error.kind, error.message, error.command, origin=error.origin)
        if done.taken is not None:
            self._taken(*done.taken)

    def _taken(self, source: str, origin: Origin | None) -> None:
        """A stop or a new track: the status names its source and no target of before."""
        self.view.last_source = source
        self.view.last_operator = origin.who if origin is not None else None
        self.view.target_info, self.view.park_raw = None, None

    def _leased(self, target: Target | None, now: float, said: str = WAITING_DROPPED) -> str | None:
        """Rule 23: why ``target``, judged before the lease's holder now, may not go out, or
        None (the holder's own, the bridge's own move, the lease free); ``said``: how the
        words begin."""
        if target is None or target.source in OWN_MOVES:
            return None
        return self._barred(target.origin, target.source, now, said)

    def _start_leased(self, start: Track | Follow, now: float, said: str) -> str | None:
        """Rule 23: why ``start`` (tracking or following), judged before the lease's holder
        now, may not start (in the claim's own batch, or at its look-up's answer), or None;
        ``said``: how the words begin."""
        return self._barred(start.origin, start.source, now, said)

    def _barred(self, origin: Origin | None, source: Source, now: float, said: str) -> str | None:
        """Rule 23: why a command from ``origin`` (or ``source``, unnamed) may not turn the
        rotor under the lease as the session has it now, or None."""
        control: Control | None = self.view.control
        if control is None:
            return None
        if same_operator(
            control.operator, sender(origin, source)
        ):  # (as the judge asks: lease.py rule 5)
            return None
        offset = self.wall_offset_s if self._lease_offset_s is None else self._lease_offset_s
        held = control.held_text(now + offset)  # (its minutes as the judge counts them)
        return f"{said}: {held}: only they may turn it (control lease)"

    def _lease_taken(self, now: float) -> None:
        """Rule 23: the lease changed (a claim, a release, its end): a waiting target never
        sent that its new holder did not send is dropped, said and audited."""
        targets = self.targets
        waiting, again = targets.unsent, targets.again_now
        why = self._leased(waiting, now, AGAIN_DROPPED if again else WAITING_DROPPED)
        if waiting is not None and why is not None:
            targets.clear()
            if again:  # (its first try never moved the rotor: its turn is over)
                self.controller.forgo(now)
            self._refuse_leased(waiting, why)

    def _lease_took(self, target: Target, now: float) -> bool:
        """Rule 23: the try more of ``target``, whose first frame never moved the rotor, is not
        sent when the lease is now another operator's (judged at the reading that would send
        it, against the lease then: a claim released since takes nothing), said and audited;
        its turn, which never began, is over. True if so."""
        targets = self.targets
        if target is not targets.standing or targets.pending is not None:
            return False  # (it would not go anyway: targets.py rule 8)
        why = self._leased(target, now, AGAIN_DROPPED)
        if why is None:
            return False
        targets.unstand()
        self.controller.forgo(now)  # (no stall)
        self._refuse_leased(target, why)
        return True

    def _refuse_leased(self, target: Target, why: str) -> None:
        """Rule 23: said on R/error, and (with its sender) in the audit trail."""
        self._drop(target)
        self._refuse_dropped(target, why)

    def _refuse_dropped(
        self, target: Target, message: str, kind: ErrorKind = ErrorKind.REFUSED
    ) -> None:
        """Rule 24: a target dropped here before it went out (or its try more), said on
        R/error (as ``kind``: a restart's drop is said as the ``serial`` fault it is) and,
        with its sender, in the audit trail as a refusal of its command."""
        origin = target.origin or Origin(target.source)
        self._error(kind, message, command=describe_command(target), origin=origin)

    def _drop(self, target: Target) -> None:
        """Rule 23, wind.py rule 1: ``target`` dropped before it moved the rotor; on a rotator of
        two boxes the other box drops its half of that sender's target (``forsake``)."""
        self.drops += 1
        self.dropped = target

    def _wait(
        self,
        not_after_s: float | None,
        what: str,
        said: str,
        by: Origin,
        part: bool = False,
        ends: bool = True,
    ) -> None:
        """Rule 13: a start taken (``what``): under a hold, with an expiry, what it began ends
        if the hold ends past it (``_waited``; ``said``: how that is said); it takes the place
        of the start before it, whose tracking, following or part's motion it ended
        (``ends``). A satellite's look-up ends no tracking or following until its answer
        (review 37: an
        unknown name took the place of a late ``track sun`` waiting, and the sun was tracked
        at the marker): the two are judged as one, by the sooner expiry (the safe side: a
        late look-up also ends following begun in time under the same hold). ``by``: who sent
        it (rule 24). One without an expiry is kept too (never past): a hold that ends
        clearing ends what it began, its sender's refusal (``_fence``)."""
        new = None
        if self.fence.held:
            expiry = math.inf if not_after_s is None else not_after_s
            new = _Waiting(expiry, what, said, part, by)
        if not ends:  # (a look-up: its own, for when its answer begins tracking)
            self._lookup_held, self._lookup_waiting = self.fence.held, new
        before = None if ends else self._waiting
        if new is None or before is None:
            self._waiting = new if ends or before is None else before
            return
        first = new if new.not_after_s < before.not_after_s else before
        self._waiting = first._replace(part=new.part or before.part)

    def _waited(self, now: float) -> None:
        """Rule 13: the hold ended: what a stamped start taken under it began ends if its
        expiry passed (tracking, following, a part's own motion and the target it proposed),
        said once."""
        waiting, self._waiting = self._waiting, None
        self._lookup_held, self._lookup_waiting = False, None
        if waiting is None or not _past(waiting.not_after_s, now) or not self._began(waiting):
            return
        self._end(EXPIRED, now)
        pending = self.targets.pending
        if waiting.part and pending is not None and pending.source not in OWN_MOVES:
            self.targets.clear()  # (the target its part proposed, said once: below)
        said = f"{waiting.said}: {EXPIRED}"  # (rule 24: with its sender, in the audit trail)
        self._error(ErrorKind.REFUSED, said, command=waiting.what, origin=waiting.origin)

    def _began(self, waiting: _Waiting) -> bool:
        """Rule 13: what the start ``waiting`` began is not over already (a part's motion is
        the part's to end; tracking, a look-up or following may have ended)."""
        tracker = self.tracker
        if waiting.part or tracker.body is not None or tracker.lookup is not None:
            return True
        return self.follower.info is not None

    def _part_waited(self, target: Target, now: float) -> bool:
        """Rule 24: ``target`` is the one a feature's command taken under the hold proposed,
        whose expiry passed: ``_waited`` ends that command and drops the target, said once as
        the command its sender sent (review 80: the target was refused first, as a ``target
        az 200`` nobody sent, and the command again)."""
        waiting = self._waiting
        if waiting is None or not _past(waiting.not_after_s, now):
            return False
        return _proposed(target, waiting)

    def _drop_pending(self, why: str | None) -> None:
        """The target waiting dropped; with ``why``, said and audited (rule 24); without,
        unsaid (a lock ON's, whose own line says it; another box's, which said it)."""
        dropped = self.targets.clear()
        if dropped is not None and why:
            self._refuse_dropped(dropped, f"{DROPPED}: {why}")

    def _error(
        self,
        kind: ErrorKind,
        message: str,
        command: str | None = None,
        *,
        said: str | None = "",
        origin: Origin | None = None,
    ) -> None:
        """An error on R/error and in the log (``said``: what the log line adds; None: the
        line at debug level, rule 22; ``origin``: the sender of a command dropped here, for
        the audit trail, rule 23)."""
        what = f" ({command})" if command else ""
        level = logging.DEBUG if said is None else logging.WARNING
        log.log(level, "%s: %s%s%s", self.name, message, what, said or "")
        self.view.last_error = message
        self._actions.append(Report(kind, message, command, origin))

    def _say(self, part: str, now: float) -> str | None:
        """Rule 22: whether part ``part``'s error now gets a log line (what it adds: the count
        of its errors left out since its last one), or None (at debug level)."""
        logged, unsaid = self._part_said.get(part, (-math.inf, 0))
        if now - logged < PART_ERROR_LOG_S:
            self._part_said[part] = (logged, unsaid + 1)
            return None
        self._part_said[part] = (now, 0)
        return f" ({unsaid} more such error(s) since the last such line)" if unsaid else ""

    def _heed(self, now: float) -> None:
        """What the controller noted, applied in the order it came."""
        for note in self.controller.take_notes():
            if isinstance(note, Report):
                message = note.message
                if note.kind is ErrorKind.STALLED and message.endswith(SEND_AGAIN):
                    if self._storm_park():  # wind.py rule 10: nobody can (attack 25: a stall
                        message = message[: -len(SEND_AGAIN)] + PARK_NOT_AGAIN  # said so)
                elif note.kind is ErrorKind.SERIAL and message.endswith(SEND_AGAIN):  # the
                    if self._storm_park():  # box's known restart (stops.py rule 4): no jam,
                        self.wind.lost()  # wind.py rule 7: owed again (review 80: never sent)
                        again = PARK_AGAIN if self.wind.park_owed else PARK_NOT_AGAIN
                        message = message[: -len(SEND_AGAIN)] + again
                self._error(note.kind, message, note.command)
            elif isinstance(note, Ends):
                self._end(note.reason, now)
            elif isinstance(note, Drop):
                self._drop_pending(note.why)
            elif isinstance(note, Retry):  # slew.py rule 4
                storm = self.wind.refusal() if note.target.source is not Source.WIND else None
                if storm is not None:  # wind.py rule 1: not put back, said once (a review: a
                    said = f"{note.late}: {SLEW_STOPPED}: {storm}"  # storm known from a replay,
                    self._refuse_dropped(note.target, said)  # and a SatEL's late slew's target
                    continue  # went again)
                if note.error is not None:
                    self._error(note.error.kind, note.error.message, note.error.command)
                self.targets.put_back(note.target, note.attempt, now, note.of)
            elif isinstance(note, Forgot):  # controller.py rule 14: any target waiting
                waiting = self.targets.pending  # (none after a stop or the lock cleared it)
                if waiting is not None:
                    park = self._storm_park_waiting()  # (the storm's park goes on, wind.py:
                    if not park:  # never named as dropped, a cold review)
                        self.targets.clear()
                    self.controller.restarts += 1  # (a composite's other box abandons its own)
                    error = note.error
                    message = error.message  # (the park goes on: said so, review 80)
                    if park and message.endswith(SEND_AGAIN):
                        message = message[: -len(SEND_AGAIN)] + PARK_AGAIN
                    if waiting is note.target or park or error.command is not None:
                        self._error(error.kind, message, error.command)
                    else:  # a newer target, never sent: its sender's refusal (rule 24; review
                        self._refuse_dropped(waiting, message, error.kind)  # 80: unaudited)
                    self._end("the controller restarted", now)
            elif isinstance(note, Again):  # controller.py rule 11
                took = self._lease_took(note.target, now)  # (said: its refusal is not, below)
                if self.targets.again(note.target, note.az_deg, note.el_deg, now):
                    storm = self.wind.refusal() if note.target.source is not Source.WIND else None
                    if storm is not None:  # wind.py rule 1: no frame in a storm but its park
                        self.targets.clear()  # (a cold review: a target lost on the line just
                        # before a replayed storm went out again in it, the rotor turned while
                        # motion was refused)
                        self.controller.forgo(now)  # (its turn never began: no stall)
                        self._drop(note.target)
                        self._refuse_dropped(note.target, f"{TRY_DROPPED}: {storm}")
                        continue
                    log.warning(
                        "%s: the target did not move the rotor, or was refused before it did "
                        "(lost or garbled on the line?): sending it once more",
                        self.name,
                    )
                    continue
                if self.targets.forsaken(note.target):  # (its feature ended: targets.py rule 8)
                    self.controller.forgo(now)  # (its turn never began: no stall)
                if note.refused is not None and not took:  # (its refusal, as it would have
                    # been told; not when the lease took it: one word, as a storm's, a cold
                    # review: 'target not sent again' and the refusal, two on R/error)
                    self._error(note.refused.kind, note.refused.message, note.refused.command)
                if note.ends is not None:
                    self._end(note.ends, now)

    # -- the features' state the commands, the sky and the status reach by name (rule 17) -------
    def _activity(self, now: float) -> None:
        """Something happened: auto-park's quiet spell starts again (autopark.py rule 1)."""
        self.autopark.activity(now)

    def _ask_sky(self) -> None:
        """What tracking asks of the sky worker (tracking.py rule 8), sent with its generation."""
        asks = self.tracker.take_asks()
        if asks:
            generation = self.tracker.generation
            self._actions.extend(Ask(generation, q) for q in asks)

    # -- the rules, run after every input, in this order ---------------------------------------
    def _step(self, now: float) -> list[Action]:
        ctl = self.controller
        ctl.line_work(now)  # an overdue reply (slew.py), a due stop, the outbox, junk
        if self.targets.forgo_owed():  # (targets.py rule 8: a try more its feature's end took)
            ctl.forgo(now)  # (its turn never began: no stall)
        ctl.tick(now)  # the motion machine's clock, an enable owed
        if ctl.notes:
            self._heed(now)
        if self._answered and not ctl.answering:  # wind.py rule 7: offline in a storm,
            self.wind.lost()  # its park (stopped at the offline, or dropped) owed again
        elif self._storm_park_seen():
            self.wind.arrived()  # (wind.py rule 7: the last status saw it at the storm's park)
        self._answered = ctl.link is not None and ctl.answering
        self.wind.answering(self._answered)  # (wind.py rule 9: what its park waits for)
        if ctl.link is not None and ctl.answering:
            going = self.targets.pending is not None and not self.fence.held
            ctl.check_stop(now, going, self.locked)  # (stops.py rule 7: the lock's own check)
            if ctl.notes:
                self._heed(now)
            self._parts(self._deciding, now)  # rule 17: the parts that decide
            waits = self.targets.pending is not None
            ctl.send_options(now, waits)  # (one that may go while a target waits goes first:
            if waits:  # the turn starts at the speed set, not the box's own: an attack pass)
                self._try_target(ctl.link, now)
        ctl.halt_owed(self.features.owing)  # (feature_commands.py rule 7: owed while the
        # refused start's feature is on, however it ended since; motion.py rule 4)
        ctl.poll(now, self.targets.pending is not None)  # commands go ahead of the next poll
        if ctl.notes:
            self._heed(now)
        if self._answered and not ctl.answering:  # wind.py rule 7: the poll's own offline,
            self.wind.lost()  # told now (review 80: a reply as the very next input made it
            self._answered = False  # answering again before any step saw it offline, and
            self.wind.answering(False)  # the park it cut short was never owed again)
        self._parts(self._measuring, now)  # what they measure is in the status
        self._emit_status(now)
        frames = ctl.link.output() if ctl.link is not None else None
        if frames:
            self._actions += [Write(frame) for frame in frames]
        self._ask_sky()
        off = self._deciding_off()  # (a part that is off is asked for no wake-up: rule 17)
        waking = self._waking_measuring if off else self._waking
        wakeup, self._poll_until = self._next_wakeup(now, waking, off and self._poll_alone())
        self._wakeup = self._step_wakeup = wakeup
        actions, self._actions = self._actions, []
        return actions

    def _parts(self, parts: tuple[Part[RotatorSession], ...], now: float) -> None:
        """Rule 17: each part that is on and that something woke, in the order handed in."""
        if self._storm_look() != self._storm_seen:  # (its look, without a call when the
            self._storm(now)  # storm is as it was: twice at every step)
        for part in parts:
            if not part.on(self):
                continue
            if part.wakes is _BY_MOTION:  # only a motion it has not seen
                motion = self.controller.motion
                if self._seen_motion.get(part.name) is motion:
                    continue
                self._seen_motion[part.name] = motion
            self._part(part, now)
            if self._storm_look() != self._storm_seen:
                self._storm(now)

    def _storm(self, now: float) -> None:
        """parts.py rule 7: a storm that began ends every part's own motion, as it ends
        tracking and following (rule 15). One that ended starts auto-park's quiet spell
        again, as unlocking does (autopark.py rule 1): the reading that ended it moves
        nothing (an attack pass: auto-park's spell, long over in the storm, parked the rotor
        the instant a calm reading ended it), and the storm's park still waiting goes no more
        (wind.py rule 8). A storm that ended and a next that began since the last look (both
        judged at readings, wind.py rule 2: the controller silent meanwhile) are both."""
        storm = self.wind.storm
        seen, storms = self._storm_seen
        new = self.wind.storms != storms
        if seen and (not storm or new):
            self._activity(now)
            self.targets.clear_from(Source.WIND)  # wind.py rule 8: a park still waiting (a
            # STOP's hold) or its try more goes no more, unsaid (review 60: it went when the
            # hold ended after the storm, the rotor turned 90 degrees unasked)
        if storm and (not seen or new):
            why = self.wind.refusal() or "storm"
            self._end_parts(why, now)
            for ended in (Source.TRACKING, Source.WSJTX, Source.AUTO_PARK):  # (the storm
                self.targets.clear_from(ended)  # ends them: their own ``*_ended`` says why; a
                # cold review, a WSJT-X target waiting for a Rotor-EZ's brake was refused on
                # R/error as a 'target az 296.065' nobody sent, and so was auto-park's park,
                # waiting for a fresh reading, as 'target az 0')
            pending = self.targets.pending  # wind.py rules 1 and 6: a target not sent yet is
            if pending is not None and pending.source is not Source.WIND:  # refused too (an
                self._drop(pending)
                self._drop_pending(why)  # attack pass: a storm known only from a replay
                # parked nothing in its place, and a Rotor-EZ's target, waiting for the brake,
                # went out 6 s into the storm)
        self._storm_seen = self._storm_look()

    def _storm_look(self) -> tuple[bool, int]:
        """``_storm``'s look: whether in a storm, and the storms begun so far."""
        return self.wind.storm, self.wind.storms

    def _part(self, part: Part[RotatorSession], now: float) -> None:
        """A part decides on a read-only scene; its proposal is applied here."""
        link, motion, pending = self.controller.link, self.controller.motion, self.targets.pending
        slewing = link is not None and link.slew is not None
        parked, offset_s = self.status.parked, self.wall_offset_s
        parking = self.view.last_source == Source.AUTO_PARK.value
        held = self.locked or self.lock_unknown  # (parts.py rule 7: a lock not known yet)
        speeds = self.controller.cfg.speeds  # (parts.py rule 9: the speeds in effect)
        scene = Scene(
            now, motion, pending, held, parked, slewing, offset_s, speeds, parking, self.judge_whole
        )
        try:  # (_guarded's, without a closure: the measuring parts run at every reading)
            proposal = part.step(self, scene)
        except Exception:
            self._failed(part.name, now)
            return
        if proposal is not None and proposal.target is not None and self._still(proposal.target):
            proposal = replace(proposal, target=None)  # parts.py rule 7
        if proposal is not None:
            self._propose(proposal, now, part.command is not None, part.name)

    def _feature_command(self, command: FeatureCommand, now: float) -> None:
        """parts.py rule 5: a feature's own command to its part; what it proposes, applied."""
        what = describe_command(command)
        part = self._parts_named.get(command.feature)
        run = part.command if part is not None else None
        if part is None or run is None:
            message = f"no feature {command.feature!r} takes commands on this rotator"
            self._error(ErrorKind.REFUSED, message, command=what)
            return
        if command.moves:  # the later command wins: it ends tracking and following, as a
            self._end(f"{command.feature} command", now)  # target does (rules 10, 15)
            refused = self._refused()  # and, refused, it reaches no part, as a track start
            late = _late(command.not_after_s, now, f"{command.feature} command not carried out")
            refused = refused or late  # (rule 13)
            if refused is not None:
                self._error(ErrorKind.REFUSED, refused, command=what)
                return
            by = command.origin or Origin(command.source)
            said = f"{command.feature} command ended"
            self._wait(command.not_after_s, what, said, by, part=True)
        proposal = self._guarded(part.name, lambda: run(self, command, now), now)
        if proposal is None:
            return
        if (proposed := proposal.target) is not None:
            refused = self._refused() if command.moves else "the command does not move the rotor"
            if refused is None:
                refused = self._outside(proposed)
            if refused is not None:
                self._error(ErrorKind.REFUSED, refused, command=what)
                proposal = replace(proposal, target=None)
            elif command.not_after_s is not None:  # rule 13: the target goes by its expiry
                ends = replace(proposed, not_after_s=command.not_after_s)  # (attack 8: left by
                proposal = replace(proposal, target=ends)  # a later command, it went at once)
        self._propose(proposal, now, True, part.name)

    def _storm_park(self) -> bool:
        """The turn under way is the storm's park (wind.py): on a rotator of two boxes, one
        box's park goes on when the other stops answering (runtime/composite.py rule 8), as
        it parks alone in a storm begun while the other did not answer."""
        return self.wind.storm and self.view.last_source == Source.WIND.value

    def _storm_park_seen(self) -> bool:
        """wind.py rule 7: the last status saw the rotor at rest at the storm's park. Never on a
        controller that cannot report where it stands (a DCU-1): its ``parked`` says only that
        the estimated move is over (a review of 3e4f0f4: a DCU-1 whose adapter had wedged when
        the storm began never heard its park, was unplugged and plugged in again, and the park
        was not sent again: the antenna stood 150 degrees from it for the whole storm)."""
        return (
            self.cfg.spec.can_report_position
            and self.status.parked
            and self._storm_park()
            and self.targets.pending is None
        )

    def _storm_park_waiting(self) -> bool:
        """The target waiting is the storm's park (wind.py): on a rotator of two boxes, kept
        when the other box stops answering (runtime/composite.py rule 8), as one under way
        goes on (``_storm_park``; an attack pass: a Rotor-EZ azimuth box's park, held back by
        its brake delay when the elevation box fell silent, was dropped, and nothing sent it
        again: the antenna stood 150 degrees short of the park for the whole storm)."""
        pending = self.targets.pending
        return self.wind.storm and pending is not None and pending.source is Source.WIND

    def _still(self, target: Target) -> bool:
        """parts.py rule 7: no part's step target goes to a locked rotor, nor to one whose
        lock is not known yet (runtime/kept.py rule 10: the wind's park neither), nor in a
        storm but the wind's own park (auto-park waits, tracking and following are ended),
        nor once the bridge's end began but the storm's park (rule 21)."""
        if self.locked or self.lock_unknown:
            return True
        return (self.wind.storm or self.ending) and target.source is not Source.WIND

    def _outside(self, target: Target) -> str | None:
        """Why the controller may not be sent a part's target (its limits, a keep-out sector:
        pointing.py rule 8), if it may not: a feature's part judges its own, checked here."""
        try:
            self.cfg.aim.check_raw(target)
        except Refused as exc:
            return exc.message
        return None

    def _propose(self, proposal: Proposal, now: float, commanded: bool, name: str) -> None:
        """A part's proposal, applied in this order (parts.py rule 1); ``commanded``: the part
        takes its feature's own commands (on a rotator of two boxes it runs in one alone);
        ``name``: the part's."""
        if proposal.busy:
            self._activity(now)  # (tracking.py rule 7)
        if proposal.error is not None:
            error = proposal.error
            self._error(error.kind, error.message, error.command, said=self._say(name, now))
        if proposal.ended is not None:
            self.features.end(proposal.ended)  # (tracking may have ended itself)
            self.targets.clear_from(Source.TRACKING)
        if proposal.halt:  # following: a transmission began during its turn (follow.py rule 3);
            # the wind: its storm's park refused (wind.py rule 5)
            self._halt(now)
            self.part_halts += commanded  # (a composite's other box: runtime/composite.py rule 6)
        if proposal.drop is not None:  # (auto-park's, a hand before it went: autopark.py rule 3)
            self.targets.clear_from(proposal.drop)
        if proposal.target is not None:
            self.targets.put(proposal.target, now)
            if proposal.target.source in UNASKED and self._place is not None:
                # (Order: the bridge's own turn, auto-park's or the storm's park, takes a place
                # of its own, after every command asked before it began, and the status shows
                # every place up to it: a remote's STOP asked before it never ends it, one
                # asked against it does: interfaces/mqtt/remote.py rule 10, review 83; the
                # place is the rotator's, one turn one place however often begun, both boxes'
                # parks one place on a composite: mailbox.py rule 10b, runtime/composite.py
                # rule 10, reviews 86 and 91)
                self._turn_place = self._place(self._own_turn(proposal.target.source, now))
                self._taking = max(self._taking, self._turn_place)

    def _own_turn(self, source: Source, now: float) -> OwnTurn:
        """mailbox.py rule 10b: what names a turn of the bridge's own as it begins: the storm's
        park by its storm (one turn, however often begun in it: again once the controller
        answers, wind.py rule 7, or by a composite's other box plugged back, review 91),
        auto-park's by the moment it began (a composite's two boxes park together, in one
        serve: runtime/composite.py rule 10; the next spell's park is another turn)."""
        if source is Source.WIND:  # (storms 0: the storm kept across the restart, review 96)
            kept = self._storm_place if self.wind.storms == 0 else 0
            return OwnTurn(source, self.wind.storms, kept)
        return OwnTurn(source, now)

    def _guarded(self, name: str, run: Callable[[], T], now: float) -> T | None:
        """Rule 14: a part that raises is reset and reported (``_failed``); nothing else
        stops."""
        try:
            return run()
        except Exception:
            self._failed(name, now)
            return None

    def _failed(self, name: str, now: float) -> None:
        """Rule 14, in the handler of what part ``name`` raised: logged with it, reset (its own
        reset, the ``Part`` handed in under ``name``: one not handed in has none), reported."""
        log.exception("%s: %s failed", self.name, name)
        part = self._parts_named.get(name)
        if part is not None:
            part.reset(self, now)
        self._seen_motion.pop(name, None)  # a new part has seen nothing yet
        self._error(ErrorKind.INTERNAL, f"{name} failed (a bug, see the log): {name} reset")

    def _try_target(self, link: Link, now: float) -> None:
        ctl, pending = self.controller, self.targets.pending
        assert pending is not None
        if ctl.options.unanswered:  # options.py rule 1: a reply never came (was the box off?):
            if link.free():  # the target follows an answer, and the settings it owes first
                link.poll_now(now)
            return
        if now < link.setting_until:  # link.py rule 4: a refusal now is the setting's
            return
        # (the controller's configuration: a speed setting's settle time, controller.py rule 7,
        # the one its stop's repeat, stops.py rule 2, counts with too: a cold review)
        todo = decide(ctl.cfg, link, ctl.motion, self.targets, self.fence.held, now)
        if todo.go is Go.DONE:
            self._aimed(self.targets.done(), todo.wire)
        elif todo.go is Go.STOP_FIRST:
            ctl.stop(now)
        elif todo.go is Go.ASK_FIRST:
            link.poll_now(now, self.cfg.moving_poll_interval_s)  # ask first; the target
            # follows the answer (a noisy line: at the moving rate, link.py rule 11)
        elif todo.go is Go.SEND:
            attempt = self.targets.sent(now)
            ctl.send(todo, pending, attempt, now)
            if attempt == 1 and pending.source in UNASKED:  # rule 25: the trail names the
                self._actions.append(Audit(Origin(pending.source), "park"))  # feature, sent
            self._aimed(pending, todo.wire)

    def _aimed(self, target: Target | None, wire: tuple[float, float | None]) -> None:
        """What the status says about the target now taken (status.py rule 4)."""
        if target is not None:
            view = self.view
            view.last_source, view.last_operator = st.sent_by(target, view.last_operator)
            self.view.target_info = target.info
            self.view.park_raw = wire if target.park else None
            if target.source is Source.WIND:
                self.wind.sent(wire)  # (wind.py rule 10: where it is parked, as held there)

    def _emit_status(self, now: float) -> None:
        """Rule 18: the status is built again only when something it shows may have changed."""
        ctl, tracker, follower, wind, health = (
            self.controller,
            self.tracker,
            self.follower,
            self.wind,
            self.health,
        )
        link, view = ctl.link, self.view
        slew = link.slew if link is not None else None
        wind.held_back(self.fence.held and self._storm_park_waiting())  # (wind.py rule 9)
        if wind.storm:  # (wind.py rule 10: where the rotor stands against the park sent)
            m = ctl.motion
            going = m.target_deg is not None or m.el_target_deg is not None or slew is not None
            both = self.cfg.wind is not None and self.cfg.wind.park[1] is not None  # (its
            where = ctl.where(both=both) if m.position_deg is not None else ""  # elevation too)
            wind.seen(m, going or self._storm_park_waiting(), where)
        key: tuple[object, ...] = (  # one flat tuple: this runs at every step
            # (the bearings first: a turning rotor's every reading changes one, and the
            # comparison ends there, before the motion's __eq__ compares its every field)
            ctl.az_shown.value,
            ctl.el_shown.value,
            ctl.motion,
            ctl.cfg,
            link,
            link is not None and link.stop_due,  # (a stop waiting drops the target shown)
            slew,  # (its end ends the estimate)
            ctl.answering,
            ctl.version,
            ctl.controller_time,
            ctl.options.revision,
            self.targets.pending,
            self.locked and self.lock_shown,  # (runtime/kept.py rule 2)
            self.lock_unknown,  # (runtime/kept.py rule 10)
            view.last_error,
            view.last_source,
            view.target_info,
            view.park_raw,
            view.last_operator,
            view.control,
            ctl.stops.owed,  # (kept across a restart: runtime/kept.py)
            self._turn_place,  # (Order: a new turn is a new status, the same bearing too)
            self._lock_place,
            # what the parts show (st.Features, in its order: the last _SHOWN of the key)
            tracker.info,
            tracker.ended,
            follower.info,
            follower.ended,
            wind.info if wind.on else None,
            health.report,
            self._shown(now) if self._showing else None,  # parts.py rule 6
        )
        if key == self._status_key and slew is None and ctl.cfg.spec.can_report_position:
            return  # (a slew's estimate and a DCU-1's estimated move read the time: status
            # rules 2 and 3)
        self._status_key = key
        shown = st.Features._make(key[-_SHOWN:])
        seen = ctl.seen(
            self.status,
            self.view,
            self.targets.pending,
            self.locked and self.lock_shown,  # in effect and saved: kept.py rule 2
            self.wall_offset_s,
            shown,
        )
        # the last status's Order while it says the same places: R/status's text keeps what a
        # reading leaves by its very objects (payloads.py StatusText), and an Order made anew
        # at every reading made the rest of that text again at every one
        order = self.status.order
        if order is None or (order.run, order.taken, order.turn, order.lock) != (
            self._run,
            self._taking,
            self._turn_place,
            self._lock_place,
        ):
            order = Order(self._run, self._taking, self._turn_place, self._lock_place, self._since)
        status = st.current(ctl.cfg, seen, now, order)  # (controller.py rule 7)
        if self.lock_unknown:  # (runtime/kept.py rule 10)
            status = replace(status, lock_unknown=True)
        if st.worth_emitting(status, self.status):
            self._actions.append(Publish(status))
        self.status = status  # also when only the controller's clock changed (status rule 4)
        self.target_unshown = ctl.pending_unshown  # (after the status: ``newest_applied``)

    def _shown(self, now: float) -> dict[str, object]:
        """parts.py rule 6: what each part shows in the status, by its name (one that raises
        shows nothing; rule 14 once per kind of failure: rule 19)."""
        shown: dict[str, object] = {}
        for name, status in self._showing:
            try:
                value = status(self)
            except Exception as exc:
                failed = self._status_failed.setdefault(name, set())
                if type(exc) not in failed:  # rule 19: said (and reset) once per kind
                    failed.add(type(exc))
                    self._failed(name, now)
                continue
            if value is not None:
                shown[name] = value
        return shown

    def _next_wakeup(
        self, now: float, waking: tuple[Part[RotatorSession], ...], alone: bool
    ) -> tuple[float, float]:
        """The soonest of the controller's, the stream's and ``waking``'s (the parts with a
        wake-up: all of them, or those a step did not find off); and rule 20's time, if
        ``alone`` (the session's part of it holds: ``_poll_alone``), -inf if not (the
        controller's ``wakeups`` judges its own part of it with the same look at the line)."""
        wakeup, until = self.controller.wakeups(now, now + IDLE_WAKEUP_S, alone)
        stream = self.targets.stream_deadline(now) if self.targets.pending is not None else None
        if stream is not None and stream < wakeup:
            wakeup = stream
        return self._parts_wakeup(now, wakeup, waking), until

    def _parts_wakeup(
        self, now: float, wakeup: float, waking: tuple[Part[RotatorSession], ...]
    ) -> float:
        """``wakeup``, or sooner if a part of ``waking`` that is on asks for it."""
        for part in waking:
            if part.on(self) and part.wakeup is not None:
                t = part.wakeup(self, now)
                if t is not None and t < wakeup:
                    wakeup = t
        return wakeup


def _leaves_out(target: Target, half: Target) -> bool:
    """Whether ``target`` names neither axis ``half`` names (it keeps that axis's target)."""
    az = half.az_deg is not None and target.az_deg is not None
    el = half.el_deg is not None and target.el_deg is not None
    return not (az or el)


def _proposed(target: Target, waiting: _Waiting) -> bool:
    """Rule 24: ``target`` is the one the feature's command ``waiting`` had its part propose
    (its end is said once, as that command)."""
    return waiting.part and target.source not in OWN_MOVES and target.origin == waiting.origin


def _past(not_after_s: float | None, now: float) -> bool:
    """Rule 13: a stamped command's expiry (None: none) passed."""
    return not_after_s is not None and now > not_after_s


def _expired(target: Target, now: float) -> bool:
    """Rule 13: a stamped target past its expiry."""
    return _past(target.not_after_s, now)


def _late(not_after_s: float | None, now: float, said: str) -> str | None:
    """Rule 13: why a stamped start taken past its expiry is refused (``said``: how the words
    begin), or None."""
    return f"{said}: {EXPIRED_TAKEN}" if _past(not_after_s, now) else None


class _Waiting(NamedTuple):
    """Rule 13: a start taken under a hold (``RotatorSession._wait``)."""

    not_after_s: float  # its expiry (inf: none)
    what: str  # the command, as the error names it
    said: str  # how its end is said
    part: bool  # a feature's own command (its part's motion), not a track or follow start
    origin: Origin  # who sent it: its end is a refusal of that sender's command (rule 24)
