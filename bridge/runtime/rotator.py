"""A rotator as the front ends (MQTT, rotctld) see it: submit commands, read the status.

This is the one judge of commands: every front end submits here (``submit``, the one entry: a
value of core/model.py's ``Command`` union, dispatched on its type; front.py), and here alone are
the safety lock, the wind park, the configured limits and keep-out sectors (pointing.py: targets
arrive as true bearings and leave as the controller's raw values), the model's capabilities and
the link state checked against a command. A refused command raises Refused (with a RefusalCode
front ends map, e.g. to a Hamlib RPRT number) and is reported as an error event; it never
reaches the mailbox, so it can never move anything. The worker judges nothing anew: it only
drops an accepted target that the lock or a lost link overtook before it could be sent, and
reports that as a refusal too. Motion is judged in one order: the lock (and a lock not known
yet: kept.py rule 10), the wind (safety), the control lease (coordination), the pointing
judge, the link (``_check``). Each command carries
who sent it (``origin``): the lease (operators.py) refuses a target, a controller setting, a track
or follow start from anyone but its holder (and the session drops another's target judged before
a claim that still waits unsent: session.py rule 23, said and audited through ``_session_event``;
the mailbox refuses one judged before the claim and put after it, and so a track or follow
start and a feature's own command, the lease's generation read before the judge and judged at
the put: mailbox.py rule 14, refused here as ``leased``; a controller setting judged before
another's claim is refused so in its owner's step);
nothing refuses a stop, lock or tracking/following OFF (docs/architecture.md rule 11); every
command judged here, executed or refused, is an audit event, written in one place (``submit``,
after the put; a value outside the union is refused as unsupported), which says whether it was
a halt that changed nothing (a lock ON while ON, tracking or following OFF with nothing to end:
runtime/audit.py rule 10). The bridge's own moves
(auto-park, the wind park, tracking's and following's targets) are the session's, never
judged by the lease. The safety state has one owner per rotator (kept.py rule 5,
docs/architecture.md rule 14): a lock word, and the lease's claims, releases and end
(operators.py rule 1), are decided, put in the mailbox and their save queued in
one step under the owner's lock, from every interface; the lock the judge asks is that owner's
(kept.py rule 2). A stop takes no part in it: it never waits for the owner's lock. A motion
command judged before a stop or lock ON never runs after it, whichever threads brought the two:
the judge reads the mailbox's halt count before it judges a target, a track or follow start (a
preset, park, nudge, a place are targets), and the mailbox drops one whose count a stop or lock
ON put since has made old (mailbox.py rule 10); the judge reports that as a refusal
(``STALE_MESSAGE``, code ``stale``), on R/error and in the audit trail like any. A rotator of
two boxes (``axes``) is judged here like any, against its one merged status; behind its
mailbox, composite.py drives the two boxes. A feature's own command (``FeatureCommand``, for
its session part: session/parts.py rule 5) is judged here generically, naming no feature: one
for no part of this rotator's that takes commands is refused (``unsupported``); one that moves
the rotor like a track start (the lock, the wind, the lease, the link; put with its halt
count), one that does not like a controller setting (the lease alone). It is never a stop,
never on the stop lane, and a stop or lock ON drops it as it drops a target (mailbox.py
rule 12). A stop or lock ON from any interface but MQTT (the console, rotctld, GS-232, Easycomm,
DCU-1, the loggers) is told to the ``fence`` right before it is put and right after (never
under the owner's lock, and a fence that raises costs the halt nothing): the MQTT service then
refuses a move, or a lock OFF, that its main connection reads for this rotator but was
published before that halt (interfaces/mqtt/lastword.py rule 11); MQTT's own halts are ordered
by the last word. As a move does, the main connection's lock OFF comes with the halt count read
before the fence was asked (``since``): while the lock is ON, one that a stop or lock ON put
since has made old is refused (``stale``, the lock stays ON), decided under the owner's lock, so
a lock ON put between that look and the lock OFF's put is the last word.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable, Hashable
from dataclasses import replace
from functools import partial
from typing import NoReturn, Protocol, TypeVar

import serial

from bridge.core.errors import RefusalCode, Refused
from bridge.core.haltwatch import HaltWatchers
from bridge.core.model import (
    COMMANDS,
    AuditEvent,
    Claim,
    Command,
    ControllerCommand,
    ErrorEvent,
    ErrorKind,
    FeatureCommand,
    FollowQso,
    GoToPreset,
    Lock,
    MotionState,
    Nudge,
    Origin,
    Park,
    Release,
    ResetHealth,
    RotatorStatus,
    SentAt,
    SetOption,
    Source,
    Stop,
    TakePath,
    Target,
    Toward,
    TrackBody,
    describe_command,
    same_operator,
    sender,
)
from bridge.feature import session_parts
from bridge.pointing import Limits, toward
from bridge.protocols.axes import bearing_is_elevation
from bridge.protocols.base import ModelSpec
from bridge.runtime.composite import CompositeWorker
from bridge.runtime.health_memory import HealthMemory
from bridge.runtime.kept import Kept, Owner
from bridge.runtime.lines import Lines
from bridge.runtime.operators import EXECUTED, Operators
from bridge.runtime.port import PortWatch, open_port
from bridge.runtime.state_store import StateStore
from bridge.runtime.worker import Worker, WorkerConfig
from bridge.session.actions import Audit
from bridge.session.feature_commands import PLACE, body_to_track, check_azimuth, check_can_follow
from bridge.session.follow import Follow as Following
from bridge.session.follow import Heard
from bridge.session.mailbox import LeaseChanged, Mailbox
from bridge.session.tracking import Track as Tracking
from bridge.sky.catalog import TleCatalog
from bridge.sky.worker import LookupQuestion, SkyWorker

log = logging.getLogger(__name__)
_T = TypeVar("_T")

# mailbox.py rule 10: judged, then overtaken by a stop or lock ON from another thread
STALE_MESSAGE = "a STOP or lock ON came while it was being judged: not carried out"
OFFLINE_MESSAGE = "rotator offline (serial link down or controller silent)"
NEWER_MESSAGE = "a newer command came after it was asked: not carried out"
LOCK_OFF_STALE_MESSAGE = (
    "lock OFF not carried out: a STOP or lock ON was put while it was being judged; the lock "
    "stays ON (make sure nobody is working on the tower, then send lock OFF again)"
)
HEARD_LOCK_MESSAGE = (  # kept.py rule 10
    "lock ON kept from the broker: R/lock/state said ON before this start, and the state file "
    "did not say this rotator's lock (a new or another state_file?); lock OFF releases it"
)
HEARD_OVER_OFF_MESSAGE = (  # kept.py rule 10 (attack 15): the file said OFF
    "lock ON kept from the broker: R/lock/state said ON before this start, and this bridge's "
    "state file says OFF (a lock set by another run of the bridge, on another state_file, or "
    "an OFF that never reached the broker?); lock OFF releases it"
)
UNREAD_LOCK_MESSAGE = (  # kept.py rule 10 (review 62): the broker drops what it sends there
    "cannot read R/lock/state (the broker's ACL?): it may hold a lock ON that this start cannot "
    "see; motion refused and R/lock/state left as the broker holds it until a lock word is sent "
    "(lock ON, or lock OFF once the tower is known clear)"
)
UNHEARD_LOCK_MESSAGE = (  # kept.py rule 10
    "motion refused: the state file does not say this rotator's safety lock is ON, and the "
    "broker's R/lock/state, which may say ON, has not been read yet (the MQTT broker not "
    "reached); a lock OFF releases it"
)
ON_ITS_WAY_MESSAGE = (
    "a command sent just before it is still on its way to the controller: send it again"
)


class HaltFence(Protocol):
    """The module's docstring: what is told of a halt from an interface other than MQTT
    (interfaces/mqtt/service.py rule 11)."""

    def fence_asked(self, rotator_id: str) -> None: ...
    def fence_carried(self, rotator_id: str, lock: bool) -> None: ...


class Rotator:
    def __init__(
        self,
        cfg: WorkerConfig,
        store: StateStore,
        on_status: Callable[[RotatorStatus], None],
        on_event: Callable[[ErrorEvent], None],
        name: str | None = None,
        *,
        clock: Callable[[], float] = time.monotonic,
        wall: Callable[[], float] = time.time,
        port_opener: Callable[..., serial.Serial] = open_port,
        lines: Lines | None = None,
        station: tuple[float, float] | None = None,
        catalog: TleCatalog | None = None,
        sky: SkyWorker | None = None,
        on_audit: Callable[[AuditEvent], None] | None = None,
        axes: tuple[WorkerConfig, WorkerConfig] | None = None,  # a composite's (composite.py)
        port_watch: PortWatch | None = None,
        fence: HaltFence | None = None,
        lease_clock: Callable[[], float] | None = None,  # operators.py rule 5 (``wall``: None)
    ) -> None:
        self.id = cfg.rotator_id
        self._fence = fence  # the module's docstring: another interface's halt, to MQTT
        self.name = name or cfg.rotator_id
        self.spec: ModelSpec = cfg.spec
        self.pointing = cfg.aim  # limits, offset, keep-out, presets, park: the judge's terms
        self.station = station  # (latitude, longitude): targets by locator or coordinates
        self.catalog = catalog or TleCatalog(None)  # satellites to track by name
        self._has_sky = cfg.tracking.sky is not None
        self.can_track = (  # (feature_commands.py: what ``body_to_track`` refuses)
            self._has_sky and cfg.spec.can_report_position and not bearing_is_elevation(cfg.spec)
        )
        self._follow = cfg.follow  # follow.py: the station, the [wsjtx] listener
        self._parts = cfg.parts  # the session's parts (a feature's command goes to its own)
        self._store = store
        self._on_event = on_event
        self._wall = wall
        self._mailbox = Mailbox()
        self._kept = Kept(
            store,
            self.id,
            self.spec,
            report=self.report,
            saved_lock=partial(self._mailbox.put_lock_saved, wake=False),
            wake=self._mailbox.wake_once,
            clock=clock,
            wind=cfg.wind is not None,  # kept.py rule 6: a storm kept is heeded
        )
        self._mailbox.places_after(self._kept.since)  # kept.py rule 12: on from earlier runs
        kept_order = (self._kept.since, self._kept.turn_place, self._kept.lock_place)
        self._leaving: str | None = None  # ``leave``: why nothing but a halt is taken now
        self._owner = Owner(store, self._mailbox)  # kept.py rule 5: the lock's, the lease's
        self._unheard = False  # kept.py rule 10: the lock waits for the broker (await_heard_lock)
        self._unread = False  # kept.py rule 10: ... which would not let it read R/lock/state
        self._health = HealthMemory(store, self.id)  # what rotor health learned, kept
        self._on_status = on_status
        self._worker: Worker | CompositeWorker
        if axes is None:
            self._worker = Worker(
                cfg,
                self._mailbox,
                self._status,
                self._session_event,
                options=self._kept.options(),
                locked=self._kept.locked,
                health=store.health(self.id),
                storm=self._kept.storm,  # kept.py rule 4
                storm_halted=self._kept.storm_halted,
                storm_arrived=self._kept.storm_arrived,
                storm_place=self._kept.storm_place,  # kept.py rule 4 (mailbox.py rule 10b)
                stop_owed=self._kept.stop_owed,  # kept.py rule 8
                short_of=self._kept.short_of,  # kept.py rule 9
                turn_kept=self._kept.turn_kept,  # kept.py rule 13
                order=kept_order,  # kept.py rule 12
                wall=wall,
                port_opener=port_opener,
                sky=sky,  # the app shares one among all rotators (skywork.py)
                port_watch=port_watch,  # the stop express's copy of the port (port.py rule 7)
                on_audit=self._session_audit,  # session.py rule 25
            )
        else:  # two boxes, one judge (this one), one mailbox, one status (composite.py)
            self._worker = CompositeWorker(
                cfg,
                axes,
                self._mailbox,
                self._status,
                self._session_event,
                locked=self._kept.locked,
                health=store.health(self.id),
                storm=self._kept.storm,
                storm_halted=self._kept.storm_halted,
                storm_arrived=self._kept.storm_arrived,
                storm_place=self._kept.storm_place,  # kept.py rule 4 (mailbox.py rule 10b)
                stop_owed=self._kept.stop_owed,  # kept.py rule 8
                short_of=self._kept.short_of,  # kept.py rule 9
                turn_kept=self._kept.turn_kept,  # kept.py rule 13
                order=kept_order,  # kept.py rule 12
                wall=wall,
                port_opener=port_opener,
                sky=sky,
                on_audit=self._session_audit,  # session.py rule 25
            )
        self._lines = lines or Lines(clock)  # the app shares one among all rotators
        self.operators = Operators(
            self.id,
            store,
            self._mailbox,
            wall=wall,
            lease_clock=lease_clock,
            bearing=lambda: self.status.bearing_deg,
            report=self.report,
            on_audit=on_audit,
            owner=self._owner,
        )
        self._stopped = False
        # the last STOP or lock ON put in the mailbox (monotonic), from any front end: the
        # console refuses a command under way before it (interfaces/web/commands.py rule 5)
        self.last_halt_s = -math.inf
        # the latest of the halts' send times, each the earlier of when it came and when its
        # sender stamped it (monotonic), and that halt's stamp on the station's clock if it
        # had one (core/model.py ``SentAt``): a move stamped before it is stale (``_halted``)
        self.halted: tuple[float, float | None] = (-math.inf, None)
        self._halted_lock = threading.Lock()
        self._problem = store.problems.get(self.id)  # state_store.py rule 2
        if self._problem is not None:  # the lock is ON for it; the status's last error says why
            self._mailbox.put_note(self._problem)

    def _status(self, status: RotatorStatus) -> None:
        """Every status to the listeners, once rotor health's memory had a look at it."""
        self._health.seen(status.health)
        self._kept.seen_wind(status.wind)
        self._kept.seen_stop(status.stop_owed)
        self._kept.seen_short_of(status.short_of_deg)
        self._kept.seen_turn(status.turn_kept, status.turn_kept_until)
        self._kept.seen_version(status.version)
        self._kept.seen_order(status.order)
        if status.version is None and self._kept.version is not None:  # kept.py rule 11
            status = replace(status, version=self._kept.version)
        self._on_status(status)

    def _session_event(self, event: ErrorEvent) -> None:
        """The session's error events to the listeners; one that names a sender (a target the
        session dropped before it went out: session.py rules 23, 24) is in the audit trail
        too, as a refusal of that sender's command."""
        self._on_event(event)
        if event.origin is not None:
            self.audit_refusal(event.message, event.command or "target", event.origin)

    def _session_audit(self, audit: Audit) -> None:
        """A move of the bridge's own (auto-park's, the storm's park: session.py rule 25),
        in the audit trail as the feature's command, executed."""
        self.operators.audit(audit.origin, audit.command, EXECUTED)

    def _reset_health(self) -> None:
        """A new health baseline (after a repair); it moves nothing, so it is never refused."""
        self._health.reset()
        self._mailbox.put_health_reset()

    @property
    def status(self) -> RotatorStatus:
        return self._worker.status

    @property
    def version(self) -> str | None:
        """The controller's version as the statuses say it: its own, or until it reports one,
        the one it reported last, kept (kept.py rule 11)."""
        return self._kept.version

    @property
    def limits(self) -> Limits:
        """The mechanical limits (the controller's raw values)."""
        return Limits.of(self.pointing)

    @property
    def commands_block(self) -> bool:
        return False  # a command is judged and queued, never waited for (the console asks)

    @property
    def locked(self) -> bool:
        return self._kept.locked

    def start(self) -> None:
        """Once: a stopped rotator's mailbox is closed (build a new Rotator instead)."""
        if self._stopped:
            raise RuntimeError(f"{self.id}: a stopped rotator cannot start again")
        self._lines.add(self._worker)
        self.operators.start()
        if self._problem is not None:  # state_store.py rule 2: said once on R/error too (an
            # event before the broker's first connection waits for it: mqtt/client.py rule 3)
            self._on_event(ErrorEvent(ErrorKind.STATE, self._problem, None, self._wall()))

    def stop(self, timeout_s: float = 3.0) -> None:
        self._stopped = True
        self.operators.stop()
        if self._lines.remove(self._worker, timeout_s):
            self._mailbox.close()  # only once nothing can wait on it any more
        self._health.flush()  # what the last moves taught (app.py flushes the store)

    def submit(
        self,
        command: Command,
        described: str | None = None,
        *,
        hold: int | None = None,
        echo: bool = False,
        since: int | None = None,
        ticket: int | None = None,
        seen_s: float | None = None,
        reader: Hashable | None = None,
        read_s: float | None = None,
    ) -> None:
        """The one way a front end reaches the judge (rules in the module header): queue
        ``command`` (a value of core/model.py's ``Command`` union) or raise Refused, reported on
        R/error and in the audit trail. ``described``: the words the user sent (the error
        event's and the audit trail's). Stop and lock ON are never refused; ``hold`` (a stop or
        lock ON from the stop lane): no target goes out until ``release`` reaches that marker
        (session rule 13); ``echo``: a halt the stop lane carried out already
        (interfaces/mqtt/halts.py), not audited twice; ``since``: the halt count (``halts``)
        when the command was asked, for a front end that submits it a while later (the DX
        cluster's look-up): a stop or lock ON put since then overtakes it, however late it is
        judged (mailbox.py rule 10); ``ticket``: for such a command, its place in the order of
        commands taken when it was asked (``ticket()``): any motion command put since then
        overtakes it too (mailbox.py rule 10a). ``seen_s``, ``reader``, ``read_s`` (front.py
        rule 3): not used here, the halt count says what came before a halt."""
        del seen_s, reader, read_s  # (the remote's stamp, front.py rule 3)
        if not isinstance(command, COMMANDS):  # a front end's bug, never a user's input
            message = f"not a command the bridge knows: {type(command).__name__}"
            self.report(ErrorKind.REFUSED, message, described)
            raise Refused(RefusalCode.UNSUPPORTED, message)
        who = command.origin or Origin(command.source)
        # a lock word is audited in one wording, whichever interface said it
        what = describe_command(command) if isinstance(command, Lock) else None
        what = what or described or describe_command(command)
        epoch = self._mailbox.epoch if since is None else since  # before the judge (rule 10)
        ends = self._ends_something(command)  # (a halt that changed nothing: before its put)
        try:
            result, idle = self._carry(command, what, who, hold, epoch, ticket, since)
        except Refused as exc:
            self.report_refusal(exc.message, what, origin=who)
            raise
        if not echo:  # after the put (operators.py rule 3)
            stop = isinstance(command, Stop)
            # runtime/audit.py rule 10: a lock ON while ON, an OFF that ended nothing, changed
            # nothing; rule 9: such a halt sent again by its sender with nothing carried out
            # between changes nothing either, unless the judge says it did (a storm's park it
            # gave up: a review found it folded into its sender's run)
            unchanged = not ends() if ends is not None else idle
            judged = ends is not None or (isinstance(command, Lock) and command.on)
            kinds = Target | Claim | Release | SetOption | Lock  # (a Lock not judged: OFF)
            same = unchanged if judged else isinstance(command, kinds)
            # rule 10's halts fold by the command as read (a tracking OFF padded anew each time
            # is the one command); the rest by the sender's words (a claim's say whose it is)
            halt_read = describe_command(command) if ends is not None else ""
            self.operators.audit(
                who,
                what,
                result,
                halt=stop,
                same_again=same,
                unchanged=unchanged,
                read_as=halt_read,
            )

    def _ends_something(self, command: Command) -> Callable[[], bool] | None:
        """For a tracking or following OFF (None for anything else): whether it ended anything,
        asked once it is put (runtime/audit.py rule 10: one that ended nothing is folded like a
        stop). Looked at before the put and again after it: a body tracked, a look-up under
        way, following on (in either box of two: session.py ``features_on``), or a start on its
        way to the session (mailbox.py rule 10a) at either look is something it may have ended;
        a start put after it only makes it say so when it did not."""
        if isinstance(command, TrackBody) and command.off:
            which = 0
        elif isinstance(command, FollowQso) and not command.on:
            which = 1
        else:
            return None
        worker, mailbox = self._worker, self._mailbox

        def on() -> bool:
            shown = worker.newest_applied  # (first: the features read are at least as new)
            return worker.features_on[which] or mailbox.motion_unseen(shown)

        before = on()
        return lambda: before or on()

    def _carry(
        self,
        command: Command,
        what: str,
        who: Origin,
        hold: int | None,
        epoch: int,
        ticket: int | None = None,
        since: int | None = None,
    ) -> tuple[str, bool]:
        """The decision for each kind: the audit trail's result (a health reset's too: it
        moves nothing, but ends a baseline and its warnings, an attack pass) and whether it was
        a lock ON that changed nothing (runtime/audit.py rule 10: ``_lock``), or Refused
        (reported by ``submit``).
        ``epoch``: the halt count read before any of it was judged (mailbox.py rule 10);
        ``since``: the one the caller read (a lock OFF's, ``_lock``)."""
        src, by = command.source, command.origin
        if self._leaving is not None and not isinstance(command, Stop | Lock):
            raise Refused(RefusalCode.OFFLINE, self._leaving)  # (``leave``)
        match command:
            case Stop() if src is not Source.MQTT:  # (a stop is judged by nothing)
                self._fenced(False, lambda: self._judged(command, epoch, hold))
            case Lock() if command.on and src is not Source.MQTT:
                locking = partial(self._lock, True, hold, sent_s=command.sent_s)
                return EXECUTED, self._fenced(True, locking)  # (idle: ON while ON)
            case Target() | Stop() | SetOption():
                self._judged(command, epoch, hold)
            case Lock():
                return EXECUTED, self._lock(command.on, hold, since, command.sent_s)
            case Claim():
                self.operators.claim(command.operator, command.minutes, who)
            case Release():
                if self.operators.release(who) is None:
                    return f"{EXECUTED} (was free)", False
            case TrackBody():
                self._track(command, what, epoch)
            case FollowQso():
                self._start_follow(command, what, epoch)
            # the other ways of naming a target (pointing.py rule 6), judged like any
            case GoToPreset():
                late = command.not_after_s  # (its stamp's expiry: Target.not_after_s)
                target = Target(*self.pointing.preset(command.name), src, origin=by)
                self._judged(replace(target, not_after_s=late), epoch)
            case Park():
                target = Target(*self.pointing.parking(), src, park=True, origin=by)
                self._judged(replace(target, not_after_s=command.not_after_s), epoch)
            case Nudge():
                ticket = self._mailbox.ticket()  # (before the look: rule 10a)
                status, halted = self._seen()
                step = self.pointing.nudge(status, command.d_az_deg, command.d_el_deg, halted)
                late = command.not_after_s
                self._judged(
                    replace(step, source=src, origin=by, not_after_s=late), epoch, ticket=ticket
                )
            case Toward():
                lat, lon = command.latitude_deg, command.longitude_deg
                self._toward(command, epoch, lat, lon, ticket=ticket)
            case TakePath():
                ticket = self._mailbox.ticket()  # (before the look: rule 10a)
                status, halted = self._seen()
                info = None if halted else status.target_info  # the place of the current target
                if info is None:
                    message = "no locator or coordinate target to take the other path to"
                    raise Refused(RefusalCode.INVALID, message)
                lat, lon, locator = info.latitude_deg, info.longitude_deg, info.locator
                self._toward(command, epoch, lat, lon, locator, ticket=ticket)
            case ResetHealth():  # (audited: it ends the baseline and its warnings)
                self._reset_health()
            case FeatureCommand():
                self._feature(command, epoch)
        return EXECUTED, False

    def _fenced(self, lock: bool, halt: Callable[[], _T]) -> _T:
        """The module's docstring: another interface's stop (``lock``: lock ON), told to the
        fence before and after it is put; a fence that fails is logged, the halt goes on.
        What ``halt`` returns."""
        fence = self._fence
        if fence is None:
            return halt()
        try:
            fence.fence_asked(self.id)
        except Exception:
            log.exception("%s: the MQTT fence failed (the halt goes on)", self.id)
        try:
            return halt()
        finally:  # (asked and never fenced, it would refuse every MQTT move for good)
            try:
                fence.fence_carried(self.id, lock)
            except Exception:
                log.exception("%s: the MQTT fence failed (the halt went out)", self.id)

    def leave(self, why: str) -> None:
        """From now on only a stop or a lock word is taken, every other command refused with
        ``why`` (app.py: a bridge that yields its base topic stops every rotor, and a front
        end not closed yet must not turn one again: a review, a rotctld client's P after that
        stop turned the rotor until the front ends had closed). The session is told too: from
        then on it starts no move of its own but the storm's park (session.py rule 21)."""
        self._leaving = why
        self._mailbox.put_ending()

    def may_turn(self) -> bool:
        """Whether the rotor may be turning, or about to, as far as the bridge knows: its
        status says moving, or shows a target (one that waits out a brake delay, or a reply on
        a half-duplex line, goes out by itself once it may), it tracks or follows, or a motion
        command was put that the status does not show yet (app.py rule 6: what the bridge
        stops before it ends). A storm's park is left to go on (session/wind.py: a stop would
        keep it from being tried again). The place first, then the status (``_seen``'s order:
        the lines thread writes them the other way round, so a target applied between the two
        reads shows in one of them)."""
        shown = self._worker.newest_applied
        status = self.status
        if status.wind is not None and status.wind.parks:
            return False  # (a storm known only from a replay parks nothing: wind.py rule 6)
        if status.state is MotionState.MOVING:
            return True
        if status.target_az_deg is not None or status.target_el_deg is not None:
            return True  # (a target that waits out a brake delay or a reply: on its way too)
        if status.tracking is not None or status.following is not None:
            return True
        return self._mailbox.motion_unseen(shown)

    def on_its_way(self) -> bool:
        """A motion command put that the status does not show yet (mailbox.py rule 10a): a
        command made from the status (a nudge, the other path) is refused as ``_seen`` says
        until it shows; the console waits for that before it judges one (interfaces/web/
        server.py rule 10)."""
        return self._mailbox.motion_unseen(self._worker.newest_applied)

    def ticket(self) -> int:
        """A place in the order of commands (mailbox.py rule 10a): what a front end that
        submits a motion command a while after it was asked takes when it is asked, and hands
        to ``submit`` (``ticket``)."""
        return self._mailbox.ticket()

    @property
    def halts(self) -> int:
        """The halt count now (mailbox.py rule 10): what a front end that submits a command a
        while after it was asked reads when it is asked, and hands to ``submit`` (``since``)."""
        return self._mailbox.epoch

    @property
    def halt_watchers(self) -> HaltWatchers:
        """Told right before each halt is counted (mailbox.py rule 10; interfaces/tcplines.py
        rule 9)."""
        return self._mailbox.halt_watchers

    def halts_for(self, source: Source) -> int:
        """The count a command of ``source`` asked now hands to ``submit`` as ``since``: the
        halt count, every front end's (the remote's counts its own front ends': remote/
        rotator.py ``halts_besides``)."""
        return self._mailbox.epoch

    @property
    def halts_applied(self) -> int:
        """The halt count the session has carried out up to (mailbox.py rule 10)."""
        return self._worker.halts_applied

    @property
    def stop_written(self) -> bool:
        """No stop waits for the line (a half-duplex one owes a reply first: link.py rule 3)."""
        return not self._worker.stop_due

    def _seen(self) -> tuple[RotatorStatus, bool]:
        """The status a command relative to the target is made from, and whether a stop or
        lock ON put before it is not in that status yet (mailbox.py rule 10): the target it
        shows is then the one that halt dropped, and nothing is on its way. A motion command
        put before it, after the last halt, and not in that status yet (rule 10a) makes the
        target it shows an old one: refused, to be sent again (an attack pass: target 100,
        then a nudge of +10 before the lines thread took the target, went to the old target's
        bearing plus 10, and the 100 was never sent; a review: the same with a STOP before the
        target). The command made from it is put with a ticket taken before this look, so one
        put after the look overtakes it (rule 10a)."""
        worker = self._worker
        applied, shown = worker.halts_applied, worker.newest_applied  # first: the status read
        status, halted = self.status, self._mailbox.epoch > applied  # next is at least as new
        if self._mailbox.motion_unseen(shown):
            raise Refused(RefusalCode.STALE, ON_ITS_WAY_MESSAGE)
        return status, halted

    def _toward(
        self,
        command: Toward | TakePath,
        epoch: int,
        latitude_deg: float,
        longitude_deg: float,
        locator: str | None = None,
        *,
        ticket: int | None = None,
    ) -> None:
        """A place, by the path asked for: a target with where it lies (``target_info``); never
        on a rotator whose bearing is an elevation (session/feature_commands.py rule 6)."""
        check_azimuth(self.spec, PLACE)
        if isinstance(command, Toward):
            locator = command.locator
        az, info = toward(
            self.station,
            latitude_deg,
            longitude_deg,
            long_path=command.long_path,
            locator=locator,
        )
        target = Target(az, None, command.source, info=info, origin=command.origin)
        target = replace(target, not_after_s=command.not_after_s)
        self._judged(target, epoch, ticket=ticket)

    def _judged(
        self,
        command: ControllerCommand,
        epoch: int,
        hold: int | None = None,
        *,
        ticket: int | None = None,
    ) -> None:
        """A target, a stop or an option: judged (``_check``) and put in the mailbox (a
        target with ``epoch``, the halt count read before it was judged: mailbox.py rule 10,
        and the lease's generation read before it was judged: a claim by another operator put
        since refuses it there, rule 14; an option's, in its owner's step: ``_claimed_since``)."""
        lease = self._mailbox.lease  # (before the judge: mailbox.py rule 14)
        judged = self._check(command)
        if isinstance(judged, SetOption):
            with self._owner:  # the session and the state file in the same order (kept.py)
                self._claimed_since(judged, lease)  # (in the step: no claim comes between)
                self._kept.save_option(judged.name, judged.value)
                self._mailbox.put(judged, wake=False)  # woken after the step
        elif isinstance(judged, Stop):
            self._halted(judged.sent_s)
            self._mailbox.put(judged, hold=hold)
        else:
            try:
                put = self._mailbox.put(judged, epoch=epoch, ticket=ticket, lease=lease)
            except LeaseChanged as changed:  # (mailbox.py rule 14)
                self._claimed(changed)
            if not put:
                self._overtaken(newer=self._mailbox.epoch == epoch)

    def _claimed(self, changed: LeaseChanged) -> NoReturn:
        """A motion command or a feature's own, judged before another operator's claim and
        put after it (mailbox.py rule 14): refused as the judge refuses one (``leased``),
        saying the claim came while it was judged."""
        message = self.operators.claimed_meanwhile(changed.control)
        raise Refused(RefusalCode.LEASED, message) from None

    def _claimed_since(self, option: SetOption, lease: int) -> None:
        """In the owner's step: Refused if another operator claimed the lease since ``lease``,
        the generation read before ``option`` was judged (a setting is control too: as
        mailbox.py rule 14 refuses a target)."""
        held = self.operators.holder if self._mailbox.lease != lease else None
        if held is not None and not same_operator(held.operator, self._who(option)):
            raise Refused(RefusalCode.LEASED, self.operators.claimed_meanwhile(held))

    def release(self, marker: int, *, clear: bool = False) -> None:
        """The holds up to ``marker`` end (``clear``: what waits meanwhile is dropped)."""
        self._mailbox.put_release(marker, clear=clear)

    def express_hold(self, n: int) -> None:
        """No target goes out until the stop express has answered sync word ``n`` (mqtt/
        express.py rule 8): put before the stop it comes with."""
        self._mailbox.put_express_hold(n)

    def express_release(self, n: int, lost: bool = False) -> None:
        """The stop express answered up to sync word ``n``: its holds up to it end (``lost``:
        by its connection's end or its own, what waited is dropped: session/stops.py rule 5)."""
        self._mailbox.put_express_release(n, lost)

    def _track(self, command: TrackBody, what: str, epoch: int) -> None:
        """Follow the sun, the moon or a satellite (by name from the TLE file, or its TLE);
        ``off`` ends it (never refused, like a stop). A name is looked up in the TLE file by
        the sky worker, not here (paho's thread): an unknown one is refused by the session, as
        an error event. Tracking started by the lease's holder goes on (its targets are the
        bridge's own, never judged by the lease)."""
        source, origin, name = command.source, command.origin, command.name
        if command.off:
            self._mailbox.put_track(Tracking(None, source, origin=origin))
            return
        lease = self._mailbox.lease  # (before the judge: mailbox.py rule 14)
        body = body_to_track(self.catalog, self.spec, self._has_sky, name, command.tle)
        self._check_start(origin or Origin(source))
        if body is None:
            lookup = LookupQuestion(self.catalog, name)
            track = Tracking(None, source, lookup, what, origin)
        else:
            track = Tracking(body, source, None, what, origin)
        track = replace(track, not_after_s=command.not_after_s)  # (its stamp's, as a Target's)
        try:
            put = self._mailbox.put_track(track, epoch=epoch, lease=lease)
        except LeaseChanged as changed:
            self._claimed(changed)
        if not put:
            self._overtaken()

    @property
    def can_follow(self) -> bool:
        """A QSO partner can be followed: the [wsjtx] listener runs and the station is known,
        and the rotator turns in azimuth (feature_commands.py: what ``check_can_follow``
        refuses)."""
        follow = self._follow
        return follow.wsjtx and follow.station is not None and not bearing_is_elevation(self.spec)

    @property
    def followed(self) -> str | None:
        """The program (WSJT-X's Id) its follow part listens to, as its latest status says
        (follow.py rule 8); None: not following, or following the first heard (any thread:
        the WSJT-X listener keeps room for its statuses, interfaces/wsjtx/server.py rule 5)."""
        following = self.status.following
        return None if following is None else following.instance

    def _start_follow(self, command: FollowQso, what: str, epoch: int) -> None:
        """Follow the QSO partner WSJT-X names (follow.py); off ends it (never refused, like a
        stop). Judged like a track start (the lease included); what the holder started goes
        on, its targets are the bridge's own (``wsjtx``)."""
        on, origin = command.on, command.origin
        lease = self._mailbox.lease if on else None  # (before the judge: mailbox.py rule 14)
        if on:
            check_can_follow(self._follow, self.spec)
            self._check_start(origin or Origin(command.source))
        follow = Following(on, command.long_path, command.source, what, origin)
        follow = replace(follow, not_after_s=command.not_after_s)  # (as a track start's)
        try:
            put = self._mailbox.put_follow(follow, epoch=epoch if on else None, lease=lease)
        except LeaseChanged as changed:
            self._claimed(changed)
        if not put:
            self._overtaken()

    def _feature(self, command: FeatureCommand, epoch: int) -> None:
        """A feature's own command (the module's docstring): judged like a track start when
        it moves the rotor, like a controller setting when it does not, then put for its
        part."""
        parts = self._parts if self._parts is not None else session_parts()
        if not any(p.name == command.feature and p.command is not None for p in parts):
            message = f"no feature {command.feature!r} takes commands on this rotator"
            raise Refused(RefusalCode.UNSUPPORTED, message)
        who = command.origin or Origin(command.source)
        lease = self._mailbox.lease  # (before the judge, moving or not: mailbox.py rule 14)
        if not command.moves:
            leased = self.operators.refusal(who.who)
            if leased is not None:
                raise Refused(RefusalCode.LEASED, leased)
            try:
                self._mailbox.put_feature(command, lease=lease)
            except LeaseChanged as changed:
                self._claimed(changed)
            return
        self._check_start(who)
        try:
            put = self._mailbox.put_feature(command, epoch=epoch, lease=lease)
        except LeaseChanged as changed:
            self._claimed(changed)
        if not put:
            self._overtaken()

    def wind(self, speed_kmh: float, replayed: bool = False) -> None:
        """A wind reading (MQTT's thread): an input for the wind park (session/wind.py)."""
        self._mailbox.put_wind(speed_kmh, replayed)

    def heard(self, heard: Heard) -> None:
        """What WSJT-X says of the QSO (interfaces/wsjtx/server.py's thread): an input for
        following."""
        self._mailbox.put_heard(heard)

    def _overtaken(self, newer: bool = False) -> NoReturn:
        """A motion command the mailbox dropped: a stop or lock ON from another thread was put
        while it was judged (mailbox.py rule 10), or (``newer``) a motion command put after
        it was asked (rule 10a). Refused like any, and said so."""
        raise Refused(RefusalCode.STALE, NEWER_MESSAGE if newer else STALE_MESSAGE)

    def _check_start(self, who: Origin) -> None:
        """A track or follow start: the judge's order (``_check``), with no target to judge."""
        self._check_motion(who.who)
        if not self.status.available:
            raise Refused(RefusalCode.OFFLINE, OFFLINE_MESSAGE)

    def _halted(self, sent_s: float | None) -> None:
        """A STOP or lock ON is put now (``sent_s``: its sender's stamp, on the steady clock):
        ``last_halt_s`` is now, ``halted_s`` the latest of the halts' send times, a stamped
        one's never later than it came (a sender's clock ahead cannot make older moves look
        stale for ever, nor a stamp in the past make the halts before it count less); with
        it, that halt's stamp (``SentAt.unix``) as it came, which a move's stamp is compared
        with (interfaces/mqtt/service.py rule 9). A stamp ahead of when it came (a fast clock,
        up to heartbeat.py's AHEAD_S) is not clamped: that clock's move sent before this STOP
        is stamped before it and refused (review 28), and a right clock's move sent in the
        moment after is refused too, the safe side: the two cannot be told apart (review 26
        asked the other way). Of two stamped halts the later is the later stamp (on the
        steady clock the two could swap by a moment the thread lost)."""
        now = time.monotonic()
        self.last_halt_s = now
        sent = now if sent_s is None or not sent_s < now else sent_s
        unix = sent_s.unix if isinstance(sent_s, SentAt) else None  # (its stamp: one clock)
        with self._halted_lock:
            halted_s, halted_unix = self.halted
            if unix is not None and halted_unix is not None:  # (two stamps: by their clock)
                later = unix > halted_unix
            else:
                later = sent > halted_s
            if later:  # (one value: read whole, never half of two halts)
                self.halted = max(sent, halted_s), unix

    @property
    def halted_s(self) -> float:
        """The latest of the halts' send times (``_halted``), monotonic."""
        return self.halted[0]

    def _lock(
        self, locked: bool, hold: int | None, since: int | None = None, sent_s: float | None = None
    ) -> bool:
        """Whether it was a lock ON that changed nothing (runtime/audit.py rule 10): the lock
        was ON already, and no storm's park was owed that a lock ON ends (wind.py rule 3: it
        is not tried again after one). Never refused, but a lock OFF put with a halt count
        (``since``, as for ``submit``) that a stop or lock ON put since has made old while the
        lock is ON: it may be older than that lock ON (interfaces/mqtt/lastword.py rule 11), and
        the lock stays ON.
        ``hold`` as for ``submit``. The lock, the mailbox put and the save queued for the state
        file are one step (kept.py rules 2, 5), from every interface."""
        with self._owner:
            if not locked and since is not None and self._kept.locked:
                if self._mailbox.epoch != since:
                    raise Refused(RefusalCode.STALE, LOCK_OFF_STALE_MESSAGE)
            idle = locked and self._kept.locked and not self._storm_parks()
            if not locked and not self._kept.locked and not self._kept.lock_unsaid:
                # a lock OFF while the last word was OFF changes nothing: no save queued, no
                # put, no wake of the lines thread (attack 24: a flood of OFFs from another
                # client cost each one an owner's step, a save and a mailbox wake); its place
                # in the order is the OFF before it, which every later word follows anyway
                return False
            unread_off = not locked and self.lock_waits  # (kept.py rule 10: said below)
            self._kept.set_lock(locked)
            if locked:
                self._halted(sent_s)
            self._mailbox.put_lock(locked, hold=hold, wake=False)  # woken after the step
        if unread_off:
            log.warning(
                "%s: lock OFF ends the wait for the broker's word on the lock before its "
                "R/lock/state was read: a lock ON it holds (another run's, a stranger's) may "
                "have been released",
                self.id,
            )
        return idle

    def _storm_parks(self) -> bool:
        """Whether the status shows a storm whose park a lock ON would stop or hold back for
        good (wind.py rule 3): a lock ON then changes something, even while the lock is ON. So
        may it when a live wind reading is on its way that the status does not show yet
        (mailbox.py rule 9: the lock ON put behind it stops that reading's park; a review
        found it called idle and folded); the reading may be calm: a line too many, never one
        too few."""
        applied = self._worker.winds_applied  # (first: the status read is at least as new)
        wind = self.status.wind
        if wind is not None and wind.parks and not wind.halted:
            return True
        return self._mailbox.wind_unseen(applied)

    def await_heard_lock(self) -> None:
        """kept.py rule 10: motion is refused while the state file has not said the lock ON and
        ``heard_lock`` has not been called (before the front ends start); the status says the
        lock is not known meanwhile (``lock_unknown``), a lock word or ``heard_lock`` ends it."""
        self._unheard = True
        if self._kept.lock_unsaid:
            self._mailbox.put_lock_unknown(True)
            log.info(
                "%s: motion refused until the broker's R/lock/state is read, or a lock word is "
                "sent (the state file does not say the lock ON)",
                self.id,
            )

    @property
    def lock_waits(self) -> bool:
        """kept.py rule 10: motion waits for the broker's word on the lock, or a lock word."""
        return self._unheard and self._kept.lock_unsaid

    def lock_unread(self) -> bool:
        """kept.py rule 10 (review 62): the broker's first look could not read ``R/lock/state``
        (it drops what it sends there: its ACL). A rotator that waits for it waits on, said
        (kind ``state``, and in the log), until a lock word; True if it does."""
        with self._owner:
            waits = self._unread = self.lock_waits
        if waits:
            self.report(ErrorKind.STATE, UNREAD_LOCK_MESSAGE, "lock")
            log.warning("%s: %s", self.id, UNREAD_LOCK_MESSAGE)
        return waits

    def heard_lock(self, payload: bytes | None) -> bool:
        """kept.py rule 10: ``R/lock/state`` as the broker held it from an earlier run (MQTT's
        first look; None: it held none); ON locks the rotator if the state file did not say its
        lock ON (nothing, or OFF) and no lock word came since the start. True if it did.
        Motion waits no more."""
        with self._owner:  # (one step with every lock word: one said since is newer)
            if payload is None and self._unread:  # (another's late witness: nothing of ours)
                return False
            self._unread = False  # (a value read there after all: it is the broker's word)
            took = payload == b"ON" and self._kept.lock_unsaid and not self._kept.locked
            if took:
                self._kept.set_lock(True)
                self._halted(None)
                self._mailbox.put_lock(True, wake=False)  # woken after the step
            self._unheard = False  # (after the lock: a target judged meanwhile is overtaken)
            if not took:  # (a lock put says it is known: mailbox.py ``put_lock``)
                self._mailbox.put_lock_unknown(False, wake=False)
        if not took:
            if payload not in (None, b"", b"ON", b"OFF"):  # (an attack pass: not a word said)
                log.warning(
                    "%s: the broker held R/lock/state %r from before this start, neither ON nor "
                    "OFF: not read as a lock%s",
                    self.id,
                    payload[:40],
                    "; the rotator starts unlocked" if self._kept.lock_unsaid else "",
                )
            return False
        who = Origin(Source.MQTT, "retained R/lock/state")
        self.operators.audit(who, describe_command(Lock(on=True)), EXECUTED)
        said = HEARD_OVER_OFF_MESSAGE if self._kept.said_off else HEARD_LOCK_MESSAGE
        self.report(ErrorKind.STATE, said, "lock")
        log.warning("%s: %s", self.id, said)
        return True

    def note(self, message: str) -> None:
        """Show ``message`` as the status's last error (a problem found outside the rotator)."""
        self._mailbox.put_note(message)

    def report_refusal(
        self, message: str, command: str | None, *, origin: Origin | None = None
    ) -> None:
        """Publish a refusal (also for input that never became a command, e.g. a bad payload);
        with ``origin`` (who sent it) it is in the audit trail too."""
        self.report(ErrorKind.REFUSED, message, command)
        if origin is not None:
            self.audit_refusal(message, command or "input", origin)

    def audit_refusal(self, message: str, command: str, origin: Origin) -> None:
        """A refusal in the audit trail alone (a group's command refused before it was split
        among its members, said once on ``G/error``: interfaces/mqtt/service.py rule 10)."""
        self.operators.audit(origin, command, f"refused: {message}")

    def report(self, kind: ErrorKind, message: str, command: str | None) -> None:
        self._mailbox.put_note(message)
        self._on_event(ErrorEvent(kind, message, command, self._wall()))

    def _check(self, command: ControllerCommand) -> ControllerCommand:
        """``command`` as it goes to the controller (targets in raw values), or Refused."""
        if isinstance(command, Stop):
            return command
        if isinstance(command, SetOption):
            setting = self.spec.setting(command.name)
            if setting is None:
                have = ", ".join(self.spec.options) or "none"
                name = command.name  # (cut short: any name an interface took, of any length)
                shown = repr(name) if len(name) <= 40 else f"{name[:40]!r}… ({len(name)} chars)"
                raise Refused(
                    RefusalCode.UNSUPPORTED,
                    f"{self.spec.display_name} has no option {shown} (options: {have})",
                )
            try:  # the declaration is the judge of a value (protocols/base.py rule 6)
                judged = replace(command, value=setting.read(command.value))
            except ValueError as exc:
                raise Refused(RefusalCode.INVALID, f"option {exc}") from None
            # a setting is control too (a speed in the middle of a turn): the lease's
            leased = self.operators.refusal(self._who(command))
            if leased is not None:
                raise Refused(RefusalCode.LEASED, leased)
            return judged
        self._check_motion(self._who(command))
        status = self.status
        offline = not status.available
        if offline and status.raw_bearing_deg is None and command.within_deg is not None:
            # a group member's limits need a reading (pointing.py rule 9): the link is why
            # there is none, and the refusal says so, not the limits (a review)
            raise Refused(RefusalCode.OFFLINE, OFFLINE_MESSAGE)
        raw = self.pointing.judge(command, status.raw_bearing_deg)  # pointing.py: the judge
        if offline:
            raise Refused(RefusalCode.OFFLINE, OFFLINE_MESSAGE)
        return raw

    @staticmethod
    def _who(command: Target | SetOption) -> str:
        return sender(command.origin, command.source)

    def check_motion(self, origin: Origin) -> None:
        """Refused if motion from ``origin`` would be refused now for the lock, the wind or the
        lease (``_check_motion``): for a front end that asks a command and submits it a while
        later (the DX cluster's call), judged when asked too; reported by the caller."""
        self._check_motion(origin.who)

    def _check_motion(self, who: str) -> None:
        """Refused for motion now, in this order (docs/architecture.md rule 11; never asked
        for a stop or lock): the lock (or one not known yet), then the wind (safety), then the
        lease (coordination);
        the pointing judge and the link come after, in ``_check``."""
        if self._kept.locked:  # the owner's lock: the one copy (kept.py rule 2)
            raise Refused(RefusalCode.LOCKED, "rotator is locked (safety lock ON): motion refused")
        if self._unheard and self._kept.lock_unsaid:  # kept.py rule 10: not known yet
            raise Refused(RefusalCode.LOCKED, UNHEARD_LOCK_MESSAGE)
        wind = self.status.wind
        if wind is not None and wind.refusal:  # session/wind.py rule 1
            raise Refused(RefusalCode.LOCKED, wind.refusal)
        leased = self.operators.refusal(who)
        if leased is not None:
            raise Refused(RefusalCode.LEASED, leased)
