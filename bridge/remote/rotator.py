"""One station rotator as the remote sees it: what rotctld's, GS-232's, the loggers' and the
console's commands ask of a Rotator (front.py: ``id``, ``spec``, ``status``, ``submit``,
``report_refusal``; and ``pointing``, ``limits``), answered from the station's retained
topics and carried out by publishing on its command topics.

Rules:
1. ``status`` is the newest retained ``R/status`` read back into a RotatorStatus, and counts only
   while it is current: the remote connected, ``B/bridge/state`` and ``R/availability`` both
   received as ``online`` on this connection (positive word, whatever order they come in), and
   the station's heartbeat heard as published within heartbeat.py's SILENT_S on the remote's
   clock (a broker restored from its file says ``online`` for a bridge long dead: only a
   heartbeat says it lives).
   Otherwise the rotator reads as unavailable (rotctld answers an error code), never as the
   last number seen. The station publishes a status when something changes, not on a clock,
   so the age of a still rotor's status says nothing about staleness: the bridge's last will
   and the availability topic do. A MOVING rotor's bearing changes with every poll, so a
   ``moving`` status counts only while one came from the station, as it published it, within
   ``moving_max_age_s`` on the remote's own clock: older, the station went quiet mid-move (its
   last will comes only after 1.5 keepalives); replayed from the broker's store (the retain
   flag, interfaces/mqtt/remote.py rule 4), it is of unknown age until the next one. Its ``time`` is
   the station's clock, which need not agree with ours: not used.
2. What the rotator is comes from the station's ``R/info``: the model (its ModelSpec, for
   Hamlib's facts), the target ranges in true bearings, park. Nothing of it is configured here.
   The remote judges a target against these facts (a target out of range or in a keep-out
   sector gets its error code at once), but the station's judge is the one that counts: what
   it refuses (the lock, say) is on ``R/error``, while the client got RPRT 0 once the command
   was on its way.
3. ``submit``: each command (core/model.py's union) is one publish on the station's own topic for
   it (docs/mqtt.md): a Target on ``R/target`` as JSON, a Stop on ``R/stop``, the lock on
   ``R/lock``, a preset, a nudge, tracking on theirs, through the link (interfaces/mqtt/remote.py:
   QoS 1, expiry, operator), an elevation alone on ``R/target/elevation`` (attack 17: Hamlib's
   PstRotator client sends ``P 200 30`` as an azimuth datagram and an elevation one, and the
   remote refused every elevation: the antenna never lifted); one the station takes on no
   topic (an option, the lease, following) is refused (UNSUPPORTED). While the
   link is down each is refused with OFFLINE at once. A command that moves (a target, park, a
   place) is refused with OFFLINE at once too while the station is not current (rule 1: its
   bridge or the rotator offline), as the station's own rotctld refuses it for a rotator
   offline: nobody would take it. A stop is
   refused only while the link is down (the station's bridge may be offline on its main
   connection and still take a stop on its stop lane, interfaces/mqtt/lane.py), and then it is kept
   and sent first on reconnect (interfaces/mqtt/remote.py rule 6): OFFLINE tells the client it has
   not reached the station yet. The lock and tracking off, like a stop, never move: they go
   whenever the link is up. A lock ON sent while the station's bridge is not heard (offline,
   or no heartbeat) is answered with OFFLINE once the broker has it (LOCK_UNHEARD): a bridge
   that is down never reads it (its session is clean) and starts again unlocked, and someone
   about to climb the tower must not be told it is locked (an attack pass: the console said
   lock ON, the station's bridge restarted, the rotator was unlocked). So is a stop
   (STOP_UNHEARD): rotctld answered ``RPRT 0`` and the page OK while the rotor, its bridge
   down, turned on to its last target. Both go again once the station's bridge is heard
   (interfaces/mqtt/remote.py rule 6, ``until_heard``; an attack pass: a STOP while the
   station's bridge restarted mid-move never reached the bridge that started again, and the
   rotor turned on); nothing that moves can be sent before that. A stop or lock ON the
   station's bridge was heard for is held by the link too, and sent again when the station's
   bridge connected again and its status still shows the turn (or the lock OFF) the halt was
   asked against, taken no later than the halt's stamp (interfaces/mqtt/remote.py rule 10,
   by the order of the station's commands; attack 26: its route to the broker died without a
   word, the broker took the STOP, ``RPRT 0``, and the rotor turned on to its target).
4. The other ways the front ends name a target: ``Park`` goes to ``R/park`` when the station
   has a park position, ``Toward`` sends the place itself (``{"locator": ...}`` or
   coordinates) on ``R/target``: the station knows where it is, the remote does not.
5. A refusal here (not connected, out of range, no park) is logged, at most once per
   REFUSAL_LOG_S and front end with the count since (Gpredict sends a target every few
   seconds), and raised; the station's own refusals are on its ``R/error``, not the remote's.
   What the sender wrote is logged escaped on one line and cut short, as the station logs it
   (an attack pass: a PstRotator tag holding a line break wrote a line of its own).
6. A move is refused at once (LEASED: rotctld answers ``RPRT -9``) while the station's retained
   ``R/control`` says another operator holds the control lease, in the words the station
   would use; the station judges it again (a lease that ended a moment ago): this only spares
   the client a silent refusal on the station's ``R/error``. Its end is a time on the
   station's clock, so it is compared with that clock as the heartbeats let the remote reckon
   it (``wall``; heartbeat.py rule 3), never with this computer's: a station an hour behind
   (a Raspberry Pi without a clock chip) had every lease look long over, and each move was
   answered ``RPRT 0`` and refused at the station (an attack pass).
   Likewise (LOCKED, ``RPRT -9``) while the station's ``R/lock/state`` is ``ON``.
7. A command is answered only once the station's broker acknowledged it (interfaces/mqtt/remote.py
   rule 7), ``submit`` returning then: ``RPRT 0`` means the broker has it (the PstRotator
   ports, whose protocol answers no command, hand their moves to a sender thread instead and
   go on: courier.py), stamped with its send time for the station to
   refuse it if a link held it up (heartbeat.py). A command a front end says when it was
   seen (``seen_s``, front.py rule 3: a TCP port's or a pty's look, tcplines.py rule 9; a
   datagram's arrival, loggers/server.py rule 9) is stamped with that time instead, a stop
   and a lock ON too; a move never before the stamp of the last STOP or lock ON the link sent
   for this rotator (its ``after``: its stop and lock topics) from the move's own source
   (``reader``: the connection or port that read it, which orders its own bytes), which is that
   halt's own seen time: a STOP the station took another way after the move came refuses
   it, however late it was read, and the client's own ``S`` read with it does not
   (heartbeat.py rule 10); another front end's STOP seen after the move came does not lift
   it either (an attack pass: Gpredict's ``P`` seen at 8 s, read after PstRotator's STOP seen
   at 9 s, went out stamped 9 s and turned the rotor). A stop and a lock ON carry ``read_s``
   too (front.py rule 3: their latest arrival): another source's move seen before it is
   refused by the link (interfaces/mqtt/remote.py rule 8). The console says nothing: its
   commands are stamped when sent.
8. The ``StationView`` keeps what the remote reads, bounded by the station's rotators, not by
   what anyone publishes (attack 31: it kept every ``B/<id>/...`` topic it read, error events
   too, until its connection dropped: a neighbour on a shared broker publishing under 2,000 ids
   grew it by 2,000 topics). Under ``B/<id>`` it keeps the topics of the ids served (the
   endpoints' rotators, ``serve``: named in the settings before it connects, and each rotator
   made since) and of at most MAX_OTHER_IDS ids more, the first read on a connection (a station
   rotator no endpoint names, for the console, and leftovers: rule 2 names them); what comes
   under another id beyond them is not kept (said once a connection). An ``R/error`` message is
   an event, never retained and never read again: kept only as the newest of a rotator served
   (one each). The station's own topics (``B/bridge/...``, the one rotator's under ``B``) are
   the subscriptions' fixed few.
"""

from __future__ import annotations

import json
import logging
import math
import threading
import time
from collections.abc import Callable, Hashable
from typing import Any, Protocol

from bridge.core.errors import RefusalCode, Refused
from bridge.core.haltwatch import HaltWatchers
from bridge.core.model import (
    Command,
    GoToPreset,
    Lock,
    MotionState,
    Nudge,
    Origin,
    Park,
    RotatorStatus,
    Source,
    Stop,
    TakePath,
    Target,
    Toward,
    TrackBody,
    describe_command,
    same_operator,
)
from bridge.features import control, tracking
from bridge.interfaces.mqtt.heartbeat import SILENT_S
from bridge.interfaces.mqtt.payloads import one_line
from bridge.interfaces.mqtt.topics import RotatorTopics, StationTopics
from bridge.pointing import Limits
from bridge.remote.readings import Info, InfoError, parse_control, parse_status

__all__ = ["Info", "InfoError", "RemoteRotator", "StationView", "parse_status"]

log = logging.getLogger(__name__)

REFUSAL_LOG_S = 10.0  # rule 5
MAX_OTHER_IDS = 64  # rule 8: ids under B kept beside the ones served (a station's rotators)
STATION_AWAY = "the station's rotator is offline (its bridge or its controller): nothing sent"
STATION_SILENT = (
    f"the station's bridge is not heard (no heartbeat within {SILENT_S:g} s): nothing sent"
)
LOCKED = "the station's safety lock is ON: nothing turns until it is switched off"
STOP_UNHEARD = (
    "stop sent, but the station's bridge is not heard (offline, or no heartbeat): it may not "
    "have reached the rotator, which may still be turning to its last target; sent again once "
    "the station's bridge is heard"
)
LOCK_UNHEARD = (
    "lock ON sent, but the station's bridge is not heard (offline, or no heartbeat): it may "
    "never reach the rotator (sent again once the station's bridge is heard, while this remote "
    "runs); make sure the station shows the lock ON before anyone works on the tower"
)
HALTED_SINCE = "a STOP or lock ON went out after it was asked: not sent (send it again)"


class Sender(Protocol):
    @property
    def up(self) -> bool: ...

    def send(
        self,
        topic: str,
        payload: str,
        operator: str,
        expiry_s: int,
        check: Callable[[], None] | None = None,
        *,
        until_heard: bool = False,
        seen_s: float | None = None,
        after: tuple[str, ...] = (),
        reader: Hashable | None = None,
        read_s: float | None = None,
    ) -> None: ...


def place_doc(latitude_deg: float, longitude_deg: float, locator: str | None) -> dict[str, Any]:
    """A place as the station's ``R/target`` takes it (docs/mqtt.md): the locator when there is
    one (the station reads it as the user typed it), else the coordinates."""
    if locator is not None:
        return {"locator": locator}
    return {"latitude": latitude_deg, "longitude": longitude_deg}


class StationView:
    """The retained topics the remote reads, newest first; written on paho's thread. Each value
    keeps when it came (``clock``) and whether the broker replayed it from its store. Rule 8:
    given the station's ``base``, it keeps the ``B/<id>/...`` topics of the ids served and of
    MAX_OTHER_IDS more, and an error event only as a served rotator's newest."""

    def __init__(self, clock: Callable[[], float] = time.monotonic) -> None:
        self._lock = threading.Condition()
        self._topics: dict[str, bytes] = {}
        self._came: dict[str, tuple[float, bool]] = {}  # topic -> (when, replayed)
        self._clock = clock
        self._base: str | None = None  # rule 8 (None: all kept, as a test's view handed them)
        self._fixed: set[str] = set()  # rule 8: topics under ``B`` that name no id
        self._served: set[str] = set()  # rule 8: ids under B kept whatever comes
        self._others: dict[str, set[str]] = {}  # rule 8: another id -> its topics kept
        self._left_out = False  # rule 8: said on this connection

    def bound_to(self, base: str) -> None:
        """Rule 8: the station's base topic, before anything is read."""
        with self._lock:
            self._base = base
            # the station's own topics and the one rotator's under ``B`` (``B/lock/state``
            # among them, whose first level is no id): the subscriptions' fixed few
            self._fixed = {t for t in StationTopics(base).subscriptions() if "+" not in t}

    def serve(self, root: str) -> None:
        """Rule 8: the rotator at ``root`` (``B/<id>``, or ``B`` itself) is served: its topics
        are kept, its newest error event too."""
        rid = self._id(root + "/")
        if rid is None:
            return
        with self._lock:
            self._served.add(rid)
            self._others.pop(rid, None)

    def _id(self, topic: str) -> str | None:
        """The ``<id>`` of a ``B/<id>/...`` topic (None: the station's own or the one
        rotator's, a fixed few)."""
        if self._base is None or topic in self._fixed or not topic.startswith(self._base + "/"):
            return None
        rid, sep, _leaf = topic[len(self._base) + 1 :].partition("/")
        return rid if sep and rid != "bridge" else None

    def _kept(self, topic: str, payload: bytes) -> bool:
        """Rule 8: whether ``topic`` is kept (called under the lock)."""
        rid = self._id(topic)
        if rid is None or rid in self._served:
            return True
        if topic == f"{self._base}/{rid}/error":
            return False  # an event: only a served rotator's newest
        kept = self._others.get(rid)
        if kept is None:
            if not payload:
                return True  # (a deletion of nothing kept)
            if len(self._others) >= MAX_OTHER_IDS:
                if not self._left_out:
                    self._left_out = True
                    log.warning(
                        "the station's broker has topics under more than %d rotator ids "
                        "beside the ones served (%s and more): those are not kept",
                        MAX_OTHER_IDS,
                        one_line(f"{self._base}/{rid}"),
                    )
                return False
            kept = self._others[rid] = set()
        if payload:
            kept.add(topic)
        else:
            kept.discard(topic)
            if not kept:
                del self._others[rid]  # (its place free again)
        return True

    def put(self, topic: str, payload: bytes, replayed: bool = False) -> None:
        with self._lock:
            if not self._kept(topic, payload):
                self._lock.notify_all()  # (a wait for the next message: this was one)
                return
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
            self._others.clear()  # (rule 8: the next connection's ids take the places)
            self._left_out = False

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
        station: StationTopics,
        info: Info,
        view: StationView,
        link: Sender,
        operator: str,
        expiry_s: int,
        moving_max_age_s: float = 10.0,
        clock: Callable[[], float] = time.monotonic,
        wall: Callable[[], float] = time.time,  # rule 6: the station's clock (run.py's)
    ) -> None:
        self.id = rotator_id
        self.topics = topics
        self.name = info.name
        self.spec = info.spec
        self.pointing = info.pointing
        self._station = station
        self._view = view
        self._link = link
        self._operator = operator
        self._expiry_s = expiry_s
        self._moving_max_age_s = moving_max_age_s
        # the last R/status payload read and what it read as (readings.py rule 4: one attribute,
        # so a thread never reads one without the other)
        self._read: tuple[bytes, RotatorStatus] | None = None
        # the last stop sent (monotonic; interfaces/web/port.py rule 2), and how many (rule 2a),
        # of them how many each front end sent (rule 2b): counted together, under one lock
        self.last_halt_s = -math.inf
        self.halts = 0
        self.halt_watchers = HaltWatchers()  # told before each halt is counted (halted)
        self._halts_from: dict[Source, int] = {}
        self._halts_lock = threading.Lock()
        self._clock = clock
        self._wall = wall
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
        return self._link.up and self.away() is None

    def away(self) -> str | None:
        """Rule 1: why the station is not current while the link is up (None: it is)."""
        view = self._view
        if not view.live_within(self._station.bridge_heartbeat, SILENT_S):
            return STATION_SILENT
        if (
            view.get(self._station.bridge_state) != b"online"
            or view.get(self.topics.availability) != b"online"
        ):
            return STATION_AWAY
        return None

    def bridge_unheard(self) -> bool:
        """Rule 3: the station's bridge itself is offline or silent (a rotator offline under
        a bridge that runs still takes its lock)."""
        view = self._view
        return (
            not view.live_within(self._station.bridge_heartbeat, SILENT_S)
            or view.get(self._station.bridge_state) != b"online"
        )

    @property
    def status(self) -> RotatorStatus:
        raw = self._view.get(self.topics.status)
        if raw is None or not self.current:
            return RotatorStatus(self.id, connected=self._link.up)
        read = self._read
        if read is not None and read[0] is raw:  # (the same payload: read once)
            status = read[1]
        else:
            try:  # (the last one's objects where it says the same: readings.py rule 4)
                status = parse_status(self.id, raw, None if read is None else read[1])
            except (ValueError, TypeError):
                return RotatorStatus(self.id, connected=self._link.up)
            self._read = raw, status
        if status.state is MotionState.MOVING and not self._view.live_within(
            self.topics.status, self._moving_max_age_s
        ):
            return RotatorStatus(self.id, connected=self._link.up)  # rule 1: gone quiet
        return status

    def submit(
        self,
        command: Command,
        described: str | None = None,
        *,
        since: int | None = None,
        seen_s: float | None = None,
        reader: Hashable | None = None,
        read_s: float | None = None,
        asked: int | None = None,
    ) -> None:
        """Rules 3 to 5: the command on the station's own topic for it, or Refused. ``since``:
        the count of the stops and lock ONs of every front end but the command's own
        (``halts_besides`` its source) read when it was asked (interfaces/web/port.py rules 2a
        and 2b): a move is refused if one went out since, up to the moment it is handed to
        the link, under the link's send lock (the order the broker takes them in).
        ``seen_s``: when the command was seen (the monotonic clock, the link's; front.py rule
        3): it is stamped so (rule 7). ``reader``: its source (the connection or port that read
        it: front.py rule 3), whose own last halt alone may lift a move's stamp (rule 7).
        ``read_s``: a halt's latest arrival, where the front end knows it (front.py rule 3;
        None: when it is sent), before which another source's move is refused (rule 7).
        ``asked``: the halt count when the move was asked, where that was before this call
        (remote/courier.py rule 1: a move queued for its sender); None: now."""
        # a front end that asks and submits at once (rotctld, GS-232, the loggers): its move is
        # asked now, and a stop or lock ON of any front end counted from here on refuses it up
        # to the hand-off, as the station's judge drops one judged before a halt (mailbox.py
        # rule 10; an attack pass: the remote's rotctld P, judged, then the console's STOP sent
        # first: the P reached the broker after it and the station turned the rotor)
        # and with ``since`` too: from here on every front end's counts, its own included (a
        # review: the DCU-1 endpoint's since, halts_besides(DCU1), left out another DCU-1
        # client's ';' counted between this submit and the hand-off, and the AM1's bearing,
        # asked before that stop, went to the broker after it)
        if asked is None:
            asked = self.halts
        try:
            self._send(command, since, asked, seen_s, reader, read_s)
        except Refused as exc:
            self.report_refusal(exc.message, described)
            raise

    def _send(
        self,
        command: Command,
        since: int | None = None,
        asked: int | None = None,
        seen_s: float | None = None,
        reader: Hashable | None = None,
        read_s: float | None = None,
    ) -> None:
        """Rule 3: what never moves goes whatever the remote thinks of the station; rule 4:
        a place goes as the place, park as park. ``asked``: the count of every front end's
        stops and lock ONs when the move was handed to ``submit``, ``since`` or not;
        ``seen_s``, ``reader``, ``read_s``: as ``submit``'s (rule 7)."""
        t = self.topics
        match command:
            case Stop():
                unheard = self.bridge_unheard()  # rule 3: sent, maybe to nobody, and again
                self.halted(command.source)  # (before it goes: it may wait for its PUBACK,
                self.publish(
                    t.stop,
                    "stop",
                    until_heard=unheard,
                    seen_s=seen_s,
                    reader=reader,
                    read_s=read_s,
                )  # or be kept)
                if unheard:  # once the station's bridge is heard
                    raise Refused(RefusalCode.OFFLINE, STOP_UNHEARD)
                return
            case Lock():
                unheard = command.on and self.bridge_unheard()  # rule 3, as a stop
                if command.on:
                    self.halted(command.source)
                on_seen = seen_s if command.on else None  # (rule 7: a halt's)
                self.publish(
                    t.lock,
                    "ON" if command.on else "OFF",
                    until_heard=unheard,
                    seen_s=on_seen,
                    reader=reader,
                    read_s=read_s if command.on else None,
                )
                if unheard:
                    raise Refused(RefusalCode.OFFLINE, LOCK_UNHEARD)
                return
            case TrackBody() if command.off:
                self.publish(t.feature(tracking.COMMAND), command.name)
                return
        # a move from here on: judged now, and ``since`` again as it is handed to the link
        source = command.source
        guard: Callable[[], None] | None = None
        if since is not None or asked is not None:

            def guard() -> None:
                if since is not None:
                    self._not_halted_since(since, source)
                if asked is not None:
                    self._not_halted_at_all_since(asked)

        match command:
            case Target() if command.az_deg is not None:
                self.check_move(since, source)
                self.pointing.judge(command, None)  # early word; the station judges again
                if command.park:  # the station's park position, so that it shows "parked"
                    self.publish(t.park, "park", guard, seen_s=seen_s, reader=reader, move=True)
                else:
                    doc: dict[str, float] = {"azimuth": self._end_named(command)}
                    if command.el_deg is not None:
                        doc["elevation"] = command.el_deg
                    self._send_json(t.target, doc, guard, seen_s, reader)
            case Park():  # rule 3 first: the link's word, then the station's park position
                self.check_move(since, source)
                park = Target(*self.pointing.parking(), source, park=True)
                self._send(park, since, asked, seen_s, reader)
            case Toward():
                lat, lon = command.latitude_deg, command.longitude_deg
                place = place_doc(lat, lon, command.locator)
                if command.long_path:
                    place["path"] = "long"
                self.check_move(since, source)
                self._send_json(t.target, place, guard, seen_s, reader)
            case TakePath():
                self.check_move(since, source)
                path = {"path": "long" if command.long_path else "short"}
                self._send_json(t.target, path, guard, seen_s, reader)
            case GoToPreset():
                self.check_move(since, source)
                self.publish(t.preset, command.name, guard, seen_s=seen_s, reader=reader, move=True)
            case Nudge():
                step = {"azimuth": command.d_az_deg}
                if command.d_el_deg is not None:
                    step["elevation"] = command.d_el_deg
                self.check_move(since, source)
                self._send_json(t.nudge, step, guard, seen_s, reader)
            case TrackBody() if command.tle is None:
                self.check_move(since, source)
                self.publish(
                    t.feature(tracking.COMMAND),
                    command.name,
                    guard,
                    seen_s=seen_s,
                    reader=reader,
                    move=True,
                )
            case Target() if command.el_deg is not None:  # an elevation alone (rule 3)
                if not self.spec.has_elevation:
                    raise Refused(RefusalCode.UNSUPPORTED, "this rotator has no elevation")
                self.check_move(since, source)
                self.pointing.judge(command, None)  # early word; the station judges again
                payload = f"{command.el_deg:g}"
                self.publish(
                    t.target_elevation, payload, guard, seen_s=seen_s, reader=reader, move=True
                )
            case _:
                raise Refused(
                    RefusalCode.UNSUPPORTED,
                    f"the remote does not send {describe_command(command).split(' ')[0]!r}: "
                    "targets, stops, the lock, presets, park, nudges, places and tracking",
                )

    def _end_named(self, target: Target) -> float:
        """Rule 3: the azimuth the station is sent for ``target``: north that names neither
        end (``Target.az_either_end``: a DCU-1's 000) as the end of the travel nearer the
        station's reading, for the station's ``R/target`` takes 0 named for the
        counter-clockwise end (pointing.py rule 2; review 64: a DCU-1 program's north through
        the remote turned a Yaesu at 355 back through south); equals, or no reading: 0. The
        loggers' north picks its end the same way (``Pointing.least_turn``)."""
        az = target.az_deg
        assert az is not None
        if not target.az_either_end or az % 360.0 != 0.0:
            return az
        return self.pointing.least_turn((az,), self.status)

    def check_move(self, since: int | None, source: Source) -> None:
        """Rule 3: no move while the station is not current (the link down: the link's word);
        rule 6: nor while the station is locked or another operator holds its control lease;
        nor (``since``) after a stop or lock ON of another front end than ``source``'s went
        out since it was asked."""
        if since is not None:
            self._not_halted_since(since, source)
        away = self.away() if self._link.up else None
        if away is not None:
            raise Refused(RefusalCode.OFFLINE, away)
        if self._view.get(self.topics.lock_state) == b"ON":
            raise Refused(RefusalCode.LOCKED, LOCKED)
        held = parse_control(self._view.get(self.topics.feature(control.STATE)))
        now = self._wall()
        if (
            held is not None
            and not same_operator(held.operator, self._operator)
            and now < held.until_unix
        ):
            text = held.held_text(now)
            raise Refused(RefusalCode.LEASED, f"{text}: only they may turn it (control lease)")

    def _not_halted_at_all_since(self, asked: int) -> None:
        with self._halts_lock:
            if self.halts != asked:
                raise Refused(RefusalCode.STALE, HALTED_SINCE)

    def _not_halted_since(self, since: int, source: Source) -> None:
        if self.halts_besides(source) != since:
            raise Refused(RefusalCode.STALE, HALTED_SINCE)

    def _send_json(
        self,
        topic: str,
        doc: dict[str, Any],
        guard: Callable[[], None] | None = None,
        seen_s: float | None = None,
        reader: Hashable | None = None,
    ) -> None:
        self.publish(
            topic,
            json.dumps(doc, separators=(",", ":")),
            guard,
            seen_s=seen_s,
            reader=reader,
            move=True,
        )

    def halted(self, source: Source) -> None:
        """A stop or a lock ON from ``source``'s front end goes out: ``last_halt_s`` is now
        (interfaces/web/port.py rule 2), and ``halts`` counts it (rule 2a), as the front end's
        own count does (rule 2b), before it is published (a move asked before it is refused
        from then on, while it waits for its acknowledgement or is kept)."""
        self.halt_watchers()  # (tcplines.py rule 9: before it is counted)
        with self._halts_lock:  # (two threads' halts: two numbers, and both counts agree)
            self.last_halt_s = self._clock()
            self.halts += 1
            self._halts_from[source] = self._halts_from.get(source, 0) + 1

    def halts_for(self, source: Source) -> int:
        """The count a command of ``source`` asked now hands to ``submit`` as ``since``
        (``halts_besides``: its own front end's halts do not refuse its move)."""
        return self.halts_besides(source)

    def halts_besides(self, source: Source) -> int:
        """The stops and lock ONs sent from every front end but ``source``'s
        (interfaces/web/port.py rule 2b)."""
        with self._halts_lock:
            return self.halts - self._halts_from.get(source, 0)

    def publish(
        self,
        topic: str,
        payload: str,
        guard: Callable[[], None] | None = None,
        *,
        until_heard: bool = False,
        seen_s: float | None = None,
        reader: Hashable | None = None,
        read_s: float | None = None,
        move: bool = False,
    ) -> None:
        """A command on one of the station's topics (rule 3): sent now, or Refused(OFFLINE);
        ``guard``, if given, is asked under the link's send lock, right before it is handed on
        (it raises Refused for a move that may not go any more); ``until_heard``: a halt sent
        again once the station's bridge is heard (rule 3); ``seen_s``: stamped with when it
        was seen, a ``move`` never before the stamp of this rotator's last halt from the same
        source, ``reader``; ``read_s``: a halt's latest arrival (rule 7)."""
        t = self.topics
        self._link.send(
            topic,
            payload,
            self._operator,
            self._expiry_s,
            guard,
            until_heard=until_heard,
            seen_s=seen_s,
            reader=reader,
            after=(t.stop, t.lock) if move else (),
            read_s=read_s,
        )

    def report_refusal(
        self, message: str, command: str | None, *, origin: Origin | None = None
    ) -> None:
        """Rule 5: logged here, rarely (per front end: the first word of ``command``);
        ``origin`` is not sent (the remote's operator is, rule 3)."""
        kind = (command or "").split(" ", 1)[0]
        with self._refusals_lock:
            count, logged_s = self._refusals.get(kind, (0, -REFUSAL_LOG_S))
            now = self._clock()
            if now - logged_s < REFUSAL_LOG_S:
                self._refusals[kind] = (count + 1, logged_s)
                return
            self._refusals[kind] = (0, now)
        more = f" ({count} more since)" if count else ""
        said = one_line(command or "a command")  # (a sender's words: never a line of its own)
        log.warning("%s: %s refused: %s%s", self.id, said, one_line(message), more)
