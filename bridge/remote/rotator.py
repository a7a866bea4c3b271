"""One station rotator as the remote sees it: what rotctld's, GS-232's and the loggers' commands
ask of a Rotator (``id``, ``spec``, ``pointing``, ``limits``, ``status``, ``submit``, ``park``,
``go_toward``, ``report_refusal``), answered from the station's retained topics and carried out
by publishing on its command topics.

Rules:
1. ``status`` is the newest retained ``R/status`` read back into a RotatorStatus, and counts only
   while it is current: the remote connected, ``B/bridge/state`` and ``R/availability`` both
   received as ``online`` on this connection (positive word, whatever order they come in).
   Otherwise the rotator reads as unavailable (rotctld answers an error code), never as the
   last number seen. The station publishes a status when something changes, not on a clock,
   so the age of a still rotor's status says nothing about staleness: the bridge's last will
   and the availability topic do. A MOVING rotor's bearing changes with every poll, so a
   ``moving`` status counts only while one came from the station, as it published it, within
   ``moving_max_age_s`` on the remote's own clock: older, the station went quiet mid-move (its
   last will comes only after 1.5 keepalives); replayed from the broker's store (the retain
   flag, mqtt/remote.py rule 4), it is of unknown age until the next one. Its ``time`` is the
   station's clock, which need not agree with ours: not used.
2. What the rotator is comes from the station's ``R/info``: the model (its ModelSpec, for
   Hamlib's facts), the target ranges in true bearings, park. Nothing of it is configured here.
   The remote judges a target against these facts (a target out of range or in a keep-out
   sector gets its error code at once), but the station's judge is the one that counts: what
   it refuses (the lock, say) is on ``R/error``, while the client got RPRT 0 once the command
   was on its way.
3. ``submit``: a Target is published on ``R/target`` as JSON, a Stop on ``R/stop``, through the
   link (mqtt/remote.py: QoS 1, expiry, operator). While the link is down both are refused with
   OFFLINE at once. A command that moves (a target, park, a place) is refused with OFFLINE at
   once too while the station is not current (rule 1: its bridge or the rotator offline), as
   the station's own rotctld refuses it for a rotator offline: nobody would take it. A stop is
   refused only while the link is down: the station's bridge may be offline on its main
   connection and still take a stop on its stop lane (mqtt/lane.py).
4. The other ways the front ends name a target (what the GS-232, Easycomm and PstRotator
   endpoints use of a Rotator): ``park`` goes to ``R/park`` when the station has a park
   position, ``go_toward`` sends the place itself (``{"locator": ...}`` or coordinates) on
   ``R/target``: the station knows where it is, the remote does not.
5. A refusal here (not connected, out of range, no park) is logged, at most once per
   REFUSAL_LOG_S and front end with the count since (Gpredict sends a target every few
   seconds), and raised; the station's own refusals are on its ``R/error``, not the remote's.
"""

from __future__ import annotations

import json
import logging
import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from datetime import datetime
from typing import Any, Protocol

from bridge.errors import RefusalCode, Refused
from bridge.model import (
    Command,
    MotionState,
    RotatorStatus,
    Source,
    Stop,
    Target,
    TargetInfo,
    TrackingInfo,
)
from bridge.mqtt.topics import RotatorTopics
from bridge.pointing import Limits, Pointing
from bridge.protocols import REGISTRY
from bridge.protocols.base import ModelSpec

log = logging.getLogger(__name__)

REFUSAL_LOG_S = 10.0  # rule 5
STATION_AWAY = "the station's rotator is offline (its bridge or its controller): nothing sent"


class Sender(Protocol):
    @property
    def up(self) -> bool: ...

    def send(self, topic: str, payload: str, operator: str, expiry_s: int) -> None: ...


class InfoError(ValueError):
    """The station's R/info cannot be used (a model this version does not know)."""


@dataclass(frozen=True)
class Info:
    """The station's ``R/info``, parsed."""

    name: str
    spec: ModelSpec
    pointing: Pointing

    @classmethod
    def parse(cls, payload: bytes) -> Info:
        doc = json.loads(payload)
        model = str(doc["model"])
        spec = REGISTRY.get(model)
        if spec is None:
            raise InfoError(f"the station's model {model!r} is unknown to this rotor-bridge")
        az_lo, az_hi = (_finite(v) for v in doc["azimuth_range"])
        el = doc.get("elevation_range") or [spec.el_min_deg, spec.el_max_deg]
        park = doc.get("park") or None
        at = (_finite(park[0]), None if park[1] is None else _finite(park[1])) if park else None
        # the station's ranges are true bearings already: no offset here (pointing.py rule 1)
        aim = Pointing.of(
            spec,
            (az_lo, az_hi),
            (_finite(el[0]), _finite(el[1])),
            keep_out=tuple((_finite(a), _finite(b)) for a, b in doc.get("keep_out") or ()),
            park=at,
        )
        return cls(str(doc.get("name") or model), spec, aim)


def _finite(value: object) -> float:
    """A number of R/info; ValueError for NaN and infinities: the judge would raise on them."""
    try:
        n = float(value)  # type: ignore[arg-type]  # TypeError for what is no number: caller's
    except OverflowError:  # an integer past a float's range
        n = math.inf
    if not math.isfinite(n):
        raise ValueError(f"{value!r:.20} is not a finite number")
    return n


def _num(doc: dict[str, Any], key: str) -> float | None:
    """A number, or None (Python's json reads NaN, Infinity, 1e400: never shown, rule 1)."""
    v = doc.get(key)
    if not isinstance(v, int | float) or isinstance(v, bool):
        return None
    try:
        return _finite(v)
    except ValueError:
        return None


def _unix(text: object) -> float | None:
    try:
        return datetime.fromisoformat(str(text)).timestamp() if text is not None else None
    except ValueError:
        return None


def _target_info(doc: object) -> TargetInfo | None:
    if not isinstance(doc, dict):
        return None
    lat, lon = _num(doc, "latitude"), _num(doc, "longitude")
    short, long = _num(doc, "short_path_deg"), _num(doc, "long_path_deg")
    if lat is None or lon is None or short is None or long is None:
        return None
    locator = doc.get("locator")
    return TargetInfo(
        lat,
        lon,
        _num(doc, "distance_km") or 0.0,
        short,
        long,
        "long" if doc.get("path") == "long" else "short",
        locator if isinstance(locator, str) else None,
    )


def _tracking(doc: object) -> TrackingInfo | None:
    if not isinstance(doc, dict) or not isinstance(doc.get("body"), str):
        return None
    nxt_or = doc.get("next")
    nxt: dict[str, Any] = nxt_or if isinstance(nxt_or, dict) else {}
    track = doc.get("pass_track") or []
    return TrackingInfo(
        doc["body"],
        str(doc.get("phase", "")),
        _num(doc, "azimuth"),
        _num(doc, "elevation"),
        _num(nxt, "azimuth"),
        _num(nxt, "elevation"),
        _unix(doc.get("aos")),
        _unix(doc.get("los")),
        _num(doc, "max_elevation"),
        _num(doc, "aos_azimuth"),
        bool(doc.get("flip")),
        tuple((float(a), float(e)) for a, e in track if isinstance(track, list)),
    )


def parse_status(rotator_id: str, payload: bytes) -> RotatorStatus:
    """``R/status`` (docs/mqtt.md) back into a RotatorStatus: what a reading needs, and what
    the console draws (the place targeted, the body tracked)."""
    doc = json.loads(payload)
    if not isinstance(doc, dict):  # anyone allowed on the topic can put any JSON there
        raise ValueError(f"a status is a JSON object, not {type(doc).__name__}")

    def num(key: str) -> float | None:
        return _num(doc, key)

    options = doc.get("options")

    return RotatorStatus(
        rotator_id,
        state=MotionState(doc.get("state", "offline")),
        bearing_deg=num("bearing"),
        elevation_deg=num("elevation"),
        target_az_deg=num("target"),
        target_el_deg=num("target_elevation"),
        connected=bool(doc.get("connected")),
        available=bool(doc.get("available")),
        locked=bool(doc.get("locked")),
        version=doc.get("version"),
        last_error=doc.get("last_error"),
        last_command_source=doc.get("last_command_source"),
        estimated=bool(doc.get("estimated")),
        parked=bool(doc.get("parked")),
        options={str(k): bool(v) for k, v in options.items()} if isinstance(options, dict) else {},
        controller_time=doc.get("controller_time"),
        expected_end_unix=_unix(doc.get("expected_end")),
        raw_bearing_deg=num("raw_bearing"),
        overlap=doc.get("overlap"),
        target_info=_target_info(doc.get("target_info")),
        tracking=_tracking(doc.get("tracking")),
        tracking_ended=doc.get("tracking_ended"),
    )


class StationView:
    """The retained topics the remote reads, newest first; written on paho's thread. Each value
    keeps when it came (``clock``) and whether the broker replayed it from its store."""

    def __init__(self, clock: Callable[[], float] = time.monotonic) -> None:
        self._lock = threading.Condition()
        self._topics: dict[str, bytes] = {}
        self._came: dict[str, tuple[float, bool]] = {}  # topic -> (when, replayed)
        self._clock = clock

    def put(self, topic: str, payload: bytes, replayed: bool = False) -> None:
        with self._lock:
            if payload:
                self._topics[topic] = payload
                self._came[topic] = (self._clock(), replayed)
            else:  # an empty retained message deletes the topic
                self._topics.pop(topic, None)
                self._came.pop(topic, None)
            self._lock.notify_all()

    def clear(self) -> None:
        with self._lock:
            self._topics.clear()
            self._came.clear()

    def live_within(self, topic: str, max_age_s: float) -> bool:
        """Whether ``topic``'s value came as published (not replayed) within ``max_age_s``."""
        with self._lock:
            came = self._came.get(topic)
            return came is not None and not came[1] and self._clock() - came[0] <= max_age_s

    def get(self, topic: str) -> bytes | None:
        with self._lock:
            return self._topics.get(topic)

    def topics(self) -> list[str]:
        with self._lock:
            return list(self._topics)

    def wait(self, timeout_s: float) -> None:  # until the next message or timeout_s
        with self._lock:
            self._lock.wait(timeout_s)


class RemoteRotator:
    """Rule 1-3: one station rotator, its topics under ``B`` or ``B/<id>`` (``topics``)."""

    def __init__(
        self,
        rotator_id: str,
        topics: RotatorTopics,
        bridge_state: str,
        info: Info,
        view: StationView,
        link: Sender,
        operator: str,
        expiry_s: int,
        moving_max_age_s: float = 10.0,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.id = rotator_id
        self.topics = topics
        self.name = info.name
        self.spec = info.spec
        self.pointing = info.pointing
        self._bridge_state = bridge_state
        self._view = view
        self._link = link
        self._operator = operator
        self._expiry_s = expiry_s
        self._moving_max_age_s = moving_max_age_s
        self.last_halt_s = -math.inf  # the last stop sent (monotonic; web/port.py rule 2)
        self._clock = clock
        self._refusals_lock = threading.Lock()  # rule 5: front ends call from their threads
        self._refusals: dict[str, tuple[int, float]] = {}  # front end -> (not logged, when)

    @property
    def limits(self) -> Limits:
        return Limits.of(self.pointing)

    @property
    def link_up(self) -> bool:
        return self._link.up

    @property
    def current(self) -> bool:
        """Rule 1: whether the retained status may be shown."""
        view = self._view
        return (
            self._link.up
            and view.get(self._bridge_state) == b"online"
            and view.get(self.topics.availability) == b"online"
        )

    @property
    def status(self) -> RotatorStatus:
        raw = self._view.get(self.topics.status)
        if raw is None or not self.current:
            return RotatorStatus(self.id, connected=self._link.up)
        try:
            status = parse_status(self.id, raw)
        except (ValueError, TypeError):
            return RotatorStatus(self.id, connected=self._link.up)
        if status.state is MotionState.MOVING and not self._view.live_within(
            self.topics.status, self._moving_max_age_s
        ):
            return RotatorStatus(self.id, connected=self._link.up)  # rule 1: gone quiet
        return status

    def submit(self, command: Command, described: str | None = None) -> None:
        """Rules 3 and 5."""
        try:
            self._submit(command)
        except Refused as exc:
            self.report_refusal(exc.message, described)
            raise

    def _submit(self, command: Command) -> None:
        if isinstance(command, Stop):
            self.publish(self.topics.stop, "stop")
            self.halted()
            return
        if not isinstance(command, Target) or command.az_deg is None:
            raise Refused(RefusalCode.UNSUPPORTED, "the remote sends azimuth targets and stops")
        self._station_there()
        self.pointing.judge(command, None)  # early word for the client; the station judges again
        if command.park:  # the station's park position, so that it shows "parked"
            self.publish(self.topics.park, "park")
            return
        doc: dict[str, float] = {"azimuth": command.az_deg}
        if command.el_deg is not None:
            doc["elevation"] = command.el_deg
        self._send_target(doc)

    def _station_there(self) -> None:
        """Rule 3: no move while the station is not current (the link down: the link's word)."""
        if self._link.up and not self.current:
            raise Refused(RefusalCode.OFFLINE, STATION_AWAY)

    def _send_target(self, doc: dict[str, Any]) -> None:
        self.publish(self.topics.target, json.dumps(doc, separators=(",", ":")))

    def halted(self) -> None:
        """A stop or a lock ON has gone out: ``last_halt_s`` is now (web/port.py rule 2)."""
        self.last_halt_s = self._clock()

    def publish(self, topic: str, payload: str) -> None:
        """A command on one of the station's topics (rule 3): sent now, or Refused(OFFLINE)."""
        self._link.send(topic, payload, self._operator, self._expiry_s)

    def park(self, source: Source, described: str) -> None:
        """Rule 4: Refused when the station has no park position."""
        try:
            where = self.pointing.parking()
        except Refused as exc:
            self.report_refusal(exc.message, described)
            raise
        self.submit(Target(*where, source, park=True), described)

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
        """Rule 4: the place, for the station to turn into its bearing."""
        place: dict[str, Any] = (
            {"locator": locator}
            if locator is not None
            else {"latitude": latitude_deg, "longitude": longitude_deg}
        )
        if long_path:
            place["path"] = "long"
        try:
            self._station_there()
            self._send_target(place)
        except Refused as exc:
            self.report_refusal(exc.message, described)
            raise

    def report_refusal(self, message: str, command: str | None) -> None:
        """Rule 5: logged here, rarely (per front end: the first word of ``command``)."""
        kind = (command or "").split(" ", 1)[0]
        with self._refusals_lock:
            count, logged_s = self._refusals.get(kind, (0, -REFUSAL_LOG_S))
            now = self._clock()
            if now - logged_s < REFUSAL_LOG_S:
                self._refusals[kind] = (count + 1, logged_s)
                return
            self._refusals[kind] = (0, now)
        more = f" ({count} more since)" if count else ""
        log.warning("%s: %s refused: %s%s", self.id, command or "a command", message, more)
