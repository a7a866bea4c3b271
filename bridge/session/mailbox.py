"""Pending commands for one rotator: the only hand-off point into the lines thread.

Rules:
1. A stop pre-empts everything: it is taken first and drops any target that came before it,
   and any judged before it that comes after it (rule 10).
2. A newer target replaces an older pending one (a dragged slider sends dozens; the last counts);
   an axis the newer one leaves out is kept from the older (model.combine: an azimuth, then an
   elevation alone, from one sender, is one target; a park takes nothing: targets.py rule 9).
   A track command (start or off) replaces a target put before it; a target put after it is
   kept, and the session lets it end the tracking (the later command wins either way).
3. Options and the lock are settings: the latest value per name wins, order between names kept.
4. ``put`` never blocks on the worker; it wakes the worker through a pipe the lines thread polls,
   so a command reaches the wire while the worker waits for serial bytes, never after a timeout.
   ``take`` drains the pipe *before* it takes the batch: a ``put`` that lands between the two
   then leaves its wake byte in the pipe (one spurious wake-up at worst). Draining after taking
   would swallow the byte of a command that is not in the batch taken, and that command (a stop)
   would wait for the next serial byte or timeout.
5. One wake byte per batch: a ``put`` writes one only if none is owed since the last ``take``
   (a flood of targets cost a system call and a lines-thread round per message, half the
   bridge's CPU at 10,000 a second). ``take`` clears the debt when it swaps the batch, under
   the lock: a ``put`` after that writes a byte again; one before it is in the batch taken.
   A put in a rotator's owner step (runtime/kept.py rule 5) passes ``wake=False`` and the step
   calls ``wake_once`` when it has let go: no system call while the owner's lock is held (the
   write gives the GIL away, and a lock ON waiting for the step would wait for it too).
6. A hold (interfaces/mqtt/lastword.py rule 2) comes with the stop or lock ON that starts it, in one
   put; a release ends the holds up to its marker. A release that clears (the connection that
   would have caught up was lost) ends every hold and drops a target or track put before it;
   a target or hold put after it is newer and stays (the session applies it first).
   The stop express's hold (interfaces/mqtt/express.py rule 8) has numbers of its own:
   ``put_express_hold`` and ``put_express_release``; nothing clears it but its own release,
   which drops what waited if it came by the express's loss (stops.py rule 5).
7. A lock ON leaves its stop in the batch (``lock_on``) even when a lock OFF follows it in the
   same batch: the lock ON always stops the rotor.
8. ``close`` and a wake-up are one step under their own lock: a put racing a shutdown never
   writes into a descriptor number the system has handed to someone else meanwhile.
9. A follow command (on or off) is a command like a track command (rule 2): on, it replaces a
   target or track command put before it, and one put after it replaces it; a stop or lock ON
   drops it. What WSJT-X says (``put_heard``) is no command: each program's newest status is
   kept (HEARD_KEPT programs at most, in the order put), never dropped by anything (follow.py
   rule 4 decides whether it is fresh): a second program's status put after the followed
   one's "transmitting" in the same batch replaced it, and the beam turned on through the
   transmission (follow.py rule 3); nor is a wind reading
   (``put_wind``: the highest since the last take, so that no gust is lost; one the broker
   replayed apart, wind.py rule 6). A stop or lock ON keeps its place among the live
   readings: those put before it are kept apart (``wind_halted``), and the session applies
   them before the halt and the rest after it, so a STOP put just before a storm's first
   reading is no stop in that storm (wind.py rule 3; attack 14: the two taken in one batch,
   the reading applied first, and the STOP cancelled the storm's park for the whole storm).
   The live readings put are counted too (``winds``, carried by each batch as its ``epoch``
   is): a lock ON judged while a reading the status does not show yet is on its way may stop
   that reading's park (``wind_unseen``; runtime/audit.py rule 10: a review, such a lock ON
   was called one that changed nothing and folded, though it gave the storm's park up).
10. The halt count (``epoch``): every stop and lock ON put adds one to it, under the lock the
    put takes anyway (nothing else: a stop waits for nothing new). A motion command (a target,
    a track or follow start) is put with the count its judge read before judging it
    (runtime/rotator.py); one whose count is older than the mailbox's was judged before a stop
    or lock ON that is in already, on another thread, and is dropped under the same lock (the
    put returns False; the judge reports the refusal). So a motion command judged before a stop
    or lock ON never runs after it, whichever front end's thread brought which, and a lock OFF
    that follows in the same batch lets no such target through. A command put without a count
    (tracking or following OFF, the session's own) is never dropped by it. A batch taken
    carries the count (``Batch.epoch``): the session's status after applying it shows every
    stop and lock ON up to it (session.py ``halts_applied``), so a judge that reads a larger
    count knows the status it sees predates a halt (a nudge is then from the bearing, not from
    the target the stop dropped: runtime/rotator.py). Right before a stop or lock ON is
    counted, ``halt_watchers`` are told (core/haltwatch.py), on the putting thread and outside
    the lock: the TCP front ends look at what each connection has sent by then
    (interfaces/tcplines.py rule 9).
10a. A place in the order of commands (``ticket``): a front end that asks a motion command
    now and puts it a while later (the DX cluster's call, looked up on a thread of its own)
    takes a ticket when it is asked, and puts it with it; every motion command, stop or lock
    ON put without one takes the next at its put, and so does a lock OFF (a command asked while
    the lock was ON is not carried out after it; one asked while another held the control
    lease is refused when asked: interfaces/dxcluster/client.py rule 4; a target put before
    a claim and not sent yet is the session's to drop: session.py rule 23). One put with a ticket
    older than the newest put is dropped (the put returns False): a target sent after the call
    was asked is the later word, however long the look-up took (an attack pass: the call,
    looked up after a plain target of 200 was put, turned the rotor back to the call's
    bearing). A lock OFF is no motion command: a nudge after it still sees a target put before
    it as on its way (``motion_unseen``; a review). A batch taken
    carries the newest place put (``Batch.newest``), as it carries the halt count: a judge
    that reads a newer one in the mailbox knows the status it sees predates a motion command
    (a nudge is then refused: runtime/rotator.py). The places go on across runs of the
    bridge (``places_after``: from the block the state file reserved, runtime/kept.py rule 12),
    so a remote can order a place of an earlier run against one of this (review 86).
10b. A turn of the bridge's own (auto-park's park, the storm's: session.py ``Order``) takes a
    ticket when it begins (``own_place``), after every command asked before it, and that one
    turn named again (``turn``, the session's name for it: the same storm's park, begun again
    by a controller back from its offline, wind.py rule 7, or begun by a composite's other
    box, runtime/composite.py rule 10) keeps that place while no motion command and no stop
    or lock ON was put after it. Each begin drawing its own, one storm's park showed two
    places with no command between (review 91: a composite's elevation box plugged back
    mid-storm), and a remote's STOP asked against the park read the second as a newer turn
    (interfaces/mqtt/remote.py rule 10). A turn named otherwise (another storm's park, an
    auto-park's of another moment), or the same one after a motion command or a halt put
    since, is a new turn and takes the next ticket: a park begun after a STOP is never
    stopped by it, and a turn begun after the park never looks older than it. The storm's
    park a start sends again (a storm kept across a restart, its park not stopped nor seen
    reached: wind.py rule 7) is that same turn: it keeps the place it took in the run before
    (``OwnTurn.kept``, the place the state file kept with the storm: runtime/kept.py rule 4)
    while no motion command, stop or lock ON was put in this run (each of those takes a
    place past the file's ``since``, so past it). Drawing this run's first ticket, it showed
    a place past every place the run before showed for it, no command between, and a
    remote's STOP held against the park let it go (review 96: a power blip cuts the link
    and restarts the bridge). A park the run before never sent (the controller silent, the
    lock ON) has no place kept and takes the next ticket: the turn the file kept then is an
    older one, and a STOP held against that must not stop the park. What came in the run
    before after the park is in the file already: a STOP or lock ON halted the park (it is
    not sent again: wind.py rule 3), and a motion command was refused in the storm, so a
    STOP held since was asked against the park, and stops it, as rule 3 has it.
11. ``halts()``: the stops and lock ONs put in any mailbox so far, counted once the batch holds
    them. The lines thread reads it to know whether one came while it served others (lines.py
    rule 5) without asking every mailbox after every rotator it serves. Each put sets it to a
    number of its own from one counter (``next`` on an ``itertools.count`` is one step under
    the interpreter's lock), so puts into two mailboxes at once can never both write the number
    a reader has already seen: any put after a read makes the next read differ.
12. A feature's own command (``put_feature``, core/model.py ``FeatureCommand``) is kept in a
    list in the order put. One that moves is a motion command: it is put with its halt count
    (rule 10), replaces a target put before it, is replaced by a track or follow start put
    after it (the session applies those before it), and a stop, a lock ON or a clearing
    release drops it as it drops a target. One that does not move is dropped by nothing; but
    a stop, a lock ON or OFF and a clearing release put after it in the same batch leave a
    mark behind it in that list (``PartsEnd``), where the session ends the parts' motion again
    (session/parts.py rule 7): a part it turned on never turns the rotor after that stop, nor
    once the lock it was given under is released, nor on a word the clearing dropped, though
    the two came in one batch (the lines thread busy); one put after the mark is the later
    word and stands.
13. The bridge's end (``put_ending``, runtime/rotator.py ``leave``; app.py rule 6) is a
    setting that is never taken back: the batch says it once, and the session keeps it.
14. The lease's generation (``lease``): every change of the control lease put
    (``put_control``: a claim, a renewal, a release, its end) adds one to it and keeps the
    lease as it is now, under the lock the put takes anyway. A target, a track or follow
    start, and a feature's own command (rule 12, moving or not: the lease refuses both) are
    put with the generation their judge read before judging them (runtime/rotator.py); one
    whose generation is older was judged before a change of the lease that is in already,
    and is judged again here, under the same lock, against the lease now: one whose sender
    is not the holder is refused (``LeaseChanged``, naming the lease; nothing is put). So a
    target judged before a claim never turns the rotor for another operator after it: put
    before the claim, it is the session's to drop (session.py rule 23); put after it, it is
    refused here (a review: G4XYZ's target judged allowed, DL1ABC's claim put and taken
    meanwhile, and the target, put in a batch of its own, turned the rotor for someone the
    lease refuses). Nor does a start judged so (tracking's and following's bearings are the
    bridge's own, never judged by the lease again: a review, G4XYZ's track sun put just
    after DL1ABC's claim, and the rotor followed the sun under DL1ABC's lease); put before
    the claim, a start is the session's to refuse, as a target is its to drop (session.py
    rule 23). The holder's own, and anyone's once the lease is free, go on; an OFF is put
    with no generation and never refused.
"""

from __future__ import annotations

import itertools
import os
import threading
from dataclasses import dataclass, field
from typing import Literal, NamedTuple

from bridge.core.haltwatch import HaltWatchers
from bridge.core.model import (
    Control,
    FeatureCommand,
    SetOption,
    Source,
    Stop,
    Target,
    combine,
    same_operator,
    sender,
)
from bridge.session.follow import Follow, Heard
from bridge.session.tracking import Track


class OwnTurn(NamedTuple):
    """What names a turn of the bridge's own as it begins (session.py ``_own_turn``; rule
    10b places it): its source, and ``of``: the storm's park the storm's number (wind.py
    ``storms``; a rotator of two boxes: the newest storm either box saw begin,
    runtime/composite.py rule 10), auto-park's park the moment it began; ``kept``: the place
    an earlier run's park of this same storm took, kept in the state file (a storm kept
    across a restart, its park sent again by the start: wind.py rule 7, runtime/kept.py rule
    4; 0: none)."""

    source: Source
    of: float
    kept: int = 0


HEARD_KEPT = 8  # rule 9: the programs whose newest status a batch keeps (a flood of names: 8)

Halt = Literal["stop", "lock", "unlock", "clear"]  # what a PartsEnd marks (rule 12)


@dataclass(frozen=True)
class PartsEnd:
    """Rule 12: where, among the feature commands, a stop (``stop``), a lock ON (``lock``),
    a lock OFF (``unlock``) or a clearing release (``clear``) was put."""

    what: Halt


@dataclass
class Batch:
    """Everything taken from the mailbox in one go, in the order the worker must apply it."""

    stop: Stop | None = None
    target: Target | None = None
    options: list[SetOption] = field(default_factory=list)
    lock: bool | None = None
    lock_saved: bool | None = None  # the lock the state file now holds (runtime/kept.py rule 2)
    lock_unknown: bool | None = None  # runtime/kept.py rule 10: whether the lock is not known
    notes: list[str] = field(default_factory=list)
    track: Track | None = None  # applied after the stop and before the target (tracking.py)
    lock_on: bool = False  # rule 7: a lock ON was put, whatever ``lock`` ends as
    hold: int | None = None  # rule 6: the newest marker a hold waits for
    release: int | None = None  # rule 6: holds up to this marker end
    release_clear: bool = False
    express_hold: int | None = None  # rule 6: the newest sync word the express's hold waits for
    express_release: int | None = None  # ... and the one its answer reached
    express_lost: bool = False  # ... given by its connection's end, not its word (stops.py rule 5)
    lost_target: Target | None = None  # ... and the target that waited for it in this batch
    follow: Follow | None = None  # rule 9: applied after the track command
    heard: tuple[Heard, ...] = ()  # rule 9: each program's newest status, in the order put
    wind: float | None = None  # rule 9: the newest wind reading (km/h)
    wind_halted: float | None = None  # rule 9: ... the highest put before the last stop or
    # lock ON of the batch (the session applies it before the halt, ``wind`` after)
    wind_replayed: float | None = None  # rule 9: ... and one the broker replayed
    health_reset: bool = False  # a new health baseline (health.py)
    ending: bool = False  # rule 13: the bridge's end began (session.py rule 21)
    activity: bool = False  # a command to a composite's other box (runtime/composite.py rule 7)
    ends: str | None = None  # a target to a composite's other box: what it ends here too, as
    # that target would (runtime/composite.py rule 2: tracking, following, a part's motion)
    offline: str | None = None  # a composite's other box does not answer (why): no target is
    # taken here, and one waiting is dropped (runtime/composite.py rule 8)
    epoch: int = 0  # rule 10: the halt count when taken (every stop and lock ON up to it is
    # in this batch or an earlier one)
    newest: int = 0  # rule 10a: the newest place put when taken (likewise)
    winds: int = 0  # rule 9: the live wind readings put when taken (likewise)
    # rule 12, in the order put, with where a stop, lock or clearing came among them
    feature_commands: list[FeatureCommand | PartsEnd] = field(default_factory=list)

    control: Control | None = None  # the control lease as the judge has it now...
    control_set: bool = False  # ...when it changed (runtime/lease.py)
    control_unix: float | None = None  # ...at this time on the lease's clock (operators.py 5)

    def __bool__(self) -> bool:
        settings = (
            self.options
            or self.lock is not None
            or self.lock_saved is not None
            or self.lock_unknown is not None
            or self.notes
            or self.health_reset
            or self.control_set
            or self.ending
        )
        fence = self.hold is not None or self.release is not None
        fence = fence or self.express_hold is not None or self.express_release is not None
        feeds = self.follow is not None or bool(self.heard)
        feeds = feeds or self.wind is not None or self.wind_replayed is not None
        feeds = feeds or self.wind_halted is not None
        feeds = feeds or bool(self.feature_commands) or self.activity or self.ends is not None
        feeds = feeds or self.offline is not None
        return bool(self.stop or self.target or settings or self.track or fence or feeds)

    def drop_moving(self) -> None:
        """Rule 12: a stop, a lock ON or a clearing release drops the features' motion."""
        kept = [c for c in self.feature_commands if isinstance(c, PartsEnd) or not c.moves]
        self.feature_commands = kept

    def clear_waiting(self) -> None:
        """Rule 6: a clearing release (the lane's, or the stop express's lost answer) drops the
        motion put before it: the target, a track or follow command, the features' moves."""
        self.target = None
        self.track = None
        self.follow = None
        if self.feature_commands:  # rule 12
            self.drop_moving()
            self.mark("clear")

    def halt_wind(self) -> None:
        """Rule 9: a stop or lock ON is put: the live readings put so far came before it."""
        if self.wind is not None:
            held = self.wind_halted
            self.wind_halted = self.wind if held is None else max(held, self.wind)
            self.wind = None

    def mark(self, what: Halt) -> None:
        """Rule 12: a stop, lock or clearing came after the feature commands put so far."""
        if self.feature_commands and self.feature_commands[-1] != PartsEnd(what):
            self.feature_commands.append(PartsEnd(what))


class LeaseChanged(Exception):
    """Rule 14: a target judged before a change of the lease that its sender may not turn the
    rotor under (``control``: the lease now, its holder another operator)."""

    def __init__(self, control: Control) -> None:
        super().__init__(control.operator)
        self.control = control


def _barred(command: Target | Track | Follow | FeatureCommand, control: Control) -> bool:
    """Rule 14: the lease ``control``'s holder did not send ``command`` (the judge's test,
    runtime/lease.py rule 5, on the sender's name as the session reads it)."""
    return not same_operator(control.operator, sender(command.origin, command.source))


class _Halts:
    count = 0  # rule 11
    numbers = itertools.count(1)


def halts() -> int:
    """Rule 11: a number that changes whenever a stop or lock ON is put in any mailbox."""
    return _Halts.count


class Mailbox:
    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._batch = Batch()
        self._option_order: dict[str, SetOption] = {}
        self._rfd, self._wfd = os.pipe()
        self._woken = False  # rule 5: a wake byte is owed for the batch being filled
        self._fd_lock = threading.Lock()  # rule 8
        self._epoch = 0  # rule 10: stops and lock ONs put so far
        self._tickets = itertools.count(1)  # rule 10a
        self._newest = 0  # rule 10a: the ticket of the newest motion command or halt put
        self._halt_placed = 0  # rule 10a: ... and of the newest halt
        self._motion_placed = 0  # rule 10a: ... and of the newest motion command
        self._own: tuple[OwnTurn, int] | None = None  # rule 10b: the own turn's name, place
        self._winds = 0  # rule 9: live wind readings put so far
        self._lease = 0  # rule 14: changes of the control lease put so far
        self._control: Control | None = None  # rule 14: ... and the lease as the last one put
        self.halt_watchers = HaltWatchers()  # rule 10: told before each halt is counted
        os.set_blocking(self._rfd, False)
        os.set_blocking(self._wfd, False)

    def fileno(self) -> int:
        return self._rfd

    @property
    def urgent(self) -> bool:
        """A stop or lock ON waits (read without the lock: a hint for the lines thread)."""
        batch = self._batch
        return batch.stop is not None or batch.lock_on

    @property
    def epoch(self) -> int:
        """Rule 10: the halt count, read before judging a motion command (one attribute read:
        a count read late is only newer, never one that lets a stale command in)."""
        return self._epoch

    @property
    def lease(self) -> int:
        """Rule 14: the lease's generation, read before judging a target (one attribute read,
        as ``epoch``)."""
        return self._lease

    def places_after(self, since: int) -> None:
        """Rule 10a: the places counted on after ``since`` (the places earlier runs reserved:
        runtime/kept.py rule 12), before any is taken."""
        self._tickets = itertools.count(since + 1)

    def ticket(self) -> int:
        """Rule 10a: a place in the order of commands, for one asked now and put later (``next``
        on an ``itertools.count`` is one step under the interpreter's lock)."""
        return next(self._tickets)

    def own_place(self, turn: OwnTurn) -> int:
        """Rule 10b: the place of the bridge's own turn named ``turn`` as it begins: the one it
        took, while no motion command or halt was put after it; else the next ticket. (Only
        the lines thread, which serves the rotator, asks.)"""
        with self._lock:
            newer = max(self._motion_placed, self._halt_placed)
        own = self._own
        if own is not None and own[0] == turn and newer < own[1]:
            return own[1]
        if own is None and turn.kept and newer < turn.kept:  # (a storm's park a restart
            self._own = (turn, turn.kept)  # sends again, at the place it took: review 96)
            return turn.kept
        place = self.ticket()
        self._own = (turn, place)
        return place

    def _placed(self, ticket: int | None) -> int:
        """Rule 10a (under the lock): 0 if ``ticket`` is older than the newest put; else the
        newest is this one (a command put without a ticket takes the next), returned."""
        if ticket is None:
            self._newest = next(self._tickets)
        elif ticket < self._newest:
            return 0
        else:
            self._newest = ticket
        return self._newest

    def motion_unseen(self, applied: int) -> bool:
        """Rule 10a: whether a motion command was put after the place ``applied`` (the newest
        a status shows) and after the newest halt: a target that status does not show is on
        its way."""
        with self._lock:
            # (a lock OFF or a change of the lease takes a place but is not motion, and
            # must not hide a motion command put before it: a review)
            placed = self._motion_placed
            return placed > applied and placed > self._halt_placed

    def wind_unseen(self, applied: int) -> bool:
        """Rule 9: whether a live wind reading was put after the ``applied`` one (the count of
        the batches a status shows: ``winds``): a storm that status does not show may be on
        its way."""
        with self._lock:
            return self._winds > applied

    def put(
        self,
        command: Target | Stop | SetOption,
        *,
        hold: int | None = None,
        wake: bool = True,
        epoch: int | None = None,
        ticket: int | None = None,
        lease: int | None = None,
    ) -> bool:
        """``hold``: a stop that holds the rotator until that marker (rule 6); ``wake``: rule 5;
        ``epoch``: the halt count a target was judged at (rule 10); ``ticket``: its place in the
        order of commands, taken when it was asked (rule 10a); ``lease``: the lease's
        generation it was judged at (rule 14). False: dropped (rules 10, 10a); LeaseChanged:
        refused (rule 14)."""
        if isinstance(command, Stop):
            self.halt_watchers()  # rule 10: before it is counted
        with self._lock:
            if isinstance(command, Stop):
                self._halt_placed = self._placed(None)  # rule 10a
                self._epoch += 1  # rule 10
                self._batch.stop = command
                self._batch.halt_wind()  # rule 9: the readings put before it
                self._batch.target = None
                self._batch.track = None  # the stop ends tracking anyway
                self._batch.follow = None  # and following (rule 9)
                if self._batch.feature_commands:  # and a feature's motion (rule 12)
                    self._batch.drop_moving()
                    self._batch.mark("stop")
                self._hold(hold)
                _Halts.count = next(_Halts.numbers)  # rule 11: once the batch holds it
            elif isinstance(command, Target):
                if self._stale(epoch):
                    return False
                self._judge_lease(command, lease)  # rule 14 (before it takes a place)
                if not self._placed(ticket):
                    return False
                self._motion_placed = self._newest  # rule 10a
                self._batch.target = combine(command, self._batch.target)
            else:
                self._option_order.pop(command.name, None)
                self._option_order[command.name] = command
        if wake:
            self._wake_once()
        return True

    def _stale(self, epoch: int | None) -> bool:
        """Rule 10 (under the lock): judged before a stop or lock ON that is in already."""
        return epoch is not None and epoch != self._epoch

    def _judge_lease(
        self, command: Target | Track | Follow | FeatureCommand, lease: int | None
    ) -> None:
        """Rule 14 (under the lock): LeaseChanged if ``command``, judged at the lease's
        generation ``lease``, was judged before a change that now bars its sender."""
        held = self._control if lease not in (None, self._lease) else None
        if held is not None and _barred(command, held):
            raise LeaseChanged(held)

    def put_lock(self, locked: bool, *, hold: int | None = None, wake: bool = True) -> None:
        if locked:
            self.halt_watchers()  # rule 10: before it is counted
        with self._lock:
            self._batch.lock = locked
            self._batch.lock_unknown = False  # (runtime/kept.py rule 10: a word says it)
            # rule 10a: a lock OFF takes a place too, so a motion command asked before it (while
            # the lock was ON) and put after it is not carried out (an attack pass: a DX call
            # asked while locked, looked up after the OFF, turned the rotor; a plain target at
            # its place was refused by the lock). Not motion: a nudge is not refused by it.
            placed = self._placed(None)
            if locked:
                self._halt_placed = placed
            if not locked and self._batch.feature_commands:  # rule 12
                self._batch.mark("unlock")
            if not locked:  # runtime/kept.py rule 2: an ON after it is said once it is saved,
                self._batch.lock_saved = False  # not by a save said before this OFF (a review)
            if locked:
                self._epoch += 1  # rule 10
                self._batch.lock_on = True  # rule 7
                self._batch.halt_wind()  # rule 9: the readings put before it
                self._batch.target = None
                self._batch.track = None
                self._batch.follow = None
                if self._batch.feature_commands:  # rule 12
                    self._batch.drop_moving()
                    self._batch.mark("lock")
                self._hold(hold)
                _Halts.count = next(_Halts.numbers)  # rule 11: once the batch holds it
        if wake:  # rule 5
            self._wake_once()

    def put_lock_unknown(self, unknown: bool, *, wake: bool = True) -> None:
        """runtime/kept.py rule 10: whether the status says the lock is not known yet."""
        with self._lock:
            self._batch.lock_unknown = unknown
        if wake:
            self._wake_once()

    def put_lock_saved(self, locked: bool, *, wake: bool = True) -> None:
        """The state writer has saved the lock as ``locked`` (or failed to, and said so): the
        status shows it from now on (runtime/kept.py rule 2)."""
        with self._lock:
            self._batch.lock_saved = locked
        if wake:
            self._wake_once()

    def put_release(self, marker: int, *, clear: bool = False) -> None:
        """Rule 6: the holds up to ``marker`` end; ``clear``: what waits before it is dropped."""
        with self._lock:
            batch = self._batch
            batch.release = marker if batch.release is None else max(batch.release, marker)
            if clear:
                batch.release_clear = True
                batch.clear_waiting()
                batch.hold = None  # ended with the rest: a hold put after it is newer
        self._wake_once()

    def put_express_hold(self, n: int) -> None:
        """Rule 6: no target goes out until ``put_express_release`` reaches ``n`` (put before
        the stop it comes with; no wake-up: the stop's put wakes the worker)."""
        with self._lock:
            held = self._batch.express_hold
            self._batch.express_hold = n if held is None else max(held, n)

    def put_express_release(self, n: int, lost: bool = False) -> None:
        """Rule 6: the stop express's holds up to ``n`` end (``lost``: its connection ended,
        or it did, before its word came back)."""
        with self._lock:
            batch = self._batch
            done = batch.express_release
            batch.express_release = n if done is None else max(done, n)
            if lost:  # what waited in this batch is dropped too, as a clearing release drops it
                batch.express_lost = True  # (a review: only the session's waiting one was)
                batch.lost_target = batch.target or batch.lost_target
                batch.clear_waiting()
        self._wake_once()

    def _hold(self, marker: int | None) -> None:
        if marker is not None:
            held = self._batch.hold
            self._batch.hold = marker if held is None else max(held, marker)

    def put_track(
        self, track: Track, *, epoch: int | None = None, lease: int | None = None
    ) -> bool:
        """Start or end tracking; it replaces a target put before it (the later command wins).
        ``epoch``: a start's halt count (rule 10); ``lease``: its lease's generation (rule
        14). False: dropped; LeaseChanged: refused."""
        with self._lock:
            if self._stale(epoch):
                return False
            self._judge_lease(track, lease)  # rule 14
            if (track.body or track.lookup) is not None:
                self._motion_placed = self._placed(None)  # rule 10a
            self._batch.track = track
            self._batch.target = None
            self._batch.follow = None  # rule 9: the later command wins
            if (track.body or track.lookup) is not None and self._batch.feature_commands:
                self._batch.drop_moving()  # rule 12: and over a feature's motion put before
        self._wake_once()
        return True

    def put_follow(
        self, follow: Follow, *, epoch: int | None = None, lease: int | None = None
    ) -> bool:
        """Rule 9: start or end following; it replaces a target or track put before it.
        ``epoch``: a start's halt count (rule 10); ``lease``: its lease's generation (rule
        14). False: dropped; LeaseChanged: refused."""
        with self._lock:
            if self._stale(epoch):
                return False
            self._judge_lease(follow, lease)  # rule 14
            self._batch.follow = follow
            if follow.on:  # following off ends nothing else
                self._motion_placed = self._placed(None)  # rule 10a
                self._batch.target = None
                self._batch.track = None
                if self._batch.feature_commands:
                    self._batch.drop_moving()  # rule 12
        self._wake_once()
        return True

    def put_feature(
        self, command: FeatureCommand, *, epoch: int | None = None, lease: int | None = None
    ) -> bool:
        """Rule 12: a feature's own command, for its part. ``epoch``: the halt count one that
        moves was judged at (rule 10); ``lease``: the lease's generation it was judged at,
        moving or not (rule 14). False: dropped; LeaseChanged: refused."""
        with self._lock:
            if self._stale(epoch):
                return False
            self._judge_lease(command, lease)  # rule 14
            if command.moves:
                self._motion_placed = self._placed(None)  # rule 10a
                self._batch.target = None  # rule 12: the later command wins
            self._batch.feature_commands.append(command)
        self._wake_once()
        return True

    def put_heard(self, heard: Heard) -> None:
        """Rule 9: what WSJT-X said; each program's newest is kept."""
        with self._lock:
            others = [h for h in self._batch.heard if h.instance != heard.instance]
            self._batch.heard = (*others[max(0, len(others) - HEARD_KEPT + 1) :], heard)
        self._wake_once()

    def put_note(self, message: str) -> None:
        """A refusal decided outside the worker, so that the status shows it as the last error
        (the newest alone is kept: it is the one the status shows, and a flood of refusals
        keeps no list)."""
        with self._lock:
            self._batch.notes = [message]
        self._wake_once()

    def put_wind(self, speed_kmh: float, replayed: bool = False) -> None:
        """Rule 9: a wind reading (``replayed`` by the broker: wind.py rule 6)."""
        with self._lock:
            b = self._batch  # the highest of a batch: no gust is lost (wind.py)
            held = b.wind_replayed if replayed else b.wind
            speed_kmh = speed_kmh if held is None else max(held, speed_kmh)
            if replayed:
                b.wind_replayed = speed_kmh
            else:
                b.wind = speed_kmh
                self._winds += 1
        self._wake_once()

    def put_health_reset(self) -> None:
        """Start a new health baseline (a setting: it moves nothing)."""
        with self._lock:
            self._batch.health_reset = True
        self._wake_once()

    def put_ending(self) -> None:
        """Rule 13: the bridge's end began (a setting: it moves nothing)."""
        with self._lock:
            self._batch.ending = True
        self._wake_once()

    def put_control(
        self, control: Control | None, *, wake: bool = True, now_unix: float | None = None
    ) -> None:
        """The control lease changed (the status shows its holder); ``wake``: rule 5. A target
        judged before it is judged again at its put (rule 14). ``now_unix``: the lease's clock
        then (session.py rule 23 counts its minutes on it)."""
        with self._lock:
            self._batch.control, self._batch.control_set = control, True
            self._batch.control_unix = now_unix
            self._lease += 1  # rule 14
            self._control = control
        if wake:
            self._wake_once()

    def take(self) -> Batch:
        try:  # first the wake bytes, then the batch (rule 4)
            while os.read(self._rfd, 4096):
                pass
        except BlockingIOError:
            pass
        with self._lock:
            batch, self._batch = self._batch, Batch()
            batch.epoch = self._epoch  # rule 10
            batch.newest = self._newest  # rule 10a
            batch.winds = self._winds  # rule 9
            self._woken = False  # rule 5
            batch.options = list(self._option_order.values())
            self._option_order = {}
        return batch

    def wake(self) -> None:
        """Wake the worker without a command (shutdown)."""
        self._wake()

    def wake_once(self) -> None:
        """Rule 5: after puts made with ``wake=False``."""
        self._wake_once()

    def _wake_once(self) -> None:
        """Rule 5: after a put (outside the lock: the write is a system call)."""
        with self._lock:
            owed, self._woken = self._woken, True
        if not owed:
            self._wake()

    def _wake(self) -> None:
        with self._fd_lock:  # rule 8
            if self._wfd < 0:
                return  # closed: the rotator has stopped
            try:
                os.write(self._wfd, b"\0")
            except BlockingIOError:
                pass  # the pipe is full: the worker is going to wake up anyway

    def close(self) -> None:
        """Once nothing waits on it any more; a second close does nothing."""
        with self._fd_lock:  # rule 8
            fds, self._rfd, self._wfd = (self._rfd, self._wfd), -1, -1
            for fd in fds:
                if fd >= 0:
                    try:
                        os.close(fd)
                    except OSError:
                        pass
