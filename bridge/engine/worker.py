"""One thread per rotator: the only code that touches that rotator's serial port.

The loop: open the port (back-off on failure), then select() on the port and the mailbox pipe,
so a command is written the moment it arrives, also while a poll reply is awaited. Replies go
through the model's codec into the pure motion state machine; when the status changes it is
emitted (the second and last hand-off point, ARCHITECTURE.md rule 3).

Rules:
1. Any serial error closes the port, marks the rotator offline and retries with back-off; the
   thread never dies of one.
2. A controller that reports positions is "available" only after a valid reading, and stops
   being available after ``silence_timeout_s`` without one. A DCU-1 is available while its
   port is open (it never answers).
3. Polling is idle work: slow when idle, fast while moving or while a target waits, never for a
   controller that cannot report. A query is never sent while another is open.
4. Targets go to the controller only when ``motion.plan_target`` says so; a target waiting for a
   brake delay is replaced by newer ones and dropped by a stop, the lock, or the link going down.
   Targets that come as a stream (one replaces a still-pending one, or arrives within
   ``BURST_QUIET_S`` of the last target sent: a dragged slider, a flood) are sent when the
   stream pauses for ``BURST_QUIET_S``, and at the latest ``STREAM_MAX_WAIT_S`` after the
   stream's first unsent target (longer for controllers that must stop to re-target), so a
   continuous stream is followed without flooding the line. A single command is never delayed.
5. A stop is written at once (on a half-duplex line right after the reply in flight) and cancels
   any frame still waiting in the outbox. A stop is checked: if the rotor is still seen moving
   ``stop_resend_s`` later, it is sent again, and after three tries an error says so. Lock ON
   always sends a stop, whatever the bridge believes the rotor is doing.
6. Options are sent only while the rotor is idle, and re-sent after every (re)connect, after a
   power-on byte and every ``OPTIONS_REFRESH_S`` while idle: the controller forgets them at
   power-off, and the letters are idempotent.
7. A target for a controller that stops on re-target (Rotor-EZ) goes out only after a reading
   younger than one moving poll interval has shown the rotor idle: a front-panel move that began
   after the last poll must not be cut short.
8. A controller that is silent while it moves (SatEL) is sent nothing but a stop until its
   after-move report; meanwhile the motion machine is not fed stale data, the published
   position is an estimate from the rotor's speeds (marked ``estimated`` in the status), and a
   new target stops the slew and is sent once the rotor is still (stop and redirect). A report
   that says automatic motion is off gets it switched on again.
9. An after-move report that does not come within the slew's bound (link.py rule 1: twice the
   travel time at the configured speeds, plus a margin) was lost, or the rotor is slower than
   configured. Either way the bridge does not poll into a slew it cannot see: it sends the stop
   (the one input allowed during a slew), asks for the position once the stopped controller
   had its chance to report, and sends the slew's target again, so the rotor still ends where
   the last accepted command asked. An error says so, naming the speed setting. If the second
   try's report does not come either (a jammed rotor, a mechanical stop short of the point), the
   target is given up with an error: a motor is not driven against a jam again and again.
10. Any stop written during a slew (rule 9, stop and redirect, the user's stop) is followed by
   the report within one reply time or it is written again, up to SLEW_STOP_TRIES: a stop byte
   lost on the line must not let the poll that follows into a slew. Only then is the controller
   asked where it is.
11. Listeners (MQTT, rotctld, Home Assistant) are called from this thread only, and a listener
   that raises is logged once per kind of failure and otherwise ignored (``contained``): a
   display problem never closes, reopens or delays the line to the controller.
"""

from __future__ import annotations

import logging
import select
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import TypeVar

import serial

from bridge.engine import motion as mo
from bridge.engine.link import Link, Slew
from bridge.engine.mailbox import Batch, Mailbox
from bridge.engine.port import PortError, open_port
from bridge.model import ErrorEvent, MotionState, RotatorStatus, Target, describe_command
from bridge.protocols.base import (
    UNTRUSTED,
    JunkReply,
    ModelSpec,
    PositionReply,
    VersionReply,
)

log = logging.getLogger(__name__)
T = TypeVar("T")

POWER_ON_BYTE = 0xE0
OPTIONS_REFRESH_S = 60.0
BURST_QUIET_S = 0.5
STREAM_MAX_WAIT_S = {"direct": 1.0, "stop_and_wait": 5.0}
STOP_TRIES_BEFORE_ERROR = 3
SLEW_STOP_TRIES = 3  # stops written to a slewing controller before it is asked where it is
SLEW_ATTEMPTS = 2  # a target whose report did not come is sent once more, then given up


def contained(listener: Callable[[T], None], what: str) -> Callable[[T], None]:
    """``listener`` with its failures logged (once per exception type) and never raised."""
    seen: set[type[BaseException]] = set()

    def call(value: T) -> None:
        try:
            listener(value)
        except Exception as exc:
            if type(exc) not in seen:
                seen.add(type(exc))
                log.exception("%s failed (logged once; the rotator goes on)", what)

    return call


@dataclass(frozen=True)
class WorkerConfig:
    rotator_id: str
    port: str
    spec: ModelSpec
    baud: int
    motion: mo.MotionConfig
    idle_poll_interval_s: float = 1.0
    moving_poll_interval_s: float = 0.2
    deadband_deg: float = 2.0
    silence_timeout_s: float = 3.0
    reconnect_min_s: float = 0.5
    reconnect_max_s: float = 10.0
    junk_report_interval_s: float = 30.0
    az_speed_deg_s: float | None = None  # the rotor's real speeds; None: the model's nominal
    el_speed_deg_s: float | None = None


class Worker:
    def __init__(
        self,
        cfg: WorkerConfig,
        mailbox: Mailbox,
        on_status: Callable[[RotatorStatus], None],
        on_event: Callable[[ErrorEvent], None],
        *,
        options: dict[str, bool] | None = None,
        locked: bool = False,
        clock: Callable[[], float] = time.monotonic,
        wall: Callable[[], float] = time.time,
        port_opener: Callable[[str, ModelSpec, int], serial.Serial] = open_port,
    ) -> None:
        self.cfg = cfg
        self._mailbox = mailbox
        self._on_status = contained(on_status, f"{cfg.rotator_id}: status listener")
        self._on_event = contained(on_event, f"{cfg.rotator_id}: event listener")
        self._clock = clock
        self._wall = wall
        self._open = port_opener
        self._options: dict[str, bool] = dict(options or {})
        self._locked = locked
        self._motion = mo.Motion()
        self._pending: Target | None = None
        # rule 9: the target put back after a lost report, and which try it will be
        self._resend: tuple[Target, int] | None = None
        self._pending_t = 0.0
        self._pending_replaced = False  # part of a stream of targets (see rule 4)
        self._stream_t = 0.0
        self._last_target_sent_t = -1e18
        self._published_deg: float | None = None
        self._published_dir = 0
        self._published_el_deg: float | None = None
        self._published_el_dir = 0
        self._version: str | None = None
        self._controller_time: str | None = None
        self._last_error: str | None = None
        self._last_source: str | None = None
        self._status = RotatorStatus(rotator_id=cfg.rotator_id, locked=locked)
        self._stopping = threading.Event()
        self._thread = threading.Thread(target=self._run, name=f"rotator-{cfg.rotator_id}")
        self._link: Link | None = None
        self._junk_reported_t = -1e18
        self._stop_tries = 0
        self._backoff_s = cfg.reconnect_min_s
        self._port_error: str | None = None
        self._az_speed_deg_s = cfg.az_speed_deg_s or cfg.spec.nominal_speed_deg_s
        self._el_speed_deg_s = cfg.el_speed_deg_s or cfg.spec.nominal_el_speed_deg_s

    # -- public, any thread -----------------------------------------------------------------
    @property
    def status(self) -> RotatorStatus:
        return self._status

    def start(self) -> None:
        self._thread.start()

    def stop(self, timeout_s: float = 3.0) -> bool:
        """Stop the thread; True once it has ended."""
        self._stopping.set()
        self._mailbox.wake()
        if self._thread.is_alive():
            self._thread.join(timeout_s)
        return not self._thread.is_alive()

    # -- the thread ---------------------------------------------------------------------------
    def _run(self) -> None:
        self._emit_status()  # this thread is the only one that emits (rule 11)
        while not self._stopping.is_set():
            try:
                self._cycle()
            except Exception:  # a bug (or a failing callback) must not end the thread
                log.exception("%s: unexpected error in the rotator worker", self.cfg.rotator_id)
                self._stopping.wait(1.0)

    def _cycle(self) -> None:
        """One attempt: open the port, serve it until it fails, then wait out the back-off."""
        try:
            port = self._open(self.cfg.port, self.cfg.spec, self.cfg.baud)
        except PortError as exc:
            if str(exc) != self._port_error:
                self._port_error = str(exc)
                self._error("serial", str(exc))
            self._emit_status()
            self._idle_offline(self._backoff_s)
            self._backoff_s = min(self._backoff_s * 2, self.cfg.reconnect_max_s)
            return
        log.info("%s: opened %s", self.cfg.rotator_id, self.cfg.port)
        self._backoff_s, self._port_error = self.cfg.reconnect_min_s, None
        try:
            self._serve(port)
        except (serial.SerialException, OSError) as exc:
            self._error("serial", f"serial link to {self.cfg.port} lost: {exc}")
        except Exception:  # a bug must not kill the rotator: log it, reconnect
            log.exception("%s: unexpected error, reconnecting", self.cfg.rotator_id)
            self._error("internal", "unexpected error in the rotator worker (see the log)")
        finally:
            try:
                port.close()
            except Exception:  # closing a yanked port may fail too
                pass
            self._link = None
            self._motion = mo.link_down(self._motion)
            self._drop_pending("serial link down")
            self._emit_status()
        if not self._stopping.is_set():
            self._idle_offline(self._backoff_s)

    def _idle_offline(self, wait_s: float) -> None:
        """Wait for the next reconnect attempt, still taking commands from the mailbox."""
        deadline = self._clock() + wait_s
        while not self._stopping.is_set():
            now = self._clock()
            if now >= deadline:
                return
            readable, _, _ = select.select([self._mailbox], [], [], deadline - now)
            if readable:
                self._apply(self._mailbox.take(), self._clock())
                self._emit_status()

    def _serve(self, port: serial.Serial) -> None:
        spec = self.cfg.spec
        now = self._clock()
        link = Link(port, spec.codec_factory(), spec, now, self._clock, self.cfg.rotator_id)
        self._link = link
        self._motion = mo.link_up(self._motion, self.cfg.motion, now)
        link.answering = not spec.can_report_position
        if link.answering:
            link.options_due = set(self._options)
        for frame in link.codec.encode_connect(self._wall()):
            link.write(frame)
        self._emit_status()
        while not self._stopping.is_set():
            now = self._clock()
            batch = self._mailbox.take()
            if batch:
                self._apply(batch, now)
            if link.reply_overdue(now):
                self._reply_overdue(link, now)
            self._flush_stop(now)
            link.flush_outbox(now)
            junk = link.quiet_junk(now)
            if junk is not None:
                self._report_junk(*junk, now)
            self._advance(now)  # commands go ahead of the next poll
            self._poll_if_due(now)
            self._emit_status()
            timeout = self._next_wakeup(now) - now
            readable, _, _ = select.select([port, self._mailbox], [], [], max(0.0, timeout))
            if port in readable:
                data = port.read(port.in_waiting or 1)
                if not data:
                    raise serial.SerialException("port readable but no data (adapter unplugged?)")
                self._received(data, self._clock())

    # -- inbound: commands ----------------------------------------------------------------------
    def _apply(self, batch: Batch, now: float) -> None:
        for note in batch.notes:
            self._last_error = note
        if batch.lock is not None:
            self._locked = batch.lock
            if batch.lock:
                self._drop_pending(None)
                if self._link is not None:
                    self._send_stop(now)  # whatever we believe: the lock is for tower work
        if batch.stop is not None:
            self._pending = None
            self._last_source = batch.stop.source.value
            if self._link is not None:
                self._send_stop(now)
        for opt in batch.options:
            self._options[opt.name] = opt.enabled
            if self._link is not None:
                self._link.options_due.add(opt.name)
        if batch.target is not None:
            if self._locked:
                self._error("refused", "rotator is locked", command=describe_command(batch.target))
            elif self._link is None or not self._link.answering:
                self._error("refused", "rotator offline", command=describe_command(batch.target))
            else:
                recent = now - self._last_target_sent_t < BURST_QUIET_S
                if self._pending is None:
                    self._stream_t = now
                self._pending_replaced = self._pending is not None or recent
                self._pending = batch.target
                self._pending_t = now

    def _turning(self, now: float) -> bool:
        m = self._motion
        if self.cfg.spec.can_report_position:
            return m.state is MotionState.MOVING
        return m.busy_until_t is not None and now < m.busy_until_t and m.stop_sent_t is None

    def _reply_overdue(self, link: Link, now: float) -> None:
        slew = link.slew
        if slew is not None and slew.stops == 0:  # rule 9
            late = (
                f"no report from the controller {now - slew.start_t:.0f} s after a move that "
                f"takes {self._travel_s(slew):.0f} s at {self._az_speed_deg_s:g}/"
                f"{self._el_speed_deg_s:g} deg/s"
            )
            if slew.attempt >= SLEW_ATTEMPTS:
                self._error(
                    "serial",
                    f"{late}, the second time for this target: stopping it and giving the target "
                    "up (rotor jammed or held short of the point? if it is that slow, set "
                    "az_speed_deg_s / el_speed_deg_s)",
                    command=describe_command(Target(slew.to_az_deg, slew.to_el_deg)),
                )
            else:
                self._error(
                    "serial",
                    f"{late}: stopping it to ask where it is, then going on to the target (if "
                    "the rotor is that slow, set az_speed_deg_s / el_speed_deg_s)",
                )
                if self._pending is None:
                    target = Target(slew.to_az_deg, slew.to_el_deg, slew.source)
                    self._pending, self._pending_t, self._stream_t = target, now, now
                    self._pending_replaced = False
                    self._resend = (target, slew.attempt + 1)
            self._send_stop(now)
            return
        if slew is not None and slew.stops < SLEW_STOP_TRIES:  # rule 10
            log.warning(
                "%s: no report %g s after a stop during a slew; stopping again before asking",
                self.cfg.rotator_id,
                self.cfg.spec.reply_timeout_s,
            )
            self._send_stop(now)
            return
        link.give_up_reply(now)
        if slew is not None:
            self._motion = mo.track_lost(self._motion)
            self._error("serial", "no report after the stopped slew; asking the controller")

    def _send_stop(self, now: float) -> None:
        link = self._link
        assert link is not None
        link.outbox.clear()
        link.stop_due = True
        self._flush_stop(now)

    def _flush_stop(self, now: float) -> None:
        """Write a due stop now, or as soon as a half-duplex line is free (one reply time)."""
        link = self._link
        if link is None or not link.stop_due or not link.free(for_stop=True):
            return
        link.stop_due = False
        link.write_stop(now)
        self._motion = mo.stop_sent(self._motion, self.cfg.motion, now)

    def _drop_pending(self, why: str | None) -> None:
        if self._pending is not None and why:
            self._error(
                "refused", f"target dropped: {why}", command=describe_command(self._pending)
            )
        self._pending = None

    # -- outbound -------------------------------------------------------------------------------
    def _poll_if_due(self, now: float) -> None:
        link = self._link
        if link is None or not self.cfg.spec.can_report_position:
            return
        self._check_silence(now)
        link.poll(now, self._poll_interval())

    def _poll_interval(self) -> float:
        busy = self._motion.state is MotionState.MOVING or self._pending is not None
        return self.cfg.moving_poll_interval_s if busy else self.cfg.idle_poll_interval_s

    def _check_silence(self, now: float) -> None:
        link = self._link
        assert link is not None
        timeout_s = self.cfg.silence_timeout_s
        if link.reply_deadline is not None:
            return  # a reply is owed and may still come (a slew report takes the whole slew)
        if link.answering and link.silent_for(now) >= timeout_s:
            link.answering = False
            self._motion = mo.link_down(self._motion)
            self._error(
                "serial",
                f"controller on {self.cfg.port} stopped answering "
                f"(no valid reply for {timeout_s:g} s)",
            )
            self._drop_pending("controller not answering")
        elif (
            link.last_reply_t is None
            and not link.silence_reported
            and link.silent_for(now) >= timeout_s
        ):
            link.silence_reported = True
            self._error("serial", f"controller on {self.cfg.port} does not answer")

    def _advance(self, now: float) -> None:
        """Time-driven motion, then whatever the pending target and options may do now."""
        link = self._link
        if link is None or link.slew is None:  # no reports during a slew: nothing to judge
            self._motion, events = mo.tick(self._motion, self.cfg.motion, now)
            self._motion_events(events, now)
        if link is None or not link.answering:
            return
        if link.enable_due and link.slew is None and link.free() and not link.stop_due:
            enable = link.codec.encode_enable()
            if enable:
                link.write(enable)
            link.enable_due = False
        self._verify_stop(now)
        if self._pending is not None:
            self._try_target(now)
        idle = self._motion.state is MotionState.IDLE
        if idle and self._options and now - link.options_sent_t >= OPTIONS_REFRESH_S:
            link.options_due = set(self._options)
        if link.options_due and idle and self._pending is None and link.free():
            for name in sorted(link.options_due):
                try:
                    frame = link.codec.encode_option(name, self._options[name])
                except (KeyError, ValueError):
                    log.warning("%s: option %r not supported; skipped", self.cfg.rotator_id, name)
                    continue
                link.write(frame)
            link.options_due.clear()
            link.options_sent_t = now

    def _verify_stop(self, now: float) -> None:
        """A stop that did not take (a byte lost to RF, a garbled frame) is sent again."""
        m = self._motion
        if m.stop_sent_t is None:
            self._stop_tries = 0
            return
        moved_since = m.last_move_t is not None and m.last_move_t > m.stop_sent_t
        late = now - m.stop_sent_t >= self.cfg.motion.stop_resend_s
        if m.state is MotionState.MOVING and moved_since and late and self._pending is None:
            self._stop_tries += 1
            if self._stop_tries == STOP_TRIES_BEFORE_ERROR:
                self._error(
                    "stop",
                    f"rotor still turning after {self._stop_tries} stop commands; "
                    "stop it at the controller",
                )
            log.warning("%s: still turning after a stop; stopping again", self.cfg.rotator_id)
            self._send_stop(now)

    def _try_target(self, now: float) -> None:
        link = self._link
        assert link is not None and self._pending is not None
        if link.stop_due:
            return  # the stop goes first
        m, mcfg = self._motion, self.cfg.motion
        az, el = self._resolve(self._pending)
        if az is None:
            return  # no reading yet to keep the other axis where it is
        wire = link.codec.wire_target(az, el)
        if m.target_deg is not None and (m.target_deg, m.el_target_deg) == wire:
            self._pending = None  # already on its way there
            return
        if (
            self.cfg.spec.can_report_position
            and m.state is MotionState.IDLE
            and m.position_deg is not None
            and mo.angle_error(m.position_deg, wire[0], mcfg.az_wraps) <= mcfg.tolerance_deg
            and (
                wire[1] is None
                or m.el_position_deg is None
                or abs(m.el_position_deg - wire[1]) <= mcfg.tolerance_deg
            )
        ):
            log.info("%s: already within tolerance of %s", self.cfg.rotator_id, wire)
            self._pending = None
            return
        plan = mo.plan_target(m, mcfg, now)
        if plan is mo.Plan.STOP_FIRST:
            log.info("%s: turning; stopping before the new target %s", self.cfg.rotator_id, wire)
            self._send_stop(now)
            return
        if plan is not mo.Plan.SEND or not link.free():
            return  # braking, or a half-duplex line with a reply in flight: right after it
        if self._stream_wait(now):
            return  # a stream of targets: wait for it to pause
        if self._needs_fresh_reading(now):
            link.next_poll = now  # ask first; the target follows the answer
            return
        if plan is mo.Plan.SEND:
            link.send(link.codec.encode_target(az, el), now)
            if not self.cfg.spec.reports_while_moving:
                source = self._pending.source
                resend = self._resend
                attempt = resend[1] if resend and resend[0] is self._pending else 1
                slew = Slew(
                    now,
                    m.position_deg,
                    m.el_position_deg,
                    wire[0],
                    wire[1],
                    source,
                    attempt=attempt,
                )
                link.begin_slew(slew, self._travel_s(slew))
            self._resend = None
            self._motion = mo.commanded(m, mcfg, wire[0], now, wire[1])
            self._last_source = self._pending.source.value
            self._pending = None
            self._last_target_sent_t = now
            link.next_poll = min(link.next_poll, now + self.cfg.moving_poll_interval_s)

    def _travel_s(self, slew: Slew) -> float:
        spec = self.cfg.spec
        return slew.travel_s(
            self._az_speed_deg_s,
            self._el_speed_deg_s,
            self.cfg.motion.az_span_deg,
            spec.el_max_deg - spec.el_min_deg,
        )

    def _stream_wait(self, now: float) -> bool:
        if not self._pending_replaced:
            return False
        max_wait = STREAM_MAX_WAIT_S[self.cfg.spec.retarget.value]
        return now - self._pending_t < BURST_QUIET_S and now - self._stream_t < max_wait

    def _needs_fresh_reading(self, now: float) -> bool:
        spec, link = self.cfg.spec, self._link
        if link is None or not spec.can_report_position or self.cfg.motion.direct_retarget:
            return False
        age = now - (link.last_reply_t if link.last_reply_t is not None else -1e18)
        return age > self.cfg.moving_poll_interval_s

    def _resolve(self, target: Target) -> tuple[float | None, float | None]:
        """Fill the axis a target leaves out with its current target, else its position."""
        m = self._motion
        az = target.az_deg
        if az is None:
            az = m.target_deg if m.target_deg is not None else m.position_deg
        el = target.el_deg
        if self.cfg.spec.has_elevation and el is None:
            el = m.el_target_deg if m.el_target_deg is not None else m.el_position_deg
            if el is None:
                return None, None
        return az, el

    def _next_wakeup(self, now: float) -> float:
        link = self._link
        times = [now + 1.0]
        if link is not None:
            times += link.wakeups()
            if link.slew is not None:
                times.append(now + self.cfg.moving_poll_interval_s)  # refresh the estimate
        if self._pending is not None and self._stream_wait(now):
            max_wait = STREAM_MAX_WAIT_S[self.cfg.spec.retarget.value]
            times.append(min(self._pending_t + BURST_QUIET_S, self._stream_t + max_wait))
        deadline = mo.next_deadline(self._motion, self.cfg.motion, now)
        if deadline is not None:
            times.append(deadline)
        return min(times)

    # -- inbound: bytes -------------------------------------------------------------------------
    def _received(self, data: bytes, now: float) -> None:
        link = self._link
        assert link is not None
        log.debug("%s: <- %r", self.cfg.rotator_id, data)
        for reply in link.codec.feed(data):
            if isinstance(reply, PositionReply):
                link.got_reading(now)
                link.slew = None
                if reply.motion_enabled is False:
                    link.enable_due = True
                if reply.controller_time is not None:
                    self._controller_time = reply.controller_time
                if not link.answering:
                    link.answering = True
                    link.options_due = set(self._options)
                    log.info("%s: controller answering", self.cfg.rotator_id)
                self._motion, events = mo.reading(
                    self._motion, self.cfg.motion, reply.az_deg, now, reply.el_deg
                )
                self._motion_events(events, now)
                self._publishable(reply.az_deg, reply.el_deg)
            elif isinstance(reply, VersionReply):
                if reply.version != self._version:
                    log.info("%s: controller version %s", self.cfg.rotator_id, reply.version)
                self._version = reply.version
            elif isinstance(reply, JunkReply):
                self._junk(reply, now)
                if reply.reason == UNTRUSTED:
                    link.ask_again(now)
                    if link.end_slew(now):  # the slew is over; where it ended, unseen
                        self._motion = mo.slew_ended(self._motion, now)

    def _publishable(self, az_deg: float, el_deg: float | None) -> None:
        moving = self._motion.state is MotionState.MOVING
        band, wraps = self.cfg.deadband_deg, self.cfg.motion.az_wraps
        new, self._published_dir = mo.publishable_bearing(
            self._published_deg, self._published_dir, az_deg, moving, band, wraps
        )
        if new is not None:
            self._published_deg = new
        if el_deg is not None:
            new, self._published_el_dir = mo.publishable_bearing(
                self._published_el_deg, self._published_el_dir, el_deg, moving, band, False
            )
            if new is not None:
                self._published_el_deg = new

    def _junk(self, reply: JunkReply, now: float) -> None:
        link = self._link
        assert link is not None
        if POWER_ON_BYTE in reply.data:
            log.info("%s: power-on byte seen; options will be re-applied", self.cfg.rotator_id)
            link.options_due = set(self._options)
        link.add_junk(reply.data, now)

    def _report_junk(self, data: bytes, harmless: bool, now: float) -> None:
        log.log(
            logging.INFO if harmless else logging.WARNING,
            "%s: ignored %d bytes that are no reply: %r",
            self.cfg.rotator_id,
            len(data),
            data[:64],
        )
        if harmless:
            return
        if now - self._junk_reported_t >= self.cfg.junk_report_interval_s:
            self._junk_reported_t = now
            self._error(
                "protocol", f"controller sent {len(data)} bytes that are no valid reply; ignored"
            )

    def _motion_events(self, events: list[mo.Event], now: float) -> None:
        for event in events:
            if event is mo.Event.STALLED:
                pos = self._motion.position_deg
                self._error(
                    "stalled",
                    f"rotor stalled at {pos:g}° (no progress for "
                    f"{self.cfg.motion.stall_timeout_s:g} s): brake paddle pressed or rotor stuck",
                )
                if self._link is not None:
                    self._link.write_stop(now)
            else:
                log.info(
                    "%s: %s at %s", self.cfg.rotator_id, event.value, self._motion.position_deg
                )

    # -- status ---------------------------------------------------------------------------------
    def _error(self, kind: str, message: str, command: str | None = None) -> None:
        log.warning("%s: %s%s", self.cfg.rotator_id, message, f" ({command})" if command else "")
        self._last_error = message
        self._on_event(ErrorEvent(kind, message, command, self._wall()))

    def _emit_status(self) -> None:
        link = self._link
        answering = link is not None and link.answering
        state = self._motion.state if answering else MotionState.OFFLINE
        target: tuple[float | None, float | None] = (
            self._motion.target_deg,
            self._motion.el_target_deg,
        )
        if self._pending is not None and link is not None:
            az, el = self._resolve(self._pending)
            target = link.codec.wire_target(az, el) if az is not None else target
        spec = self.cfg.spec
        bearing, elevation = self._published_deg, self._published_el_deg
        estimated = link is not None and link.slew is not None
        if estimated:
            assert link is not None and link.slew is not None
            bearing, elevation = link.slew.estimate(
                self._clock(), self._az_speed_deg_s, self._el_speed_deg_s
            )
        status = replace(
            self._status,
            state=state,
            bearing_deg=bearing if spec.can_report_position else None,
            elevation_deg=elevation if spec.has_elevation else None,
            estimated=estimated,
            controller_time=self._controller_time,
            target_az_deg=target[0],
            target_el_deg=target[1] if spec.has_elevation else None,
            connected=link is not None,
            available=answering,
            locked=self._locked,
            version=self._version,
            options=dict(self._options),
            last_error=self._last_error,
            last_command_source=self._last_source,
        )
        if status != self._status:
            self._status = status
            self._on_status(status)
