"""A rotator as the front ends (MQTT, rotctld) see it: submit commands, read the status.

This is the one judge of commands: every front end submits here, and here alone are the safety
lock, the configured limits and keep-out sectors (pointing.py: targets arrive as true bearings
and leave as the controller's raw values), the model's capabilities and the link state checked
against a command. A refused command raises Refused (with a RefusalCode front ends map, e.g.
to a Hamlib RPRT number) and is reported as an error event; it never reaches the mailbox, so it
can never move anything. The worker judges nothing anew: it only drops an accepted target that
the lock or a lost link overtook before it could be sent, and reports that as a refusal too.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

import serial

from bridge.engine.catalog import CatalogError, TleCatalog
from bridge.engine.follow import Follow, Heard
from bridge.engine.lines import Lines
from bridge.engine.mailbox import Mailbox
from bridge.engine.port import open_port
from bridge.engine.skywork import LookupQuestion, SkyWorker
from bridge.engine.state_store import StateStore
from bridge.engine.tracking import Track
from bridge.engine.worker import Worker, WorkerConfig
from bridge.errors import RefusalCode, Refused
from bridge.model import (
    Command,
    ErrorEvent,
    ErrorKind,
    RotatorStatus,
    SetOption,
    Source,
    Stop,
    Target,
    describe_command,
)
from bridge.pointing import Pointing, toward
from bridge.protocols.base import ModelSpec
from bridge.sky import Body, SkyError

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Limits:
    az_min_deg: float
    az_max_deg: float
    el_min_deg: float = 0.0
    el_max_deg: float = 0.0

    @classmethod
    def of(cls, p: Pointing) -> Limits:
        """The mechanical limits of a rotator's terms (the controller's raw values)."""
        return cls(p.az_min_deg, p.az_max_deg, p.el_min_deg, p.el_max_deg)


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
    ) -> None:
        self.id = cfg.rotator_id
        self.name = name or cfg.rotator_id
        self.spec: ModelSpec = cfg.spec
        self.pointing = cfg.aim  # limits, offset, keep-out, presets, park: the judge's terms
        self.station = station  # (latitude, longitude): targets by locator or coordinates
        self.catalog = catalog or TleCatalog(None)  # satellites to track by name
        self._has_sky = cfg.tracking.sky is not None
        self.can_track = self._has_sky and cfg.spec.can_report_position
        self._follow = cfg.follow  # follow.py: the station, the [wsjtx] listener
        self._store = store
        self._on_event = on_event
        self._wall = wall
        self._locked = store.locked(self.id)
        self._save_lock = threading.Lock()
        self._mailbox = Mailbox()
        self._worker = Worker(
            cfg,
            self._mailbox,
            on_status,
            on_event,
            options=self._supported_options(store),
            locked=self._locked,
            wall=wall,
            port_opener=port_opener,
            sky=sky,  # the app shares one among all rotators (skywork.py)
        )
        self._lines = lines or Lines(clock)  # the app shares one among all rotators
        self._stopped = False
        # when a STOP or lock ON was last put in the mailbox (monotonic), from any front end: a
        # front end whose commands can overtake each other (the console) refuses one that was
        # under way before it (web/commands.py rule 5)
        self.last_halt_s = -math.inf
        problem = store.problems.get(self.id)
        if problem is not None:  # the lock is ON for it; the status's last error says why
            self._mailbox.put_note(problem)

    def _supported_options(self, store: StateStore) -> dict[str, bool]:
        """Options remembered for this id that this model has (the id may have been another)."""
        kept = {}
        for name, enabled in store.options(self.id).items():
            if name in self.spec.options:
                kept[name] = enabled
            else:
                log.warning(
                    "%s: stored option %r ignored: %s has no such option",
                    self.id,
                    name,
                    self.spec.display_name,
                )
        return kept

    @property
    def status(self) -> RotatorStatus:
        return self._worker.session.status

    @property
    def limits(self) -> Limits:
        """The mechanical limits (the controller's raw values)."""
        return Limits.of(self.pointing)

    @property
    def locked(self) -> bool:
        return self._locked

    def start(self) -> None:
        """Once: a stopped rotator's mailbox is closed (build a new Rotator instead)."""
        if self._stopped:
            raise RuntimeError(f"{self.id}: a stopped rotator cannot start again")
        self._lines.add(self._worker)

    def stop(self, timeout_s: float = 3.0) -> None:
        self._stopped = True
        if self._lines.remove(self._worker, timeout_s):
            self._mailbox.close()  # only once nothing can wait on it any more

    def submit(
        self, command: Command, described: str | None = None, *, hold: int | None = None
    ) -> None:
        """Queue a command or raise Refused. Stop is never refused; ``hold`` (a stop from the
        stop lane): no target goes out until ``release`` reaches that marker (session rule 13)."""
        try:
            judged = self._check(command)
        except Refused as exc:
            self.report_refusal(exc.message, described or describe_command(command))
            raise
        if isinstance(command, SetOption):
            name, enabled = command.name, command.enabled
            self._store.later(lambda: self._save_option(name, enabled))  # state_store rule 5
        if isinstance(command, Stop):
            self.last_halt_s = time.monotonic()
        self._mailbox.put(judged, hold=hold if isinstance(command, Stop) else None)

    def release(self, marker: int, *, clear: bool = False) -> None:
        """The holds up to ``marker`` end (``clear``: what waits meanwhile is dropped)."""
        self._mailbox.put_release(marker, clear=clear)

    # -- the other ways of naming a target (pointing.py rule 6), judged like any --------------
    def go_to_preset(self, name: str, source: Source, described: str) -> None:
        self._named(lambda: Target(*self.pointing.preset(name), source), described)

    def park(self, source: Source, described: str) -> None:
        self._named(lambda: Target(*self.pointing.parking(), source, park=True), described)

    def go_toward(
        self,
        latitude_deg: float,
        longitude_deg: float,
        source: Source,
        described: str,
        *,
        locator: str | None = None,
        long_path: bool = False,
    ) -> None:
        def target() -> Target:
            az, info = toward(
                self.station, latitude_deg, longitude_deg, long_path=long_path, locator=locator
            )
            return Target(az, None, source, info=info)

        self._named(target, described)

    def take_path(self, long_path: bool, source: Source, described: str) -> None:
        """The place of the current locator or coordinate target, by the path asked for."""
        info = self.status.target_info
        if info is None:
            message = "no locator or coordinate target to take the other path to"
            self.report_refusal(message, described)
            raise Refused(RefusalCode.INVALID, message)
        self.go_toward(
            info.latitude_deg,
            info.longitude_deg,
            source,
            described,
            locator=info.locator,
            long_path=long_path,
        )

    def nudge(self, d_az: float, d_el: float | None, source: Source, described: str) -> None:
        self._named(
            lambda: Target(*self.pointing.nudged(self.status, d_az, d_el), source), described
        )

    def track(
        self,
        name: str,
        source: Source,
        described: str,
        tle: tuple[str, str, str] | None = None,
    ) -> None:
        """Follow the sun, the moon or a satellite (by name from the TLE file, or ``tle``);
        ``off`` ends it (never refused, like a stop). Raise Refused otherwise. A name is looked
        up in the TLE file by the sky worker, not here (paho's thread): an unknown one is
        refused by the session, as an error event."""
        if name.strip().casefold() == "off" and tle is None:
            self._mailbox.put_track(Track(None, source))
            return
        try:
            body = self._body(name, tle)
            if self._locked:
                raise Refused(RefusalCode.LOCKED, "rotator is locked (safety lock ON)")
            if not self.status.available:
                raise Refused(
                    RefusalCode.OFFLINE, "rotator offline (serial link down or controller silent)"
                )
        except Refused as exc:
            self.report_refusal(exc.message, described)
            raise
        if body is None:
            lookup = LookupQuestion(self.catalog, name)
            self._mailbox.put_track(Track(None, source, lookup, described))
            return
        self._mailbox.put_track(Track(body, source, None, described))

    @property
    def can_follow(self) -> bool:
        """A QSO partner can be followed: the [wsjtx] listener runs and the station is known."""
        return self._follow.wsjtx and self._follow.station is not None

    def follow(self, on: bool, source: Source, described: str, *, long_path: bool = False) -> None:
        """Follow the QSO partner WSJT-X names (follow.py); off ends it (never refused, like a
        stop). Raise Refused otherwise."""
        if not on:
            self._mailbox.put_follow(Follow(False, source=source, described=described))
            return
        try:
            if not self._follow.wsjtx:
                raise Refused(
                    RefusalCode.UNSUPPORTED,
                    "following WSJT-X needs its messages: [wsjtx] enabled = true",
                )
            if self._follow.station is None:
                raise Refused(
                    RefusalCode.UNSUPPORTED,
                    "following WSJT-X needs the station's position ([station] locator, or "
                    "latitude_deg and longitude_deg): bearings are from there",
                )
            if self._locked:
                raise Refused(RefusalCode.LOCKED, "rotator is locked (safety lock ON)")
            if not self.status.available:
                raise Refused(
                    RefusalCode.OFFLINE, "rotator offline (serial link down or controller silent)"
                )
        except Refused as exc:
            self.report_refusal(exc.message, described)
            raise
        self._mailbox.put_follow(Follow(True, long_path, source, described))

    def wind(self, speed_kmh: float) -> None:
        """A wind reading (MQTT's thread): an input for the wind park (engine/wind.py)."""
        self._mailbox.put_wind(speed_kmh)

    def heard(self, heard: Heard) -> None:
        """What WSJT-X says of the QSO (wsjtx/server.py's thread): an input for following."""
        self._mailbox.put_heard(heard)

    def _body(self, name: str, tle: tuple[str, str, str] | None) -> Body | None:
        """The body to track, or None for a satellite to look up in the TLE file."""
        if not self._has_sky:
            raise Refused(
                RefusalCode.UNSUPPORTED,
                "tracking needs the station's position ([station] locator, or latitude_deg "
                "and longitude_deg)",
            )
        if not self.spec.can_report_position:
            raise Refused(
                RefusalCode.UNSUPPORTED,
                f"the {self.spec.display_name} cannot report where it points: tracking needs a "
                "controller that does",
            )
        try:
            if tle is not None:
                return Body.satellite(*tle)
            folded = name.strip().casefold()
            if folded == "sun":
                return Body.sun()
            if folded == "moon":
                return Body.moon()
            self.catalog.check_configured(name)
            return None
        except (SkyError, CatalogError) as exc:
            raise Refused(RefusalCode.INVALID, str(exc)) from None

    def _named(self, make: Callable[[], Target], described: str) -> None:
        try:
            target = make()
        except Refused as exc:
            self.report_refusal(exc.message, described)
            raise
        self.submit(target, described)

    def set_lock(self, locked: bool, *, hold: int | None = None, save: bool = True) -> None:
        """``hold`` as for ``submit``; ``save=False``: the caller calls ``save_lock`` after
        (outside its own lock: the state file is written with an fsync)."""
        self._locked = locked
        if locked:
            self.last_halt_s = time.monotonic()
        self._mailbox.put_lock(locked, hold=hold)
        if save:
            self.save_lock()

    def _save_option(self, name: str, enabled: bool) -> None:
        if not self._store.set_option(self.id, name, enabled):
            self.report(
                ErrorKind.STATE,
                f"option {name} is in effect but could not be saved: it will not survive a "
                "restart (state file not writable)",
                name,
            )

    def save_lock(self) -> None:
        """The lock to the state file, on its writer thread (state_store.py rule 5): each save
        writes the lock as it is when it runs, so the last one writes the newest word."""
        self._store.later(self._save_lock_now)

    def _save_lock_now(self) -> None:
        with self._save_lock:
            locked = self._locked
            saved = self._store.set_locked(self.id, locked)
        if not saved:
            self.report(
                ErrorKind.STATE,
                f"lock {'ON' if locked else 'OFF'} is in effect but could not be saved: "
                "it will not survive a restart (state file not writable)",
                "lock",
            )

    def note(self, message: str) -> None:
        """Show ``message`` as the status's last error (a problem found outside the rotator)."""
        self._mailbox.put_note(message)

    def report_refusal(self, message: str, command: str | None) -> None:
        """Publish a refusal (also for input that never became a command, e.g. a bad payload)."""
        self.report(ErrorKind.REFUSED, message, command)

    def report(self, kind: ErrorKind, message: str, command: str | None) -> None:
        self._mailbox.put_note(message)
        self._on_event(ErrorEvent(kind, message, command, self._wall()))

    def _check(self, command: Command) -> Command:
        """``command`` as it goes to the controller (targets in raw values), or Refused."""
        if isinstance(command, Stop):
            return command
        if isinstance(command, SetOption):
            if command.name not in self.spec.options:
                have = ", ".join(self.spec.options) or "none"
                raise Refused(
                    RefusalCode.UNSUPPORTED,
                    f"{self.spec.display_name} has no option {command.name!r} (options: {have})",
                )
            return command
        if self._locked:
            raise Refused(RefusalCode.LOCKED, "rotator is locked (safety lock ON): motion refused")
        status = self.status
        if status.wind is not None and status.wind.refusal:  # engine/wind.py rule 1
            raise Refused(RefusalCode.LOCKED, status.wind.refusal)
        raw = self.pointing.judge(command, status.raw_bearing_deg)  # pointing.py: the judge
        if not status.available:
            raise Refused(
                RefusalCode.OFFLINE, "rotator offline (serial link down or controller silent)"
            )
        return raw
