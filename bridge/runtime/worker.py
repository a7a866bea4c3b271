"""One rotator's serial line: its port, the back-off between attempts to open it, and its session.
I/O only, and no thread of its own: lines.py runs every worker from one thread.

The loop (lines.py) asks ``wants(now)`` (what to wait for: the port and the mailbox pipe, until
when) and calls ``serve(ready, now)``. Whatever happened (bytes, commands, time) goes into the
rotator's session (session.py, where every decision is made) and the actions it hands back are
carried out: bytes written, statuses and error events handed to the listeners (the second and
last hand-off point, docs/architecture.md rule 3).

Rules:
1. Any serial error closes the port, tells the session the link is down and retries with
   back-off (``reconnect_min_s`` doubling up to ``reconnect_max_s``); a worker never dies of
   one. Commands are still taken while the port is closed (they are refused with a reason).
   While the session owes the controller a stop (session/stops.py rule 3: a STOP or lock ON
   that came while the port was out), the port is tried again every OWED_RETRY_S instead,
   however far the back-off has grown: that stop is the first frame once the adapter is back,
   and a rotor that kept its power turns on until it goes (attack 23: an adapter out 17 s had
   the next try up to 10 s after it was back, and the rotor turned on 36 degrees). Trying a
   missing path is cheap (one failed open() on a thread of its own), and a try that hangs is
   bounded (rule 4). The back-off is kept while nothing is owed: then nothing is lost by
   waiting.
2. Everything the port has is read in one go and handed to the session as one chunk; while the
   session says a reply cannot be complete yet (link.py rule 7) only the mailbox is watched,
   and when that hold ends the port is read without waiting to be told it is readable (up to
   one quiet time late when other lines are served then: link.py rule 7, lines.py rule 7).
3. Listeners (MQTT, rotctld, Home Assistant) are called from the lines thread only, and one
   that raises is logged once per kind of failure and otherwise ignored (listeners.py): a
   display problem never closes or reopens the line to the controller.
   Listeners must be quick (they only queue for the network): every line waits while one runs.
4. Opening a port and closing one (failed, or for good when the rotator stops) run on a
   short-lived thread (port.py PendingOpen, close_in_background): a wedged USB adapter must
   not hold up the other lines. Meanwhile the rotator is offline and its commands are answered
   (refused) as when the port is closed. ``wait_closed`` waits for those closes, on any thread
   but the lines thread (lines.py rule 4: a stopped rotator's port is closed or being closed).
   An open that has not returned OPEN_BOUND_S after it started (a wedged adapter's driver) is
   abandoned, said once (the session's port error: R/error and a WARNING, once per reason),
   and the port is tried again at once (attack 23: a hung open() was waited for for ever, and
   the adapter pulled and plugged back in never brought the rotator back until a restart). A
   thread stuck in the kernel cannot be ended from here, so abandoned attempts still inside
   their open() are counted, and each one doubles the next attempt's bound (OPEN_BOUND_S, 2x,
   4x, ...): a driver wedged for good holds about log2(t / OPEN_BOUND_S) threads after t
   seconds (13 after a day), never one more every few seconds, and yet no attempt is waited
   for for ever (review 81: with one abandoned attempt at most, the second hung try was waited
   for as long as the first hung, for good, and an adapter replugged later than OPEN_BOUND_S
   after it wedged was never tried again). A replug need not wait for a bound: while an
   attempt is pending, the first one included (review 84: the first hung open was waited for
   its whole OPEN_BOUND_S with the path never looked at, and a STOP owed meanwhile reached the
   replugged adapter ~9 s late), the port's path is looked at every NODE_LOOK_S (one stat,
   the link followed: no open, nothing of the driver's) and a device node that changed from
   the one the pending attempt started on (gone, or another one: the link's target, the
   node's st_rdev, st_dev, st_ino; never its ctime, which a chmod or udev re-applying a rule
   moves with no replug: review 84, a thread more hung in the wedged driver per touch) is
   the replug's evidence: that attempt is abandoned too and the port tried again at once (one
   more thread per replug, a hand's act). The abandoned open hangs on the old device, the new
   attempt opens the new one. The bound is liveness, not correctness (docs/architecture.md
   rule 15): it decides when the port is tried again, never what the controller is sent; a
   port an abandoned attempt opens late is closed at once (port.py PendingOpen), unused.
5. The session's questions about the sky (``Ask``) go to the sky worker (skywork.py); each
   answer is queued here by that thread, which then wakes the lines thread through the mailbox
   pipe, and is handed to the session on the lines thread after the mailbox's commands.
6. What a worker with an open port waits for (``wants``) changes only when it is served: the
   session is touched by nothing else, and what other threads bring (commands, sky answers)
   comes through the mailbox, whose descriptor is always watched. So it is worked out once
   after each step and kept until the next (but for the end of a held reply's hold, which
   ``serve`` asks the session again after the mailbox's commands: a stop ends it, link.py
   rule 7); a port being opened is asked about every time.
"""

from __future__ import annotations

import logging
import math
import os
import threading
import time
from collections import deque
from collections.abc import Callable
from functools import partial
from typing import Any

import serial

from bridge.core.model import ErrorEvent, ErrorKind, RotatorStatus, SettingValue
from bridge.core.text import shown_path
from bridge.runtime.listeners import contained
from bridge.runtime.port import (
    PendingOpen,
    PortError,
    PortOpener,
    PortWatch,
    close_in_background,
    open_port,
    read_available,
    watched,
    write_frame,
)
from bridge.session.actions import Action, Ask, Audit, Publish, Report, Write
from bridge.session.config import WorkerConfig
from bridge.session.mailbox import Mailbox
from bridge.session.session import OwnTurn, RotatorSession
from bridge.sky.worker import Answer, SkyWorker

__all__ = ["Worker", "WorkerConfig"]

log = logging.getLogger(__name__)
_NOTHING: frozenset[int] = frozenset()
# rule 1: how soon the port is tried again while a stop is owed, whatever the back-off: a
# rotor at 6 degrees a second turns on 1.5 degrees at most, once its adapter is back, before
# the stop's try (four failed open()s a second on a missing path cost next to nothing)
OWED_RETRY_S = 0.25
# rule 4: how long an open() may take before it is given up as hung. A tty's takes
# milliseconds; a Bluetooth serial port's (rfcomm) pages the device first, some 5 s at most
OPEN_BOUND_S = 10.0
# rule 4: how often the port's path is looked at for a replug while abandoned opens still hang
NODE_LOOK_S = 1.0


class Worker:
    def __init__(
        self,
        cfg: WorkerConfig,
        mailbox: Mailbox,
        on_status: Callable[[RotatorStatus], None],
        on_event: Callable[[ErrorEvent], None],
        *,
        options: dict[str, SettingValue] | None = None,
        locked: bool = False,
        health: dict[str, object] | None = None,
        storm: bool = False,
        storm_halted: bool = False,
        storm_arrived: bool = False,
        storm_place: int = 0,  # kept.py rule 4: the place the kept storm's park took
        stop_owed: bool = False,
        short_of: float | None = None,
        turn_kept: bool = False,  # kept.py rule 13
        order: tuple[int, int, int] = (0, 0, 0),  # kept.py rule 12: since, turn, lock kept
        wall: Callable[[], float] = time.time,
        port_opener: PortOpener = open_port,
        sky: SkyWorker | None = None,
        port_watch: PortWatch | None = None,
        on_audit: Callable[[Audit], None] | None = None,
        place: Callable[[OwnTurn], int] | None = None,  # the bridge's own turns' places:
        # ``mailbox``'s unless given (a composite's box: the rotator's, runtime/composite.py
        # rule 10; mailbox.py rule 10b)
    ) -> None:
        self.cfg = cfg
        self._sky = sky or SkyWorker()
        self._answers: deque[tuple[int, Answer]] = deque()  # rule 5: filled by the sky thread
        self.session = RotatorSession(
            cfg,
            options=options,
            locked=locked,
            health=health,
            storm=storm,
            storm_halted=storm_halted,
            storm_arrived=storm_arrived,
            storm_place=storm_place,
            stop_owed=stop_owed,
            short_of=short_of,
            turn_kept=turn_kept,
            order=order,
            place=place
            or mailbox.own_place,  # (session.py's Order: the bridge's own turns' places)
        )
        self._mailbox = mailbox
        self._box = mailbox.fileno()
        self._on_status = contained(on_status, f"{cfg.rotator_id}: status listener")
        self._on_event = contained(on_event, f"{cfg.rotator_id}: event listener")
        # session.py rule 25: the bridge's own moves, to the audit trail (the judge's)
        self._on_audit = contained(on_audit or _unheard, f"{cfg.rotator_id}: audit listener")
        self._wall = wall
        self._watch = port_watch  # port.py rule 7: the stop express holds a copy of the port
        self._open = port_opener if port_watch is None else watched(port_opener, port_watch)
        self._backoff_s = cfg.reconnect_min_s
        self._port: serial.Serial | None = None
        self._fd = -1
        self._opening: PendingOpen | None = None
        self._open_until = math.inf  # when the pending open is given up as hung (rule 4)
        self._hung: list[PendingOpen] = []  # attempts given up, maybe still running (rule 4)
        self._node: tuple[str, int, int, int] | None = None  # the path's device at the try
        self._look_at = math.inf  # when the path is looked at next for a replug (rule 4)
        self._closing: list[threading.Thread] = []  # ports being closed (rule 4)
        self._wake: Callable[[], None] = lambda: None
        self._reopen_at = 0.0
        self._tried_at = 0.0  # when the port last failed: to open, or while open (rule 1)
        self._held = False
        self._wanted: tuple[list[int], float, float] | None = None  # rule 6
        self._urgent = frozenset({self._box})
        self._failures: set[type[BaseException]] = set()

    # -- called by the lines thread only -------------------------------------------------------
    def begin(self, now: float, wake: Callable[[], None]) -> None:
        self._wake = wake  # wakes the lines thread when a port opened (rule 4)
        self._do(self.session.start(now))
        self._reopen_at = self._tried_at = now

    def end(self, now: float) -> None:
        """Close the port for good (the rotator is stopping), in the background (rule 4): the
        rotator's stop() waits for that with ``wait_closed``, off this thread."""
        if self._opening is not None:
            self._closes(self._opening.abandon(self._watch))
            self._opening, self._look_at = None, math.inf
        port, self._port, self._fd = self._port, None, -1
        if port is not None:
            self._closes(close_in_background(port, self._watch))
            self._do(self.session.link_down(None, now, ErrorKind.SERIAL))

    def wait_closed(self, timeout_s: float) -> bool:
        """Whether every port this worker closed is closed, waiting up to ``timeout_s`` for it.
        Not on the lines thread (rule 4); after ``end`` it is the only one touching the list."""
        deadline = time.monotonic() + timeout_s
        for closing in self._closing:
            closing.join(max(0.0, deadline - time.monotonic()))
        return not any(closing.is_alive() for closing in self._closing)

    def _closes(self, closing: threading.Thread | None) -> None:
        self._closing = [c for c in self._closing if c.is_alive()]
        if closing is not None:
            self._closing.append(closing)

    def has_commands(self, ready: set[int]) -> bool:
        return self._box in ready

    def urgent(self) -> frozenset[int]:
        """The mailbox's descriptor when a stop or lock ON waits in it (lines.py rule 5), else
        nothing: read without the mailbox's lock, a hint for the order of a round."""
        return self._urgent if self._mailbox.urgent else _NOTHING

    def wants(self, now: float) -> tuple[list[int], float, float]:
        """The descriptors to wait on, the time to be woken at and how late that time may be
        met (lines.py rule 7): no later than it, but for a held reply's (rule 2)."""
        if self._wanted is not None:
            return self._wanted
        if self._port is None:
            if self._opening is None:
                reopen_at = self._next_try()
                return [self._box], reopen_at, reopen_at
            if self._opening.result is not None:
                return [self._box], now, now  # it is there
            until = min(self._open_until, self._look_at)
            return [self._box], until, until
        session = self.session
        until, hold = session.next_wakeup(), session.hold_reads_until()
        self._held = now < hold
        if self._held:  # rule 2
            latest = min(until, session.hold_reads_latest())
            self._wanted = [self._box], min(until, hold), latest
        else:
            self._wanted = [self._box, self._fd], until, until
        return self._wanted

    def guarded(self, step: Callable[..., None], now: float, *args: Any) -> None:
        """``step(now, *args)`` with a bug in it logged (once per kind), the port closed and
        reopened after the back-off: never raised into the lines thread (lines.py rule 2)."""
        self._wanted = None  # rule 6: what it waits for is asked anew after every step
        try:
            step(now, *args)
        except Exception as exc:
            if type(exc) not in self._failures:
                self._failures.add(type(exc))
                log.exception("%s: unexpected error, reconnecting", self.cfg.rotator_id)
            try:
                reason = "unexpected error in the rotator worker (see the log)"
                self._lost(reason, ErrorKind.INTERNAL, now)
            except Exception:
                self._port, self._fd = None, -1  # at least: no port nobody serves

    def tell_wall(self, now: float) -> None:
        """The session told the wall clock at ``now``: before any batch is handed to it (a
        clock set late, NTP after boot, moves tracking; a suspend is a gap between wind
        readings, session/wind.py rule 2), the port out (often so at a resume) as much as in.
        A rotator of two boxes hands both sessions their batches before either box is served
        (runtime/composite.py rule 1), and tells them first (review 109)."""
        self.session.set_wall(now, self._wall())

    def serve(self, now: float, ready: set[int]) -> None:
        self.tell_wall(now)  # (``tell_wall``: before the batch, the port out or in)
        if self._port is None:
            if self._box in ready:
                self._do(self.session.commands(self._mailbox.take(), now))
                self._take_answers(now)
            opening = self._opening
            if opening is not None and opening.result is not None:
                self._opened(opening.result, now)
            elif opening is not None and now >= self._open_until:
                self._open_hung(opening, now, self._hung_reason())
            elif opening is not None and now >= self._look_at:
                if _device_node(self.cfg.port) != self._node:  # rule 4: replugged
                    self._open_hung(opening, now, self._replugged_reason())
                else:
                    self._look_at = now + NODE_LOOK_S
            elif opening is None and now >= self._next_try():
                self._start_open(now)
            return
        session, acted = self.session, False
        try:
            if self._box in ready:
                batch = self._mailbox.take()
                if batch:
                    self._do(session.commands(batch, now))
                    acted = True
                acted = self._take_answers(now) or acted
            readable = self._fd in ready
            # rule 2: asked again, not as wants saw it: a stop just taken ends the hold
            if readable or (self._held and now >= session.hold_reads_until()):
                data = read_available(self._fd, readable, self.cfg.port)
                if data:
                    actions = session.bytes_received(data, now)
                    if actions:
                        acted = True
                        self._do(actions)
                elif not readable:  # the reply is late (link.py rule 7)
                    session.nothing_read(now)
            if not acted and now >= session.next_wakeup():
                actions = session.tick(now)
                if actions:
                    self._do(actions)
        except (serial.SerialException, OSError) as exc:
            self._lost(self._link_lost(exc), ErrorKind.SERIAL, now)

    def carry_out(self, now: float, actions: list[Action]) -> None:
        """What the session decided on a batch taken from another mailbox (a composite
        rotator's, composite.py), carried out as for the worker's own: a port that fails
        meanwhile is the link lost (rule 1), as in ``serve``."""
        try:
            self._do(actions)
        except (serial.SerialException, OSError) as exc:
            self._lost(self._link_lost(exc), ErrorKind.SERIAL, now)

    @property
    def status(self) -> RotatorStatus:
        return self.session.status

    @property
    def halts_applied(self) -> int:
        """mailbox.py rule 10: the halt count the status shows every stop and lock ON up to."""
        return self.session.halts_applied

    @property
    def stop_due(self) -> bool:
        """A stop waits for the line (link.py rule 3: a half-duplex line owes a reply first);
        read from another thread (claim rule 4's halt), an attribute read."""
        link = self.session.controller.link
        return link is not None and link.stop_due

    @property
    def newest_applied(self) -> int:
        """mailbox.py rule 10a: the newest place the status shows every command up to."""
        return self.session.newest_applied

    @property
    def winds_applied(self) -> int:
        """mailbox.py rule 9: the live wind readings the status shows (``wind_unseen``)."""
        return self.session.winds_applied

    @property
    def features_on(self) -> tuple[bool, bool]:
        """What a tracking OFF and a following OFF would end now (session.py ``features_on``)."""
        return self.session.features_on

    def _next_try(self) -> float:
        """When the port is tried again: after the back-off, or OWED_RETRY_S after the last
        failure while a stop is owed (rule 1; asked anew each time: a STOP taken while the
        port is out shortens the wait it came in)."""
        if self.session.controller.stops.owed:
            return min(self._reopen_at, self._tried_at + OWED_RETRY_S)
        return self._reopen_at

    def _start_open(self, now: float) -> None:
        """Rule 4: an attempt on a thread of its own, bounded by OPEN_BOUND_S doubled for each
        abandoned attempt still inside its open(); the path looked at for a replug meanwhile,
        the first attempt's wait included."""
        self._hung = [hung for hung in self._hung if hung.running]
        self._node = _device_node(self.cfg.port)
        attempt = partial(self._open, self.cfg.port, self.cfg.spec, self.cfg.baud)
        self._opening = PendingOpen(attempt, self._wake)
        self._open_until = now + OPEN_BOUND_S * 2 ** len(self._hung)
        self._look_at = now + NODE_LOOK_S  # review 84: the first hung open's wait too

    def _hung_reason(self) -> str:
        return (
            f"opening {self.cfg.shown_port} hung for {OPEN_BOUND_S:g} s or more (the adapter or "
            "its driver wedged? unplug it and plug it back in): given up and tried again"
        )

    def _replugged_reason(self) -> str:
        return (
            f"{self.cfg.shown_port} is another device now (replugged?) while opening it hung: "
            "tried again"
        )

    def _open_hung(self, opening: PendingOpen, now: float, reason: str) -> None:
        """Rule 4: the pending open outlasted its bound, or the device it was opening changed:
        given up, kept count of while it still hangs, and tried again at once."""
        self._closes(opening.abandon(self._watch))  # (a port it opened just now: closed)
        self._hung.append(opening)
        self._opening, self._look_at = None, math.inf
        self._do(self.session.open_failed(reason, now))  # once per reason (controller.py)
        self._tried_at = self._reopen_at = now  # the bound was the wait

    def _opened(self, result: serial.Serial | Exception, now: float) -> None:
        self._opening, self._look_at = None, math.inf
        if isinstance(result, Exception):
            if not isinstance(result, PortError):
                log.error(
                    "%s: opening %s failed: %s",
                    self.cfg.rotator_id,
                    self.cfg.shown_port,
                    shown_path(repr(result)),
                )
            self._do(self.session.open_failed(str(result), now))
            self._tried_at, self._reopen_at = now, now + self._backoff_s
            self._backoff_s = min(self._backoff_s * 2, self.cfg.reconnect_max_s)
            return
        log.info("%s: opened %s", self.cfg.rotator_id, self.cfg.shown_port)
        self._backoff_s = self.cfg.reconnect_min_s
        self._port, self._fd = result, result.fileno()
        self._do(self.session.link_up(now, self._wall()))

    def _link_lost(self, exc: Exception) -> str:
        """What is said of a port that failed: its error may name the path too (pyserial's
        do), spelled as ``shown_path`` spells it (core/text.py)."""
        return shown_path(f"serial link to {self.cfg.port} lost: {exc}")

    def _lost(self, reason: str, kind: ErrorKind, now: float) -> None:
        port, self._port, self._fd = self._port, None, -1
        if port is not None:
            self._closes(close_in_background(port, self._watch))  # rule 4
        self._tried_at, self._reopen_at = now, now + self._backoff_s
        self._do(self.session.link_down(reason, now, kind))

    def _take_answers(self, now: float) -> bool:
        """Rule 5 (after the mailbox's take, which drained the wake bytes of these answers)."""
        acted = False
        while self._answers:
            generation, answer = self._answers.popleft()
            self._do(self.session.sky_answer(generation, answer, now))
            acted = True
        return acted

    def _answered(self, generation: int, answer: Answer) -> None:
        """On the sky worker's thread: queue, and wake the lines thread."""
        self._answers.append((generation, answer))
        self._mailbox.wake()

    def _do(self, actions: list[Action]) -> None:
        for action in actions:
            if isinstance(action, Write):
                if self._port is not None:
                    write_frame(self._port, action.data)
                    log.debug("%s: -> %r", self.cfg.rotator_id, action.data)
            elif isinstance(action, Publish):
                self._on_status(action.status)
            elif isinstance(action, Report):
                when = self._wall()
                event = ErrorEvent(action.kind, action.message, action.command, when, action.origin)
                self._on_event(event)
            elif isinstance(action, Audit):
                self._on_audit(action)
            elif isinstance(action, Ask):
                self._sky.ask(action.question, partial(self._answered, action.generation))


def _device_node(path: str) -> tuple[str, int, int, int] | None:
    """Rule 4: the device a port's path names now, or None if it names none: the node the links
    resolve to (a by-id link's target) and that node's identity (st_rdev, st_dev, st_ino). A
    replug makes a new node (udev removes the old one and creates it, and links the stable name,
    anew); a node touched in place (chmod, chown, an ACL, udev re-applying a rule at a change
    event) keeps all of these and moves only its ctime, which is not looked at (review 84)."""
    try:
        node = os.path.realpath(path)
        st = os.stat(node)
    except (OSError, ValueError):
        return None
    return node, st.st_rdev, st.st_dev, st.st_ino


def _unheard(audit: Audit) -> None:
    """No audit listener (a worker on a bench): a move of the bridge's own goes unwritten."""
