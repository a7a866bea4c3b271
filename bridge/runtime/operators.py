"""Who is turning a rotator: its control lease as the judge keeps it (the pure lease is
lease.py) and the audit trail of every command judged. Rotator (rotator.py) owns one.

Rules:
1. The lease is judged on the front ends' threads (the judge's), in the rotator's owner step
   (kept.py rule 5): the decision, the change put in the mailbox (the status shows the holder,
   ``R/control`` says it) and its save queued for the store's writer thread (state_store.py
   rule 5: no fsync on a front end's thread) are one step, so that the judge, the status and
   the state file name the same holder whichever claims and releases race. The lease here is
   the judge's one copy. The change put is all the session needs to drop a target another
   operator sent before a claim that still waits unsent (session/session.py rule 23), and all
   the mailbox needs to refuse one judged before the claim and put after it (the put judges
   the lease's generation: session/mailbox.py rule 14, ``claimed_meanwhile`` its words). A save
   in line takes the changes made before it runs: the newest is written, once (an attack pass:
   1,500 renewing claims queued 1,500 writes, each with its fsync, and a lock ON's save waited
   a minute behind them).
2. A lease ends by itself: a timer (daemon, one at a time) fires at its end, so that the status
   and ``R/control`` say it is free without anyone asking, and the audit trail has it (its
   operator the holder, interface ``lease``). A timer that fires early (the wall clock was set
   back) arms itself again. The end is a step like a release (rule 1); the timer is armed
   after the step, under a lock of its own (starting a thread waits for it: never in the
   owner's step), for the lease as it is then, so the last arming follows the last change.
   The lease's end is the station's clock's (rule 5) and the timer's wait the monotonic
   clock's: a wall clock stepped forward (NTP on a board without a clock chip, after a
   restart that restored the lease) ended it for the judge while the status named the
   holder until the timer, up to the whole lease later (an attack pass). So the timer waits
   LEASE_CHECK_S at most, and the judge ends a lease it finds over (``refusal``) as the timer
   would, before it answers.
   A lease kept in the state file that ended while the bridge was stopped ends at the start:
   audited, and gone from the file (it stayed there, and a clock set back later revived it).
   A claim or a release that finds the lease over by the clock ends it first, said and
   audited (a review: a release then found it free, and the status named its holder).
3. Every command judged, executed or refused, from every interface, is one audit event handed
   to ``on_audit`` (the audit file's queue and ``R/audit``, both of which only queue). A
   listener that raises is logged and ignored (docs/architecture.md rule 8): the audit trail
   never costs a command, and a stop is put in the mailbox before its event is made.
4. Claims and releases are commands too (core/model.py ``Claim``, ``Release``): the judge's
   ``submit`` (rotator.py) audits them, and reports a refused one on ``R/error``, as any.
5. The lease is on the station's clock (``lease_clock``: the app's is the one its heartbeats
   carry, interfaces/mqtt/heartbeat.py rule 6, the wall clock never set back; the wall clock
   where none is given), the clock ``R/control``'s end is read on, here and by the remote
   (remote/rotator.py rule 6). On the raw wall clock set back 10 minutes the lease was held
   10 minutes past the end its heartbeats said had come (docs/architecture.md rule 15: the
   wall clock stepped back stretched it): ``R/control`` named the holder past that end and
   the remote answered ``RPRT 0`` to a move the station refused (an attack pass). Set
   forward, both clocks follow at once. The audit trail's times are the wall clock's.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from typing import Protocol

from bridge.core.errors import RefusalCode, Refused
from bridge.core.model import AuditEvent, Control, ErrorKind, Origin, Source
from bridge.runtime.kept import Owner
from bridge.runtime.lease import Lease, LeaseError, restorable
from bridge.runtime.state_store import StateStore
from bridge.session.mailbox import Mailbox

log = logging.getLogger(__name__)

EXECUTED = "executed"
LEASE_CHECK_S = 60.0  # rule 2: the longest the timer waits before it looks at the wall clock


class Timer(Protocol):
    def cancel(self) -> None: ...


def thread_timer(delay_s: float, fire: Callable[[], None]) -> Timer:
    """Rule 2's timer: a daemon thread that calls ``fire`` after ``delay_s``."""
    timer = threading.Timer(delay_s, fire)
    timer.daemon = True
    timer.start()
    return timer


class Operators:
    def __init__(
        self,
        rotator_id: str,
        store: StateStore,
        mailbox: Mailbox,
        *,
        wall: Callable[[], float],
        lease_clock: Callable[[], float] | None = None,
        bearing: Callable[[], float | None],
        report: Callable[[ErrorKind, str, str | None], None],
        on_audit: Callable[[AuditEvent], None] | None = None,
        timer: Callable[[float, Callable[[], None]], Timer] = thread_timer,
        owner: Owner | None = None,
    ) -> None:
        self._id = rotator_id
        self._store = store
        self._mailbox = mailbox
        self._wall = wall  # the audit trail's times
        self._now = wall if lease_clock is None else lease_clock  # the lease's (rule 5)
        self._bearing = bearing
        self._report = report
        self._on_audit = on_audit
        kept = store.lease(rotator_id)  # state_store.py rule 6
        self._forget = False  # rule 2: a kept lease that cannot hold, gone from the file at start
        if kept is not None and restorable(kept, self._now()) is None:  # lease.py rule 6
            log.warning("%s: control lease in the state file ignored: %r", rotator_id, kept)
            kept, self._forget = None, True
        self._lease = Lease(kept)
        self._owner = owner or Owner(store, mailbox)  # rule 1: the rotator's, shared with the lock
        self._timer_lock = threading.Lock()  # rule 2
        self._start_timer = timer
        self._timer: Timer | None = None
        self._stopped = False
        self._unsaved: list[Control | None] = []  # rule 1: the newest lease not saved yet
        self._unsaved_guard = threading.Lock()  # the owner's step and the writer's

    def start(self) -> None:
        """The lease kept across a restart shows in the status, and ends by itself."""
        with self._owner:
            now = self._now()
            ended = self._ended(now)  # rule 2: one that ended while the bridge was down
            held = self._lease.holder(now)
            if held is not None:
                self._mailbox.put_control(held, wake=False, now_unix=now)  # woken after it
            elif self._forget:
                self._changed(None)
        self._arm()
        self._said_ended(ended)

    def stop(self) -> None:
        with self._timer_lock:
            self._stopped = True
        self._arm()

    @property
    def holder(self) -> Control | None:
        return self._lease.holder(self._now())

    def refusal(self, who: str) -> str | None:
        """lease.py rule 5: why a motion command from ``who`` is refused, or None; a lease the
        wall clock ended before its timer fired is ended first (rule 2). Never asked in an
        owner's step (the judge asks before its step)."""
        if self._lease.has_ended(self._now()):
            self._expire()
        return self._lease.refusal(who, self._now())

    def claimed_meanwhile(self, held: Control) -> str:
        """Why a target judged before ``held`` was claimed is refused at its put (session/
        mailbox.py rule 14): the refusal ``refusal`` would now give, saying when it came."""
        text = held.held_text(self._now())
        return (
            f"{held.operator} claimed the control lease while it was judged: {text}: only they "
            "may turn it (control lease)"
        )

    # -- claims and releases (rule 4) -----------------------------------------------------
    def claim(self, operator: object, minutes: object, origin: Origin) -> Control:
        """Raise Refused if the claim is refused (the judge reports and audits it, as every
        command: rotator.py ``submit``)."""
        ended: Control | None = None
        try:
            with self._owner:  # rule 1
                ended = self._ended(self._now())  # rule 2: over by the clock: said first
                held = self._lease.claim(operator, minutes, self._now())
                self._changed(held)
        except LeaseError as exc:
            raise Refused(RefusalCode.INVALID, str(exc)) from None
        finally:
            self._said_ended(ended)
        self._arm()
        log.info("%s: %s holds the control lease (%s)", self._id, held.operator, origin.who)
        return held

    def release(self, origin: Origin) -> Control | None:
        """Anyone may (lease.py rule 4); releasing a free lease changes nothing (None)."""
        with self._owner:  # rule 1
            ended = self._ended(self._now())  # rule 2: over by the clock (a review: the
            held = self._lease.release(self._now())  # release found it free, and the status
            if held is not None:  # named its holder for good)
                self._changed(None)
        self._said_ended(ended)
        self._arm()
        if held is not None:
            log.info("%s: %s released the control lease", self._id, origin.who)
        return held

    def _ended(self, now: float) -> Control | None:
        """Rule 2, in an owner's step: the lease the wall clock ended, ended (to the status
        and the state file), once; ``_said_ended`` audits it after the step."""
        ended = self._lease.expired(now)
        if ended is not None:
            self._changed(None)
        return ended

    def _said_ended(self, ended: Control | None) -> None:
        if ended is None:
            return
        log.info("%s: the control lease of %s has ended", self._id, ended.operator)
        self.audit(Origin(Source.LEASE, ended.operator), "control expired", EXECUTED)

    def _changed(self, held: Control | None) -> None:
        """In the owner's step (rule 1): to the status, and in line for the state file."""
        # woken after the step (kept.py rule 5); the lease's clock with it (rule 5)
        self._mailbox.put_control(held, wake=False, now_unix=self._now())
        with self._unsaved_guard:  # one save in line, of the newest (as kept.py rule 7)
            queued, self._unsaved = bool(self._unsaved), [held]
        if not queued:
            self._store.queue(self._save)

    def _save(self) -> None:
        with self._unsaved_guard:
            unsaved, self._unsaved = self._unsaved, []
        if unsaved and not self._store.set_lease(self._id, unsaved[0]):
            self._report(
                ErrorKind.STATE,
                "the control lease is in effect but could not be saved: it will not survive a "
                "restart (state file not writable)",
                "control",
            )

    # -- its end (rule 2) --------------------------------------------------------------------
    def _arm(self) -> None:
        """After a step: the one timer for the end of the lease as it is now (none if free)."""
        with self._timer_lock:
            if self._timer is not None:
                self._timer.cancel()
                self._timer = None
            now = self._now()
            held = self._lease.holder(now)
            if held is None or self._stopped:
                return
            wait_s = min(LEASE_CHECK_S, max(0.0, held.until_unix - now))  # (rule 2)
            self._timer = self._start_timer(wait_s, self._expire)

    def _expire(self) -> None:
        with self._owner:  # rule 1: an end is a change like a release
            ended = self._ended(self._now())
        self._arm()  # early (rule 2): a new timer for the rest; ended: none
        self._said_ended(ended)

    # -- the trail (rule 3) ------------------------------------------------------------------
    def audit(
        self,
        origin: Origin,
        command: str,
        result: str,
        *,
        halt: bool = False,
        same_again: bool = False,
        unchanged: bool = False,
        read_as: str = "",
    ) -> None:
        """``halt``: an executed stop (audit.py rule 6); ``same_again``: a command that changes
        nothing when sent again (rule 9); ``unchanged``: a halt that changed nothing (rule 10);
        ``read_as``: the command as read, what rules 9 and 10 fold by (empty: ``command``)."""
        if self._on_audit is None:
            return
        try:
            bearing = self._bearing()
            event = AuditEvent(
                self._wall(),
                self._id,
                origin,
                command,
                result,
                bearing,
                halt,
                same_again=same_again,
                unchanged=unchanged,
                read_as=read_as,
            )
            self._on_audit(event)
        except Exception:
            log.exception("%s: audit listener failed", self._id)
