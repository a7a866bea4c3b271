"""Every decision about one rotator, sans-IO (in the shape of h11's Connection): events in,
actions out. No port, no thread, no select, no clock: time comes in with every input.

Inputs: ``start``, ``link_up`` / ``link_down`` / ``open_failed``, ``commands`` (a mailbox batch),
``bytes_received`` (whatever the port had), ``sky_answer`` (the sky worker's answer to an ``Ask``),
``tick`` (nothing happened, but time passed).
Outputs: a list of actions (``Write`` bytes, ``Publish`` a status, ``Report`` an error event,
``Ask`` the sky worker) and ``next_wakeup``, the time by which ``tick`` must be called if nothing
else happens first.

Rules:
1. The link's state belongs to ``Link`` (line discipline) and the motion machine's to
   ``motion``; this class decides and keeps the controller's state: answering or not, options
   owed, motion to re-enable.
2. A controller that reports positions is "available" only after a valid reading, and stops
   being available after ``silence_timeout_s`` without one. A DCU-1 is available while its
   port is open (it never answers).
3. Polling is idle work: slow when idle, fast while moving or while a target waits, never for a
   controller that cannot report. A query is never sent while another is open.
4. Targets go to the controller only when ``motion.plan_target`` says so (targets.py keeps the
   pending one and the stream rules); a target waiting for a brake delay is replaced by newer
   ones and dropped by a stop, the lock, or the link going down.
5. A stop is written at once (on a half-duplex line right after the reply in flight) and cancels
   any frame still waiting in the outbox. One that comes within the brake window (at least
   STOP_MERGE_MIN_S) of another, with no target sent and no reading showing the rotor turning
   since, is merged into it: nothing more goes on the wire. A stop is checked: if the rotor is
   still seen moving ``stop_resend_s`` later, it is sent again, and after three tries an error
   says so. Lock ON always sends a stop, whatever the bridge believes the rotor is doing.
6. Options are sent only while the rotor is idle, and re-sent after every (re)connect, after a
   power-on byte and every ``OPTIONS_REFRESH_S`` while idle: the controller forgets them at
   power-off, and the letters are idempotent.
7. A target for a controller that stops on re-target (Rotor-EZ) goes out only after a reading
   younger than one moving poll interval has shown the rotor idle: a front-panel move that began
   after the last poll must not be cut short.
8. A controller that is silent while it moves (SatEL) is sent nothing but a stop until its
   after-move report (slewing.py has the rules for a report that does not come); meanwhile the
   motion machine is not fed stale data, and a new target stops the slew and is sent once the
   rotor is still (stop and redirect). A report that says automatic motion is off gets it
   switched on again.
9. Bytes that complete no reply change nothing: the codec keeps them, and the rest of the rules
   run only when a reply (or junk) came, a command came, or ``next_wakeup`` passed.
10. Tracking (tracking.py) puts its own targets, judged like any; a stop, the lock, a track
   command or any other target ends it. Its targets skip the "already within tolerance"
   check a target gets before it is sent: a track's steps may be finer than the tolerance.
   What it needs of the sky goes out as ``Ask`` actions and comes back through ``sky_answer``.
11. A stop is never lost: one (or a lock ON) that comes while the port is closed or reopening,
   one still waiting for the line when the port failed, or one written less than
   STOP_UNSURE_S before it failed, is the first frame written once it is open again
   (stopping is always safe).
12. ``last_error`` is the last thing refused or gone wrong since the last batch of commands
   that was taken: a command after it that is carried out clears it.
13. The last word (mqtt/lastword.py): a stop or lock ON from the stop lane holds the rotator:
   no target (the user's, tracking's, auto-park's) goes to the controller until the batch
   that releases it, put by the main connection when it has caught up. A release that clears
   drops whatever target or tracking waits.
14. A part that raises (tracking, auto-park) is a bug contained here: it is reset (tracking
   ends, "internal error"), an error event of kind internal names it, and the link, the
   stops and every other rule go on (a feature's failure never takes a link down, and never
   costs a stop).
"""

from __future__ import annotations

import logging
from collections.abc import Callable

from bridge.engine import autopark, slewing, tracking
from bridge.engine import motion as mo
from bridge.engine import status as st
from bridge.engine.actions import Action, Ask, Publish, Report, Write
from bridge.engine.config import WorkerConfig
from bridge.engine.link import Link
from bridge.engine.mailbox import Batch
from bridge.engine.skywork import Answer
from bridge.engine.slew import Slew
from bridge.engine.targets import Targets, resolve
from bridge.model import (
    ErrorKind,
    MotionState,
    RotatorStatus,
    Source,
    Target,
    describe_command,
)
from bridge.protocols.base import JunkReason, JunkReply, PositionReply, VersionReply
from bridge.sky import Body

log = logging.getLogger(__name__)

OPTIONS_REFRESH_S = 60.0
STOP_TRIES_BEFORE_ERROR = 3
STOP_MERGE_MIN_S = 1.0  # stops merge within the brake window, or at least this long
STOP_UNSURE_S = 1.0  # rule 11: a stop written this recently when the port failed is sent again
IDLE_WAKEUP_S = 1.0  # a session with nothing due still looks at the clock this often


class RotatorSession:
    def __init__(
        self, cfg: WorkerConfig, *, options: dict[str, bool] | None = None, locked: bool = False
    ) -> None:
        self.cfg = cfg
        self.options: dict[str, bool] = dict(options or {})
        self.locked = locked
        self.motion = mo.Motion()
        self.link: Link | None = None
        self.targets = Targets(cfg)
        self.autopark = autopark.AutoPark(cfg.park_after_idle_s, cfg.aim.park)
        self.tracker = tracking.Tracker(cfg.tracking)
        self.answering = False
        self._silence_reported = False
        self._options_due: set[str] = set()
        self._options_sent_t = 0.0
        self._enable_due = False
        self._stop_tries = 0
        self._junk_reported_t = -1e18
        self._stop_at_rest = False  # turned away (motion rule 5): a stop when it is still
        self._port_error: str | None = None
        self._stop_owed = False  # rule 11: a stop came while the port was closed
        self.hold: int | None = None  # rule 13: no target goes out until this marker is back
        self.wall_offset_s = 0.0
        self.az_shown = st.Hysteresis()
        self.el_shown = st.Hysteresis()
        self.view = st.View()
        self.status = RotatorStatus(rotator_id=cfg.rotator_id, locked=locked)
        self._actions: list[Action] = []
        self._wakeup = 0.0

    # -- inputs -------------------------------------------------------------------------------
    def start(self, now: float) -> list[Action]:
        """The first status, whatever it says (nothing has been published for this rotator)."""
        self._actions.append(Publish(self.status))
        self.autopark.activity(now)
        return self._step(now)

    def open_failed(self, reason: str, now: float) -> list[Action]:
        if reason != self._port_error:
            self._port_error = reason
            self.error(ErrorKind.SERIAL, reason)
        return self._step(now)

    def link_up(self, now: float, wall_s: float) -> list[Action]:
        spec = self.cfg.spec
        self._port_error = None
        self.wall_offset_s = wall_s - now
        self.link = Link(spec.codec_factory(), spec, now, self.cfg.baud)
        self.autopark.activity(now)  # never park the moment a controller comes back
        self.motion = mo.link_up(self.motion, self.cfg.motion, now)
        self.answering = not spec.can_report_position
        self._silence_reported = False
        self._enable_due = False
        self._options_sent_t = 0.0
        self._options_due = set(self.options) if self.answering else set()
        if self._stop_owed:  # rule 11: before anything else the controller gets
            self._stop_owed = False
            log.info("%s: sending the stop that came while the port was closed", self.name)
            self.link.write_stop(now)
            self.motion = mo.stop_sent(self.motion, self.cfg.motion, now)
        for frame in self.link.codec.encode_connect(wall_s):
            self.link.write(frame, now)
        return self._step(now)

    def link_down(
        self, reason: str | None, now: float, kind: ErrorKind = ErrorKind.SERIAL
    ) -> list[Action]:
        """The port is closed (``reason`` says why; None on shutdown)."""
        if reason is not None:
            self.error(kind, reason)
            self._stop_owed = self._stop_owed or self._stop_unsure(now)  # rule 11
        # tracking after a reconnect needs a new command (reason None: the bridge is stopping)
        self.tracker.end("serial link down" if reason is not None else "bridge stopped")
        self.link = None
        self.answering = False
        self.motion = mo.link_down(self.motion)
        self._drop_pending("serial link down")
        return self._step(now)

    def commands(self, batch: Batch, now: float) -> list[Action]:
        link = self.link
        if batch.stop or batch.target or batch.lock is not None or batch.options or batch.track:
            self.view.last_error = None  # rule 12: until this batch refuses something again
        for note in batch.notes:
            self.view.last_error = note
        if batch.lock is not None:
            self.locked = batch.lock
        if batch.lock_on:  # mailbox.py rule 7: even when an OFF followed it in the batch
            self.tracker.end("lock")
            self._drop_pending(None)
            self._stop_or_owe(now)  # whatever we believe: the lock is for tower work
        if batch.stop is not None or batch.target is not None or batch.lock is not None:
            self.autopark.activity(now)  # autopark.py rule 1 (unlocking starts a new spell)
        if batch.stop is not None:
            self.tracker.end("stop")
            self.targets.clear()
            self.view.last_source = batch.stop.source.value
            self.view.target_info, self.view.park_raw = None, None
            if link is None or not self._stop_merges(now):
                self._stop_or_owe(now)
        self._fence(batch, now)
        for opt in batch.options:
            self.options[opt.name] = opt.enabled
            if link is not None:
                self._options_due.add(opt.name)
        if batch.track is not None:
            self._track(batch.track, now)
        if batch.target is not None:
            what = describe_command(batch.target)
            if self.tracker.end(f"{batch.target.source.value} target"):
                self.drop_tracking_target()  # never combined with the user's target
            if self.locked:
                self.error(ErrorKind.REFUSED, "rotator is locked", command=what)
            elif link is None or not self.answering:
                self.error(ErrorKind.REFUSED, "rotator offline", command=what)
            else:
                self.targets.put(batch.target, now)
        return self._step(now)

    def _stop_or_owe(self, now: float) -> None:
        """Rule 11: a stop now, or, while the port is closed, as the first frame it gets."""
        if self.link is not None:
            self.stop_now(now)
        else:
            self._stop_owed = True

    def _stop_unsure(self, now: float) -> bool:
        """Rule 11: a stop still waiting for the line, or written so recently (a failed write
        closes the port too) that the controller may never have had it."""
        link, sent = self.link, self.motion.stop_sent_t
        return (link is not None and link.stop_due) or (
            sent is not None and now - sent < STOP_UNSURE_S
        )

    def _fence(self, batch: Batch, now: float) -> None:
        """Rule 13: a hold starts with its stop and ends with its marker; one that ends with
        clearing drops what waited meanwhile (its place in line was lost)."""
        if batch.release_clear and self.hold is not None:  # (mailbox rule 6: before the rest)
            self.hold = None
            why = (
                "a stop or lock from the stop lane came before it, and the MQTT connection that "
                "would have told which was published first dropped; send it again"
            )
            self._drop_pending(why)
            if self.tracker.end("a stop or lock came first; send the track command again"):
                self.drop_tracking_target()
        if batch.hold is not None:
            self.hold = batch.hold if self.hold is None else max(self.hold, batch.hold)
        if batch.release is not None and self.hold is not None and self.hold <= batch.release:
            self.hold = None
            log.debug("%s: hold ended", self.name)

    def drop_tracking_target(self) -> None:
        """Tracking has ended: a target of its own still waiting must not go out after it."""
        pending = self.targets.pending
        if pending is not None and pending.source is Source.TRACKING:
            self.targets.clear()

    def _track(self, track: tracking.Track, now: float) -> None:
        if track.body is None and track.lookup is None:
            self.tracker.end("off")
            self.drop_tracking_target()
            return
        name = track.body.name if track.body is not None else track.lookup and track.lookup.name
        what = track.described or f"track {name}"
        if self.locked:
            self.error(ErrorKind.REFUSED, "rotator is locked", command=what)
        elif self.link is None or not self.answering:
            self.error(ErrorKind.REFUSED, "rotator offline", command=what)
        elif track.body is None:
            self.tracker.look_up(track)  # tracking.py rule 8: the answer comes as an input
        else:
            self.tracker.end("another body")
            self.targets.clear()
            self.tracker.start(track.body)
            self.view.last_source = track.source.value
            self.view.target_info, self.view.park_raw = None, None
            log.info("%s: tracking %s", self.name, track.body.name)

    def bytes_received(self, data: bytes, now: float) -> list[Action]:
        link = self.link
        if link is None:
            return []
        log.debug("%s: <- %r", self.cfg.rotator_id, data)
        link.got_bytes(len(data), now)
        replies = link.codec.feed(data)
        if not replies:
            return []  # rule 9
        for reply in replies:
            if isinstance(reply, PositionReply):
                self._reading(link, reply, now)
            elif isinstance(reply, VersionReply):
                if reply.version != self.view.version:
                    log.info("%s: controller version %s", self.cfg.rotator_id, reply.version)
                self.view.version = reply.version
            elif isinstance(reply, JunkReply):
                if reply.reason is JunkReason.POWER_ON:
                    log.info("%s: power-on byte seen; options will be re-applied", self.name)
                    self._options_due = set(self.options)
                link.add_junk(reply.data, now)
                if reply.reason is JunkReason.UNTRUSTED:
                    link.ask_again(now)
                    if link.end_slew(now):  # the slew is over; where it ended, unseen
                        self.motion = mo.slew_ended(self.motion, now)
        return self._step(now)

    def sky_answer(self, generation: int, answer: Answer, now: float) -> list[Action]:
        """The sky worker's answer to an ``Ask`` of ``generation`` (tracking.py rule 8)."""
        if generation == self.tracker.generation:
            self._part("tracking", lambda: self._answered(answer, now), now)
        return self._step(now)

    def _answered(self, answer: Answer, now: float) -> None:
        lookup = self.tracker.lookup
        if lookup is not None and answer.question == lookup.lookup:
            self.tracker.lookup = None
            body = answer.value
            if answer.failure is not None or not isinstance(body, Body):
                refusal = answer.failure or "no such satellite"
                self.error(ErrorKind.REFUSED, refusal, lookup.described)
            else:
                self._track(tracking.Track(body, lookup.source, None, lookup.described), now)
            return
        ends = self.tracker.answered(answer)
        if ends is not None:
            log.warning("%s: tracking ends: %s", self.name, ends)
            self.tracker.end(ends)
            self.drop_tracking_target()

    def set_wall(self, now: float, wall_s: float) -> None:
        """The wall clock (unix seconds) at ``now``: tracking reads the sky by it."""
        self.wall_offset_s = wall_s - now

    def tick(self, now: float) -> list[Action]:
        return self._step(now)

    def next_wakeup(self) -> float:
        return self._wakeup

    def hold_reads_until(self) -> float:
        """Bytes arriving before this time can wait in the port (link.py rule 7)."""
        return self.link.hold_reads_until() if self.link is not None else 0.0

    # -- what the parts below share -----------------------------------------------------------
    @property
    def name(self) -> str:
        return self.cfg.rotator_id

    def error(self, kind: ErrorKind, message: str, command: str | None = None) -> None:
        log.warning("%s: %s%s", self.name, message, f" ({command})" if command else "")
        self.view.last_error = message
        self._actions.append(Report(kind, message, command))

    def _stop_merges(self, now: float) -> bool:
        """Rule 5: a stop to a rotor that already had one this brake window, and that no reading
        since shows turning, adds nothing on the wire (a flood of stops to an idle Rotor-EZ had
        it answer each with its banner, crowding out the readings)."""
        m, cfg = self.motion, self.cfg.motion
        if not cfg.can_report_position or m.stop_sent_t is None or m.target_deg is not None:
            return False  # a target went out after the last stop: this stop is needed
        window = max(cfg.brake_delay_s, STOP_MERGE_MIN_S)
        turning = m.state is MotionState.MOVING
        return not turning and now - m.stop_sent_t < window

    def stop_now(self, now: float) -> None:
        assert self.link is not None
        self.link.want_stop()
        self._flush_stop(now)

    def _flush_stop(self, now: float) -> None:
        """Write a due stop now, or as soon as a half-duplex line is free (one reply time)."""
        if self.link is not None and self.link.flush_stop(now):
            self.motion = mo.stop_sent(self.motion, self.cfg.motion, now)

    def _drop_pending(self, why: str | None) -> None:
        dropped = self.targets.clear()
        if dropped is not None and why:
            self.error(
                ErrorKind.REFUSED, f"target dropped: {why}", command=describe_command(dropped)
            )

    # -- the rules, run after every input ------------------------------------------------------
    def _step(self, now: float) -> list[Action]:
        link = self.link
        if link is not None:
            if link.reply_overdue(now):
                slewing.reply_overdue(self, link, now)
            self._flush_stop(now)
            link.flush_outbox(now)
            junk = link.quiet_junk(now)
            if junk is not None:
                self._report_junk(*junk, now)
        self._advance(now)  # commands go ahead of the next poll
        self._poll_if_due(now)
        self._emit_status(now)
        if self.link is not None:
            self._actions.extend(Write(frame) for frame in self.link.output())
        tr = self.tracker
        self._actions.extend(Ask(tr.generation, q) for q in tr.asks)
        tr.asks.clear()
        self._wakeup = self._next_wakeup(now)
        actions, self._actions = self._actions, []
        return actions

    def _part(self, name: str, run: Callable[[], None], now: float) -> None:
        """Rule 14: a part that raises is reset and reported; nothing else stops."""
        try:
            run()
        except Exception:
            log.exception("%s: %s failed", self.name, name)
            if name == "tracking":
                self.tracker.end("internal error")
                self.drop_tracking_target()
            else:
                self.autopark = autopark.AutoPark(self.cfg.park_after_idle_s, self.cfg.aim.park)
                self.autopark.activity(now)
            self.error(ErrorKind.INTERNAL, f"{name} failed (a bug, see the log): {name} reset")

    def _reading(self, link: Link, reply: PositionReply, now: float) -> None:
        link.got_reading(now)
        if reply.motion_enabled is False:
            self._enable_due = True
        if reply.controller_time is not None:
            self.view.controller_time = reply.controller_time
        if not self.answering:
            self.answering = True
            self.autopark.activity(now)
            self._options_due = set(self.options)
            log.info("%s: controller answering", self.name)
        self.motion, events = mo.reading(
            self.motion, self.cfg.motion, reply.az_deg, now, reply.el_deg
        )
        self._motion_events(events, now)
        moving = self.motion.state is MotionState.MOVING
        band, wraps = self.cfg.deadband_deg, self.cfg.motion.az_wraps
        self.az_shown.feed(reply.az_deg, moving, band, wraps)
        if reply.el_deg is not None:
            self.el_shown.feed(reply.el_deg, moving, band, False)

    def _poll_if_due(self, now: float) -> None:
        link = self.link
        if link is None or not self.cfg.spec.can_report_position:
            return
        self._check_silence(link, now)
        busy = self.motion.state is MotionState.MOVING or self.targets.pending is not None
        cfg = self.cfg
        link.poll(now, cfg.moving_poll_interval_s if busy else cfg.idle_poll_interval_s)

    def _check_silence(self, link: Link, now: float) -> None:
        timeout_s = self.cfg.silence_timeout_s
        if link.reply_owed:
            return  # a reply is owed and may still come (a slew report takes the whole slew)
        if self.answering and link.silent_for(now) >= timeout_s:
            self.answering = False
            self.tracker.end("controller not answering")
            self.motion = mo.link_down(self.motion)
            self.error(
                ErrorKind.SERIAL,
                f"controller on {self.cfg.port} stopped answering "
                f"(no valid reply for {timeout_s:g} s)",
            )
            self._drop_pending("controller not answering")
        elif (
            link.last_reply_t is None
            and not self._silence_reported
            and link.silent_for(now) >= timeout_s
        ):
            self._silence_reported = True
            self.error(ErrorKind.SERIAL, f"controller on {self.cfg.port} does not answer")

    def _advance(self, now: float) -> None:
        """Time-driven motion, then whatever the pending target and options may do now."""
        link = self.link
        if link is None or link.slew is None:  # no reports during a slew: nothing to judge
            self.motion, events = mo.tick(self.motion, self.cfg.motion, now)
            self._motion_events(events, now)
        if link is None or not self.answering:
            return
        if self._enable_due and link.slew is None and link.free() and not link.stop_due:
            enable = link.codec.encode_enable()
            if enable:
                link.write(enable, now)
            self._enable_due = False
        self._verify_stop(now)
        self._part("tracking", lambda: tracking.step(self, now), now)  # rule 14
        self._part("auto-park", lambda: autopark.step(self, now), now)
        if self.targets.pending is not None:
            self._try_target(link, now)
        idle = self.motion.state is MotionState.IDLE
        if idle and self.options and now - self._options_sent_t >= OPTIONS_REFRESH_S:
            self._options_due = set(self.options)
        if self._options_due and idle and self.targets.pending is None and link.free():
            for name in sorted(self._options_due):
                try:
                    frame = link.codec.encode_option(name, self.options[name])
                except (KeyError, ValueError):
                    log.warning("%s: option %r not supported; skipped", self.name, name)
                    continue
                link.write(frame, now)
            self._options_due.clear()
            self._options_sent_t = now

    def _verify_stop(self, now: float) -> None:
        """A stop that did not take (a byte lost to RF, a garbled frame) is sent again."""
        m = self.motion
        if m.stop_sent_t is None:
            self._stop_tries = 0
            return
        moved_since = m.last_move_t is not None and m.last_move_t > m.stop_sent_t
        late = now >= m.stop_sent_t + self.cfg.motion.stop_resend_s  # as next_deadline
        pending = self.targets.pending is not None and self.hold is None  # (held: not going)
        if m.state is MotionState.MOVING and moved_since and late and not pending:
            self._stop_tries += 1
            if self._stop_tries == STOP_TRIES_BEFORE_ERROR:
                self.error(
                    ErrorKind.STOP,
                    f"rotor still turning after {self._stop_tries} stop commands; "
                    "stop it at the controller",
                )
            log.warning("%s: still turning after a stop; stopping again", self.name)
            self.stop_now(now)

    def _try_target(self, link: Link, now: float) -> None:
        pending = self.targets.pending
        assert pending is not None
        if link.stop_due or self.hold is not None:
            return  # the stop goes first; a held target waits for its marker (rule 13)
        m, mcfg = self.motion, self.cfg.motion
        az, el = self.resolve(pending)
        if az is None:
            return  # no reading yet to keep the other axis where it is
        wire = link.codec.wire_target(az, el)
        if m.target_deg is not None and (m.target_deg, m.el_target_deg) == wire:
            self._aimed(self.targets.clear(), wire)  # already on its way there
            return
        small = pending.source is not Source.TRACKING  # a track's steps may be finer
        if small and self.cfg.spec.can_report_position and mo.within_tolerance(m, mcfg, wire):
            log.info("%s: already within tolerance of %s", self.name, wire)
            self._aimed(self.targets.clear(), wire)
            return
        plan = mo.plan_target(m, mcfg, now)
        if plan is mo.Plan.STOP_FIRST:
            doing = "turning" if self.cfg.spec.can_report_position else "may still be turning"
            log.info("%s: %s; stopping before the new target %s", self.name, doing, wire)
            self.stop_now(now)
            return
        if plan is not mo.Plan.SEND or not link.free():
            return  # braking, or a half-duplex line with a reply in flight: right after it
        if self.targets.stream_wait(now):
            return  # a stream of targets: wait for it to pause
        if self._needs_fresh_reading(link, now):
            link.poll_now(now)  # ask first; the target follows the answer
            return
        link.send(link.codec.encode_target(az, el), now)
        attempt = self.targets.sent(now)
        if not self.cfg.spec.reports_while_moving:
            slew = Slew(
                now, m.position_deg, m.el_position_deg, wire[0], wire[1], pending.source, 0, attempt
            )
            link.begin_slew(slew, slewing.travel_s(self, slew))
        self.motion = mo.commanded(m, mcfg, wire[0], now, wire[1])
        self._aimed(pending, wire)
        link.poll_by(now + self.cfg.moving_poll_interval_s)

    def _aimed(self, target: Target | None, wire: tuple[float, float | None]) -> None:
        """What the status says about the target now taken (status.py rule 4)."""
        if target is not None:
            self.view.last_source = target.source.value
            self.view.target_info = target.info
            self.view.park_raw = wire if target.park else None

    def _needs_fresh_reading(self, link: Link, now: float) -> bool:
        if not self.cfg.motion.can_report_position or self.cfg.motion.direct_retarget:
            return False
        age = now - (link.last_reply_t if link.last_reply_t is not None else -1e18)
        return age > self.cfg.moving_poll_interval_s

    def resolve(self, target: Target) -> tuple[float | None, float | None]:
        return resolve(target, self.motion, self.cfg.aim)

    def _next_wakeup(self, now: float) -> float:
        link = self.link
        times = [now + IDLE_WAKEUP_S]
        if link is not None:
            times += link.wakeups()
            if link.slew is not None:
                times.append(now + self.cfg.moving_poll_interval_s)  # refresh the estimate
        waits = (self.targets.stream_deadline(now), self.autopark.wakeup(now))
        for wait in (*waits, self.tracker.wakeup(now)):
            if wait is not None:
                times.append(wait)
        deadline = mo.next_deadline(self.motion, self.cfg.motion, now)
        if deadline is not None:
            times.append(deadline)
        return min(times)

    def _report_junk(self, data: bytes, harmless: bool, now: float) -> None:
        if harmless:  # a banner after a stop, a blank line: nothing a user acts on
            log.debug("%s: ignored %d harmless bytes: %r", self.name, len(data), data[:64])
            return
        log.warning("%s: ignored %d bytes that are no reply: %r", self.name, len(data), data[:64])
        if now - self._junk_reported_t >= self.cfg.junk_report_interval_s:
            self._junk_reported_t = now
            self.error(
                ErrorKind.PROTOCOL,
                f"controller sent {len(data)} bytes that are no valid reply; ignored",
            )

    def _motion_events(self, events: list[mo.Event], now: float) -> None:
        for event in events:
            if event is mo.Event.STALLED:
                self.tracker.end("stalled")
                self.drop_tracking_target()
                pos = self.motion.position_deg
                self.error(
                    ErrorKind.STALLED,
                    f"rotor stalled at {pos:g}° (no progress for "
                    f"{self.cfg.motion.stall_timeout_s:g} s): brake paddle pressed or rotor stuck",
                )
                if self.link is not None:
                    self.link.write_stop(now)
            elif event is mo.Event.TURNED_AWAY:
                self.tracker.end("turned by hand")
                self.drop_tracking_target()
                self._stop_at_rest = True  # a controller driving the wrong way: stop it then
                self.error(
                    ErrorKind.STALLED,
                    f"rotor turned away from its target at {self.motion.position_deg:g}° (the "
                    "front panel, or a controller driving the wrong way): target dropped, and "
                    "a stop follows when it comes to rest",
                )
            elif event is mo.Event.STOPPED and self._stop_at_rest:
                self._stop_at_rest = False
                pos = self.motion.position_deg
                log.info("%s: at rest at %s after turning away: stop", self.name, pos)
                if self.link is not None:
                    self.link.write_stop(now)
            else:
                if event is mo.Event.ARRIVED:
                    self._stop_at_rest = False
                log.info("%s: %s at %s", self.name, event.value, self.motion.position_deg)

    def _emit_status(self, now: float) -> None:
        status = st.current(self, now)
        if st.worth_emitting(status, self.status):
            self._actions.append(Publish(status))
        self.status = status  # also when only the controller's clock changed (status rule 4)
