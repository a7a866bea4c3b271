"""What a rotator keeps in the state file of its own settings: the options its model has, the
safety lock, and a storm it is parked for; and the one owner of its safety state (``Owner``).
Rotator (rotator.py) owns one of each; the state file is written on its writer thread
(state_store.py rule 5), never on a front end's nor the lines thread's.

Rules:
1. An option remembered for this id that this model does not have (the id may have been
   another model's), or a value its declaration refuses, is logged and left out.
2. ``locked`` is the lock: the judge asks it, and nothing else keeps a copy that could differ
   (the session's comes from the mailbox, in the same step). Each lock word queues a save of
   the value it set, in the owner's step (rule 5): saves run in the order of the words, so the
   last word is the last written, whatever order the front ends asked in; words that come
   while a save waits for the writer join it, which writes the last of them (rule 7). A
   word is in effect at once (its stop, the judge's refusals). The status (``R/lock/state``,
   ``R/status``) shows the lock ON only while it is in effect and the writer has saved it,
   so a crash after the bridge said lock ON never restarts it unlocked (an attack pass: the
   bridge killed the moment ``R/lock/state`` said ON came back OFF in 4 of 6 rounds, and a
   target turned the rotor), and a lock OFF at once, so the status never says locked while
   a target turns the rotor (a review); a host that dies before that OFF is saved restarts
   locked, the safe side. A save that fails is said as rule 3 has it, and the lock it could
   not save is shown (it is in effect). A save says ON only if no lock word came after it
   read the lock (under the guard the words take), and a lock OFF takes back, in the
   mailbox, an ON said before it (a review: ON, OFF, ON said the second ON at once, from the
   first one's save, while the writer wrote the OFF: the file held OFF under a status ON).
3. A save that fails is reported (kind ``state``): the setting is in effect but will not
   survive a restart.
4. A storm outlives a restart (wind.py rule 2: only readings end it): ``seen_wind`` looks at
   every status on the lines thread and hands a storm begun or ended, and its park stopped or
   seen reached, to the writer; the next start begins in the storm (motion refused) until
   readings end it, and parks again unless its park was stopped or seen reached. One whose
   park a STOP or lock ON stopped (wind.py rule 3) is not parked again: the operator's last
   word outlives the restart, as the lock does. Nor is one whose park the rotor was seen to
   reach (wind.py rule 7, the status's ``arrived``): someone may have turned it by hand at the
   controller since, and it is not turned back by itself; one whose park was not seen reached
   (the bridge died mid-park; a DCU-1, which is never seen there) parks again. A storm known
   only from a replayed reading (wind.py rule 6) is not kept: it parked nothing, and the
   broker replays it to the next start. The place in the order of commands the storm's park
   took (rule 12; the turn a status in the storm shows first past the one shown before it:
   motion is refused in the storm, so a turn begun in it is its park) is kept with the storm
   (``storm_place``), so the park the next start sends again keeps it (session/mailbox.py
   rule 10b, review 96: it took the new run's first place, and a remote's STOP held against
   the park let it go); a park never sent has none kept, and takes a place of the new run
   (the turn kept then is an older one's). The wind park
   has one owner, the session on the lines thread: it alone decides a storm, the judge reads
   the session's status, and the save is queued on that same thread in the order the storms
   came; the lines thread takes no owner's lock (docs/architecture.md rule 14).
5. ``Owner`` is one rotator's safety step (docs/architecture.md rule 14): a lock word, a
   claim, a release or the end of the control lease, and an option, are decided, put in the
   mailbox and their save queued under its one lock, from every interface's thread, so that
   the judge, the session (and so the retained state) and the state file cannot disagree. The
   step is short: no I/O, no thread started, nothing that waits (the save is queued; the lines
   thread and the writer are woken once the step has let go, and once every core/afterlock.py
   ``Deferring`` lock around it has let go too: halts.py takes its steps under one, so nothing
   under that lock writes a byte or starts a thread either); the lines thread never takes it,
   and a stop never waits for it. Steps take turns in the order they came: a lock ON waits for
   the steps already under way or waiting, never for a flood of words after it.
6. A lock kept from the state file is said in the log at start: motion will be refused. So
   is a storm kept (rule 4), with what the start does with its park (not sent again: it was
   reached, a STOP after that or none, or a STOP stopped it short; or sent again, at once or
   held back by the lock kept with it until a lock OFF), in the session's words
   (session/wind.py ``kept_start``), or that it is let go (no ``wind_topic`` configured any
   more). Review 106: a start in a storm kept turned the rotor to its park, 160 degrees,
   with nothing in the log naming the storm or the state file. Review 109: a park reached,
   then a STOP, was said "stopped by a STOP or lock ON" while the status said "parked for
   the storm" (the file's ``halted`` read before its ``arrived``), and a park the lock kept
   ON holds back (session/wind.py rules 4 and 9: said waiting) was said "parking again"
   while the rotor stood still.
7. Options waiting for the writer are saved together, the last value of each, and so are lock
   words (one save of each queued at a time): anyone who may publish ``R/option/<name>`` (or
   lock, never refused) can send thousands a second, and each was a rewrite of the state file
   with its fsyncs, in line before a lock word said after them (its save held back for
   minutes on an SD card, the card worn for nothing).
8. A stop owed outlives a restart (session/stops.py rule 3: one taken while the port was out,
   or the controller silent, is its first frame when it can have one): ``seen_stop`` looks at
   every status on the lines thread (``stop_owed``) as ``seen_wind`` does, and hands a stop
   owed, or owed no more, to the writer; the next start owes it (session.py rule 11). An
   attack pass: a STOP sent while the adapter was out, the bridge restarted before it came
   back, and the rotor turned on to its old target. A save that fails is reported (rule 3).
9. The target a Rotor-EZ or RotorCard keeps and its rotor rests short of (session/controller.py
   rule 10, ``short_of_deg`` in the status) outlives a restart as a stop owed does: the next
   start guards a turn on to it (noticed in an attack pass: stopped short of 300, the bridge
   restarted, and a poll garbled into ``AM1;`` turned the rotor on to 300 unsaid). It is
   saved only when it changes: at a stop short of the target, and at the next turn.
10. Only a state file's lock ON is the last word on the lock at a start. A file that does not
   say ON (a new one: the service run by hand, whose default ``state_file`` is another; a
   container recreated without its volume; the file deleted; a lock ON its save failed to
   keep, rule 3; or one that says OFF) leaves the lock to the broker too: the ``R/lock/state``
   ON it held from an earlier run (interfaces/mqtt/look.py rule 14) locks the rotator
   (``heard_lock``), saved as any lock ON and said (kind ``state``, and in the log), unless a
   lock word has been said since the start (it is newer). An attack pass: the lock ON set for
   tower work came back OFF after a restart on a new state file, the retained ON was put back
   as OFF without a word, and a target turned the rotor. Attack 15: the same with a file that
   says OFF, the OFF the service saved before the bridge was run by hand on another file
   (``state_file`` left out) and locked there; the file's OFF won, as it did until then, though
   it was older than the ON. A file's OFF cannot tell the ON the broker holds older or newer,
   and a lock is safety state: losing an ON without a word is dangerous, keeping an unlock
   too long only inconvenient. So an OFF saved while the broker was away (its OFF not
   published), then a restart before the broker came back, starts locked from the broker's
   older ON, said (``said_off``: the wording says the file's OFF): the safe side; a lock OFF
   ends it. A stranger's retained ON there locks it too, said.
   Until that look has said it (the broker down, or slower to start than the bridge;
   ``await_heard_lock``), such a rotator refuses motion, as a locked one does (a review:
   rotctld, the console and the loggers run before the look, and a tracking program's target
   turned the rotor meanwhile); a lock word ends the wait. So a start with the broker down
   refuses motion until the broker is read whatever the file says but ON (the price of the
   rule above: docs/mqtt.md ``R/lock``). Only the bridge waits (app.py, which always has a
   broker to ask); a rotator built without ``await_heard_lock`` never waits. The status says
   so meanwhile (``lock_unknown``): ``locked`` false is no OFF then (an attack pass: the
   console showed "Lock OFF" while it refused every click for a lock that may be ON). The
   bridge's own moves wait too (session/parts.py rule 7): auto-park (``park_after_idle_s``) and
   the park of a storm kept in the file (rule 4) send nothing while the lock is not known; a
   lock ON heard then refuses them (wind.py rule 3: that park is not tried again), nothing
   heard lets them go (a review: auto-park parked, and a kept storm's park turned, a rotor
   whose lock only the broker still held, while the broker stayed away, before the look said
   it).
   A broker that does not let the bridge read ``R/lock/state`` (its ACL; interfaces/mqtt/
   look.py rule 14's probe does not come back) is no look that said it: such a rotator waits
   on (``lock_unread``), said (kind ``state``, and in the log), and nothing is published over
   what the broker holds there until a lock word ends the wait (review 62: the look ended as
   if the broker held nothing, the rotator started unlocked, OFF went over a stranger's ON
   and a target turned the rotor, unsaid). A rotator that waits says so in the log once at
   start; a lock OFF that ends the wait before the broker was read says that in the log too
   (the operator may have released a lock ON the broker holds).
   A file that says ON wins, and waits for no broker: the broker's OFF (or none) is older, or
   a stranger's, or an OFF said on another run's file: kept locked, the safe side.
11. The version its controller reported last outlives a restart (state_store.py rule 12), kept
   with the model's name: at the next start it is the rotator's version (``version``; in its
   status, so ``R/version``, ``R/status`` and Home Assistant's ``sw_version`` say it) until the
   controller reports one, and one that differs takes its place at once (and is saved). So a
   restart with the same firmware publishes each discovery config once, with its version, also
   while the controller is unplugged (each config went out twice: without the version, then
   again with it, about 50 ms later, once per rotator at every start). A version kept for
   another model (the controller swapped, the configuration's model changed) is none: nothing
   is claimed for the new one until it answers (interfaces/mqtt/service.py clears
   ``R/version`` meanwhile). A rotator of two boxes keeps their two versions as one (its
   status's): its status has none until every box whose model reports one has said it
   (runtime/composite.py rule 3), so the pair kept stands until then, and a restart with the
   same boxes publishes each config once too.
   ``seen_version`` looks at every status on the lines thread, as
   ``seen_wind`` does, and hands a new version to the writer, one save queued at a time
   (rule 7's way: it writes the latest): a box that says a new version in every line (an
   Easycomm III's ``VE...`` is taken whenever it comes) queued a write of the state file
   with its fsyncs for each, a lock word's save waiting behind them all (an attack pass: 200
   such lines, 139 saves). A save that fails is not
   reported as rule 3 has it (the log says it): it costs only a second round of discovery at
   the next start.
12. The places in the order of commands (session/mailbox.py rule 10a; ``R/status``'s
   ``order``) go on across restarts (review 86: a remote orders a STOP or lock ON it holds
   against them, and a turn or lock OFF of the run before a restart, counted from 1 again,
   looked older than that STOP or lock ON and was undone by it). The state file keeps the last
   place reserved (state_store.py rule 14): a start counts on after it (``since``, shown as
   the order's ``since``), the status that shows its first command taken reserves PLACES_BLOCK
   more (the lines thread, ``seen_order``, hands the save to the writer: nothing written, no
   writer started, before a command), and a status that shows half the block taken reserves
   the next. So a flood of targets writes the file once per half a block, not per message, and
   a run killed at any time used no place the next run counts again (unless the writer fell
   half a block behind, or the first command's reservation was not written yet: the next run's
   ``since`` is then below places of that run, which a remote then compares with none of the
   next run's, as before). The place of the turn shown and of the last lock word are kept with
   it (``turn``, ``lock``), at most once every ORDER_SAVE_S, and a turn's place at most
   ORDER_SAVES times in any ORDER_WINDOW_S, a lock word's whenever it moves (review 92: a
   rotctld client tracking with a target a second wrote and fsynced the whole file every
   second, an SD card's wear; now some eight times in ten minutes) (the status that shows a newer
   place after that saves it: a turn the restart would carry over goes on showing statuses,
   its bearing's), one save queued at a time, which writes the latest (a lock word's save
   waiting writes them too, in its one write): a flood of targets or lock words writes the
   file a few times a second at most, and a lock word's own save (rule 2) waits behind one at
   most. The next start shows them until a command of its own replaces them, so what the
   restart kept (the lock, a turn the box went on with under ``unasked_moves = "follow"``) is
   shown at its own place. A run killed within ORDER_SAVE_S of a command shows the place
   before it (a remote may then take a turn begun right before the kill for an older one, or
   send an older lock ON again over a lock OFF: the safe side; in a long stream of targets,
   the turn's place of the window's last save). A save of the places writes the lock word's
   place only while the file holds the lock that word left (no lock save waiting, none
   failed): review 92, a save queued before a lock ON wrote the ON's place with the lock still
   OFF, and a power cut before the ON's own save left a file whose lock word looked newer than
   a remote's held lock ON, which the remote then dropped. A save that fails is said in the
   log only.
13. A turn the bridge sent to a box with no feedback (a DCU-1) outlives a restart while it may
   be in flight (session/motion.py rule 6, ``turn_kept`` in the status): ``seen_turn`` looks at
   every status on the lines thread, as ``seen_stop`` does, and hands the change to the writer,
   so the file is written when a turn begins from rest and when it is over (a stop went out,
   or ``TURN_KEPT_S`` past its end assumed), never per target. The next start takes such a
   box as possibly finishing it (a start refused then halts it: review 89, the DCU-1 turned
   on 95 degrees after a restart mid-turn); one with no turn kept (a new file, a run that sent
   none or saw it over) as at rest (review 93: every start took it as turning, and a refused
   start stopped the operator's own turn at the panel). A save that fails is reported (rule 3).
   The file keeps with it when it runs out (state_store.py rule 15: the kernel's boot id and
   its boot clock, never the wall clock), so a run that ended within the hold (shut down, a
   crash, a power cut) leaves no turn kept for good: a start on the same boot after that end
   takes the box at rest (review 97: a bare true stopped a hand at the panel at a refused
   start an hour later). The end the status says (``turn_kept_until``, on ``clock``, the
   session's) moves on at every target; the file is written to run out TURN_FILED_AHEAD_S
   past it, and again only when a later target's end passes the one written, so targets in
   a row write it once in some ten minutes, not per target; the two ends are compared on the
   boot clock (review 104: ``clock`` stops at a suspend, and a target after one wrote
   nothing while the end on file was long past). The price: a run ended within
   that while is taken as possibly turning at a start on the same boot up to ten minutes more
   (the safe side: a refused start then stops a box at rest or a hand). A start on another
   boot, one whose boot clock cannot be read, or a turn kept with no end (its time counts
   from a connect not yet made) keeps the turn: how long the machine was down is not known.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections import deque
from collections.abc import Callable

from bridge.core.afterlock import later
from bridge.core.model import ErrorKind, Order, SettingValue, WindInfo
from bridge.protocols.base import ModelSpec, SettingKind
from bridge.runtime.state_store import StateStore
from bridge.session.mailbox import Mailbox
from bridge.session.wind import kept_start

log = logging.getLogger(__name__)

PLACES_BLOCK = 1 << 16  # rule 12: the places reserved at a time
ORDER_SAVE_S = 0.5  # rule 12: the turn's and the lock word's places saved at most this often
ORDER_SAVES = 8  # rule 12: ... and at most this many times ...
ORDER_WINDOW_S = 600.0  # ... in any ten minutes (a target a second: an SD card's wear)
TURN_FILED_AHEAD_S = 600.0  # rule 13: a turn kept is written to run out this much later


class Owner:
    """Rule 5: ``with owner:`` is one step of a rotator's safety state; its puts pass
    ``wake=False`` (mailbox.py rule 5) and its saves are queued (state_store.py rule 5): the
    lines thread and the writer are woken once the step has let go. The steps take turns in
    the order they came: a step that ends hands the turn to the oldest one waiting, so a lock
    ON waits for the steps that came before it and never for a flood of words after it (a
    plain lock lets the thread that let go take it again at once, for as long as it holds the
    GIL)."""

    def __init__(self, store: StateStore, mailbox: Mailbox) -> None:
        self._store = store
        self._mailbox = mailbox
        self._guard = threading.Lock()  # only around the books below: a few bytecodes
        self._busy = False
        self._waiting: deque[threading.Lock] = deque()  # each one's turn, oldest first

    def __enter__(self) -> None:
        with self._guard:
            if not self._busy:
                self._busy = True
                return
            turn = threading.Lock()
            turn.acquire()
            self._waiting.append(turn)
        turn.acquire()  # handed over by the step before (``__exit__``)

    def __exit__(self, *exc: object) -> None:
        with self._guard:
            if self._waiting:
                self._waiting.popleft().release()  # the next step's turn: still busy
            else:
                self._busy = False
        later(self._wake)  # rule 5: once a caller's Deferring lock (halts.py) let go too

    def _wake(self) -> None:
        self._mailbox.wake_once()
        self._store.wake()


class Kept:
    def __init__(
        self,
        store: StateStore,
        rotator_id: str,
        spec: ModelSpec,
        *,
        report: Callable[[ErrorKind, str, str | None], None],
        saved_lock: Callable[[bool], None] = lambda locked: None,
        wake: Callable[[], None] = lambda: None,
        clock: Callable[[], float] = time.monotonic,  # rule 12's ORDER_SAVE_S
        wind: bool = True,  # rule 6: a wind topic is configured (the storm kept is heeded)
    ) -> None:
        self._store = store
        self._saved_lock = saved_lock  # rule 2: the status shows the lock once it is saved
        self._wake = wake  # ... and the lines thread is woken for it (not under the guard)
        self._id = rotator_id
        self._spec = spec
        self._report = report
        self._unsaved: dict[str, SettingValue] = {}  # rule 7: options whose save is queued
        self._unsaved_guard = threading.Lock()  # the owner's step and the writer's
        self._lock_unsaved = False  # rule 7: a lock save is queued and has not read the lock
        self.locked = store.locked(rotator_id)  # rule 2: the one copy
        # rule 10: only a file's ON is the last word; its OFF is said apart (``said_off``)
        self.said_off = store.holds_lock(rotator_id) and not self.locked
        self.lock_unsaid = not self.locked  # rule 10 (and no word since start)
        if self.locked:  # rule 6
            log.warning("%s: safety lock ON, kept from the state file", rotator_id)
        self.storm = store.storm(rotator_id)  # rule 4: as the last start left it
        self.storm_halted = self.storm and store.storm_halted(rotator_id)
        self.storm_arrived = self.storm and store.storm_arrived(rotator_id)
        if self.storm:  # rule 6
            log.warning("%s: %s", rotator_id, self._storm_said(wind))
        self.stop_owed = store.stop_owed(rotator_id)  # rule 8
        self.short_of = store.short_of(rotator_id)  # rule 9
        self.turn_kept = store.turn_kept(rotator_id)  # rule 13
        # rule 13: its end as this run wrote it (the boot id, and on that boot's clock)
        self._turn_filed: tuple[str | None, float] | None = None
        self.version = store.version(rotator_id, spec.name)  # rule 11
        self._version_queued = False  # rule 11: a save of the latest version waits
        # rule 12: the places earlier runs reserved, and the turn and lock word kept
        self.since, self.turn_place, self.lock_place = store.order(rotator_id)
        # rule 4: the place the kept storm's park took (0: none known): a park the next start
        # sends again keeps it (session/mailbox.py rule 10b, review 96); a place past ``since``
        # is no place of an earlier run
        place = store.storm_place(rotator_id) if self.storm else 0
        self.storm_place = place if place <= self.since else 0
        self._turn_seen = self.turn_place  # rule 4: the turn the last status showed
        self._storm_from = self.since  # ... and before the storm: a turn past it is its park
        # (the first command taken reserves this run's block: half of none is taken)
        self._reserved = self.since + PLACES_BLOCK // 2
        self._order_queued = False  # rule 12: a save of the latest places waits
        self._clock = clock
        self._order_saved_s = -math.inf  # rule 12: when a save of the places was last queued
        self._order_saves: deque[float] = deque()  # ... and the saves of the last window
        # rule 12: the lock word's place the file holds with the lock it holds (a save of the
        # places writes a newer one only while the file's lock is the lock: review 92)
        self._file_locked = self.locked
        self._file_lock_place = self.lock_place

    def _storm_said(self, wind: bool) -> str:
        """Rule 6: what a start does with the storm kept, in wind.py's words (``kept_start``:
        rules 3 and 7, as the session's ``WindPark`` takes the storm)."""
        if not wind:
            return "a storm kept from the state file is let go: no wind_topic configured"
        said = "in a storm kept from the state file: motion refused until wind readings end it"
        arrived = self.storm_arrived and self._spec.can_report_position  # (as session.py)
        park = kept_start(halted=self.storm_halted, arrived=arrived, locked=self.locked)
        return f"{said}; {park}"  # (the lock is the file's: read above, rule 2)

    def seen_wind(self, wind: WindInfo | None) -> None:
        """Rule 4 (lines thread: it only compares and hands over)."""
        storm = wind is not None and wind.parks  # (wind.py rule 6: a replay's is not kept)
        halted = storm and wind is not None and wind.halted
        arrived = storm and wind is not None and wind.arrived
        if storm != self.storm:  # (a storm begun: its park is a turn past the last one shown)
            self.storm_place, self._storm_from = 0, self._turn_seen
        if (storm, halted, arrived) != (self.storm, self.storm_halted, self.storm_arrived):
            self.storm, self.storm_halted, self.storm_arrived = storm, halted, arrived
            self._save_storm()

    def _save_storm(self) -> None:
        """Rule 4: the storm as last seen, handed to the writer (lines thread)."""
        storm, halted, arrived = self.storm, self.storm_halted, self.storm_arrived
        place = self.storm_place
        self._store.later(lambda: self._save_storm_now(storm, halted, arrived, place))

    def seen_stop(self, owed: bool) -> None:
        """Rule 8 (lines thread: it only compares and hands over)."""
        if owed != self.stop_owed:
            self.stop_owed = owed
            self._store.later(lambda: self._save_stop_now(owed))

    def seen_short_of(self, raw_az: float | None) -> None:
        """Rule 9 (lines thread: it only compares and hands over)."""
        if raw_az != self.short_of:
            self.short_of = raw_az
            self._store.later(lambda: self._save_short_of_now(raw_az))

    def seen_turn(self, kept: bool, until: float | None = None) -> None:
        """Rule 13 (lines thread: it only compares and hands over): ``until``, when the turn
        kept runs out on ``clock`` (None: no end known yet)."""
        if not kept or until is None:
            if kept != self.turn_kept:  # (kept with no end: as the file said it, or true)
                self.turn_kept, self._turn_filed = kept, None
                self._store.later(lambda: self._save_turn_now(kept, None))
            return
        # compared on the boot clock the file keeps it on (``clock`` stops at a suspend, the
        # boot clock does not: review 104, a target after one wrote nothing, the end on file
        # long past); no boot clock: on ``clock`` (the file then keeps the turn: rule 13)
        boot = self._store.boot()
        end = (None, until) if boot is None else (boot[0], until + boot[1] - self._clock())
        filed = self._turn_filed
        if self.turn_kept and filed is not None and filed[0] == end[0] and end[1] <= filed[1]:
            return  # (the file's end is later: targets in a row write nothing)
        self.turn_kept, self._turn_filed = True, (end[0], end[1] + TURN_FILED_AHEAD_S)
        ahead = until + TURN_FILED_AHEAD_S
        self._store.later(lambda: self._save_turn_now(True, ahead))

    def seen_version(self, version: str | None) -> None:
        """Rule 11 (lines thread: it only compares and hands over): the controller's own; one
        save queued at a time, which writes the latest."""
        if version and version != self.version:
            self.version = version
            if not self._version_queued:
                self._version_queued = True
                self._store.later(self._save_version_now)

    def seen_order(self, order: Order | None) -> None:
        """Rule 12 (lines thread: it only compares and hands over): the next block reserved
        once half of this one is taken, at once; the turn's and the lock word's places kept,
        at most once every ORDER_SAVE_S; one save queued at a time, which writes the latest."""
        if order is None:
            return
        self._turn_seen = order.turn  # rule 4: a turn begun in a storm is its park (motion
        # is refused in it: wind.py rule 1), its place kept with the storm
        if self.storm and order.turn > self._storm_from and order.turn != self.storm_place:
            self.storm_place = order.turn
            self._save_storm()
        reserve = order.taken > self._reserved - PLACES_BLOCK // 2
        if reserve:
            self._reserved = order.taken + PLACES_BLOCK
        now = self._clock()
        changed = (order.turn, order.lock) != (self.turn_place, self.lock_place)
        saves = self._order_saves
        while saves and now - saves[0] >= ORDER_WINDOW_S:
            saves.popleft()
        due = now - self._order_saved_s >= ORDER_SAVE_S and len(saves) < ORDER_SAVES
        if reserve or (changed and due):
            with self._unsaved_guard:  # (a lock word's save waiting writes them: one write)
                self.turn_place, self.lock_place = order.turn, order.lock
                if self._lock_unsaved or self._order_queued:
                    return
                self._order_queued = True
            self._order_saved_s = now
            saves.append(now)
            self._store.later(self._save_order_now)

    def _save_order_now(self) -> None:
        with self._unsaved_guard:  # (before the read: a newer one queues a save of its own)
            self._order_queued = False
            lock_place = self.lock_place
            if self._lock_unsaved or self._file_locked != self.locked:
                lock_place = self._file_lock_place  # (review 92: never a word's place alone)
            places = self._reserved, self.turn_place, lock_place
        if self._store.set_order(self._id, *places):
            with self._unsaved_guard:
                if self._file_locked == self.locked:
                    self._file_lock_place = lock_place

    def _places(self) -> tuple[int, int, int] | None:
        """Rule 12 (under the guard): the places to write with a lock word's save; None before
        this run reserved any (nothing of its own to keep yet)."""
        if self._reserved <= self.since + PLACES_BLOCK // 2:
            return None
        return self._reserved, self.turn_place, self.lock_place

    def _save_version_now(self) -> None:
        self._version_queued = False  # (before the read: a newer one queues a save of its own)
        version = self.version
        if version:
            self._store.set_version(self._id, self._spec.name, version)  # (a failure: rule 11)

    def _save_short_of_now(self, raw_az: float | None) -> None:
        if not self._store.set_short_of(self._id, raw_az):
            self._report(
                ErrorKind.STATE,
                "where the rotor was stopped short of its target could not be saved: after a "
                "restart a turn on to it would not be stopped (state file not writable)",
                None,
            )

    def _save_stop_now(self, owed: bool) -> None:
        if not self._store.set_stop_owed(self._id, owed):
            self._report(
                ErrorKind.STATE,
                f"a stop {'owed' if owed else 'sent'} could not be saved: a restart would "
                f"{'not owe it' if owed else 'send it again'} (state file not writable)",
                "stop",
            )

    def _save_turn_now(self, kept: bool, filed: float | None) -> None:
        until = None  # rule 13: the end on the boot clock, read beside ``clock`` (no end: kept)
        if filed is not None and (boot := self._store.boot()) is not None:
            until = (boot[0], boot[1] + filed - self._clock())
        if not self._store.set_turn_kept(self._id, kept, until):
            self._report(
                ErrorKind.STATE,
                f"a turn {'sent' if kept else 'over'} could not be saved: after a restart a "
                f"start refused at once would {'not halt it' if kept else 'send a stop'} "
                "(state file not writable)",
                None,
            )

    def _save_storm_now(self, storm: bool, halted: bool, arrived: bool, place: int) -> None:
        if not self._store.set_storm(self._id, storm, halted=halted, arrived=arrived, place=place):
            self._report(
                ErrorKind.STATE,
                f"the storm's {'start' if storm else 'end'} could not be saved: a restart "
                "would not know it (state file not writable)",
                "wind",
            )

    def options(self) -> dict[str, SettingValue]:
        """Rule 1: each as its model's declaration reads it (one it refuses is left out)."""
        kept: dict[str, SettingValue] = {}
        for name, value in self._store.options(self._id).items():
            setting = self._spec.setting(name)
            try:
                if setting is None:
                    raise ValueError(f"{self._spec.display_name} has no such option")
                if (setting.kind is SettingKind.BOOL) != isinstance(value, bool):
                    raise ValueError(f"{value!r} is no value of a {setting.kind} setting")
                kept[name] = setting.read(value)
            except ValueError as exc:
                log.warning("%s: stored option %r ignored: %s", self._id, name, exc)
        return kept

    def save_option(self, name: str, value: SettingValue) -> None:
        """In the owner's step (rule 5); joins a save already queued (rule 7)."""
        with self._unsaved_guard:
            queued = bool(self._unsaved)
            self._unsaved[name] = value
        if not queued:
            self._store.queue(self._save_options_now)

    def _save_options_now(self) -> None:
        with self._unsaved_guard:
            unsaved, self._unsaved = self._unsaved, {}
        for name, value in unsaved.items():
            if not self._store.set_option(self._id, name, value):
                self._report(
                    ErrorKind.STATE,
                    f"option {name} is in effect but could not be saved: it will not survive "
                    "a restart (state file not writable)",
                    name,
                )

    def set_lock(self, locked: bool) -> None:
        """Rule 2, in the owner's step (rule 5): the lock is ``locked``, and saved as that."""
        with self._unsaved_guard:
            self.locked = locked
            self.lock_unsaid = False  # rule 10: a word since the start is newer
            queued, self._lock_unsaved = self._lock_unsaved, True
        if not queued:
            self._store.queue(self._save_lock_now)

    def _save_lock_now(self) -> None:
        with self._unsaved_guard:  # rule 7: the last word so far
            locked, self._lock_unsaved = self.locked, False
            places = self._places()  # rule 12: in the same write
        try:
            saved = self._store.set_locked(self._id, locked, places)
            if saved:  # rule 12: the file's lock and the lock word's place with it
                with self._unsaved_guard:
                    self._file_locked = locked
                    if places is not None:
                        self._file_lock_place = places[2]
        finally:  # rule 2: now the status says it (and, failed, the error below)
            with self._unsaved_guard:  # (a word since: its own save says it; a review: an
                # ON said by a save that read it before an OFF, with the OFF being written)
                self._saved_lock(locked and not self._lock_unsaved)  # (no wake byte here:
            self._wake()  # the owner's step takes this guard, and writes nothing: rule 5)
        if not saved:
            self._report(
                ErrorKind.STATE,
                f"lock {'ON' if locked else 'OFF'} is in effect but could not be saved: "
                "it will not survive a restart (state file not writable)",
                "lock",
            )
