"""Composition root: settings -> rotators (workers) -> MQTT; signals; ordered shutdown."""

from __future__ import annotations

import errno
import gc
import logging
import signal
import sys
import threading
import time
from collections.abc import Callable
from functools import partial
from typing import TYPE_CHECKING, Any

from bridge.dxcluster import CtyError, DxCluster
from bridge.dxcluster.setup import dxcluster
from bridge.engine.audit import AuditTrail
from bridge.engine.catalog import TleCatalog
from bridge.engine.config import FollowConfig
from bridge.engine.lines import Lines
from bridge.engine.listeners import contained
from bridge.engine.port import PortOpener, open_port
from bridge.engine.rotator import Rotator
from bridge.engine.skywork import SkyWorker
from bridge.engine.state_store import StateStore
from bridge.features import FEATURES
from bridge.gs232 import EMULATIONS
from bridge.homeassistant import DiscoveryPublisher, GroupInfo, RotatorInfo
from bridge.loggers import LoggerEndpoints
from bridge.mqtt.claim import Claim, Instance
from bridge.mqtt.client import MqttClient
from bridge.mqtt.connection import MQTT311_LOSES
from bridge.mqtt.express import Express
from bridge.mqtt.lane import StopLane
from bridge.mqtt.payloads import ConsoleFacts
from bridge.mqtt.service import MqttService
from bridge.mqtt.topics import DiscoveryTopics, Topics
from bridge.ptylines import PtyLineServer
from bridge.rotctld import RotctldServer
from bridge.settings import ConfigError, Settings
from bridge.sky import Sky
from bridge.tcplines import LineServer
from bridge.web.files import installation_secret
from bridge.web.view import RotatorFacts
from bridge.wiring import axis_configs, group_of, worker_config
from bridge.wsjtx import WsjtxListener

if TYPE_CHECKING:  # the console's server and aiohttp are imported only when it is on
    from bridge.web.server import WebConsole

__all__ = ["App", "NotYet", "run", "worker_config"]

log = logging.getLogger(__name__)

GIL_SWITCH_S = 0.0005
STEPPED_DOWN = (  # on B/bridge/info while mqtt.protocol "auto" speaks MQTT 3.1.1
    "the MQTT broker did not take MQTT 5, so the bridge speaks MQTT 3.1.1: "
    + MQTT311_LOSES
    + '; if the broker does speak MQTT 5, set mqtt.protocol = "5"'
)
CATALOG_CHECK_S = 30.0  # the TLE file's names for Home Assistant's track select, this often


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
        groups = {g.id: settings.group_topic(g) for g in settings.groups}  # mqtt/groups.py
        self.topics = Topics(settings.mqtt.base_topic, roots, groups)
        # the service publishes through the client; the client hands every message to the service
        self.me = Instance.me(settings.mqtt.effective_client_id())  # mqtt/claim.py
        self.failure: str | None = None  # set when the bridge must not go on (claim rule 2, 4)
        self.failed = threading.Event()
        self._lane_started = False
        self.client = MqttClient(
            settings.mqtt,
            will_topic=self.topics.bridge_state,
            subscriptions=[],  # the service's, added once its features are (end of __init__)
            on_message=lambda topic, payload, retain, operator, stamp: self.mqtt.on_message(
                topic, payload, retain, operator, gated=self.client.gated, stamp=stamp
            ),
            heartbeat=self.topics.bridge_heartbeat,  # client.py rule 2
            wall=wall,
            on_denied=self._denied,
            on_allowed=self._allowed,
            on_connect=self._connected,
            on_new_connection=self._main_new,
            on_connection_lost=lambda: self.mqtt.main_gone(),
            no_replay=self.topics.stop_lane(),
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
            ),
            on_refused=self._refused,
            fence_topic=self.topics.bridge_fence,  # client.py rule 16
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
        )
        store = self.store = StateStore(settings.state_file)
        try:
            store.check_writable()
        except OSError as exc:
            where = f" ({exc.filename})" if exc.filename else ""
            raise ConfigError(
                f"state_file {settings.state_file} cannot be written: {exc.strerror or exc}{where}"
            ) from None
        self.lines = Lines()  # one thread serves every serial line (engine/lines.py)
        self._stopped = threading.Event()
        self.rotators: list[Rotator] = []
        audit = settings.audit_file, settings.audit_max_bytes  # every command judged: R/audit
        self.audit = AuditTrail(*audit, self.mqtt.publish_audit, self.rotators)  # and the file
        self.rotctld: list[RotctldServer] = []  # one per rotator with a rotctld_port
        self.emulations: list[LineServer | PtyLineServer] = []  # GS-232, Easycomm, DCU-1 (gs232/)
        position = settings.station.position
        sky = Sky(*position) if position is not None else None
        catalog = self.catalog = TleCatalog(settings.tracking.tle_file)  # one file for all
        self.sky = SkyWorker()  # one thread computes the sky for all (engine/skywork.py)
        self.web: WebConsole | None = None  # the operator console ([web])
        if settings.web.enabled:
            from bridge.web.server import WebConsole  # aiohttp: a tenth of a start-up's CPU

            password = settings.web.password
            self.web = WebConsole(
                settings.web.bind,
                settings.web.port,
                password=password.get_secret_value() if password is not None else None,
                frame_ancestors=list(settings.web.frame_ancestors),
                host_names=list(settings.web.host_names),
                secret=installation_secret(settings.state_file.with_name("console-secret"))
                if password is not None
                else b"",
                station=position,
                locator=settings.station.locator,
                satellites=catalog.names,
                wall=wall,
            )
        satellites = tuple(catalog.names())  # for R/info, read once (mqtt/payloads.py)
        follow = FollowConfig(position, wsjtx=settings.wsjtx.enabled)
        self.express = self._express(settings)  # mqtt/express.py: a stop's frame first
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
                axes=axis_configs(r, sky, follow),  # a composite's two boxes (wiring.py)
                port_watch=self.express.watch(r.id),
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
                self.web.attach(rot, RotatorFacts(r.beamwidth_deg, r.nudge_step_deg))
            self.rotators.append(rot)
            if r.rotctld_port is not None:
                server = RotctldServer(
                    rot, r.rotctld_port, r.rotctld_bind, idle_timeout_s=r.rotctld_idle_timeout_s
                )
                self.rotctld.append(server)
            for emulation in EMULATIONS.values():
                self.emulations += emulation.offered(rot, r)
        for g in settings.groups:  # turned together from G/target and G/stop (mqtt/groups.py)
            self.mqtt.attach_group(group_of(g))
        self.loggers = LoggerEndpoints()  # the loggers' UDP ports, one thread for all
        for r, rot in zip(settings.rotators, self.rotators, strict=True):
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
        wsjtx = settings.wsjtx  # what WSJT-X says goes to every rotator (wsjtx/server.py)
        self.wsjtx = WsjtxListener(wsjtx.port, wsjtx.bind, wsjtx.multicast_group)
        self.wsjtx.rotators += self.rotators if wsjtx.enabled else []
        self.dxcluster: DxCluster | None = None  # spots on B/spots, R/target {"call": ...}
        if settings.dxcluster.enabled:
            to_mqtt = partial(self.client.publish_retained, self.topics.spots)
            web = self.web  # its map shows the spots too (web/live.py rule 6)
            from bridge.web.live import with_console  # (with the console's server, above)

            publish = to_mqtt if web is None else with_console(to_mqtt, web.on_spots)
            try:
                self.dxcluster = dxcluster(settings.dxcluster, position, publish, wall=wall)
            except CtyError as exc:
                raise ConfigError(str(exc)) from None
            self.mqtt.aim_calls_with(self.dxcluster.aim)
        pairs = list(zip(settings.rotators, self.rotators, strict=True))
        for feature in FEATURES:  # the inputs of the user's topics (bridge/feature.py)
            given = feature.inputs(pairs) if feature.inputs is not None else None
            if given is not None:
                self.mqtt.add_feature(given.subscriptions, given.on_message)
        self.discovery: DiscoveryPublisher | None = None
        if settings.homeassistant.enabled:
            self.discovery = self._discovery(settings)
        self.client.add_subscriptions(self.mqtt.subscriptions())
        self.lane = StopLane(
            settings.mqtt,
            subscriptions=self.mqtt.stop_lane_subscriptions(),
            on_message=self.mqtt.on_lane_message,
            on_denied=self._denied,
            on_new_connection=self.mqtt.lane_connected,
            on_subscribed=self.mqtt.lane_subscribed,
            no_replay=self.mqtt.no_replay_subscriptions(),
        )
        self.client.before_message = self.lane.first  # mqtt/lane.py rule 4: a stop before a backlog
        self.client.watch_owned(self.topics.owned())

    def _express(self, settings: Settings) -> Express:
        """The stop express (mqtt/express.py) for the rotators whose model takes a stop frame
        at any moment (its rule 4); none with ``mqtt.stop_express`` off."""
        topics: dict[str, tuple[str, str]] = {}
        frames: dict[str, bytes] = {}
        for r in settings.rotators:
            # (a rotator of two boxes has two ports: its stops take the stop lane)
            # (nor does a stop of several frames: an RC2800's, paced by the session)
            if settings.mqtt.stop_express and r.spec.stop_anytime and not r.axes:
                stop = r.spec.codec_factory().encode_stop()
                if not isinstance(stop, bytes):
                    continue
                t = self.topics.rotator(r.id)
                topics[t.stop], topics[t.lock] = (r.id, "stop"), (r.id, "lock")
                frames[r.id] = stop
        return Express(settings.mqtt, topics=topics, frames=frames, on_problem=self._info)

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

    def _discovery(self, settings: Settings) -> DiscoveryPublisher:
        ha = settings.homeassistant
        client = self.client
        discovery_topics = DiscoveryTopics(ha.discovery_prefix)
        infos = []
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
                    features=frozenset(f.name for f in FEATURES if f.on_for(r)),
                    dxcluster=self.dxcluster is not None,
                )
            )
        publisher = DiscoveryPublisher(
            prefix=ha.discovery_prefix,
            status_topic=ha.status_topic,
            topics=self.topics,
            rotators=infos,
            groups=tuple(  # a device each (mqtt/groups.py)
                GroupInfo(g.id, g.label, self.topics.group(g.id), tuple(g.rotators))
                for g in settings.groups
            ),
            publish_retained=partial(client.publish_retained, qos=1),
            clear_retained=client.clear_retained,
            republish_state=lambda: client.republish_retained(skip_prefix=discovery_topics.subtree),
            birth_delay_s=ha.birth_delay_s,
            publish_again=partial(client.publish_retained, qos=1, only_if_changed=False),
        )
        self.mqtt.add_feature(publisher.subscriptions, publisher.on_message, publisher.on_status)
        if self.dxcluster is not None:
            self.dxcluster.on_calls = publisher.set_spot_calls
        return publisher

    def _denied(self, topic: str, problem: str) -> None:
        """The broker refused a topic (client.py rule 11): the rotator's status says so, and
        ``B/bridge/info`` lists every such problem."""
        if problem not in self.client.problems:  # the stop lane's (the client's are there)
            self.client.problems.append(problem)
        if topic == self.topics.bridge_fence:
            self.mqtt.markers_denied()
        elif topic == self.topics.bridge_fence_lane:
            self.mqtt.lane_markers_denied()
        rid = self.topics.rotator_of(topic)
        for rot in self.rotators:
            if rid is None or rot.id == rid:
                rot.note(problem)
        self.client.publish_retained(self.topics.bridge_info, self.me.info(self.client.problems))

    def _allowed(self, topic: str) -> None:
        """The broker takes a topic it refused before (client.py rule 16: the fence's probe
        came back on a new connection): the markers go out again, ``B/bridge/info`` without it."""
        if topic == self.topics.bridge_fence:
            self.mqtt.markers_allowed()
        self.client.publish_retained(self.topics.bridge_info, self.me.info(self.client.problems))

    def _info(self, problem: str, on: bool) -> None:
        """A problem said on ``B/bridge/info`` while it lasts (a long hold: mqtt/halts.py)."""
        problems = self.client.problems
        if on and problem not in problems:
            problems.append(problem)
        elif not on and problem in problems:
            problems.remove(problem)
        self.client.publish_retained(self.topics.bridge_info, self.me.info(problems))

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
            if not self.client.v5:  # mqtt.protocol "auto" stepped down (mqtt/connection.py)
                self.lane.use_mqtt311()
            self.lane.start()
            self.express.start(mqtt311=not self.client.v5)
        stepped_down = self.settings.mqtt.protocol == "auto" and not self.client.v5
        if stepped_down != (STEPPED_DOWN in self.client.problems):
            # said while it lasts (mqtt/connection.py rule 1); not on paho's thread, which
            # holds paho's mutex here while the publish takes the client's lock
            threading.Thread(
                target=self._info, args=(STEPPED_DOWN, stepped_down), daemon=True
            ).start()

    def _refused(self, message: str) -> None:
        """Another bridge owns the base topic (mqtt/claim.py): ``run`` stops, exit code 2."""
        self.failure = message
        self.failed.set()

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
        """ConfigError, before anything runs or is published, if a rotctld port cannot be had."""
        # the sky worker computes in Python for up to a second; a thread waking for a stop waits
        # for the interpreter lock up to this long, each time it takes it (5 ms by default)
        sys.setswitchinterval(GIL_SWITCH_S)
        try:
            for server in self._text_ports():
                server.listen()
            if self.loggers:
                self.loggers.listen()
            if self.settings.wsjtx.enabled:
                self.wsjtx.listen()
            if self.web is not None:
                self.web.listen()
        except OSError as exc:
            for server in self._text_ports():
                server.stop()
            self.loggers.stop()
            self.wsjtx.stop()
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
            if self.settings.wsjtx.enabled:
                self.wsjtx.start()
            if self.dxcluster is not None:
                self.dxcluster.start()
        except OSError:  # e.g. the port is taken: fail the start, leave nothing running
            self.stop()
            raise

    def _text_ports(self) -> list[LineServer | PtyLineServer]:
        """rotctld's, GS-232's and Easycomm's TCP ports and ptys: listened on (a pty linked),
        started, stopped alike."""
        return [*self.rotctld, *self.emulations]

    def stop(self) -> None:
        self._stopped.set()
        self.client.shutting_down()
        if self.discovery is not None:
            self.discovery.stop()
        for server in self._text_ports():
            server.stop()
        self.loggers.stop()
        self.wsjtx.stop()
        if self.dxcluster is not None:
            self.dxcluster.stop()
        if self.web is not None:
            self.web.stop()  # each page sees the bridge go (web/server.py rule 6)
        for rot in self.rotators:
            rot.stop()
        self.store.flush()  # the last lock or option set is on disk (state_store.py rule 5)
        self.audit.stop()  # what is queued is written (audit.py rule 4)
        self.mqtt.stop()  # first: its offline goes out, and it stops reconnecting
        self.lane.stop()  # (a stop on it now reaches no rotator: they are stopped)
        self.express.stop()  # (the ports are closed: it holds none)
        log.info("stopped")


def run(settings: Settings, stop_event: threading.Event | None = None) -> int:
    """Run until SIGTERM/SIGINT (or ``stop_event``); exit code 0 on a clean stop."""
    done = stop_event or threading.Event()

    def _signal(signum: int, _frame: object) -> None:
        log.info("%s received, shutting down", signal.Signals(signum).name)
        done.set()

    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, _signal)
        signal.signal(signal.SIGINT, _signal)
    try:
        app = App(settings)
    except OSError as exc:  # not foreseen, but a start that cannot work all the same
        raise ConfigError(f"cannot start: {exc}") from None
    app.start()
    # rule 12: a full collection no longer walks the start-up's 70,000 objects (30-80 ms)
    gc.collect()
    gc.freeze()
    try:
        while not done.wait(1.0) and not app.failed.is_set():
            pass
    finally:
        app.stop()
        gc.unfreeze()  # a caller that runs the bridge again (the tests) keeps no garbage
    if app.failure is not None:
        raise ConfigError(app.failure)
    return 0
