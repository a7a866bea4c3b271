"""``rotor-bridge remote``: connect to the station's broker, learn its rotators, serve the local
endpoints until SIGINT or SIGTERM.

Rules:
1. Nothing is served before the station has described every endpoint's rotator (``R/info``):
   a rotator that does not show within ``info_wait_s`` is a start-up error that names the topic
   looked at and the likely cause (a wrong base_topic or rotator id, the bridge not running).
   A refused login or a failed TLS handshake ends the start at once, in one line that says
   which (interfaces/mqtt/remote.py rule 5).
   SIGINT or SIGTERM meanwhile (``stopping``) ends the wait within STOP_LOOK_S, as a start
   error; one before it connects (cli.py holds the signals from the command's first step, its
   modules still loading) ends the start before it does, as a start error too.
2. A rotator named ``X`` is found at ``B/X`` (a station with several rotators) or, when the
   station has one rotator and publishes under ``B`` itself, there; an endpoint without a
   rotator takes ``B``, and is told the ids when the station has several, also when ``B/info``
   is there beside them (one or the other left from an earlier configuration: nothing clears
   a retained description). An endpoint whose rotator is a group's id (its ``G/info`` there,
   claim.py rule 5) is a start-up error that says so and names the station's rotators (review
   85: it was parsed as a rotator's description and said "not the station's description:
   'model'").
3. One line per endpoint goes to stdout at start, naming everything it serves:
   ``DL1ABC -> host: tower (rotorez, 0..360) on rotctld 127.0.0.1:4533, gs232 /tmp/rotor-gs232,
   pst udp 127.0.0.1:12000``.
4. The station's topics read before a connection drops are forgotten when it does: the next
   connection's retained messages are the station's word again (the rotator's description,
   read at start, is kept).
5. Every endpoint's address is taken (TCP ports, the PST UDP ports, the ptys' links) before
   any is served; one that cannot be had is a start-up error naming it, and nothing is left
   listening or linked.
6. With ``[web]`` enabled, the console (remote/console.py) shows every rotator the station
   described by the time the endpoints' rotators were found, and its line names its URL:
   ``DL1ABC -> host: console for tower on http://127.0.0.1:8754/``. Its block is
   ``_start_console``; it stops first.
7. What the station refuses is logged here too, as it comes on a rotator's ``R/error`` (not
   replayed from the broker's store): a rotctld, GS-232 or PstRotator client was told its
   command went, and the operator reads here why nothing turned. At most ERROR_SAY_BURST
   lines at once, then one every ERROR_SAY_EVERY_S, the rest at DEBUG and counted in the next
   line said, as every other log of the bridge's is held (interfaces/web/server.py rule 7,
   interfaces/tcplines.py rule 5): anyone who may publish on ``R/error`` (a neighbour on a
   shared broker, a flow gone wrong) wrote a WARNING a message into the operator's log, no
   limit (attack 31: 500 lines for 500 messages).
8. The endpoints are served once the station's heartbeat was heard (a move sent at once would
   be refused until then: remote/rotator.py rule 1), or after heartbeat.py's SILENT_S without
   one, said in the log: a station whose bridge is away still starts the remote. The wait is
   said when it begins; SIGINT or SIGTERM meanwhile ends it within STOP_LOOK_S, as a start
   error (rule 1).
9. The console's tokens are issued and judged on this computer's wall clock never set back
   (heartbeat.py's ``StationTime`` of ``wall``; interfaces/web/auth.py rule 2): set back 10
   minutes (a laptop's time server), every page's token was "issued in the future" and each
   click was refused as expired (an attack pass).
"""

from __future__ import annotations

import json
import logging
import secrets
import signal
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

from bridge.core.ending import Ending
from bridge.core.ratelimit import TokenBucket
from bridge.core.text import shown_path
from bridge.interfaces.gs232 import EMULATIONS
from bridge.interfaces.loggers import LoggerEndpoints
from bridge.interfaces.mqtt.heartbeat import SILENT_S, StationTime
from bridge.interfaces.mqtt.payloads import is_group_info, one_line
from bridge.interfaces.mqtt.remote import RemoteLink, Standing
from bridge.interfaces.mqtt.topics import RotatorTopics, StationTopics
from bridge.interfaces.rotctld import RotctldServer
from bridge.interfaces.web.server import WebConsole
from bridge.interfaces.web.view import RotatorFacts
from bridge.remote.console import ConsoleFeed, RemoteConsoleRotator, drawn_of, parse_event
from bridge.remote.courier import Courier
from bridge.remote.readings import status_order
from bridge.remote.rotator import Info, InfoError, RemoteRotator, StationView
from bridge.remote.settings import Endpoint, RemoteSettings
from bridge.settings import ConfigError

log = logging.getLogger(__name__)

# rules 1 and 8: how soon a wait at start sees SIGINT or SIGTERM (the station's messages wake it
# at once; a signal's handler may not touch the view's lock, so the wait looks this often)
STOP_LOOK_S = 0.25
ONE_ROTATOR_GRACE_S = 0.5  # rule 2: B/X/info may come just after B/info in one burst
ERROR_SAY_BURST = 10  # rule 7: the station's refusals said at once, then one every
ERROR_SAY_EVERY_S = 1.0  # ERROR_SAY_EVERY_S, the rest at DEBUG (counted in the next said)


class Served(Protocol):
    """A line server (interfaces/tcplines.py, interfaces/ptylines.py): its address taken, then
    served, then ended."""

    def listen(self) -> None: ...
    def start(self) -> None: ...
    def stop(self, timeout_s: float = 3.0) -> None: ...


class StartError(ConfigError):
    """The remote cannot start (no broker, no such rotator); the CLI prints it, exit code 2."""


def _g(n: float) -> str:
    return f"{n:g}"


@dataclass
class Remote:
    """The running remote: its link, its rotators and its servers (``start`` / ``stop``)."""

    settings: RemoteSettings
    view: StationView = field(default_factory=StationView)
    rotators: list[RemoteRotator] = field(default_factory=list)
    servers: list[Served] = field(default_factory=list)
    loggers: LoggerEndpoints = field(default_factory=LoggerEndpoints)  # the PST UDP ports
    link: RemoteLink | None = None
    console: WebConsole | None = None  # rule 6
    feed: ConsoleFeed | None = None
    stopping: Ending = field(default_factory=Ending)  # rule 1: SIGTERM
    wall: Callable[[], float] = time.time  # rule 9: the console's tokens' (never set back)
    _stops: set[str] = field(default_factory=set)  # the rotators' stop topics (_last_word)
    _errors: dict[str, str] = field(default_factory=dict)  # error topic -> rotator id (rule 7)
    _errors_said: ErrorsSaid = field(default_factory=lambda: ErrorsSaid())  # rule 7
    _locks: set[str] = field(default_factory=set)
    _statuses: dict[str, RotatorTopics] = field(default_factory=dict)  # status -> its rotator's
    # one RemoteRotator per station rotator, however many endpoints name it: its halt count is
    # what refuses a move judged before another front end's STOP (remote/rotator.py ``submit``)
    _made: dict[RotatorTopics, RemoteRotator] = field(default_factory=dict)
    # the PstRotator ports' sender of each rotator (courier.py), one however many ports
    _couriers: dict[str, Courier] = field(default_factory=dict)

    def __post_init__(self) -> None:
        # remote/rotator.py rule 8: the view keeps what the station's rotators need, the ids
        # the endpoints name kept whatever else comes
        self.view.bound_to(self.station.base)
        for ep in self.settings.endpoints:
            if ep.rotator:
                self.view.serve(self.station.rotator(ep.rotator).root)

    @property
    def station(self) -> StationTopics:
        return StationTopics(self.settings.mqtt.base_topic)

    def start(self) -> list[str]:
        """Connect, find the rotators, listen; the start-up lines (rule 3). StartError."""
        s = self.settings
        self.link = RemoteLink(
            s.mqtt,
            s.client_id(),
            self.station.subscriptions(),
            self._on_message,
            on_change=self._on_link,
            last_word=self._last_word,
            heartbeat=self.station.bridge_heartbeat,
            station_state=self.station.bridge_state,
            proof=self._proof,
            ack_wait_s=s.ack_wait_s,
        )
        self.link.start()
        try:
            lines = []
            for ep in s.endpoints:
                rot = self._find(ep)
                self.rotators.append(rot)
                spec, (lo, hi) = rot.spec, rot.pointing.target_range()
                lines.append(
                    f"{s.operator} -> {s.mqtt.host}: {rot.id} ({spec.name}, {_g(lo)}..{_g(hi)}) "
                    f"on {', '.join(self._endpoints(ep, rot))}"
                )
            self._await_heartbeat()
            try:  # rule 5
                for server in self.servers:
                    server.listen()
                if self.loggers:
                    self.loggers.listen()
            except OSError as exc:
                raise StartError(exc.strerror or str(exc)) from None
            if s.web.enabled:
                lines.append(self._start_console())
            for server in self.servers:
                server.start()
            if self.loggers:
                self.loggers.start()
            return lines
        except BaseException:
            self.stop()
            raise

    def _await_heartbeat(self) -> None:
        """Rule 8: the station's first heartbeat, for at most SILENT_S; no error without it."""
        deadline = time.monotonic() + SILENT_S
        beat = self.station.bridge_heartbeat
        if not self.view.live_within(beat, SILENT_S):
            log.info("waiting up to %g s for the station's heartbeat on %s", SILENT_S, beat)
        while not self.view.live_within(beat, SILENT_S):
            if self.stopping.is_set():
                raise StartError("stopped before the station's heartbeat was heard")
            left = deadline - time.monotonic()
            if left <= 0:
                log.warning(
                    "the station's bridge is not heard (no heartbeat on %s): moves are refused "
                    "until it is (is it running, and as new as this remote?)",
                    beat,
                )
                return
            self.view.wait(min(left, STOP_LOOK_S))

    def _endpoints(self, ep: Endpoint, rot: RemoteRotator) -> list[str]:
        """The endpoint's servers added (not yet listening); what each is, for rule 3."""
        said = []
        for offer in ep.offers():
            where = str(offer.where)
            if offer.key == "rotctld_port":
                self.servers.append(RotctldServer(rot, int(offer.where), offer.bind))
            elif emulation := EMULATIONS.get(offer.key.rsplit("_", 1)[0]):
                options = emulation.options_of(ep)  # gs232/'s rule 11: one table
                if offer.transport == "pty":
                    self.servers.append(emulation.pty(rot, where, **options))
                else:
                    self.servers.append(emulation.server(rot, int(where), offer.bind, **options))
            elif offer.key == "pst_udp_port":
                # its moves off the loggers' one thread (courier.py: attack 29)
                courier = self._couriers.setdefault(rot.id, Courier(rot))
                self.loggers.add_pst(courier, int(offer.where), offer.bind)
                # as interfaces/tcplines.py warns
                if offer.bind not in ("127.0.0.1", "::1", "localhost"):
                    log.warning(
                        "PstRotator UDP for %s listens on %s:%s: it has no authentication, "
                        "anyone who can reach this address can turn the antenna",
                        rot.id,
                        offer.bind,
                        where,
                    )
            name = offer.key.rsplit("_", 1)[0].replace("_", " ")  # gs232, pst udp, ...
            if offer.transport == "pty":  # a path: any bytes (core/text.py shown_path)
                where = shown_path(where)
            said.append(f"{name} {offer.bind}:{where}" if offer.bind else f"{name} {where}")
        return said

    def stop(self) -> None:
        if self.feed is not None:
            self.feed.stop()
            self.feed = None
        if self.console is not None:
            self.console.stop()  # each page sees the remote go (interfaces/web/server.py rule 6)
            self.console = None
        for server in self.servers:
            server.stop()
        self.servers.clear()
        self.loggers.stop()
        for courier in self._couriers.values():
            courier.stop()
        if self.link is not None:
            self.link.stop()
            self.link = None

    def _on_link(self) -> None:
        """Rule 4: what the broker held before a drop is not kept across it."""
        if self.link is not None and not self.link.up:
            self.view.clear()
        feed = self.feed  # read once: stop() may clear it meanwhile (paho's thread)
        if feed is not None:
            feed.refresh()  # the pages see the station go (console.py rule 3)

    def _last_word(self, topic: str, payload: bytes) -> bool:
        """A stop or lock ON to one of the station's rotators (interfaces/mqtt/remote.py rule 6);
        paho's thread or a front end's, with the send lock held."""
        return topic in self._stops or (topic in self._locks and payload.strip() == b"ON")

    def _proof(self, topic: str, payload: bytes) -> Standing | None:
        """A rotator's status on the halts to it (interfaces/mqtt/remote.py rule 10); paho's
        thread."""
        topics = self._statuses.get(topic)
        return None if topics is None else standing(topics.stop, topics.lock, payload)

    def _on_message(self, topic: str, payload: bytes, retain: bool) -> None:
        self.view.put(topic, payload, replayed=retain)
        said = self._errors.get(topic)
        if said is not None and not retain:  # rule 7
            event = parse_event(payload)
            if event is not None:
                self._errors_said.say(  # (escaped: the station's message quotes its sender's)
                    "%s: the station says: %s (%s)",
                    said,
                    one_line(event.message),
                    one_line(str(event.command)),
                )
        feed = self.feed
        if feed is not None:
            feed.on_message(topic, payload, retain)

    def _find(self, ep: Endpoint) -> RemoteRotator:
        """Rules 1 and 2."""
        s, view = self.settings, self.view
        own = self.station.rotator(ep.rotator) if ep.rotator else None
        one = self.station.rotator(None)
        deadline = time.monotonic() + s.info_wait_s
        single_seen: float | None = None
        group_seen: float | None = None
        while True:
            now = time.monotonic()
            topics = None
            if own is not None and is_group_info(view.get(own.info)):  # rule 2: a group's id
                group_seen = group_seen or now
                if now - group_seen >= ONE_ROTATOR_GRACE_S or now >= deadline:
                    raise StartError(self._group(own))
            elif own is not None and view.get(own.info) is not None:
                topics = own
            elif view.get(one.info) is not None:
                single_seen = single_seen or now
                if now - single_seen >= ONE_ROTATOR_GRACE_S:
                    topics = one
            ids = self._rotator_ids()
            if topics == one and own is None and ids:  # rule 2: one of them is a leftover
                raise StartError(
                    f"the station has rotators {', '.join(sorted(ids))} and one more on "
                    f"{one.info} (some left from an earlier configuration?): name one in "
                    "endpoints.rotator"
                )
            if topics is not None:
                return self._rotator(ep, topics)
            if self.stopping.is_set():
                raise StartError("stopped before the station's rotators were found")
            if now >= deadline or (self.link is not None and self.link.fatal):
                raise StartError(self._missing(ep, own))
            view.wait(min(deadline - now, ONE_ROTATOR_GRACE_S, STOP_LOOK_S))

    def _rotator(self, ep: Endpoint, topics: RotatorTopics) -> RemoteRotator:
        raw = self.view.get(topics.info) or b""
        try:
            info = Info.parse(raw)
        except InfoError as exc:
            raise StartError(f"{topics.info}: {exc}") from None
        except (ValueError, KeyError, TypeError, IndexError) as exc:
            raise StartError(f"{topics.info} is not the station's description: {exc}") from None
        rid = ep.rotator or info.rotator_id or info.name
        one = topics == self.station.rotator(None)
        if one and ep.rotator is not None and ep.rotator != (info.rotator_id or ep.rotator):
            log.warning(
                "the station has one rotator, %r: endpoints.rotator %r is taken to be it",
                info.rotator_id,
                ep.rotator,
            )
        return self._remote_rotator(rid, topics, info)

    # -- the console (rule 6; remote/console.py) --------------------------------------------
    def _start_console(self) -> str:
        s = self.settings
        rotators = list(dict.fromkeys(self.rotators))  # (two endpoints onto one: shown once)
        known = {rot.topics for rot in rotators}
        for rid in self._rotator_ids():
            topics = self.station.rotator(rid)
            if topics not in known:
                more = self._described(rid, topics)
                if more is not None:
                    rotators.append(more)
        shown = [
            RemoteConsoleRotator(rot, drawn_of(self.view.get(rot.topics.info)), self.view)
            for rot in rotators
        ]
        first = shown[0].drawn
        password = s.web.password
        console = WebConsole(
            s.web.bind,
            s.web.port,
            password=password.get_secret_value() if password is not None else None,
            frame_ancestors=list(s.web.frame_ancestors),
            host_names=list(s.web.host_names),
            trusted_proxies=list(s.web.trusted_proxies),
            secret=secrets.token_bytes(32),  # logins end with the remote's run
            station=first.station,
            locator=first.locator,
            satellites=lambda: sorted({n for r in shown for n in r.drawn.satellites}),
            wall=StationTime(self.wall, time.monotonic).now_unix,  # rule 9
        )
        for rot in shown:
            console.attach(rot, RotatorFacts(rot.drawn.beamwidth_deg, rot.drawn.nudge_step_deg))
            rot.pages = console
        self.feed = ConsoleFeed(shown, console)
        try:
            console.listen()
        except OSError as exc:
            raise StartError(
                f"web.port {s.web.port}: the console cannot listen on "
                f"{s.web.bind or '*'}:{s.web.port}: {exc.strerror or exc}"
            ) from None
        self.console = console
        self.feed.start()
        names = ", ".join(rot.id for rot in shown)
        return f"{s.operator} -> {s.mqtt.host}: console for {names} on {console.url}"

    def _remote_rotator(self, rid: str, topics: RotatorTopics, info: Info) -> RemoteRotator:
        """One station rotator on this remote's link; its stop and lock topics are the ones
        a dropped connection must not lose (interfaces/mqtt/remote.py rule 6)."""
        s = self.settings
        assert self.link is not None
        made = self._made.get(topics)
        if made is not None:  # another endpoint onto the same rotator: the same halt count
            return made
        self.view.serve(topics.root)  # (remote/rotator.py rule 8)
        self._stops.add(topics.stop)
        self._locks.add(topics.lock)
        self._statuses[topics.status] = topics
        said = self.view.get(topics.status)  # (read before this rotator was known: its order,
        if said is not None:  # what a halt asked from now is stamped with)
            self.link.read_status(topics.status, said)
        self._errors[topics.error] = rid
        made = self._made[topics] = RemoteRotator(
            rid,
            topics,
            self.station,
            info,
            self.view,
            self.link,
            s.operator,
            s.command_expiry_s,
            s.moving_max_age_s,
            wall=self._station_now,  # remote/rotator.py rule 6: the lease's end is the station's
        )
        return made

    def _station_now(self) -> float:
        """The station's clock as its heartbeats let the link reckon it (heartbeat.py rule 3),
        the time ``R/control``'s end is on; this computer's wall clock without a reckoning (the
        station not heard: a move is refused for that first)."""
        link = self.link
        reckoned = None if link is None else link.station_clock.now_unix()
        return time.time() if reckoned is None else reckoned

    def _rotator_ids(self) -> list[str]:
        """The ids of the station's rotators the view holds a ``B/<id>/info`` of (rule 2), but a
        group's ``G/info`` (it names its bridge: claim.py rule 5), which is no rotator."""
        ids = self.station.described(list(self.view.topics()))
        return [r for r in ids if not is_group_info(self.view.get(self.station.rotator(r).info))]

    def _described(self, rid: str, topics: RotatorTopics) -> RemoteRotator | None:
        """A station rotator no endpoint names, for the console alone (None: not usable)."""
        try:
            info = Info.parse(self.view.get(topics.info) or b"")
        except (ValueError, KeyError, TypeError, IndexError) as exc:
            log.warning("%s: the console leaves this rotator out: %s", topics.info, exc)
            return None
        return self._remote_rotator(rid, topics, info)

    def _group(self, own: RotatorTopics) -> str:
        """Rule 2: the start error of an endpoint whose ``rotator`` is a group's id (its
        ``G/info``, claim.py rule 5; review 85: parsed as a rotator's, it said "not the
        station's description: 'model'")."""
        try:
            members = json.loads(self.view.get(own.info) or b"").get("members")
        except (ValueError, RecursionError, AttributeError):
            members = None
        of = (
            f" of {', '.join(sorted(m for m in members if isinstance(m, str)))}"
            if isinstance(members, list)
            else ""
        )
        ids = sorted(self._rotator_ids())
        rotators = (
            f"the station has rotators {', '.join(ids)}" if ids else "the station has no rotator"
        )
        return (
            f"{own.info} describes a group{of}, not a rotator: a remote endpoint serves one "
            f"rotator; {rotators}: name one in endpoints.rotator"
        )

    def _missing(self, ep: Endpoint, own: RotatorTopics | None) -> str:
        s = self.settings
        where = f"{s.mqtt.host}:{s.mqtt.port}"
        assert self.link is not None
        if not self.link.up:  # interfaces/mqtt/remote.py rule 5: why, in this one line
            return (
                f"cannot reach the station's broker at {where}: {self.link.failure or 'no answer'}"
            )
        ids = self._rotator_ids()
        looked = (own or self.station.rotator(None)).info
        hint = (
            f"; the station has rotators {', '.join(ids)}: name one in endpoints.rotator"
            if ids
            else "; is base_topic the station's, and its bridge running?"
        )
        return (
            f"no description of the station's rotator on {looked} within {s.info_wait_s:g} s{hint}"
        )


class ErrorsSaid:
    """Rule 7's pace: a WARNING at most ERROR_SAY_BURST at once, then one every
    ERROR_SAY_EVERY_S; the rest at DEBUG, and how many were left out said with the next
    WARNING. Paho's thread alone calls it."""

    def __init__(self, clock: Callable[[], float] = time.monotonic) -> None:
        self._clock = clock
        self._loud = TokenBucket.full(ERROR_SAY_BURST, 1.0 / ERROR_SAY_EVERY_S, clock())
        self._left_out = 0

    def say(self, msg: str, *args: object) -> None:
        if not self._loud.take(self._clock()):
            self._left_out += 1
            log.debug(msg, *args)
            return
        if self._left_out:
            msg += " (%d more of the station's refusals not said before it)"
            args = (*args, self._left_out)
            self._left_out = 0
        log.warning(msg, *args)


def run(settings: RemoteSettings, stopping: Ending | None = None) -> int:
    """Serve until SIGINT or SIGTERM; StartError when it cannot start. ``stopping``: the
    caller's, already ended by a signal that came while it loaded this (cli.py), and closed
    by the caller."""
    own = stopping is None
    remote = Remote(settings) if stopping is None else Remote(settings, stopping=stopping)
    stopping = remote.stopping  # the start's wait for the station ends with it too (rule 1)
    try:
        # the handlers take no lock (core/ending.py): one that set an Event could land inside
        # that Event's wait on this thread, holding its lock, and wait for ever
        with stopping.on_signals(signal.SIGINT, signal.SIGTERM):
            if stopping.is_set():  # (rule 1)
                raise StartError("stopped before it connected to the station's broker")
            for line in remote.start():
                print(line, flush=True)
            try:
                stopping.wait()
            finally:
                remote.stop()
                log.info("stopped")  # the last line of its log, as the bridge's
    finally:
        if own:
            stopping.close()
    return 0


def standing(stop: str, lock: str, payload: bytes) -> Standing | None:
    """A rotator's ``R/status`` on its halts (interfaces/mqtt/remote.py rule 10): a STOP on
    ``stop`` ends the turn shown, from its place (``order.turn``; a rotor not at rest with no
    target, the box's own turn across a restart, from that place too: the one the state file
    kept), and is not judged by a status whose controller is not read; a lock ON on ``lock`` ends
    the lock OFF, from the lock word's place (``order.lock``; the lock word's place the state
    file kept across a restart), and is not judged by a status that does not
    know the lock (``lock_unknown``); None for a status without an ``order`` (no halt is held
    for it)."""
    said = status_order(payload)
    if said is None:
        return None
    unsaid = frozenset(
        ([] if said.motion_known else [(stop, b"stop")])
        + ([] if said.lock_known else [(lock, b"ON")])
    )
    return Standing(
        said.run,
        said.taken,
        (
            ((stop, b"stop"), said.turn if said.turning or said.moving else None),
            ((lock, b"ON"), None if said.locked else said.lock),
        ),
        unsaid,
        said.since,
    )
