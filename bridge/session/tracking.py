"""Following the sun, the moon or a satellite (``R/track``): the tracker owns what is tracked and
decides the targets. Pure: each step gets a read-only ``Scene`` (parts.py: the time, the
motion, the pending target) and returns a ``Proposal`` the session applies; what the sky says
comes from skytrack.py (the sky worker's answers, rule 8).

Rules:
1. Tracking starts on a Track command and ends on ``R/track off``, a stop, the lock, any
   other target (a manual one, rotctld's P, a preset, a nudge, a park), the rotor turned by
   hand (parts.py rule 8), a stall, the serial link going down or the controller falling
   silent: the rotor never turns by itself after any of these. The status says why
   (``tracking_ended``). Tracking's own targets are put here, not in the mailbox, so they
   never end it. It goes on from pass to pass until it is ended. A step is measured from the
   last target and, once the rotor has got there (arrived, not still on its way), from where
   it really is: a rotor that fell short or was turned gets the step again; one turned away
   while still holding the last step is left to the motion machine's verdict (a stall ends
   tracking), never pulled back.
2. Passes: while the body is below ``min_el_deg`` the rotator waits at the azimuth where the
   next pass rises (at the minimum elevation): at once when tracking starts, and after a pass
   when the rotor, at its real speeds, would just make it in time plus PREPOSITION_MARGIN_S
   (its way measured along its travel, motion.py rule 5: a review, a Hy-Gain rotor left at
   170 by one pass came to the next, rising at 190, 35 s late: 340 degrees timed as 20). Its
   real speeds are those in effect (``Scene.speeds``, parts.py rule 9), here and in rule 4
   (the flip): attack 19, a GS-232B set to speed 1 was timed at full speed and stood 99 degrees
   off, still turning, when the pass rose.
   At the end of a pass it parks (``at_los = "park"``, if a park position is configured) or
   stays where it is. A wall clock stepped back (NTP) has a pass that has not begun by it
   waited for again (an attack pass: five minutes back mid-pass, the pass in hand still the
   next one, the rotor stood where the satellite had been until AOS came round again).
3. During a pass a new target goes out when the body has moved ``step_deg`` on either axis
   from the last one, and only when the controller may take one: any time on a controller that
   re-targets while turning (SPID); when the rotor is idle on the others (a Rotor-EZ stops to
   re-target, a SatEL takes no input while slewing). The target leads the body by half a
   step, so the rotor straddles it: within half a step either side, plus what the rotor lags.
   Not the first target of a start (where the rotor waits for the pass, rule 2, or the first
   step of a pass under way): the track command is the user's newest, and that target is put
   while the rotor turns or slews, as any newest target is (targets.py: a Rotor-EZ's turn to
   an older target is stopped and the step sent after the brake delay, a SatEL's slew stopped
   and the step sent once still, a SPID or GS-232 re-targeted on the fly); only a stop's brake
   window and the settle time after the first reading (motion.py rule 4) are waited out, as
   for every step. Review 46: ``track sun`` typed while a Rotor-EZ turned to a target 120
   degrees from the sun waited for that turn to end, the rotor turning away from the sun for
   some 20 s, and only then turned all the way back. A stall is no window: the motion stays
   stalled until a target goes out (motion.py rule 3), so a start's first target is put then
   as well and goes as an ``R/target`` would (targets.py, motion.py ``plan_target``: once the
   stall's brake delay is over; at once on a controller that re-targets while turning).
   Review 50: a start taken after a jam freed waited on the stall for ever, nothing sent.
4. Flip: an az/el rotor whose elevation reaches 180 minus the minimum elevation flies a
   satellite's pass with elevation 180 - el and azimuth + 180 when that saves turning time
   during the pass: both axes at their real speeds, each raw azimuth picked as the judge would
   (the first from where the rotor is); the saving must exceed FLIP_SAVING_DEG at the azimuth
   speed. A step the judge refuses (a limit, a keep-out sector) counts as its share of the
   pass spent off the body, the rotor held (rule 5), for either way alike (attack 19: a limit
   counted as endless and a keep-out sector as free, a pass across the north was flown
   flipped through a southern sector, the antenna up to 60 degrees off the satellite for 137 s
   of 300, where not flipping cost one 54 s unwind). A pass across a
   stop (the north on a 0..360 rotor) then stays clear of it. Decided once per pass. Never on a
   rotator of two boxes (``TrackConfig.flip``): each box's session would decide it for its own
   axis, from what its own box knows (an attack pass: an RT-21 azimuth box never flipped, its
   GS-232B elevation box, 0..180, flew the pass at 180 - el, and the antenna faced 180 degrees
   away from the satellite for the whole pass).
5. Every target goes through the same judge as any other (pointing.py: limits, keep-out
   sectors). One it refuses is skipped, reported once per pass, and the rotor holds until the
   body is back where it may go. A pass that rises where the judge refuses (a keep-out
   sector, a limit) is waited for at the first point of its track the judge takes (an attack
   pass: the rotor stood where it was until the satellite left the sector, then turned 200
   degrees to it). A start whose first target is refused holds the rotor where it is: a turn
   under way (to an older target, or one the start found going on by itself, parts.py rule
   8) is stopped (``Proposal.halt``, parts.py rule 10: ``StartHalt``), as the start's own
   target would have stopped it (rule 3); on a DCU-1 (no readings) the turn its own target
   may still be making (review 52). The first target is the wait where the next pass rises
   (rule 2) as much as the first step of a pass under way: it counts as put (``_last``) only
   once the judge took it (attack 19: a start whose wait was refused, the whole pass in a
   keep-out sector, was taken for a later step, and a Rotor-EZ said "holding" while it turned
   on 110 degrees to the older target). Review 50: ``track sun`` with the sun in a keep-out
   sector said "holding" while a Rotor-EZ turned on to the older target, 120 degrees from the
   sun. Once per start: the stop then takes its course (review 52: a SatEL's slew, stopped
   and waited out silently, was halted again at every step, a stop five times a second and
   the status "moving" for good). A turn carried over a lost link that no reading back has
   shown yet is halted at the step the next one shows it move, the wait not judged again
   (``StartHalt.owed``, parts.py rule 10; review 70: a refused start right after a replug
   mid-turn said "holding" while the rotor turned on 95 degrees; review 84: so a turn a
   bridge just started finds, right after a restart mid-turn).
6. Azimuth-only rotors follow the azimuth; the body's elevation only decides the passes. An
   az/el rotor's elevation is held within its limits (and above ``min_el_deg``): beyond them
   it is no refusal, the azimuth is followed at the limit (``_aim``), the limit as the
   controller is sent it (a SatEL's 75 is 70: its ten-degree steps, pointing.py).
7. Tracking is activity for auto-park: a rotor that is tracking never parks by itself.
8. Nothing of the sky is computed here (docs/architecture.md, "nothing slow beside a stop"):
   pass searches, windows of the body's track, a pass's samples for the flip and TLE file
   look-ups are questions (skywork.py, skytrack.py) the session hands to the sky worker, and
   their answers come back as inputs.
   Until an answer is in, tracking waits: no target from it, the status's block as it was.
   Each start or end of tracking is a new generation: an answer asked for before it is
   dropped (a stop or ``off`` meanwhile is never undone by a late answer). An answer that says
   the sky cannot be computed (an orbit decayed, a date beyond the ephemeris) ends tracking
   with that reason. A look-up leaves what is tracked alone until its answer names a body.
9. The side: on a rotor that can pass 360 (a 450-degree Yaesu, a SPID's overlap) the pass's
   first target (where it waits for AOS, or the first step of a pass tracking starts in) is
   sent on the side from which the rest of the pass turns least (of two that turn alike, the
   one nearest the rotor, judged once a park after the pass before has left it at rest: a
   review, the side nearest where that pass ended sent the rotor 290 degrees back from its
   park), the pass's track followed from there as the judge picks each step (nearest); each
   later step takes the side nearest the target before it, not the rotor's reading: a
   controller that takes a new bearing while turning may still be on its way to the pass's
   side (an attack pass: a GS-232B 450 at 1 degree a second, started mid-pass at 182, was
   sent W369, then the next step W009 from where it then was, and unwound at the north). The
   flip (rule 4) is weighed with each way started on its best side. An attack pass: a GS-232B
   450 kept to 0..90 of elevation waited at W010 for a pass running west through the north,
   and unwound to W358 mid-pass where W370 was free.
10. A satellite tracked by its name in the TLE file is looked up again every LOOK_AGAIN_S
   while a pass is waited for (the file is read only if it changed, catalog.py rule 1): new
   elements for it are flown from then on, from the pass they give next, as if tracking had
   just started (after a pass: parked or stayed as it was). Never mid-pass: an answer that
   comes once the pass has begun is left for its end. A file that no longer has it keeps the
   elements in hand (said in the log, once a reason). Elements sent whole are kept as sent.
   (An attack pass: ISS tracked for days by the elements of the day it started, the file
   refreshed by cron every morning. Looked at once a pass only, the two boxes of one rotator
   could each read another version of the file, a moment apart, and fly a pass apart.)
11. Elements older than STALE_DAYS when tracking starts with them (or takes them, rule 10) are
   said in the log, once for them, with their age and epoch: nothing else says that a cron job
   stopped refreshing the file (an attack pass: elements four months old were flown without a
   word, passes minutes off). The status's tracking block carries their epoch and whether they
   are older than STALE_DAYS now, so a page shows it where the pass is shown (the log alone
   reached nobody at the radio). Elements dated more than AHEAD_DAYS after the station's clock
   are said the same way (``elements_ahead``): no TLE is made for a time that far on, so the
   clock is wrong (a Raspberry Pi without a real-time clock, started before its time was set,
   runs days or years behind), and every position flown is for the wrong time.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, replace
from datetime import UTC, datetime

from bridge.core.errors import Refused
from bridge.core.model import ErrorKind, MotionState, Origin, Source, Target, TrackingInfo
from bridge.pointing import angle_between
from bridge.session import motion as mo
from bridge.session.actions import Report
from bridge.session.config import WorkerConfig
from bridge.session.parts import NOTHING, Before, Proposal, Scene, StartHalt, turned_by_hand
from bridge.session.skytrack import CLOCK_BACK_S, SkyTrack, flip_times
from bridge.sky import Body, Pass, tle_epoch_unix
from bridge.sky.worker import Answer, LookupQuestion, Question

log = logging.getLogger(__name__)

SAMPLE_S = 1.0  # tracking looks at the sky at least this often
PREPOSITION_MARGIN_S = 20.0
PASS_TRACK_POINTS = 40  # the pass as the status shows it (_thinned)
INFO_EVERY_S = 5.0  # the status's tracking block is refreshed this often (and on a target)
NEXT_S = 60.0  # the status's "next" position: this far ahead
MAX_LEAD_S = 300.0
FLIP_SAVING_DEG = 30.0
STALE_DAYS = 14.0  # rule 11
AHEAD_DAYS = 3.0  # rule 11: an operator's predicted elements may be dated a day or two on
LOOK_AGAIN_S = 60.0  # rule 10


@dataclass(frozen=True)
class Track:
    """Start following ``body``; or look the satellite ``lookup`` up in the TLE file first (the
    file is read by the sky worker: rule 8); or stop (neither)."""

    body: Body | None
    source: Source = Source.MQTT
    lookup: LookupQuestion | None = None
    described: str | None = None  # the command as the user gave it (a refusal names it)
    origin: Origin | None = None  # who asked (the status's last_operator)
    from_file: LookupQuestion | None = None  # rule 10: how ``body`` was found in the TLE file
    # a stamped start's expiry (core/model.py ``Move``): one that waits for the order of a STOP
    # or lock goes no later (session.py rule 13)
    not_after_s: float | None = None


class Tracker:
    def __init__(self, rig: WorkerConfig) -> None:
        self._rig = rig
        self.cfg = rig.tracking
        self.body: Body | None = None
        self.ended: str | None = None
        self.info: TrackingInfo | None = None
        self.generation = 0  # rule 8: an answer asked for before a start or an end is stale
        self.lookup: Track | None = None  # a look-up under way (the body tracked goes on)
        self._lookups: list[Question] = []  # rule 8: look-ups not yet handed out
        self._reset(None)

    def _reset(self, body: Body | None) -> None:
        self.generation += 1
        self.lookup = None
        self._sky = SkyTrack(self.cfg, body) if body is not None and self.cfg.sky else None
        self._flip = False
        self._flip_for: float | None = None  # the AOS the flip was decided for
        self._last: tuple[float, float | None] | None = None  # last target put (true, flipped)
        self._waited_for: float | None = None  # AOS of the pass the rotor went to wait for
        self._sided_for: float | None = None  # AOS of the pass whose first target chose a side
        self._last_raw: float | None = None  # rule 9: the raw azimuth of the last target put
        # where to wait for the pass of this AOS (rules 5, 9): (AOS, az, el, side)
        self._wait_at: tuple[float, float, float | None, tuple[float | None]] | None = None
        self._parked_after: float | None = None  # LOS of the pass parked (or stayed) after
        self._refused_for: float | None = None
        self._halt = StartHalt()  # rule 5 (parts.py rule 10): the start's one halt
        self._before = Before()  # rule 1 (parts.py rule 8): the turn the start found
        self._info_t = -math.inf
        self._utc_seen = -math.inf  # rule 2: the latest wall clock a step saw
        self._from_file: LookupQuestion | None = None  # rule 10: to look the body up again by
        self._looked_at = -math.inf  # rule 10: the wall clock of the last look
        self._kept_for: str | None = None  # rule 10: why the elements in hand were last kept
        self._stayed = False  # rule 10: parked (or stayed) after the pass, by the old elements
        self._aged: Body | None = None  # rule 11: the elements whose age was judged
        self._epoch: float | None = None  # rule 11: their epoch (unix), if they have one

    @property
    def owing(self) -> bool:
        """A body is tracked and its start's refusal owes a halt to a turn not yet seen (rule
        5, parts.py rule 10): ended, it owes nothing (feature_commands.py ``owing``)."""
        return self.body is not None and self._halt.owing

    # -- rule 1 ----------------------------------------------------------------------------
    def start(self, body: Body, from_file: LookupQuestion | None = None) -> None:
        self._reset(body)
        self.body, self.ended, self.info = body, None, TrackingInfo(body.name, "waiting")
        self._from_file = from_file

    def end(self, why: str) -> bool:
        """Stop following (``why`` shows as ``tracking_ended``); whether anything was tracked.
        A look-up under way is dropped too (its answer comes too late)."""
        if self.body is None:
            self.lookup = None
            self.generation += 1
            return False
        log.info("tracking %s ended: %s", self.body.name, why)
        self.body, self.ended, self.info = None, why, None
        self._reset(None)
        return True

    def look_up(self, track: Track) -> None:
        """Rule 8: ask the sky worker for the satellite by name; whatever is tracked goes on
        until the answer (an unknown name changes nothing)."""
        assert track.lookup is not None
        self.lookup = track
        self._lookups.append(track.lookup)

    def wakeup(self, now: float) -> float | None:
        """Tracking looks at the sky at least once a second."""
        return now + SAMPLE_S if self.body is not None else None

    # -- rule 8: questions and answers -------------------------------------------------------
    def take_asks(self) -> list[Question]:
        """The questions for the sky worker not yet handed out (the session asks them)."""
        asks, self._lookups = self._lookups, []
        if self._sky is not None:
            asks += self._sky.asks
            self._sky.asks = []
        return asks

    def answered(self, answer: Answer) -> str | None:
        """Take an answer of this generation in; why tracking must end, if it must."""
        if isinstance(answer.question, LookupQuestion):
            self._renewed(answer)
            return None
        if self._sky is None:
            return None
        return self._sky.answered(answer)

    def _renewed(self, answer: Answer) -> None:
        """Rule 10: the body looked up again in the TLE file while a pass is waited for."""
        body, sky = answer.value, self._sky
        if answer.question != self._from_file or self.body is None or sky is None:
            return
        p = sky.pass_now
        if self.lookup is not None or (p is not None and self._utc_seen >= p.aos_s):
            self._looked_at = -math.inf  # (a start under way decides; mid-pass: after it)
            return
        if not isinstance(body, Body) or answer.failure is not None:
            why = answer.failure or "no such satellite"
            if why == self._kept_for:
                return
            self._kept_for = why
            log.warning(
                "%s: tracking %s goes on with the elements it has: %s",
                self._rig.rotator_id,
                self.body.name,
                why,
            )
            return
        self._kept_for = None
        if body == self.body:
            return
        log.info("%s: tracking %s by the TLE file's new elements", self._rig.rotator_id, body.name)
        self.generation += 1  # rule 8: what was asked for the old elements is stale
        self._sky = SkyTrack(self.cfg, body)
        self._sky.after_pass = sky.after_pass
        self.body, self._stayed = body, True
        self._flip_for = self._wait_at = self._waited_for = self._sided_for = None

    # -- the step ----------------------------------------------------------------------------
    def step(self, scene: Scene) -> Proposal:
        """Run by the session with its other rules, while the controller answers."""
        sky = self._sky
        if self.body is None or sky is None:
            return NOTHING
        before = self._before.look(scene)
        if scene.locked:
            return Proposal(busy=True)  # rule 7
        if self._turned_by_hand(scene, before):
            self.end("turned by hand")  # rule 1: the front panel is a command too
            return Proposal(ended="turned by hand", busy=True)
        if self._halt.owed(scene, self._last is None):  # rule 5: the start's first target
            return Proposal(busy=True, halt=True)  # refused, the carried turn seen only now
        utc = scene.now + scene.wall_offset_s
        if utc < self._utc_seen - CLOCK_BACK_S:  # rule 2: the clock stepped back (NTP)
            self._waited_for = self._sided_for = None  # (a pass not begun by it: wait again)
            self._utc_seen = utc
        self._utc_seen = max(self._utc_seen, utc)
        self._say_age(sky.body, utc)
        if sky.searching(utc):
            return Proposal(busy=True)  # rule 8: the answer comes as an input
        p = sky.pass_now
        if p is None:
            self._inform(sky, utc, None, "no pass", scene.now)
            return Proposal(busy=True)
        if self._flip_for != p.aos_s:
            flip = self._flip_saves(sky, p, scene)
            if flip is None:
                return Proposal(busy=True)  # rule 8: the pass's track is being computed
            self._flip_for, self._flip = p.aos_s, flip
        if utc < p.aos_s:  # the pass in hand has moved on past a LOS: utc <= p.los_s
            self._inform(sky, utc, p, "waiting", scene.now)
            self._look_again(p, utc)
            return self._wait_for(sky, p, utc, scene)
        self._inform(sky, utc, p, "tracking", scene.now)
        return self._follow(sky, p, utc, scene)

    def _aim(self, az: float, el: float) -> tuple[float, float | None]:
        """Rules 4 and 6: what the rotor is sent for a body at (az, el)."""
        if self._flip:
            az, el = (az + 180.0) % 360.0, 180.0 - el
        aim = self._rig.aim
        if not aim.has_elevation:
            return az, None
        el_min, el_max = aim.el_sendable()  # (a SatEL's limit of 75 is 70: pointing.py)
        lo = max(el_min, self.cfg.min_el_deg if not self._flip else -math.inf)
        hi = min(el_max, 180.0 - self.cfg.min_el_deg if self._flip else math.inf)
        return az, min(max(el, lo), hi)

    def _put(
        self, sky: SkyTrack, target: Target, scene: Scene, raw: float | None = None
    ) -> Proposal:
        """Rule 5: judged like any target; a refusal is reported once per pass. ``raw``: the
        side chosen for the pass (rule 9), sent as it is."""
        aim = self._rig.aim
        try:
            judged = aim.judge(target, scene.motion.position_deg)
            if raw is not None:
                judged = replace(judged, az_deg=raw, true_az_deg=None)
                aim.check_raw(judged)
        except Refused as exc:
            aos = sky.pass_now.aos_s if sky.pass_now is not None else None
            # (the turn the start found: stopped once, as the start's own target would; then
            # the rotor is polled and seen at rest as after any stop: review 52)
            halt = self._halt.wanted(scene, self._last is None)
            if self._refused_for != aos or aos is None:
                self._refused_for = aos
                why = f"tracking {sky.body.name}: {exc.message}; holding"
                return Proposal(error=Report(ErrorKind.REFUSED, why), busy=True, halt=halt)
            return Proposal(busy=True, halt=halt)
        self._last_raw = judged.az_deg
        return Proposal(target=judged, busy=True)

    def _wait_for(self, sky: SkyTrack, p: Pass, utc: float, scene: Scene) -> Proposal:
        """Rule 2: after a pass park or stay, then go and wait where the next one rises."""
        rig = self._rig
        if self._stayed:  # rule 10: the pass before was parked (or stayed) after already
            self._stayed, self._parked_after = False, p.aos_s
        if sky.after_pass and self._parked_after != p.aos_s:
            self._parked_after = p.aos_s
            if self.cfg.at_los == "park" and rig.aim.park is not None:
                az, el = rig.aim.park
                park = self._put(sky, Target(az, el, Source.TRACKING, park=True), scene)
                if park.target is not None:
                    log.info("%s: pass over; parking until the next one", rig.rotator_id)
                return park
        if self._waited_for == p.aos_s or scene.pending is not None:
            return Proposal(busy=True)
        m = scene.motion
        if sky.after_pass and (
            m.state in (MotionState.MOVING, MotionState.BRAKING) or mo.settling(m)
        ):  # a park still on its way: the wait target follows it, and its side is judged
            return Proposal(busy=True)  # from where the park leaves the rotor (rule 9)
        if self._wait_at is None or self._wait_at[0] != p.aos_s:  # (once a pass: the
            first = self._first_allowed(sky, p, scene)  # hours after a pass, every step)
            if first is None:
                return Proposal(busy=True)  # rule 8: the pass's track is being computed
            side = self._side(sky, p, first[0], max(utc, first[2]), scene, False)
            if side is None:
                return Proposal(busy=True)
            self._wait_at = (p.aos_s, first[0], first[1], side)
        _aos, az, el, side = self._wait_at
        margin_s = self._travel_s(scene, az, el, side[0]) + PREPOSITION_MARGIN_S
        if sky.after_pass and utc < p.aos_s - margin_s:
            return Proposal(busy=True)
        self._waited_for = self._sided_for = p.aos_s
        put = self._put(sky, Target(az, el, Source.TRACKING), scene, side[0])
        if put.target is not None:  # (after the judge: a start's refused wait halts, rule 5)
            self._last = (az, el)
        return put

    def _say_age(self, body: Body, utc: float) -> None:
        """Rule 11."""
        if self._aged == body:
            return
        self._aged, self._epoch = body, None
        if body.tle is None:
            return
        try:
            epoch = tle_epoch_unix(body.tle[0])
        except (ValueError, OverflowError):  # (sgp4 read it: a defect if it happens)
            return
        self._epoch = epoch
        age_days = (utc - epoch) / 86400.0
        if age_days > STALE_DAYS:
            log.warning(
                "%s: tracking %s by elements %.0f days old (epoch %s UTC): its passes may be "
                "minutes off; is tle_file refreshed?",
                self._rig.rotator_id,
                body.name,
                age_days,
                datetime.fromtimestamp(epoch, UTC).strftime("%Y-%m-%d %H:%M"),
            )
        elif -age_days > AHEAD_DAYS:
            log.warning(
                "%s: tracking %s by elements dated %.0f days after this station's clock "
                "(epoch %s UTC, the clock says %s): every position is for the wrong time; is "
                "the clock set?",
                self._rig.rotator_id,
                body.name,
                -age_days,
                datetime.fromtimestamp(epoch, UTC).strftime("%Y-%m-%d %H:%M"),
                datetime.fromtimestamp(utc, UTC).strftime("%Y-%m-%d %H:%M"),
            )

    def _look_again(self, p: Pass, utc: float) -> None:
        """Rule 10: the body looked up again while its pass is waited for."""
        if self._from_file is None or self.lookup is not None:
            return
        if not 0.0 <= utc - self._looked_at < LOOK_AGAIN_S:  # (a clock stepped back: at once)
            self._looked_at = utc
            self._lookups.append(self._from_file)

    def _follow(self, sky: SkyTrack, p: Pass, utc: float, scene: Scene) -> Proposal:
        """Rule 3."""
        m = scene.motion
        waiting = Proposal(busy=True)
        if scene.pending is not None:
            return waiting
        if self._last is not None:  # (the start's first target goes as any newest target)
            if scene.slewing:
                return waiting
            if not self._rig.motion.direct_retarget and m.state is not MotionState.IDLE:
                return waiting
        if m.state is MotionState.BRAKING or mo.settling(m):
            return waiting  # (settling: no brake, but maybe still turning, motion.py rule 4)
        if m.state is MotionState.STALLED and self._last is not None:
            return waiting  # (the stall ends tracking: rule 1; a start's target goes, below)
        lead = self._half_step_s(sky, utc)
        body = sky.at(min(utc + lead, p.los_s)) if lead is not None else None
        if body is None:
            return waiting  # rule 8: that part of the track is being computed
        az, el = self._aim(*body)
        if self._last is not None and _apart(self._last, (az, el)) < self.cfg.step_deg:
            if m.target_deg is not None or self._near(scene, az, el):
                return waiting  # on its way to the last step (its verdict decides)
        raw = None
        if self._sided_for != p.aos_s:  # rule 9: the pass's first target (started mid-pass)
            side = self._side(sky, p, az, utc, scene, True)
            if side is None:
                return waiting  # rule 8: the pass's track is being computed
            raw = side[0]
        elif self._last_raw is not None and not self._rig.aim.az_wraps:
            try:  # rule 9: the side of the step before (the rotor may be on its way there)
                raw = self._rig.aim.raw_for(az, self._last_raw)
            except Refused:
                pass  # (the judge refuses it, and says why: _put)
        put = self._put(sky, Target(az, el, Source.TRACKING), scene, raw)
        if put.target is not None:
            self._last = (az, el)
            self._sided_for = p.aos_s
        return put

    def _turned_by_hand(self, scene: Scene, before: bool) -> bool:
        """Rule 1 (parts.py rule 8): a hand on the front panel, further from the last tracking
        target than a step and the tolerance (a late start on a small step is not one); not the
        turn the start found under way (``before``: its first target takes its place)."""
        last = self._last[0] if self._last is not None else None
        far_deg = self.cfg.step_deg + self._rig.motion.tolerance_deg
        return turned_by_hand(scene, self._rig.aim, last, far_deg, before)

    def _near(self, scene: Scene, az: float, el: float | None) -> bool:
        """The rotor really is within a step (and its tolerance) of (az, el): the last target
        is not enough, the rotor may have been turned since or have fallen short."""
        m, aim = scene.motion, self._rig.aim
        if m.position_deg is None:
            return True  # nothing to judge by: the last target stands
        at = (aim.true_of(m.position_deg), m.el_position_deg if el is not None else None)
        return _apart(at, (az, el)) < self.cfg.step_deg + self._rig.motion.tolerance_deg

    def _half_step_s(self, sky: SkyTrack, utc: float) -> float | None:
        """How long the body takes to move half a step (rule 3), from its rate over 10 s; None
        while its track is being computed."""
        a, b = sky.at(utc), sky.at(utc + 10.0)
        if a is None or b is None:
            return None
        rate = _apart(a, b) / 10.0
        if rate <= 0.0:
            return MAX_LEAD_S
        return min(self.cfg.step_deg / 2.0 / rate, MAX_LEAD_S)

    def _travel_s(self, scene: Scene, az: float, el: float | None, raw: float | None) -> float:
        """How long the rotor takes from where it is to (az, el) at its real speeds (rule 2:
        those in effect, parts.py rule 9), to the raw azimuth ``raw`` if the side is chosen
        (rule 9), the azimuth's way measured along its travel (motion.py rule 5)."""
        rig, m, speeds = self._rig, scene.motion, scene.speeds
        if raw is None:
            try:
                raw = rig.aim.raw_for(az, m.position_deg)
            except Refused:
                return 0.0
        pos = m.position_deg
        t = 0.0 if pos is None else mo.along_travel(pos, raw, rig.motion) / speeds.az_deg_s
        if el is not None and m.el_position_deg is not None:
            t = max(t, abs(el - m.el_position_deg) / speeds.el_deg_s)
        return t + rig.spec.brake_delay_s

    def _first_allowed(
        self, sky: SkyTrack, p: Pass, scene: Scene
    ) -> tuple[float, float | None, float] | None:
        """Rule 5: where the rotor waits for the pass (aimed, rules 4 and 6) and the time the
        body is there: where it rises, or, rising in a keep-out sector or past a limit, the
        first point of its track the judge takes (where it rises if none); None while the
        pass's track is being computed."""
        rise = (*self._aim(p.aos_az_deg, self.cfg.min_el_deg), p.aos_s)
        try:
            self._rig.aim.judge(
                Target(rise[0], rise[1], Source.TRACKING), scene.motion.position_deg
            )
            return rise
        except Refused:
            pass
        track = sky.flip_track(p)
        if track is None:
            return None
        for t, (az_b, el_b) in zip(flip_times(p), track, strict=True):
            az, el = self._aim(az_b, max(el_b, self.cfg.min_el_deg))
            try:
                self._rig.aim.judge(Target(az, el, Source.TRACKING), scene.motion.position_deg)
            except Refused:
                continue
            return az, el, t
        return rise

    def _side(
        self, sky: SkyTrack, p: Pass, az: float, utc: float, scene: Scene, under_way: bool
    ) -> tuple[float | None] | None:
        """Rule 9: the raw azimuth for the pass's first target, on the side from which the rest
        of the pass from ``utc`` turns least, counting the move there if the pass is
        ``under_way`` ((None,): the judge's own, nearest side, on a scale that wraps or where
        there is one side only); None while the pass's track is being computed."""
        if self._rig.aim.az_wraps:
            return (None,)
        track = sky.flip_track(p)
        if track is None:
            return None
        ahead = [pt for t, pt in zip(flip_times(p), track, strict=True) if t >= utc]
        return (self._start(az, ahead, self._flip, scene, under_way),)

    def _start(
        self,
        az: float,
        track: list[tuple[float, float]],
        flip: bool,
        scene: Scene,
        counts_move: bool,
    ) -> float | None:
        """Rule 9: of the raw values that point at ``az``, the one from which following
        ``track`` (true bearings, flown flipped or not) turns the rotor least, counting the move
        there if ``counts_move`` (a pass under way; before AOS it is made while waiting); None
        where there is but one."""
        aim, here = self._rig.aim, scene.motion.position_deg
        starts: set[float] = set()
        for anchor in (aim.az_min_deg, aim.az_max_deg, (aim.az_min_deg + aim.az_max_deg) / 2):
            try:
                starts.add(aim.raw_for(az, anchor))
            except Refused:
                pass
        if len(starts) < 2:
            return None

        def turned(start: float) -> float:
            raw = start
            total = abs(start - here) if counts_move and here is not None else 0.0
            for az_b, _el in track:
                try:
                    nxt = aim.raw_for((az_b + 180.0) % 360.0 if flip else az_b, raw)
                except Refused:
                    continue
                total, raw = total + abs(nxt - raw), nxt
            return total

        near = (lambda r: abs(r - here)) if here is not None else (lambda r: 0.0)
        return min(sorted(starts), key=lambda r: (round(turned(r), 1), near(r)))

    def _flip_saves(self, sky: SkyTrack, p: Pass, scene: Scene) -> bool | None:
        """Rule 4: whether this pass is flown flipped (None: its track is being computed, rule
        8). Satellites only: the sun and the moon move too slowly across a "pass" of half a day
        for a flip to be worth its elevation travel."""
        aim, speeds = self._rig.aim, scene.speeds  # (parts.py rule 9)
        if not self.cfg.flip:  # (one box of two: it would decide for its own axis alone)
            return False
        if not aim.has_elevation or aim.el_max_deg < 180.0 - self.cfg.min_el_deg:
            return False
        if sky.body.kind != "satellite":
            return False
        track = sky.flip_track(p)
        if track is None:
            return None

        held_s = (p.los_s - p.aos_s) / max(1, len(track) - 1)  # a sample's share of the pass

        def travel_s(flip: bool) -> float:
            """The time the antenna is off the body during the pass: turning, on its slower
            axis at each step (both axes at the speeds in effect), an unwind through a stop
            showing as a long step; and held where the judge refuses a sample (a limit, a
            keep-out sector: rule 5, the rotor holds until the body is back where it may go),
            for that sample's share of the pass. The move to where the pass rises (or first
            may be followed) is left out: it is made while waiting."""
            raw: float | None = scene.motion.position_deg
            first = (track[0][0] + 180.0) % 360.0 if flip else track[0][0]
            start = self._start(first, track, flip, scene, False) if track else None
            raw = raw if start is None else start  # rule 9: the side the pass is started on
            el: float | None = None
            total = 0.0
            for az_b, el_b in track:
                az_want, el_want = ((az_b + 180.0) % 360.0, 180.0 - el_b) if flip else (az_b, el_b)
                try:  # (rule 5: as the judge takes each step, keep-out sectors and limits)
                    nxt = aim.judge(Target(az_want, None, Source.TRACKING), raw).az_deg
                except Refused:
                    total += held_s
                    continue
                if nxt is None:  # (never: an azimuth judged is a raw azimuth)
                    continue
                if el is not None and raw is not None:
                    total += max(
                        abs(nxt - raw) / speeds.az_deg_s, abs(el_want - el) / speeds.el_deg_s
                    )
                raw, el = nxt, el_want
            return total

        return travel_s(True) + FLIP_SAVING_DEG / speeds.az_deg_s < travel_s(False)

    def _inform(self, sky: SkyTrack, utc: float, p: Pass | None, phase: str, now: float) -> None:
        """The status's tracking block, refreshed every INFO_EVERY_S or when the phase changes."""
        old = self.info
        if old is not None and old.phase == phase and now - self._info_t < INFO_EVERY_S:
            return
        here, then = sky.at(utc), sky.at(utc + NEXT_S)
        if here is None or then is None:
            return  # rule 8: shown once its track is computed
        self._info_t = now
        (az, el), (naz, nel) = here, then
        name = sky.body.name
        info = TrackingInfo(
            name, phase, round(az, 1), round(el, 1), round(naz, 1), round(nel, 1), flip=self._flip
        )
        if self._epoch is not None:  # rule 11
            stale = utc - self._epoch > STALE_DAYS * 86400.0
            ahead = self._epoch - utc > AHEAD_DAYS * 86400.0
            info = replace(
                info, elements_epoch_unix=self._epoch, elements_stale=stale, elements_ahead=ahead
            )
        if p is not None:
            info = replace(
                info,
                aos_unix=round(p.aos_s, 1),
                los_unix=round(p.los_s, 1),
                max_elevation_deg=round(p.max_el_deg, 1),
                aos_azimuth_deg=round(p.aos_az_deg, 1),
                pass_track=_thinned(sky.flip_track(p)),
            )
        self.info = info


def _thinned(track: list[tuple[float, float]] | None) -> tuple[tuple[float, float], ...]:
    """The pass's track for the status (a sky plot draws it): at most PASS_TRACK_POINTS, the
    first and the last among them, to a tenth of a degree; nothing while it is computed."""
    if not track:
        return ()
    n = len(track)
    step = max(1, math.ceil((n - 1) / (PASS_TRACK_POINTS - 1)))
    picked = [*track[: n - 1 : step], track[-1]]
    return tuple((round(az % 360.0, 1), round(el, 1)) for az, el in picked)


def _apart(a: tuple[float, float | None], b: tuple[float, float | None]) -> float:
    daz = angle_between(a[0], b[0])
    if a[1] is None or b[1] is None:
        return daz
    return max(daz, abs(a[1] - b[1]))
