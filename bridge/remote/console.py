"""The operator console on the remote: the station's rotators, as the console
(bridge/interfaces/web/) asks for them (interfaces/web/port.py), driven by publishing on the
station's command topics, and the live feed from the station's retained topics.

Rules:
1. Every console command is one publish on the station's own command topic (docs/mqtt.md:
   ``R/target`` as JSON, a place too; ``R/stop``, ``R/lock``, ``R/preset``, ``R/park``,
   ``R/nudge``, ``R/track``), sent by the remote's rotator as the other front ends' are
   (rotator.py rule 3), through the remote's link: QoS 1, an expiry, the operator
   (interfaces/mqtt/remote.py rules 2 and 3). While the link is down each is refused with OFFLINE at
   once, STOP and lock ON included (they cannot be delivered); while it is up, STOP, the lock and
   tracking off are sent whatever the remote thinks of the station (a lock ON the station's
   bridge may not hear is answered as not delivered all the same: rotator.py rule 3). A
   command that moves is refused at once too while the station is not current (rotator.py
   rule 1: its bridge or the rotator offline, no heartbeat), locked or leased to another
   (rotator.py rule 6), as the station's judge would refuse it.
2. The station's judge has the last word: what it refuses comes back on ``R/error`` and reaches
   every page as an error event. What the remote refuses itself (offline, a target outside the
   station's ranges) is reported to the pages alone: the station never heard of it.
3. A status reaches the pages only as RemoteRotator.status has it (rotator.py rule 1): while the
   station is not current (the link down, the bridge or the rotator offline, a moving status
   gone quiet) the page gets the rotator unavailable, never the last bearing seen.
4. ``on_message`` and ``on_link`` run on paho's thread: a JSON parse and a hand-over
   (``WebConsole.on_status`` only queues onto the console's loop; docs/architecture.md rule 3).
   A status goes on only when it changed. A ticker re-reads every rotator each TICK_S, so a
   moving status that has gone quiet turns unavailable without a message.
5. What the console draws beyond the judge's terms (the station's position, the beamwidth, the
   nudge step, the satellites) is the station's ``R/info``; the presets are its ``R/presets``,
   read at each use (they may come after the description).
6. Who sent a command (``origin``, interfaces/web/port.py rule 4) is taken and not sent: the station
   hears the remote's operator (interfaces/mqtt/remote.py), the one name it knows this console by.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Protocol

from bridge.core.errors import RefusalCode, Refused
from bridge.core.haltwatch import HaltWatchers
from bridge.core.model import (
    Command,
    ErrorEvent,
    ErrorKind,
    Origin,
    RotatorStatus,
    Source,
    TrackBody,
    describe_command,
)
from bridge.pointing import Pointing
from bridge.protocols.base import ModelSpec
from bridge.remote.readings import load
from bridge.remote.rotator import STATION_AWAY, RemoteRotator, StationView

log = logging.getLogger(__name__)

TICK_S = 1.0  # rule 4
OFFLINE = STATION_AWAY


@dataclass(frozen=True)
class Drawn:
    """Rule 5: ``R/info``'s console fields (docs/mqtt.md), with the bridge's defaults when a
    station's bridge is older and has none."""

    can_track: bool = False
    station: tuple[float, float] | None = None
    locator: str | None = None
    beamwidth_deg: float = 60.0
    nudge_step_deg: float = 5.0
    satellites: tuple[str, ...] = ()

    @classmethod
    def parse(cls, payload: bytes) -> Drawn:
        doc = load(payload)
        where = doc.get("station")
        station, locator = None, None
        if isinstance(where, dict):
            station = (float(where["latitude"]), float(where["longitude"]))
            locator = where.get("locator") if isinstance(where.get("locator"), str) else None
        sats = doc.get("satellites")
        return cls(
            can_track=bool(doc.get("can_track")),
            station=station,
            locator=locator,
            beamwidth_deg=float(doc.get("beamwidth", 60.0)),
            nudge_step_deg=float(doc.get("nudge_step", 5.0)),
            satellites=tuple(str(n) for n in sats) if isinstance(sats, list) else (),
        )


def parse_presets(payload: bytes | None) -> dict[str, tuple[float, float | None]]:
    """``R/presets``: name -> azimuth or [azimuth, elevation]; anything else is left out."""
    try:
        doc = load(payload) if payload else {}  # (readings.py rule 1)
    except ValueError:
        return {}
    out: dict[str, tuple[float, float | None]] = {}
    for name, value in doc.items() if isinstance(doc, dict) else ():
        try:
            if isinstance(value, int | float) and not isinstance(value, bool):
                out[str(name)] = (float(value), None)
            elif isinstance(value, list) and len(value) == 2:
                out[str(name)] = (float(value[0]), float(value[1]))
        except (TypeError, ValueError, OverflowError):  # (an integer past a float's range)
            continue
    return out


def parse_event(payload: bytes) -> ErrorEvent | None:
    """``R/error`` (docs/mqtt.md) back into an ErrorEvent; None when it is not one."""
    try:
        doc = load(payload)
        return ErrorEvent(
            ErrorKind(doc["kind"]),
            str(doc["message"]),
            doc.get("command") if isinstance(doc.get("command"), str) else None,
            float(doc["time"]),
        )
    except (ValueError, KeyError, TypeError, OverflowError):
        return None


class Pages(Protocol):
    """Where statuses and events go: the WebConsole (server.py), which only queues."""

    def on_status(self, rotator_id: str, status: RotatorStatus) -> None: ...
    def on_event(self, rotator_id: str, event: ErrorEvent) -> None: ...


class RemoteConsoleRotator:
    """A station rotator as the console asks for it (interfaces/web/port.py), rules 1, 2 and 5."""

    def __init__(
        self,
        remote: RemoteRotator,
        drawn: Drawn,
        view: StationView,
        wall: Callable[[], float] = time.time,
    ) -> None:
        self.remote = remote
        self.drawn = drawn
        self._view = view
        self._wall = wall
        self.pages: Pages | None = None  # set once the console is built (run.py)

    # -- what it is ----------------------------------------------------------------------------
    @property
    def id(self) -> str:
        return self.remote.id

    @property
    def name(self) -> str:
        return self.remote.name

    @property
    def spec(self) -> ModelSpec:
        return self.remote.spec

    @property
    def pointing(self) -> Pointing:
        """The station's terms, with its presets as they are now (rule 5)."""
        presets = parse_presets(self._view.get(self.remote.topics.presets))
        return replace(self.remote.pointing, presets=presets)

    @property
    def can_track(self) -> bool:
        return self.drawn.can_track

    @property
    def last_halt_s(self) -> float:
        return self.remote.last_halt_s

    @property
    def halts(self) -> int:
        """interfaces/web/port.py rule 2b: the stops and lock ONs of the remote's other front
        ends (the console's own are ordered by its queue of commands)."""
        return self.remote.halts_besides(Source.WEB)

    @property
    def halt_watchers(self) -> HaltWatchers:
        """Told before each halt of the remote's front ends is counted (remote/rotator.py
        ``halted``): the console looks at its connections then (interfaces/web/looks.py)."""
        return self.remote.halt_watchers

    def on_its_way(self) -> bool:
        """The station's judge says what is on its way there (server.py rule 10 is not for a
        rotator whose commands block)."""
        return False

    @property
    def commands_block(self) -> bool:
        # a command waits for the broker's acknowledgement (interfaces/mqtt/remote.py rule 7)
        return True

    @property
    def status(self) -> RotatorStatus:
        return self.remote.status  # rule 3

    # -- commands (rule 1) ---------------------------------------------------------------------
    def submit(
        self, command: Command, described: str | None = None, *, since: int | None = None
    ) -> None:
        """Rule 1: the remote's rotator sends it (remote/rotator.py rule 3); rule 2: what is
        refused here is told to the pages alone."""
        try:
            if isinstance(command, TrackBody) and not command.off and not self.can_track:
                message = "the station's rotator cannot track (its R/info says so)"  # rule 5
                raise Refused(RefusalCode.UNSUPPORTED, message)
            self.remote.submit(command, described, since=since)
        except Refused as exc:
            self.report_refusal(exc.message, described or describe_command(command))
            raise

    def report_refusal(
        self, message: str, command: str | None, *, origin: Origin | None = None
    ) -> None:
        """Rule 2: to the pages alone."""
        if self.pages is not None:
            event = ErrorEvent(ErrorKind.REFUSED, message, command, self._wall())
            self.pages.on_event(self.id, event)


class ConsoleFeed:
    """Rules 3 and 4: the station's messages to the pages."""

    def __init__(self, rotators: list[RemoteConsoleRotator], pages: Pages) -> None:
        self._rotators = rotators
        self._pages = pages
        self._lock = threading.Lock()
        self._shown: dict[str, RotatorStatus] = {}
        self._stopping = threading.Event()
        self._ticker: threading.Thread | None = None

    def start(self) -> None:
        self.refresh()
        self._ticker = threading.Thread(target=self._ticking, name="remote-console", daemon=True)
        self._ticker.start()

    def stop(self) -> None:
        self._stopping.set()
        if self._ticker is not None:
            self._ticker.join(timeout=5.0)

    def on_message(self, topic: str, payload: bytes, replayed: bool = False) -> None:
        """paho's thread (rule 4). An error event the broker replays from its store is old news
        (the station never retains one): not shown."""
        for rot in self._rotators:
            t = rot.remote.topics
            if topic == t.error:
                event = None if replayed else parse_event(payload)
                if event is not None:
                    self._pages.on_event(rot.id, event)
                return
        self.refresh()  # a status, an availability, the bridge's state: cheap for a few

    def refresh(self) -> None:
        """Each rotator's status as the remote reads it, to the pages when it changed."""
        with self._lock:
            for rot in self._rotators:
                status = rot.remote.status
                if self._shown.get(rot.id) != status:
                    self._shown[rot.id] = status
                    self._pages.on_status(rot.id, status)

    def _ticking(self) -> None:
        while not self._stopping.wait(TICK_S):
            try:
                self.refresh()
            except Exception:  # docs/architecture.md rule 8: the link goes on
                log.exception("remote console: a status could not be read")


def drawn_of(payload: bytes | None) -> Drawn:
    """``R/info``'s console fields, or the defaults when it has none that can be read."""
    try:
        return Drawn.parse(payload or b"{}")
    except (ValueError, KeyError, TypeError, AttributeError, OverflowError) as exc:
        log.warning("the station's description has console fields that cannot be read: %s", exc)
        return Drawn()
