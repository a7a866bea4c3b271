"""Every decision about one rotator, sans-IO (in the shape of h11's Connection): events in,
actions out. No port, no thread, no select, no clock: time comes in with every input.

Inputs: ``start``, ``link_up`` / ``link_down`` / ``open_failed``, ``commands`` (a mailbox batch),
``bytes_received`` (whatever the port had), ``sky_answer`` (the sky worker's answer to an ``Ask``),
``tick`` (nothing happened, but time passed).
Outputs: a list of actions (``Write`` bytes, ``Publish`` a status, ``Report`` an error event,
``Ask`` the sky worker) and ``next_wakeup``, the time by which ``tick`` must be called if nothing
else happens first.

The session owns the link, the motion and the controller's state (answering, the hold); its
parts own theirs and decide (docs/architecture.md, "parts decide and return"): tracking.py,
autopark.py, slewing.py, stops.py, options.py, targets.py (the pending target) and status.py.
They see a read-only view (parts.Scene, status.Seen) and return what they propose; the session
applies it. None of them imports this module. ``_step`` runs them in one order, after every
input: a reply overdue (slewing), a due stop, the motion machine's clock, an enable owed, the
stop check, tracking, auto-park, the pending target, options, the poll, the status.

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
5. Stops: written at once, merged, checked and sent again as stops.py rules 1-2 say.
6. Options: options.py.
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
10. Tracking (tracking.py) proposes its own targets, judged like any; a stop, the lock, a track
   command or any other target ends it. Its targets skip the "already within tolerance"
   check a target gets before it is sent: a track's steps may be finer than the tolerance.
   What it needs of the sky goes out as ``Ask`` actions and comes back through ``sky_answer``.
11. A stop is never lost (stops.py rule 3): one owed is the first frame once the port is open.
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
from typing import TypeVar

from bridge.engine import motion as mo
from bridge.engine import slewing
from bridge.engine import status as st
from bridge.engine.actions import Action, Ask, Publish, Report, Write
from bridge.engine.autopark import AutoPark
from bridge.engine.config import WorkerConfig
from bridge.engine.link import Link
from bridge.engine.mailbox import Batch
from bridge.engine.options import Options
from bridge.engine.parts import Proposal, Scene
from bridge.engine.sending import Go, decide
from bridge.engine.skywork import Answer
from bridge.engine.slew import Slew
from bridge.engine.stops import Stops
from bridge.engine.targets import Targets, resolve
from bridge.engine.tracking import Track, Tracker
from bridge.model import ErrorKind, MotionState, RotatorStatus, Source, Target, describe_command
from bridge.protocols.base import JunkReason, JunkReply, PositionReply, VersionReply
from bridge.sky import Body

__all__ = ["Action", "Publish", "Report", "RotatorSession", "Write"]

log = logging.getLogger(__name__)
T = TypeVar("T")

IDLE_WAKEUP_S = 1.0  # a session with nothing due still looks at the clock this often


class RotatorSession:
    def __init__(
        self, cfg: WorkerConfig, *, options: dict[str, bool] | None = None, locked: bool = False
    ) -> None:
        self.cfg = cfg
        self.locked = locked
        self.motion = mo.Motion()
        self.link: Link | None = None
        self.targets = Targets(cfg)
        self.autopark = AutoPark(cfg)
        self.tracker = Tracker(cfg)
        self.stops = Stops()
        self.options = Options(options)
        self.answering = False
        self.hold: int | None = None  # rule 13: no target goes out until this marker is back
        self.wall_offset_s = 0.0
        self.az_shown, self.el_shown = st.Hysteresis(), st.Hysteresis()
        self.view = st.View()
        self.status = RotatorStatus(rotator_id=cfg.rotator_id, locked=locked)
        self._silence_reported = False
        self._junk_reported_t = -1e18
        self._port_error: str | None = None
        self._actions: list[Action] = []
        self._wakeup = 0.0

    @property
    def name(self) -> str:
        return self.cfg.rotator_id

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
        self.options.connected(self.answering)
        if self.stops.owed:  # rule 11: before anything else the controller gets
            self.stops.owed = False
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
            stop_due = self.link is not None and self.link.stop_due
            self.stops.owed = self.stops.owed or self.stops.unsure(stop_due, self.motion, now)
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
            self._taken(batch.stop.source.value)
            if link is None or not self.stops.merges(self.motion, self.cfg.motion, now):
                self._stop_or_owe(now)
        self._fence(batch)
        for opt in batch.options:
            self.options.set(opt.name, opt.enabled, link is not None)
        if batch.track is not None:
            self._track(batch.track)
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
                    self.options.all_due()
                link.add_junk(reply.data, now)
                if reply.reason is JunkReason.UNTRUSTED:
                    link.ask_again(now)
                    if link.end_slew(now):  # the slew is over; where it ended, unseen
                        self.motion = mo.slew_ended(self.motion, now)
        return self._step(now)

    def sky_answer(self, generation: int, answer: Answer, now: float) -> list[Action]:
        """The sky worker's answer to an ``Ask`` of ``generation`` (tracking.py rule 8)."""
        if generation == self.tracker.generation:
            self._guarded("tracking", lambda: self._answered(answer), now)
        return self._step(now)

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

    # -- commands, applied ----------------------------------------------------------------------
    def _stop_or_owe(self, now: float) -> None:
        """Rule 11: a stop now, or, while the port is closed, as the first frame it gets."""
        if self.link is not None:
            self._stop_now(now)
        else:
            self.stops.owed = True

    def _fence(self, batch: Batch) -> None:
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

    def _track(self, track: Track) -> None:
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
            self._taken(track.source.value)
            log.info("%s: tracking %s", self.name, track.body.name)

    def _answered(self, answer: Answer) -> None:
        lookup = self.tracker.lookup
        if lookup is not None and answer.question == lookup.lookup:
            self.tracker.lookup = None
            body = answer.value
            if answer.failure is not None or not isinstance(body, Body):
                refusal = answer.failure or "no such satellite"
                self.error(ErrorKind.REFUSED, refusal, lookup.described)
            else:
                self._track(Track(body, lookup.source, None, lookup.described))
            return
        ends = self.tracker.answered(answer)
        if ends is not None:
            log.warning("%s: tracking ends: %s", self.name, ends)
            self.tracker.end(ends)
            self.drop_tracking_target()

    def _taken(self, source: str) -> None:
        """A stop or a new track: the status names its source and no target of before."""
        self.view.last_source = source
        self.view.target_info, self.view.park_raw = None, None

    def drop_tracking_target(self) -> None:
        """Tracking has ended: a target of its own still waiting must not go out after it."""
        pending = self.targets.pending
        if pending is not None and pending.source is Source.TRACKING:
            self.targets.clear()

    def _drop_pending(self, why: str | None) -> None:
        dropped = self.targets.clear()
        if dropped is not None and why:
            self.error(
                ErrorKind.REFUSED, f"target dropped: {why}", command=describe_command(dropped)
            )

    def error(self, kind: ErrorKind, message: str, command: str | None = None) -> None:
        log.warning("%s: %s%s", self.name, message, f" ({command})" if command else "")
        self.view.last_error = message
        self._actions.append(Report(kind, message, command))

    def _report(self, report: Report | None) -> None:
        if report is not None:
            self.error(report.kind, report.message, report.command)

    def _stop_now(self, now: float) -> None:
        assert self.link is not None
        self.link.want_stop()
        self._flush_stop(now)

    def _flush_stop(self, now: float) -> None:
        """Write a due stop now, or as soon as a half-duplex line is free (one reply time)."""
        if self.link is not None and self.link.flush_stop(now):
            self.motion = mo.stop_sent(self.motion, self.cfg.motion, now)

    # -- the rules, run after every input, in this order ---------------------------------------
    def _step(self, now: float) -> list[Action]:
        link = self.link
        if link is not None:
            if link.reply_overdue(now):
                self._overdue(link, now)  # slewing.py
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
        generation = self.tracker.generation
        self._actions.extend(Ask(generation, q) for q in self.tracker.take_asks())
        self._wakeup = self._next_wakeup(now)
        actions, self._actions = self._actions, []
        return actions

    def _overdue(self, link: Link, now: float) -> None:
        todo = slewing.overdue(self.cfg, link.slew, link.reply_timeout_s, now)
        self._report(todo.error)
        if todo.retry is not None:
            self.targets.put_back(todo.retry, todo.attempt, now)
        if todo.stop:
            self._stop_now(now)
            return
        link.give_up_reply(now)
        if todo.track_lost:
            self.motion = mo.track_lost(self.motion, self.cfg.motion)

    def _advance(self, now: float) -> None:
        """Time-driven motion, then what the parts, the pending target and options do now."""
        link = self.link
        if link is None or link.slew is None:  # no reports during a slew: nothing to judge
            self.motion, events = mo.tick(self.motion, self.cfg.motion, now)
            self._motion_events(events, now)
        if link is None or not self.answering:
            return
        if self.options.enable_due and link.slew is None and link.free() and not link.stop_due:
            enable = link.codec.encode_enable()
            if enable:
                link.write(enable, now)
            self.options.enable_due = False
        going = self.targets.pending is not None and self.hold is None  # (held: not going)
        again, error = self.stops.check(self.motion, self.cfg.motion, now, going)
        self._report(error)
        if again:
            log.warning("%s: still turning after a stop; stopping again", self.name)
            self._stop_now(now)
        self._part("tracking", self.tracker.step, now)  # rule 14
        self._part("auto-park", self.autopark.step, now)
        if self.targets.pending is not None:
            self._try_target(link, now)
        idle = self.motion.state is MotionState.IDLE
        free = self.targets.pending is None and link.free()
        for name, enabled in self.options.take(idle, free, now):
            try:
                frame = link.codec.encode_option(name, enabled)
            except (KeyError, ValueError):
                log.warning("%s: option %r not supported; skipped", self.name, name)
                continue
            link.write(frame, now)

    def _part(self, name: str, step: Callable[[Scene], Proposal], now: float) -> None:
        """A part decides on a read-only scene; its proposal is applied here."""
        scene = Scene(
            now=now,
            motion=self.motion,
            pending=self.targets.pending,
            locked=self.locked,
            parked=self.status.parked,
            slewing=self.link is not None and self.link.slew is not None,
            wall_offset_s=self.wall_offset_s,
        )
        proposal = self._guarded(name, lambda: step(scene), now)
        if proposal is None:
            return
        if proposal.busy:
            self.autopark.activity(now)  # autopark.py rule 1 (tracking.py rule 7)
        self._report(proposal.error)
        if proposal.ended is not None:
            self.drop_tracking_target()
        if proposal.target is not None:
            self.targets.put(proposal.target, now)

    def _guarded(self, name: str, run: Callable[[], T], now: float) -> T | None:
        """Rule 14: a part that raises is reset and reported; nothing else stops."""
        try:
            return run()
        except Exception:
            log.exception("%s: %s failed", self.name, name)
            if name == "tracking":
                self.tracker.end("internal error")
                self.drop_tracking_target()
            else:
                self.autopark = AutoPark(self.cfg)
                self.autopark.activity(now)
            self.error(ErrorKind.INTERNAL, f"{name} failed (a bug, see the log): {name} reset")
            return None

    def _try_target(self, link: Link, now: float) -> None:
        todo = decide(self.cfg, link, self.motion, self.targets, self.hold is not None, now)
        if todo.go is Go.DONE:
            self._aimed(self.targets.clear(), todo.wire)
        elif todo.go is Go.STOP_FIRST:
            self._stop_now(now)
        elif todo.go is Go.ASK_FIRST:
            link.poll_now(now)  # ask first; the target follows the answer
        elif todo.go is Go.SEND:
            pending, m = self.targets.pending, self.motion
            link.send(link.codec.encode_target(todo.az_deg, todo.el_deg), now)
            attempt = self.targets.sent(now)
            assert pending is not None
            az, el = todo.wire
            if not self.cfg.spec.reports_while_moving:
                slew = Slew(
                    now, m.position_deg, m.el_position_deg, az, el, pending.source, 0, attempt
                )
                link.begin_slew(slew, slewing.travel_s(self.cfg, slew))
            self.motion = mo.commanded(m, self.cfg.motion, az, now, el)
            self._aimed(pending, todo.wire)
            link.poll_by(now + self.cfg.moving_poll_interval_s)

    def _aimed(self, target: Target | None, wire: tuple[float, float | None]) -> None:
        """What the status says about the target now taken (status.py rule 4)."""
        if target is not None:
            self.view.last_source = target.source.value
            self.view.target_info = target.info
            self.view.park_raw = wire if target.park else None

    def _reading(self, link: Link, reply: PositionReply, now: float) -> None:
        link.got_reading(now)
        if reply.motion_enabled is False:
            self.options.enable_due = True
        if reply.controller_time is not None:
            self.view.controller_time = reply.controller_time
        if not self.answering:
            self.answering = True
            self.autopark.activity(now)
            self.options.all_due()
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

    def _motion_events(self, events: list[mo.Event], now: float) -> None:
        for event in events:
            verdict = self.stops.verdict(event, self.motion, self.cfg.motion)
            if verdict.ends_tracking is not None:
                self.tracker.end(verdict.ends_tracking)
                self.drop_tracking_target()
            self._report(verdict.error)
            if verdict.error is None:
                log.info("%s: %s at %s", self.name, event.value, self.motion.position_deg)
            if verdict.stop and self.link is not None:
                self.link.write_stop(now)

    def _poll_if_due(self, now: float) -> None:
        """Rules 2 and 3."""
        link, cfg = self.link, self.cfg
        if link is None or not cfg.spec.can_report_position:
            return
        timeout_s = cfg.silence_timeout_s
        silent = not link.reply_owed and link.silent_for(now) >= timeout_s  # (a slew's report
        if silent and self.answering:  # takes the whole slew: a reply owed may still come)
            self.answering = False
            self.tracker.end("controller not answering")
            self.motion = mo.link_down(self.motion)
            self.error(
                ErrorKind.SERIAL,
                f"controller on {cfg.port} stopped answering (no valid reply for {timeout_s:g} s)",
            )
            self._drop_pending("controller not answering")
        elif silent and link.last_reply_t is None and not self._silence_reported:
            self._silence_reported = True
            self.error(ErrorKind.SERIAL, f"controller on {cfg.port} does not answer")
        busy = self.motion.state is MotionState.MOVING or self.targets.pending is not None
        link.poll(now, cfg.moving_poll_interval_s if busy else cfg.idle_poll_interval_s)

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

    def _emit_status(self, now: float) -> None:
        link, pending = self.link, self.targets.pending
        wire = None
        if pending is not None and link is not None:
            az, el = resolve(pending, self.motion, self.cfg.aim)
            wire = link.codec.wire_target(az, el) if az is not None else None
        seen = st.Seen(
            previous=self.status,
            view=self.view,
            motion=self.motion,
            connected=link is not None,
            answering=link is not None and self.answering,
            locked=self.locked,
            options=self.options.values,
            bearing_deg=self.az_shown.value,
            elevation_deg=self.el_shown.value,
            slew=link.slew if link is not None else None,
            pending=pending,
            pending_wire=wire,
            wall_offset_s=self.wall_offset_s,
            tracking=self.tracker.info,
            tracking_ended=self.tracker.ended,
        )
        status = st.current(self.cfg, seen, now)
        if st.worth_emitting(status, self.status):
            self._actions.append(Publish(status))
        self.status = status  # also when only the controller's clock changed (status rule 4)

    def _next_wakeup(self, now: float) -> float:
        link = self.link
        times = [now + IDLE_WAKEUP_S]
        if link is not None:
            times += link.wakeups()
            if link.slew is not None:
                times.append(now + self.cfg.moving_poll_interval_s)  # refresh the estimate
        waits = [self.targets.stream_deadline(now), self.autopark.wakeup(now)]
        waits += [self.tracker.wakeup(now), mo.next_deadline(self.motion, self.cfg.motion, now)]
        times += [t for t in waits if t is not None]
        return min(times)
