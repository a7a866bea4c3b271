"""A rotator as the front ends (MQTT, rotctld) see it: submit commands, read the status.

This is the one judge of commands: every front end submits here, and here alone are the safety
lock, the configured limits, the model's capabilities and the link state checked against a
command. A refused command raises Refused (with a RefusalCode front ends map, e.g. to a Hamlib
RPRT number) and is reported as an error event; it never reaches the mailbox, so it can never
move anything. The worker judges nothing anew: it only drops an accepted target that the lock
or a lost link overtook before it could be sent, and reports that as a refusal too.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import serial

from bridge.engine.lines import Lines
from bridge.engine.mailbox import Mailbox
from bridge.engine.port import open_port
from bridge.engine.state_store import StateStore
from bridge.engine.worker import Worker, WorkerConfig
from bridge.errors import RefusalCode, Refused
from bridge.model import (
    Command,
    ErrorEvent,
    ErrorKind,
    RotatorStatus,
    SetOption,
    Stop,
    Target,
    describe_command,
)
from bridge.protocols.base import ModelSpec

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Limits:
    az_min_deg: float
    az_max_deg: float
    el_min_deg: float = 0.0
    el_max_deg: float = 0.0


class Rotator:
    def __init__(
        self,
        cfg: WorkerConfig,
        limits: Limits,
        store: StateStore,
        on_status: Callable[[RotatorStatus], None],
        on_event: Callable[[ErrorEvent], None],
        name: str | None = None,
        *,
        clock: Callable[[], float] = time.monotonic,
        wall: Callable[[], float] = time.time,
        port_opener: Callable[..., serial.Serial] = open_port,
        lines: Lines | None = None,
    ) -> None:
        self.id = cfg.rotator_id
        self.name = name or cfg.rotator_id
        self.spec: ModelSpec = cfg.spec
        self.limits = limits
        self._store = store
        self._on_event = on_event
        self._wall = wall
        self._locked = store.locked(self.id)
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
        )
        self._lines = lines or Lines(clock)  # the app shares one among all rotators
        self._stopped = False

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

    def submit(self, command: Command, described: str | None = None) -> None:
        """Queue a command or raise Refused. Stop is never refused."""
        try:
            self._check(command)
        except Refused as exc:
            self.report_refusal(exc.message, described or describe_command(command))
            raise
        if isinstance(command, SetOption):
            self._store.set_option(self.id, command.name, command.enabled)
        self._mailbox.put(command)

    def set_lock(self, locked: bool) -> None:
        self._locked = locked
        self._mailbox.put_lock(locked)
        if not self._store.set_locked(self.id, locked):
            self.report(
                ErrorKind.STATE,
                f"lock {'ON' if locked else 'OFF'} is in effect but could not be saved: "
                "it will not survive a restart (state file not writable)",
                "lock",
            )

    def report_refusal(self, message: str, command: str | None) -> None:
        """Publish a refusal (also for input that never became a command, e.g. a bad payload)."""
        self.report(ErrorKind.REFUSED, message, command)

    def report(self, kind: ErrorKind, message: str, command: str | None) -> None:
        self._mailbox.put_note(message)
        self._on_event(ErrorEvent(kind, message, command, self._wall()))

    def _check_rounded(self, axis: str, value_deg: float, lo_deg: float, hi_deg: float) -> None:
        """A controller that takes whole degrees must not be rounded past a limit."""
        if self.spec.whole_degrees and not lo_deg <= _rounded(value_deg) <= hi_deg:
            raise Refused(
                RefusalCode.LIMITS,
                f"{axis} {value_deg:g} becomes {_rounded(value_deg):g} on the "
                f"{self.spec.display_name} (whole degrees), outside the limits "
                f"{lo_deg:g}..{hi_deg:g}",
            )

    def _check(self, command: Command) -> None:
        if isinstance(command, Stop):
            return
        if isinstance(command, SetOption):
            if command.name not in self.spec.options:
                have = ", ".join(self.spec.options) or "none"
                raise Refused(
                    RefusalCode.UNSUPPORTED,
                    f"{self.spec.display_name} has no option {command.name!r} (options: {have})",
                )
            return
        assert isinstance(command, Target)
        if self._locked:
            raise Refused(RefusalCode.LOCKED, "rotator is locked (safety lock ON): motion refused")
        lim = self.limits
        if command.az_deg is None and command.el_deg is None:
            raise Refused(RefusalCode.INVALID, "target without azimuth or elevation")
        if command.az_deg is not None:
            _check_axis("azimuth", command.az_deg, lim.az_min_deg, lim.az_max_deg)
            self._check_rounded("azimuth", command.az_deg, lim.az_min_deg, lim.az_max_deg)
        if command.el_deg is not None:
            if not self.spec.has_elevation:
                raise Refused(
                    RefusalCode.UNSUPPORTED, f"{self.spec.display_name} has no elevation axis"
                )
            _check_axis("elevation", command.el_deg, lim.el_min_deg, lim.el_max_deg)
            self._check_rounded("elevation", command.el_deg, lim.el_min_deg, lim.el_max_deg)
        if not self.status.available:
            raise Refused(
                RefusalCode.OFFLINE, "rotator offline (serial link down or controller silent)"
            )


def _rounded(value_deg: float) -> float:
    return float(math.floor(value_deg + 0.5))


def _check_axis(axis: str, value_deg: float, lo_deg: float, hi_deg: float) -> None:
    if not math.isfinite(value_deg) or not lo_deg <= value_deg <= hi_deg:
        raise Refused(
            RefusalCode.LIMITS, f"{axis} {value_deg:g} outside the limits {lo_deg:g}..{hi_deg:g}"
        )
