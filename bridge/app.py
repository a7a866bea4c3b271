"""Composition root: settings -> rotators (workers) -> MQTT; signals; ordered shutdown.

It also turns a rotator's settings into the engine's configuration (runtime/worker.py
WorkerConfig), for itself and for the tests that build a rotator of their own
(``worker_config``): the one place where the user's keys meet the engine's terms, the speeds,
limits, timings and the judge's terms resolved once, health's, tracking's, following's and the
wind park's terms; and a ``[[groups]]`` table as the group the MQTT service turns
(interfaces/mqtt/groups.py). Those functions are pure: settings in, frozen configuration out.

Rules:
1. Every value the engine uses comes from here: a key left out gets the default
   settings/defaults.py derives for the model (check-config shows the same values).
2. Wind speeds are km/h from here on, whatever the rotator's ``wind_unit``.
3. A composite rotator's two boxes (runtime/composite.py) are each configured as a rotator of
   their own model, port and rate, with every other key of the rotator's, its id, and its
   judge's terms: the azimuth box's without elevation (protocols/axes.py rule 1).
4. ``B/bridge/info``'s problems (a denied topic, a long hold, the stop express's, a step down
   to MQTT 3.1.1) come from several threads: each change of the list and the publish of the
   list as it then is are one step under one lock (``_say``), so two problems said or unsaid at
   once are both in the retained payload, and no stale list is published after a newer one.
5. Connections held open to the TCP ports and the console (anyone on the LAN can hold them, and
   each port holds up to ``most_held``) never take the descriptors the bridge needs for itself:
   before it listens, ``_room_for_files`` raises the process's soft open-files limit to what it
   has open, what those ports may hold, and FILES_SPARE and 2 a rotator more (a serial port
   reopened, the broker reconnected, the state file saved), up to the hard limit (systemd's
   default soft limit is 1024, its hard one far above), and says so; if the hard limit is short,
   a warning names it and the limit to set. An attack pass: under ``ulimit -n 256`` idle
   connections to four ports and the console took every descriptor, an unplugged controller
   could not be opened again ("Too many open files") for as long as they were held, and its stop
   with it.
6. The bridge's end (SIGTERM, SIGINT, SIGHUP, ``stop_event``) leaves no rotor turning: at once
   every rotator takes nothing but a stop or a lock word (a move asked meanwhile is refused,
   "the bridge is stopping"), every one that may turn (``Rotator.may_turn``: moving, tracking,
   following, a move on its way, a target waiting out a brake delay among them) is stopped,
   and its stop written (up to HALT_WAIT_S, as
   claim rule 4's, the controller's line rules kept); once the front ends are closed, and
   before the ports close, so is every one that may turn and was not stopped so already. The
   end is told to each session (``Rotator.leave``): from then on none starts a move of its own
   (session/session.py rule 21: auto-park's park, tracking's next step, following's next
   target; a review: an auto-park due while a front end closed turned the rotor until the
   second look, or, after it, on unwatched once the port closed). A
   storm's park goes on (a stop would keep it from being tried again after the restart). An
   attack pass: ``systemctl stop`` mid-turn closed the port in 0.2 s with no stop, and the
   rotor turned on, watched by nobody, to its target. (A review: a target put right after a
   stop, waiting out the brake, was taken for no turn, and went out while a front end closed.)
   A lock word taken until the connections close is saved before the installation's lock is
   let go (state_store.py rule 7): a review found one taken after the state file's flush left
   to the writer, and on a slow disk the bridge ended before it was written, so the next start
   read the lock OFF.
"""

from __future__ import annotations

import contextlib
import errno
import gc
import logging
import os
import signal
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import replace
from functools import partial
from typing import TYPE_CHECKING, Any

from bridge.core.ending import Ending
from bridge.core.model import Lock, Source, Stop
from bridge.core.text import shown_path
from bridge.feature import AppView, Feature, FeatureService, make_service, session_parts
from bridge.features import FEATURES
from bridge.interfaces.homeassistant import DiscoveryPublisher, GroupInfo, RotatorInfo
from bridge.interfaces.mqtt.claim import Claim, Instance, Post, installation
from bridge.interfaces.mqtt.client import MqttClient
from bridge.interfaces.mqtt.connection import MQTT311_LOSES, Connection
from bridge.interfaces.mqtt.express import Express
from bridge.interfaces.mqtt.groups import Group, Member
from bridge.interfaces.mqtt.heartbeat import StationTime
from bridge.interfaces.mqtt.lane import StopLane
from bridge.interfaces.mqtt.payloads import ConsoleFacts
from bridge.interfaces.mqtt.service import MqttService, never_published
from bridge.interfaces.mqtt.stale import StaleTopics
from bridge.interfaces.mqtt.topics import DiscoveryTopics, Topics
from bridge.protocols.axes import Axis
from bridge.runtime.audit import AuditTrail
from bridge.runtime.lines import Lines
from bridge.runtime.listeners import contained
from bridge.runtime.port import PortOpener, open_port
from bridge.runtime.rotator import Rotator
from bridge.runtime.state_store import Changed, InUse, StateStore, held, tilde_leftover
from bridge.runtime.worker import WorkerConfig
from bridge.session.config import FollowConfig, HealthConfig, TrackConfig, WindConfig
from bridge.session.motion import MotionConfig
from bridge.settings import ConfigError, GroupSettings, RotatorSettings, Settings
from bridge.settings.rotator import EMULATION_KEYS
from bridge.sky import Sky
from bridge.sky.catalog import TleCatalog
from bridge.sky.worker import SkyWorker

if TYPE_CHECKING:  # the console's server and aiohttp are imported only when it is on
    from pathlib import Path

    from bridge.interfaces.loggers import LoggerEndpoints
    from bridge.interfaces.ptylines import PtyLineServer
    from bridge.interfaces.rotctld import RotctldServer
    from bridge.interfaces.tcplines import LineServer
    from bridge.interfaces.web.server import WebConsole
    from bridge.interfaces.wsjtx import WsjtxListener

__all__ = ["App", "NotYet", "run", "worker_config"]

log = logging.getLogger(__name__)

GIL_SWITCH_S = 0.0005
STEPPED_DOWN = (  # on B/bridge/info while mqtt.protocol "auto" speaks MQTT 3.1.1
    "the MQTT broker did not take MQTT 5, so the bridge speaks MQTT 3.1.1: "
    + MQTT311_LOSES
    + '; if the broker does speak MQTT 5, set mqtt.protocol = "5"'
)
CATALOG_CHECK_S = 30.0  # the TLE file's names for Home Assistant's track select, this often
YIELDING = "the bridge is stopping: it yields its base topic to another bridge"
STOPPING = "the bridge is stopping"  # rule 6
FILES_SPARE = 64  # rule 5: descriptors kept beyond what the ports may hold (and 2 a rotator)
HALT_WAIT_S = 2.0  # claim rule 4: how long a yielding bridge waits for its stops to be written


def worker_config(
    r: RotatorSettings, sky: Sky | None = None, follow: FollowConfig | None = None
) -> WorkerConfig:
    """``r``'s engine settings; ``sky`` is the station's (None: nothing can be tracked);
    ``follow``: the station and whether WSJT-X is heard (its hold_while_tx is ``r``'s)."""
    spec = r.spec
    az_min, az_max = r.effective_az_limits
    az_speed, el_speed = r.effective_speeds_deg_s
    return WorkerConfig(
        rotator_id=r.id,
        port=r.port,
        spec=spec,
        baud=r.effective_baud,
        motion=MotionConfig(
            spec=spec,
            tolerance_deg=r.tolerance_deg,
            stall_timeout_s=r.stall_timeout_s,
            brake_delay_s=r.effective_brake_delay_s,
            settle_s=r.settle_s,
            settle_own=r.settle_own,  # (motion.py rule 4: a settle_s other than the default)
            noise_deg=r.effective_noise_deg,
            az_span_deg=az_max - az_min,
            nominal_speed_deg_s=az_speed,
            el_speed_deg_s=el_speed,
            # readings while moving come at most 1.5 intervals apart (link.py rule 8), each an
            # exchange long: the rotor may have stopped that long before the last change showed
            poll_margin_s=1.5 * r.moving_poll_interval_s + spec.exchange_time_s(r.effective_baud),
            az_limits_deg=(az_min, az_max),
            el_limits_deg=r.effective_el_limits,
        ),
        idle_poll_interval_s=r.effective_idle_poll_interval_s,
        moving_poll_interval_s=r.moving_poll_interval_s,
        deadband_deg=r.deadband_deg,
        silence_timeout_s=r.effective_silence_timeout_s,
        unasked_moves=r.effective_unasked_moves,
        az_speed_deg_s=az_speed,
        el_speed_deg_s=el_speed,
        pointing=r.pointing,
        park_after_idle_s=r.park_after_idle_s,
        health=HealthConfig(
            baseline_moves=r.health_baseline_moves,
            speed_drop_pct=r.health_speed_drop_pct,
            az_speed_deg_s=r.az_speed_deg_s,
            el_speed_deg_s=r.el_speed_deg_s,
        ),
        tracking=TrackConfig(
            sky=sky,
            min_el_deg=r.track_min_el_deg,
            step_deg=r.effective_track_step_deg,
            at_los=r.track_at_los,
        ),
        follow=replace(
            follow or FollowConfig(), hold_while_tx=r.follow_hold_while_tx, bands=tuple(r.bands)
        ),
        wind=wind_config(r),
        parts=session_parts(),  # the features', in the order the session's step runs them
    )


def wind_config(r: RotatorSettings) -> WindConfig | None:
    """The wind park's terms in km/h (settings/wind.py), or None without a wind_topic."""
    above = r.wind_kmh(r.wind_park_above)
    if r.wind_topic is None or above is None:
        return None
    park_az = r.wind_park_az_deg if r.wind_park_az_deg is not None else r.park_az_deg
    assert park_az is not None  # settings/wind.py rule 1
    release = r.wind_kmh(r.wind_release_below) or above
    hold_s, silent_s = r.wind_hold_min * 60.0, r.wind_silent_min * 60.0
    return WindConfig(above, release, hold_s, (park_az, r.park_el_deg), silent_s, r.wind_topic)


def group_of(g: GroupSettings) -> Group:
    """A ``[[groups]]`` table as the MQTT service's group (members in the table's order)."""
    members = tuple(Member(rid, g.offsets.get(rid, 0.0), g.limits.get(rid)) for rid in g.rotators)
    return Group(g.id, g.label, members)


def axis_configs(
    r: RotatorSettings, sky: Sky | None = None, follow: FollowConfig | None = None
) -> tuple[WorkerConfig, WorkerConfig] | None:
    """A composite rotator's (azimuth, elevation) boxes (rule 3); None for one controller."""
    if not r.axes:
        return None
    boxes = []
    for axis in Axis:
        spec = r.axis_spec(axis)
        own = r.axis_settings(axis)
        cfg = worker_config(own, sky, follow)
        pointing = r.pointing_for(spec, r.effective_az_limits, r.effective_el_limits)
        motion = replace(  # (motion.py rule 10: held to the rotator's limits, as judged)
            cfg.motion,
            spec=spec,
            az_limits_deg=(pointing.az_min_deg, pointing.az_max_deg),
            el_limits_deg=(pointing.el_min_deg, pointing.el_max_deg),
        )
        wind = cfg.wind
        if axis is Axis.AZIMUTH and pointing.park is not None:
            # the park's azimuth alone: the azimuth box turns no elevation, and judged with
            # one (a dish's stow, park_el_deg) its park was refused: the storm's too
            pointing = replace(pointing, park=(pointing.park[0], None))
            wind = None if wind is None else replace(wind, park=(wind.park[0], None))
        unasked = r.unasked_moves_of(axis)  # (controller.py rule 10)
        tracking = replace(cfg.tracking, flip=False)  # (tracking.py rule 4: one flip for both
        boxes.append(  # boxes cannot be decided by each box's session alone)
            replace(
                cfg,
                spec=spec,
                motion=motion,
                pointing=pointing,
                wind=wind,
                unasked_moves=unasked,
                tracking=tracking,
                box=True,
            )
        )
    return boxes[0], boxes[1]


class NotYet(ConfigError):
    """A start-up failure that may clear by itself (a rotctld address that is not up yet while
    the network comes up): one line like any, but exit code 1, so systemd tries again."""

    exit_code = 1


class App:
    def __init__(
        self,
        settings: Settings,
        *,
        port_opener: PortOpener = open_port,
        wall: Callable[[], float] = time.time,
    ) -> None:
        """``wall``: the wall clock (unix seconds) of the statuses, events and the sky; tests
        give one of their own, so the sky they judge is the same at any time of day."""
        self.settings = settings
        roots = {r.id: settings.rotator_topic(r) for r in settings.rotators}
        # interfaces/mqtt/groups.py
        groups = {g.id: settings.group_topic(g) for g in settings.groups}
        self.topics = Topics(settings.mqtt.base_topic, roots, groups)
        # the service publishes through the client; the client hands every message to the service
        self.me = Instance.me(  # interfaces/mqtt/claim.py rule 5: ``installation`` too
            settings.mqtt.effective_client_id(), installation(settings.state_file)
        )
        self.failure: str | None = None  # set when the bridge must not go on (claim rule 2, 4)
        self.failed = threading.Event()
        self.on_failed: Callable[[], None] | None = None  # (``_serve``: its wait ended at once)
        self._lane_started = False
        self._problems_lock = threading.Lock()  # rule 4
        # the heartbeat's wall clock and the one a stamped command is judged by (heartbeat.py)
        station_time = StationTime(wall, time.monotonic)
        self.client = MqttClient(
            settings.mqtt,
            will_topic=self.topics.bridge_state,
            subscriptions=[],  # the service's, added once its features are (end of __init__)
            on_message=lambda topic, payload, retain, operator, stamp: self.mqtt.on_message(
                topic, payload, retain, operator, gated=self.client.gated, stamp=stamp
            ),
            heartbeat=self.topics.bridge_heartbeat,  # client.py rule 2
            wall=station_time.now_unix,
            station=station_time.identity,  # heartbeat.py rule 7
            on_denied=self._denied,
            on_allowed=self._allowed,
            on_markers=self._markers,
            on_connect=self._connected,
            on_new_connection=self._main_new,
            on_subscribed=lambda: self._vouch("main"),
            on_connection_lost=lambda: self.mqtt.main_gone(),
            no_replay=[*self.topics.stop_lane(), *self.topics.lock_lane()],
            replayed=[  # a feature's input whose retain flag says "replayed" (the wind's)
                topic
                for f in FEATURES
                if f.replayed is not None
                for r in settings.rotators
                if (topic := f.replayed(r)) is not None
            ],
            claim=Claim(
                self.me,
                settings.mqtt.base_topic,
                self.topics.bridge_info,
                self.topics.bridge_hello,
                tuple(Post(p) for p in self.topics.posts())  # claim rule 5
                + tuple(Post(p, above=True) for p in self.topics.above()),
            ),
            on_refused=self._refused,
            fence_topic=self.topics.bridge_fence,  # client.py rule 16
            on_late=self._info,  # client.py rule 19
        )
        self.client.publish_retained(self.topics.bridge_info, self.me.info([]))  # sent on connect
        self.mqtt = MqttService(
            self.topics,
            self.client,
            wall=wall,
            error_events_per_s=settings.mqtt.error_events_per_s,
            retain_is_live=settings.mqtt.protocol != "3.1.1",  # "auto": until it steps down
            on_problem=lambda topic, problem: self._denied(topic, problem),
            on_info=lambda problem, on: self._info(problem, on),
            stamp_clock=station_time.now_unix,  # heartbeat.py rule 6
            station=station_time.identity,  # heartbeat.py rule 7
            broker_late=self.client.broker_late,  # service.py rule 12
            instance=self.me.id,  # claim.py rule 5: in each R/info
            installation=self.me.installation,
        )
        # lastword.py rule 15: a marker sent again at QoS 1; its refusal on both topics said
        self.mqtt.confirm_markers_with(
            self.client.publish_marker_confirmed, self.client.markers_refused
        )
        store = self.store = StateStore(  # (written by start; state_store.py rule 13)
            settings.state_file, deferred=True, read_from=tilde_leftover(settings.state_file)
        )
        try:
            store.check_kind()  # (a FIFO, a directory: refused now, nothing written: rule 4)
        except OSError as exc:
            raise _unwritable(settings.state_file, exc) from None
        self.lines = Lines()  # one thread serves every serial line (runtime/lines.py)
        self._stopped = threading.Event()
        self.rotators: list[Rotator] = []
        # the stop express's holds (interfaces/mqtt/express.py rule 8)
        self._by_id: dict[str, Rotator] = {}
        audit = settings.audit_file, settings.audit_max_bytes  # every command judged: R/audit
        self.audit = AuditTrail(*audit, self.mqtt.publish_audit, self.rotators)  # and the file
        self.rotctld: list[RotctldServer] = []  # one per rotator with a rotctld_port
        self.emulations: list[LineServer | PtyLineServer] = []  # GS-232, Easycomm, DCU-1 (gs232/)
        position = settings.station.position
        sky = Sky(*position) if position is not None else None
        catalog = self.catalog = TleCatalog(settings.tracking.tle_file)  # one file for all
        self.sky = SkyWorker()  # one thread computes the sky for all (sky/worker.py)
        self.web: WebConsole | None = None  # the operator console ([web])
        if settings.web.enabled:
            # aiohttp: a tenth of a start-up's CPU
            from bridge.interfaces.web.files import installation_secret
            from bridge.interfaces.web.server import WebConsole

            password = settings.web.password
            self.web = WebConsole(
                settings.web.bind,
                settings.web.port,
                password=password.get_secret_value() if password is not None else None,
                frame_ancestors=list(settings.web.frame_ancestors),
                host_names=list(settings.web.host_names),
                trusted_proxies=list(settings.web.trusted_proxies),
                secret=installation_secret(settings.console_secret())
                if password is not None
                else b"",
                station=position,
                locator=settings.station.locator,
                satellites=catalog.names,
                wall=station_time.now_unix,  # web/auth.py rule 2: never set back
            )
        satellites = tuple(catalog.names())  # for R/info, read once (interfaces/mqtt/payloads.py)
        follow = FollowConfig(position, wsjtx=settings.wsjtx.enabled)
        self.express = self._express(settings)  # interfaces/mqtt/express.py: a stop's frame first
        for r in settings.rotators:
            rot = Rotator(
                worker_config(r, sky, follow),
                store,
                on_status=self._listeners(r.id, "on_status"),
                on_event=self._listeners(r.id, "on_event"),
                name=r.name,
                port_opener=port_opener,
                wall=wall,
                lines=self.lines,
                station=settings.station.position,
                catalog=catalog,
                sky=self.sky,
                on_audit=self.audit.of(r.id),
                axes=axis_configs(r, sky, follow),  # a composite's two boxes (axis_configs)
                port_watch=self.express.watch(r.id),
                fence=self.mqtt,  # interfaces/mqtt/service.py rule 11
                lease_clock=station_time.now_unix,  # runtime/operators.py rule 5
            )
            self.mqtt.attach(  # what a console far from the station draws (remote/console.py)
                rot,
                ConsoleFacts(
                    position,
                    settings.station.locator,
                    r.beamwidth_deg,
                    r.nudge_step_deg,
                    satellites if rot.can_track else (),
                ),
            )
            if self.web is not None:
                from bridge.interfaces.web.view import RotatorFacts

                self.web.attach(rot, RotatorFacts(r.beamwidth_deg, r.nudge_step_deg))
            self.rotators.append(rot)
            self._by_id[r.id] = rot
            # each front end's code is imported only when a rotator asks for it: what a start
            # imports is most of its CPU (benchmarks/exchange_cpu.py, tests/test_cli.py)
            if r.rotctld_port is not None:
                from bridge.interfaces.rotctld import RotctldServer

                server = RotctldServer(
                    rot, r.rotctld_port, r.rotctld_bind, idle_timeout_s=r.rotctld_idle_timeout_s
                )
                self.rotctld.append(server)
            if any(
                getattr(r, f"{key}_{where}") is not None
                for key in EMULATION_KEYS
                for where in ("port", "pty")
            ):
                from bridge.interfaces.gs232 import EMULATIONS

                for emulation in EMULATIONS.values():
                    self.emulations += emulation.offered(rot, r)
        # turned together from G/target and G/stop (interfaces/mqtt/groups.py)
        for g in settings.groups:
            self.mqtt.attach_group(group_of(g))
        self.loggers: LoggerEndpoints | None = None  # the loggers' UDP ports, one thread for all
        for r, rot in zip(settings.rotators, self.rotators, strict=True):
            if r.pst_udp_port is None and r.n1mm_rotor_name is None:
                continue
            if self.loggers is None:
                from bridge.interfaces.loggers import LoggerEndpoints

                self.loggers = LoggerEndpoints()
            if r.pst_udp_port is not None:
                self.loggers.add_pst(rot, r.pst_udp_port, r.pst_udp_bind)
            if r.n1mm_rotor_name is not None:
                self.loggers.add_n1mm(
                    rot,
                    r.n1mm_rotor_name,
                    r.n1mm_udp_port,
                    r.n1mm_udp_bind,
                    r.n1mm_report_address,
                    tuple(r.bands),
                )
        # what WSJT-X says goes to every rotator (interfaces/wsjtx/server.py)
        wsjtx = settings.wsjtx
        self.wsjtx: WsjtxListener | None = None
        if wsjtx.enabled:
            from bridge.interfaces.wsjtx import WsjtxListener

            self.wsjtx = WsjtxListener(wsjtx.port, wsjtx.bind, wsjtx.multicast_group)
            self.wsjtx.rotators += self.rotators
        self.services: dict[str, FeatureService] = {}  # the station's features (the DX cluster)
        for feature in FEATURES:  # each imported only when its settings turn it on
            if feature.serves(settings):
                view = AppView(settings, position, self._publishers(feature), self.mqtt, wall)
                service = make_service(feature, view)
                if service is not None:
                    self.services[feature.name] = service
        pairs = list(zip(settings.rotators, self.rotators, strict=True))
        for feature in FEATURES:  # the inputs of the user's topics (bridge/feature.py)
            given = feature.inputs(pairs) if feature.inputs is not None else None
            if given is not None:
                self.mqtt.add_feature(given.subscriptions, given.on_message)
        self.discovery: DiscoveryPublisher | None = None
        if settings.homeassistant.enabled or not settings.base_under_discovery():
            # off: an earlier run's configs cleared (homeassistant/publisher.py rule 6), unless
            # the base topic lies under the prefix: a run with discovery on refuses that, so it
            # published nothing there, and the bridge's own topics are not read as configs
            self.discovery = self._discovery(settings, retired=not settings.homeassistant.enabled)
        self._stale(settings)  # interfaces/mqtt/stale.py: a removed rotator's retained topics
        self.client.add_subscriptions(self.mqtt.subscriptions())
        self.client.optional(self.mqtt.optional)  # (service.py rule 10, client.py rule 17)
        if self.discovery is not None:
            self.client.optional(self.discovery.optional)  # (client.py rule 17)
        self.lane = StopLane(
            settings.mqtt,
            subscriptions=self.mqtt.stop_lane_subscriptions(),
            on_message=partial(self.mqtt.on_lane_message, lane="stop"),
            on_denied=partial(self._denied, lanes=("stop",)),
            on_info=self._info,
            on_new_connection=partial(self.mqtt.lane_connected, ("stop",)),
            on_subscribed=partial(self._lane_subscribed, "stop"),
            behind_subscribe=partial(self.mqtt.lane_subscribing, ("stop",)),
            no_replay=self.topics.stop_lane(),
        )
        # interfaces/mqtt/lastword.py rule 16: the lock words on a lane of their own, so that
        # no flood of them sits ahead of a stop on the stop lane
        self.lock_lane = StopLane(
            settings.mqtt,
            subscriptions=self.mqtt.lock_lane_subscriptions(),
            on_message=partial(self.mqtt.on_lane_message, lane="lock"),
            on_denied=partial(self._denied, lanes=("lock",)),
            on_info=self._info,
            kind="lock",
            on_new_connection=partial(self.mqtt.lane_connected, ("lock",)),
            on_subscribed=partial(self._lane_subscribed, "lock"),
            behind_subscribe=partial(self.mqtt.lane_subscribing, ("lock",)),
            no_replay=self.topics.lock_lane(),
        )
        # interfaces/mqtt/lane.py rule 4: a stop (a lock ON) before a backlog
        self.client.before_message = self._lanes_first
        self.client.watch_owned(self.topics.owned())
        for rid in sorted(store.locked_ids() - set(self._by_id)):  # state_store.py rule 9
            log.warning(
                "state file %s keeps the safety lock ON for %r, which is no rotator of the "
                "configuration (renamed or removed?): that lock holds nothing now; a renamed "
                "rotator starts as its new id was kept",
                shown_path(settings.state_file),
                rid,
            )
        # runtime/kept.py rule 10: a lock ON an earlier run said, which the state file lost
        by_lock_state = {self.topics.rotator(rot.id).lock_state: rot for rot in self.rotators}
        for rot in self.rotators:
            rot.await_heard_lock()  # (no motion until the first look has said it)
        self.client.witness(set(by_lock_state), partial(_heard, by_lock_state))
        self._installation = contextlib.ExitStack()  # state_store.py rule 7 (start takes it)

    def release(self) -> None:
        """This installation's lock let go (state_store.py rule 7): at the stop, or when the
        start failed."""
        self._installation.close()

    def _publishers(self, feature: Feature) -> tuple[Callable[[str], None], ...]:
        """A feature's retained topics under the base topic (``B/spots``); the console's
        ``on_<suffix>`` gets each document first, contained (interfaces/web/live.py rule 6)."""
        out = []
        for suffix in feature.base_topics:
            to_mqtt = partial(self.client.publish_retained, self.topics.under_base(suffix))
            console = getattr(self.web, f"on_{suffix}", None)
            if console is not None:
                # (with the console's server, above)
                from bridge.interfaces.web.live import with_console

                out.append(with_console(to_mqtt, console))
            else:
                out.append(to_mqtt)
        return tuple(out)

    def _express(self, settings: Settings) -> Express:
        """The stop express (interfaces/mqtt/express.py) for the rotators whose model takes a stop
        frame at any moment (its rule 4); none with ``mqtt.stop_express`` off."""
        topics: dict[str, tuple[str, str]] = {}
        frames: dict[str, bytes] = {}
        for r in settings.rotators if settings.mqtt.stop_express else ():
            t = self.topics.rotator(r.id)
            topics[t.lock] = (r.id, "lock")  # every rotator's lock ON, said (its rule 11)
            topics[t.stop] = (r.id, "stop")  # and stop, written or said (its rules 3, 11)
            # (a rotator of two boxes has two ports: its stops take the stop lane)
            # (nor does a stop of several frames: an RC2800's, paced by the session)
            if r.spec.stop_anytime and not r.axes:
                stop = r.spec.codec_factory().encode_stop()
                if isinstance(stop, bytes):
                    frames[r.id] = stop
        groups = {  # a group's stop: each member's frame (interfaces/mqtt/groups.py)
            self.topics.group(g.id).stop: tuple(g.rotators) for g in settings.groups
        }
        express = Express(
            settings.mqtt,
            topics=topics,
            frames=frames,
            on_problem=self._info,
            groups=groups,
            sync_topic=self.topics.bridge_fence_express,
            on_hold=lambda rid, n: self._by_id[rid].express_hold(n),
            on_release=lambda rid, n, lost: self._by_id[rid].express_release(n, lost),
            on_wrote=self._express_wrote,
            on_locked=self._express_locked,
        )
        self.mqtt.hold_for_express(express.hold)  # its rule 8: a late frame stops no newer move
        return express

    def _express_wrote(
        self, rotator_id: str, t: float, operator: str | None = None, early: bool = False
    ) -> None:
        """interfaces/mqtt/express.py rule 11: a stop the express wrote a frame for at ``t``,
        or read at ``t`` and wrote none for (from ``operator``; ``early``: before its words
        came back), is the rotator's stop too when neither connection could have had that
        stop (audited as its sender's: an attack pass found it named ``mqtt`` alone)."""
        rotator = self._heard_only_by_express(rotator_id, t, "stop", early)
        if rotator is None:
            return
        log.warning(
            "%s: a stop the stop express heard while the bridge's connections may have been "
            "away: carried out here too",
            rotator_id,
        )
        stop = Stop(Source.MQTT, self.mqtt.origin(operator))
        rotator.submit(stop, "stop (heard by the stop express)")

    def _express_locked(
        self, rotator_id: str, t: float, operator: str | None, early: bool = False
    ) -> None:
        """interfaces/mqtt/express.py rule 11: a lock ON the express read at ``t`` (from
        ``operator``; ``early``: before its words came back) is set when neither connection
        could have had it."""
        rotator = self._heard_only_by_express(rotator_id, t, "lock", early)
        if rotator is None:
            return
        log.warning(
            "%s: a lock ON the stop express heard while the bridge's connections were away: "
            "the lock is set here too",
            rotator_id,
        )
        lock = Lock(True, source=Source.MQTT, origin=self.mqtt.origin(operator))
        rotator.submit(lock, "lock ON (heard by the stop express)")

    def _heard_only_by_express(
        self, rotator_id: str, t: float, kind: str, early: bool = False
    ) -> Rotator | None:
        """Rule 11's test: the rotator, if neither connection could have had the ``kind``
        ("stop" or "lock") the express read at ``t``. ``early`` (read before the express's
        words came back on its connection): its vouches do not order it, only the halts read."""
        for via in () if early else ("main", "lane" if kind == "stop" else "lock"):
            connection = self._connection(via)  # (lastword.py rule 16: the lane of the kind)
            vouched = self.express.vouched(via)  # (the express's word came after its SUBACK,
            if vouched is not None and connection.heard_since(vouched):  # and this after that)
                return None  # (it came, or comes, on one of them, in its order)
        if self.mqtt.halt_read_since(rotator_id, kind, self._connection_heard_since):
            return None  # (it came on one of them, or a later halt did: halts.py read_since)
        return self._by_id.get(rotator_id)

    def _lanes_first(self) -> None:
        """interfaces/mqtt/lane.py rule 4: the main connection waits for each lane in turn."""
        self.lane.first()
        self.lock_lane.first()

    def _lane_subscribed(self, kind: str) -> None:
        """A lane's SUBACK (lastword.py rules 9 and 16): ``kind``, "stop" or "lock"."""
        self.mqtt.lane_subscribed((kind,))
        self._vouch("lane" if kind == "stop" else "lock")

    def _connection(self, via: str) -> Connection:
        """The connection ``via`` names (halts.py ``read_since``): "main", "lane" or "lock"."""
        return {"main": self.client, "lane": self.lane, "lock": self.lock_lane}[via]

    def _vouch(self, via: str) -> None:
        """express.py rule 11: a connection's command topics subscribed (on its paho thread):
        the express is asked to vouch that the stops it says from then on came after it."""
        since = self._connection(via).subscribed_since
        if since is not None:
            self.express.vouch(via, since)

    def _connection_heard_since(self, via: str, t: float) -> bool:
        return self._connection(via).heard_since(t)

    def _listeners(self, rotator_id: str, which: str) -> Callable[[Any], None]:
        """MQTT's listener and the console's, each contained (a failing console never costs
        MQTT a status, nor the other way round)."""
        mqtt = self.mqtt.publish_status if which == "on_status" else self.mqtt.publish_event
        if self.web is None:
            return partial(mqtt, rotator_id)
        web = self.web.on_status if which == "on_status" else self.web.on_event
        both = [
            contained(partial(mqtt, rotator_id), f"{rotator_id}: MQTT {which}"),
            contained(partial(web, rotator_id), f"{rotator_id}: web console {which}"),
        ]

        def call(value: Any) -> None:
            for listener in both:
                listener(value)

        return call

    def _stale(self, settings: Settings) -> None:
        """interfaces/mqtt/stale.py rule 2: what a removed rotator or group left retained, a
        rotator's state of a feature it no longer has or a topic its model never fills (rule
        5), and a station feature's topic while the feature is off (rule 6: ``B/spots``), is
        deleted at the first look, when the base topic was this bridge's."""
        roots = {settings.rotator_topic(r) for r in settings.rotators}
        groups = {settings.group_topic(g) for g in settings.groups}
        # (rule 5: a feature's state a rotator no longer has, as the service skips it)
        unpublished = {
            self.topics.rotator(rot.id).feature(state.suffix)
            for rot in self.rotators
            for feature in self.topics.features
            for state in feature.states
            if state.needs is not None and not getattr(rot, state.needs)
        }
        options: dict[str, tuple[str, ...]] = {}  # (rule 5: and what its model never publishes)
        for r, rot in zip(settings.rotators, self.rotators, strict=True):
            t = self.topics.rotator(rot.id)
            boxes = tuple(r.axis_spec(axis) for axis in Axis) if r.axes else ()
            unpublished.update(never_published(t, rot.spec, boxes))
            options[t.root] = rot.spec.options
        # (rule 6: a station feature's topics under the base topic while its service is off)
        unpublished.update(
            self.topics.under_base(suffix)
            for feature in FEATURES
            if feature.name not in self.services
            for suffix in feature.base_topics
        )
        stale = StaleTopics(self.topics, roots | groups, groups, unpublished, options)
        clear = self.client.clear_retained

        def on_message(topic: str, payload: bytes, retain: bool) -> bool:
            doomed = stale.stale(topic, payload) if retain and payload else []
            for t in doomed:
                clear(t)
            return bool(doomed)

        self.mqtt.add_feature(stale.subscriptions, on_message)
        # (rule 4: a group's G/info is one of the bridge's own topics, judged here first)
        self.client.peek(stale.peeked, lambda topic, payload: on_message(topic, payload, True))
        self.client.spare = stale.spared  # (rule 3: judged when the look ends)

    def _discovery(self, settings: Settings, *, retired: bool) -> DiscoveryPublisher:
        ha = settings.homeassistant
        client = self.client
        discovery_topics = DiscoveryTopics(ha.discovery_prefix)
        infos = []
        on = self.services  # a feature of the station is on for every rotator
        for r, rot in zip(settings.rotators, self.rotators, strict=True):
            infos.append(
                RotatorInfo.of(
                    r.id,
                    r.name or r.id,
                    r.spec,
                    self.topics.rotator(r.id),
                    rot.pointing,
                    has_station=settings.station.position is not None,
                    nudge_step_deg=r.nudge_step_deg,
                    satellites=tuple(self.catalog.names()),
                    can_follow=rot.can_follow,
                    features=frozenset(f.name for f in FEATURES if f.on_for(r) or f.name in on),
                    boxes=tuple(r.axis_spec(axis) for axis in Axis) if r.axes else (),
                    version=rot.version,  # kept (runtime/kept.py rule 11): said at once
                )
            )
        publisher = DiscoveryPublisher(
            prefix=ha.discovery_prefix,
            status_topic=ha.status_topic,
            topics=self.topics,
            rotators=infos,
            groups=tuple(  # a device each (interfaces/mqtt/groups.py)
                GroupInfo(g.id, g.label, self.topics.group(g.id), tuple(g.rotators))
                for g in settings.groups
            ),
            publish_retained=partial(client.publish_retained, qos=1),
            clear_retained=client.clear_retained,
            republish_state=lambda: client.republish_retained(skip_prefix=discovery_topics.subtree),
            birth_delay_s=ha.birth_delay_s,
            publish_again=partial(client.publish_retained, qos=1, only_if_changed=False),
            retired=retired,
        )
        self.mqtt.add_feature(publisher.subscriptions, publisher.on_message, publisher.on_status)
        for service in self.services.values():  # (the DX cluster's spot select)
            service.with_discovery(publisher)
        return publisher

    def _denied(self, topic: str, problem: str, lanes: tuple[str, ...] = ("stop",)) -> None:
        """The broker refused a topic (client.py rule 11): the rotator's status says so, and
        ``B/bridge/info`` lists every such problem. ``lanes``: the lane's kinds, when a lane
        was refused it (lastword.py rule 16)."""
        if topic == self.topics.bridge_fence_lane:  # (the fence's: ``_markers``)
            self.mqtt.lane_markers_denied(lanes)
        rid = self.topics.rotator_of(topic)
        for rot in self.rotators:
            if rid is None or rot.id == rid:
                rot.note(problem)
        self._say(problem, True)  # a lane's (the client's is in the list already)

    def _allowed(self, topic: str) -> None:
        """The broker takes a topic it refused before (client.py rule 16: the fence's probe
        came back on a new connection): ``B/bridge/info`` without it."""
        self._say()  # (the client took it out of the list)

    def _markers(self, readable: bool) -> None:
        """client.py rule 16: whether the main connection can read back its markers, on the
        fence topic or the hello topic (lastword.py rule 7)."""
        if readable:
            self.mqtt.markers_allowed()
        else:
            self.mqtt.markers_denied()

    def _info(self, problem: str, on: bool) -> None:
        """A problem said on ``B/bridge/info`` while it lasts (a long hold:
        interfaces/mqtt/halts.py)."""
        self._say(problem, on)

    def _say(self, problem: str | None = None, on: bool = True) -> None:
        """Rule 4: ``problem`` in the list (or out of it), and the list as it then is published
        retained on ``B/bridge/info``, in one step."""
        with self._problems_lock:
            problems = self.client.problems
            if problem is not None and on and problem not in problems:
                problems.append(problem)
            elif problem is not None and not on and problem in problems:
                problems.remove(problem)
            self.client.publish_retained(self.topics.bridge_info, self.me.info(list(problems)))

    def _main_new(self) -> None:
        """A new main connection, before any of its messages: the protocol it speaks (mqtt/
        connection.py rule 1: "auto" may have stepped down) says what a retained flag means."""
        self.mqtt.retain_is_live(self.client.v5)
        self.mqtt.main_gone()

    def _connected(self) -> None:
        """The main connection is up (its first look done): the stop lane connects too, now
        that the broker is known to take the bridge (a wrong password is refused once, not
        twice per try)."""
        if not self._lane_started and not self._stopped.is_set():
            self._lane_started = True
            # mqtt.protocol "auto" stepped down (interfaces/mqtt/connection.py)
            for lane in (self.lane, self.lock_lane):
                if not self.client.v5:
                    lane.use_mqtt311()
                lane.start()
            self.express.start(mqtt311=not self.client.v5)
        stepped_down = self.settings.mqtt.protocol == "auto" and not self.client.v5
        if stepped_down != (STEPPED_DOWN in self.client.problems):
            # said while it lasts (interfaces/mqtt/connection.py rule 1); not on paho's thread,
            # which holds paho's mutex here while the publish takes the client's lock
            threading.Thread(
                target=self._info, args=(STEPPED_DOWN, stepped_down), daemon=True
            ).start()

    def _refused(self, message: str) -> None:
        """Another bridge owns the base topic (interfaces/mqtt/claim.py): ``run`` stops, exit code
        2; 1 where it yields while running (claim rule 4: ``stop`` halts every rotator first).
        Yielding, every rotator takes nothing but a halt from the verdict on, not from ``stop``
        (a review: ``_serve``'s wait, up to a second, let a front end turn one meanwhile)."""
        if self.client.yielded:
            for rot in self.rotators:
                rot.leave(YIELDING)
        self.failure = message
        self.failed.set()
        if self.on_failed is not None:
            self.on_failed()

    def _halt_all(
        self, *, turning_only: bool = False, done: frozenset[str] = frozenset()
    ) -> frozenset[str]:
        """Claim rule 4: before the bridge yields its base topic while running, every rotator
        is stopped, and the stops written (up to HALT_WAIT_S): nothing of this process is left
        to stop one after it goes. ``turning_only`` (rule 6, any other end): those that may
        turn (``Rotator.may_turn``), but those in ``done`` (stopped so already: a SatEL's
        slew shows no reading to say it took, and a second frame would add nothing). The ids
        of the rotators stopped."""
        marks = []
        why = "is stopping" if turning_only else "yields its base topic"
        for rot in self.rotators:
            if turning_only and (rot.id in done or not rot.may_turn()):
                continue
            try:
                rot.submit(Stop(Source.MQTT), f"stop: the bridge {why}")
            except Exception:  # (a stop is never refused; a bug must not keep the others)
                log.exception("%s: the stop as the bridge %s failed", rot.id, why)
                continue
            marks.append((rot, rot.halts))
        deadline = time.monotonic() + HALT_WAIT_S
        for rot, mark in marks:  # applied, and written (a review: a SPID's waits for a reply)
            while not (rot.halts_applied >= mark and rot.stop_written):
                if time.monotonic() >= deadline:
                    break
                time.sleep(0.01)  # (shutting down: nothing else waits on this thread)
        return done | {rot.id for rot, _ in marks}

    def check_catalog(self) -> None:
        """The TLE file re-read if it changed; Home Assistant's track select follows it."""
        if self.discovery is not None:
            self.discovery.set_satellites(tuple(self.catalog.names()))

    def _watch_catalog(self) -> None:
        while not self._stopped.wait(CATALOG_CHECK_S):
            try:
                self.check_catalog()
            except Exception:  # a watcher that dies would leave the select stale for good
                log.exception("checking the TLE file failed")

    def start(self) -> None:
        """ConfigError, before anything runs or is published, if a rotctld port cannot be had
        or another process runs this installation (state_store.py rule 7: its lock, taken
        first; a bridge built and never started holds none)."""
        state_file = self.settings.state_file
        try:
            self._installation.enter_context(held(state_file))
            if self.store.leftover is not None:  # (state_store.py rule 13: read as its own)
                self._installation.enter_context(held(self.store.leftover))
        except InUse as exc:
            by = f" ({exc.holder})" if exc.holder else ""
            raise ConfigError(
                f"another rotor-bridge runs this installation{by}: its state_file "
                f"{shown_path(str(state_file))} "
                "is in use. Stop that one first (two would take turns on the broker under one "
                "client id, and a stop could be lost between them), or give this one its own "
                "state_file"
            ) from None
        except OSError as exc:
            raise _unwritable(state_file, exc) from None
        try:
            self.store.check_writable()  # (state_store.py rule 3: once this one holds it)
        except Changed:
            self.release()
            raise NotYet(  # state_store.py rule 11: the next start reads it as it is now
                f"state_file {shown_path(str(state_file))} changed since this bridge read it "
                "(another bridge on it was ending?): not started, so as not to run on, and "
                "write back, what the file said before; start it again"
            ) from None
        except OSError as exc:
            self.release()
            raise _unwritable(state_file, exc) from None
        # the sky worker computes in Python for up to a second; a thread waking for a stop waits
        # for the interpreter lock up to this long, each time it takes it (5 ms by default)
        sys.setswitchinterval(GIL_SWITCH_S)
        ports_hold = sum(server.most_held for server in self._text_ports())  # rule 5
        ports_hold += self.web.most_held if self.web is not None else 0
        _room_for_files(ports_hold, FILES_SPARE + 2 * len(self.rotators))
        try:
            for server in self._text_ports():
                server.listen()
            if self.loggers:
                self.loggers.listen()
            if self.wsjtx is not None:
                self.wsjtx.listen()
            if self.web is not None:
                self.web.listen()
        except OSError as exc:
            for server in self._text_ports():
                server.stop()
            self._stop_udp()
            if exc.errno == errno.EADDRNOTAVAIL:  # an interface not up yet at boot
                raise NotYet(exc.strerror or str(exc)) from None
            raise ConfigError(exc.strerror or str(exc)) from None
        if self.discovery is not None:
            self.discovery.publish_all()  # cached now, sent on connect
        self.audit.start()
        self.mqtt.start()  # the stop lane follows the first connection (_connected)
        for rot in self.rotators:
            rot.start()  # the lines thread publishes its status, the first one included
        if self.settings.tracking.tle_file is not None and self.discovery is not None:
            threading.Thread(target=self._watch_catalog, name="tle-file", daemon=True).start()
        try:
            for server in self._text_ports():
                server.start()
            if self.loggers:
                self.loggers.start()
            if self.wsjtx is not None:
                self.wsjtx.start()
            for service in self.services.values():
                service.start()
        except OSError:  # e.g. the port is taken: fail the start, leave nothing running
            self.stop()
            raise

    def _text_ports(self) -> list[LineServer | PtyLineServer]:
        """rotctld's, GS-232's and Easycomm's TCP ports and ptys: listened on (a pty linked),
        started, stopped alike."""
        return [*self.rotctld, *self.emulations]

    def _stop_udp(self) -> None:
        """The loggers' and WSJT-X's UDP ports, those there are, stopped."""
        if self.loggers is not None:
            self.loggers.stop()
        if self.wsjtx is not None:
            self.wsjtx.stop()

    def stop(self) -> None:
        self._stopped.set()
        self.client.shutting_down()
        self.express.shutting_down()  # (its rule 7: an end from now on is not a restart)
        yielded = self.client.yielded
        # claim rule 4, rule 6: at once, before any front end takes its time to close (a web
        # console's up to 10 s: a turn went on meanwhile), and no front end still open turns one
        for rot in self.rotators:  # again
            rot.leave(YIELDING if yielded else STOPPING)
        halted = self._halt_all(turning_only=not yielded)
        if self.discovery is not None:
            self.discovery.stop()
        for server in self._text_ports():
            server.stop()
        self._stop_udp()
        for service in self.services.values():
            service.stop()
        if self.web is not None:
            self.web.stop()  # each page sees the bridge go (interfaces/web/server.py rule 6)
        # claim rule 4, rule 6: again once no front end can send a move after it (a review),
        # while the lines still run and the lane takes stops
        self._halt_all(turning_only=not yielded, done=halted)
        for rot in self.rotators:
            rot.stop()
        self.store.flush()  # the last lock or option set is on disk (state_store.py rule 5)
        self.audit.stop()  # what is queued is written (audit.py rule 4)
        self.mqtt.stop()  # first: its offline goes out, and it stops reconnecting
        self.lane.stop()  # (a stop on it now reaches no rotator: they are stopped)
        self.lock_lane.stop()
        self.express.stop()  # (the ports are closed: it holds none)
        self.store.flush()  # rule 6: a lock word taken since the flush above, before letting go
        self.release()
        log.info("stopped")


def _heard(
    by_lock_state: dict[str, Rotator], heard: dict[str, bytes], unread: frozenset[str]
) -> dict[str, Callable[[], bool]]:
    """runtime/kept.py rule 10: each rotator's ``R/lock/state`` as the broker held it before
    this start (interfaces/mqtt/look.py rule 14), None where it held none; the topics whose
    ON locked its rotator, each with whether it is locked still (left as the broker holds them
    while it is: the OFF cached before is older). A topic the broker does not let the bridge
    read (``unread``) is left alone too while its rotator waits for a lock word."""
    out: dict[str, Callable[[], bool]] = {}
    for topic, rot in by_lock_state.items():
        if topic in unread and rot.lock_unread():
            out[topic] = _waits_still(rot)
        elif topic not in unread and rot.heard_lock(heard.get(topic)):
            out[topic] = _locked_still(rot)
    return out


def _locked_still(rot: Rotator) -> Callable[[], bool]:
    return lambda: rot.locked


def _waits_still(rot: Rotator) -> Callable[[], bool]:
    return lambda: rot.lock_waits


def _room_for_files(ports_hold: int, spare: int) -> None:
    """Rule 5: the soft open-files limit raised to what is open now, what the ports may hold
    (``ports_hold``) and ``spare`` more, up to the hard limit; a warning if that is short."""
    try:
        import resource
    except ImportError:  # (no such limit where there is no ``resource``)
        return
    try:
        open_now = len(os.listdir("/proc/self/fd"))
    except OSError:
        open_now = 0
    need = open_now + ports_hold + spare
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if soft == resource.RLIM_INFINITY or soft >= need:
        return
    room = need if hard == resource.RLIM_INFINITY else min(need, hard)
    if room > soft:
        try:
            resource.setrlimit(resource.RLIMIT_NOFILE, (room, hard))
        except (OSError, ValueError) as exc:
            log.warning("cannot raise the open-files limit from %d to %d: %s", soft, room, exc)
            room = soft
        else:
            log.info(
                "open-files limit raised from %d to %d: the TCP ports and the console may hold "
                "%d connections",
                soft,
                room,
                ports_hold,
            )
    if room < need:
        log.warning(
            "the process may open %d files (ulimit -n; systemd: LimitNOFILE), but its TCP ports "
            "and the console may hold %d connections beside the %d it has open: connections "
            "held open by anyone who can reach them could leave it none to reopen a serial "
            "port, reconnect to the broker or save the state file; set the limit to %d or more",
            room,
            ports_hold,
            open_now,
            need,
        )


def _unwritable(state_file: Path | None, exc: OSError) -> ConfigError:
    """The start's words for a state file it cannot write (or lock beside)."""
    where = f" ({shown_path(exc.filename)})" if exc.filename else ""
    shown = shown_path(str(state_file))
    return ConfigError(f"state_file {shown} cannot be written: {exc.strerror or exc}{where}")


def run(settings: Settings, stop_event: threading.Event | None = None) -> int:
    """Run until SIGTERM/SIGINT (or ``stop_event``); exit code 0 on a clean stop.

    The signals end the wait through core/ending.py, whose handlers take no lock: one that set
    an Event could land while this thread held that Event's own lock, and wait for ever."""
    ending = Ending()
    # a caller's stop_event (a test's) is set from another thread: off the main thread, where no
    # signal is handled, the wait is on it; on the main thread, on the signals
    on_main = threading.current_thread() is threading.main_thread()
    wait = ending.wait if on_main or stop_event is None else stop_event.wait
    # (SIGHUP: the terminal of a bridge run by hand closed; as the others, a clean stop, but
    # not under nohup, which asked for it to be ignored: a review)
    hup = () if signal.getsignal(signal.SIGHUP) is signal.SIG_IGN else (signal.SIGHUP,)
    signals = signal.SIGTERM, signal.SIGINT, *hup
    try:
        with ending.on_signals(*signals):  # a second one: rule 3 there
            return _serve(settings, wait, ending, stop_event)
    finally:
        ending.close()


def _serve(
    settings: Settings,
    wait: Callable[[float | None], bool],
    ending: Ending,
    stop_event: threading.Event | None,
) -> int:
    try:
        app = App(settings)
    except OSError as exc:  # not foreseen, but a start that cannot work all the same
        raise ConfigError(f"cannot start: {exc}") from None
    app.on_failed = ending.end  # (no reason: the failure says its own words)
    try:
        app.start()
    except BaseException:
        app.release()
        raise
    # rule 12: a full collection no longer walks the start-up's 70,000 objects (30-80 ms). No
    # collection first: it walked them all once more (15 ms of the start's CPU) to free what a
    # start leaves as garbage, some 30 KB (Home Assistant's entities, with no finalizer), kept
    gc.freeze()
    # The wait ends on a signal or the app's failure (``ending``), at once: the thread sleeps
    # until then (a look once a second was a wake-up a second of an idle bridge's ten, each
    # costing what a hundred calls do). A caller's stop_event (a test's) is looked at once a
    # second, and app.failed with it where the wait is on that event (off the main thread).
    poll_s = None if stop_event is None else 1.0
    try:
        while not wait(poll_s) and not app.failed.is_set():
            if stop_event is not None and stop_event.is_set():
                break
        if ending.reason is not None and not app.failed.is_set():  # (a failure says its own)
            log.info("%s received, shutting down", ending.reason)
    finally:
        app.stop()
        gc.unfreeze()  # a caller that runs the bridge again (the tests) keeps no garbage
    if app.failure is not None:
        if app.client.yielded:  # claim rule 4: the next start's first look decides
            raise NotYet(app.failure)
        raise ConfigError(app.failure)
    return 0
