"""MQTT front end: inbound topics become rotator commands, rotator statuses become topics.

It reaches the rotators only through the RotatorPort interface that app.py hands it, and the
broker only through the Publisher it is given (MqttClient; a recorder in unit tests). Inbound, it
says what to subscribe to (``subscriptions()``) and takes every message (``on_message``): app.py
wires both into the client.

Rules:
1. A command that arrives retained is never executed: it is reported on the error topic. (A
   retained target would turn the rotor again on every restart of the bridge or the broker.)
   The one exception is stop: stopping never moves anything, and a dashboard button wrongly
   set to retain must still stop a turning rotor. It is executed and reported.
   An EMPTY retained message is no command: it is how a retained message is deleted (what the
   refusals themselves tell the user to do), so it is ignored silently, stop included. (With
   MQTT 3.1.1 the broker clears the retain flag of live messages, so a deletion sent while the
   bridge is connected arrives as an empty plain message: refused under rule 2, or a stop.)
2. Bad payloads (an empty one too) are refused with an error event naming what was wrong;
   nothing moves. A stop takes any payload: stopping is never refused.
3. Outbound state is retained and published only when it changed; ``R/error`` is not retained.
4. Refusals on ``R/error`` are rate-limited per rotator (limiter.py: ``mqtt.error_events_per_s``,
   10 by default, after a burst of five times as many); the next one published says how many
   were left out. Every other kind (a stall, a stop that did not take, the serial line) is
   always published: a flood of refusals must not hide it. 200,000 refused rotctld ``P 999``
   neither queue 200,000 QoS 1 messages nor delay the state.
5. Stop and lock come on both connections, the main one and the stop lane (lane.py), and
   lastword.py decides what each copy does: the main connection's carry out every word in
   order; the lane's stop or lock ON is carried out at once and holds the rotator's targets
   until the bridge's marker comes back on the main connection. The decision and the mailbox
   put it lets through are one step, under one lock.
6. While the main connection is gated (its first look runs, or the bridge refused to run:
   client.py rule 14) only halts are carried out from it.
"""

from __future__ import annotations

import json
import logging
import threading
import time
from collections.abc import Callable
from typing import Protocol

from bridge.errors import Refused
from bridge.model import ErrorEvent, ErrorKind, RotatorStatus, SetOption, Source, Stop, Target
from bridge.mqtt import payloads as pl
from bridge.mqtt.lastword import RESEND_S, LastWord
from bridge.mqtt.limiter import RATE_PER_S, EventLimiter
from bridge.mqtt.topics import Topics
from bridge.pointing import Pointing
from bridge.protocols.base import ModelSpec

log = logging.getLogger(__name__)


_MOVES = frozenset({"target", "target_elevation", "preset", "park", "nudge", "track"})


def _switch_on(payload: bytes) -> bool:
    try:
        return pl.parse_switch(payload)
    except pl.PayloadError:
        return False


def _switch_off(payload: bytes) -> bool:
    try:
        return not pl.parse_switch(payload)
    except pl.PayloadError:
        return False


class RotatorPort(Protocol):
    id: str
    spec: ModelSpec
    pointing: Pointing
    can_track: bool  # a station and a controller that reports where it points

    @property
    def status(self) -> RotatorStatus: ...
    def submit(
        self,
        command: Target | Stop | SetOption,
        described: str | None = None,
        *,
        hold: int | None = None,
    ) -> None: ...
    def set_lock(self, locked: bool, *, hold: int | None = None, save: bool = True) -> None: ...
    def save_lock(self) -> None: ...
    def release(self, marker: int, *, clear: bool = False) -> None: ...
    def report_refusal(self, message: str, command: str | None) -> None: ...
    def go_to_preset(self, name: str, source: Source, described: str) -> None: ...
    def park(self, source: Source, described: str) -> None: ...
    def take_path(self, long_path: bool, source: Source, described: str) -> None: ...
    def nudge(self, d_az: float, d_el: float | None, source: Source, described: str) -> None: ...
    def track(
        self,
        name: str,
        source: Source,
        described: str,
        tle: tuple[str, str, str] | None = None,
    ) -> None: ...
    def go_toward(
        self,
        latitude_deg: float,
        longitude_deg: float,
        source: Source,
        described: str,
        *,
        locator: str | None = None,
        long_path: bool = False,
    ) -> None: ...


class Publisher(Protocol):
    """The broker connection as the service uses it (bridge.mqtt.client.MqttClient).

    ``publish_retained`` with ``only_if_changed`` sends nothing when the payload equals the last
    one for that topic (rule 3). ``publish_offline_now`` marks retained topics ``offline`` and
    waits until the broker has them (shutdown). ``publish_marker`` sends a message to the
    bridge itself, at QoS 0, now or never (lastword.py); ``up``: a connection is accepted.
    """

    def publish_retained(
        self, topic: str, payload: str | bytes, *, only_if_changed: bool = True
    ) -> None: ...
    def publish_event(self, topic: str, payload: str | bytes) -> None: ...
    def publish_marker(self, topic: str, payload: str) -> None: ...
    def publish_offline_now(self, topics: list[str]) -> None: ...

    @property
    def up(self) -> bool: ...
    def start(self) -> None: ...
    def stop(self) -> None: ...


class MqttService:
    def __init__(
        self,
        topics: Topics,
        publisher: Publisher,
        *,
        wall: Callable[[], float] = time.time,
        error_events_per_s: float = RATE_PER_S,
        clock: Callable[[], float] = time.monotonic,
        retain_is_live: bool = True,
        on_problem: Callable[[str, str], None] | None = None,
    ) -> None:
        """``retain_is_live``: MQTT 5 (a retained stop arrives only when published, retain
        handling 2); False under MQTT 3.1.1, where one with the flag is the broker's replay."""
        self.topics = topics
        self._publisher = publisher
        self._retain_is_live = retain_is_live
        self._on_problem = on_problem  # (topic, problem): a broker problem the bridge reports
        self._wall = wall
        self._limiter = EventLimiter(clock, round(5 * error_events_per_s), error_events_per_s)
        self._rotators: dict[str, RotatorPort] = {}
        self._feature_subscriptions: list[str] = []
        self._handlers: list[Callable[[str, bytes, bool], bool]] = []
        self._status_listeners: list[Callable[[str, RotatorStatus], None]] = []
        self._clock = clock
        self._word = LastWord()  # rule 5
        self._word_lock = threading.Lock()  # two connections, two paho threads
        self._resend_timer: threading.Timer | None = None
        self._markers_denied = False

    def attach(self, rotator: RotatorPort) -> None:
        self._rotators[rotator.id] = rotator
        presets = pl.presets_json(rotator.pointing.presets)  # for dashboards; empty: none
        self._publisher.publish_retained(self.topics.rotator(rotator.id).presets, presets)

    def add_feature(
        self,
        subscriptions: list[str],
        on_message: Callable[[str, bytes, bool], bool],
        on_status: Callable[[str, RotatorStatus], None] | None = None,
    ) -> None:
        """A feature (e.g. Home Assistant discovery) with topics of its own; before
        ``subscriptions()`` is handed to the client.

        ``on_message`` gets every message that is not a rotator command and returns True when
        it was the feature's; ``on_status`` sees every status a rotator emits.
        """
        self._feature_subscriptions += subscriptions
        self._handlers.append(on_message)
        if on_status is not None:
            self._status_listeners.append(on_status)

    def subscriptions(self) -> list[str]:
        """Every topic filter the service wants messages from: commands, then features'."""
        return [*self.topics.subscriptions(), *self._feature_subscriptions]

    def stop_lane_subscriptions(self) -> list[str]:
        """Stop and lock, for the connection of their own (lane.py), also handled here; and the
        lane's own markers (lastword.py rule 4)."""
        return [*self.topics.stop_lane(), self.topics.bridge_fence_lane]

    def no_replay_subscriptions(self) -> list[str]:
        """Filters the broker is asked not to replay retained messages of (lastword.py rule 6)."""
        return self.topics.stop_lane()

    # -- the last word (lastword.py), both connections ------------------------------------------
    def main_gone(self) -> None:
        """The main connection dropped, or is new (before its first message): holds end with
        clearing (lastword.py rule 5)."""
        with self._word_lock:
            for rid in self._word.main_gone():
                rot = self._rotators.get(rid)
                if rot is not None:
                    rot.release(0, clear=True)

    def lane_connected(self) -> None:
        with self._word_lock:
            self._word.lane_connected()

    def markers_denied(self) -> None:
        """The main connection cannot read the markers: the lane's halts hold nothing
        (lastword.py rule 7)."""
        with self._word_lock:
            self._markers_denied = True
        self.main_gone()

    def lane_markers_denied(self) -> None:
        """The lane cannot read its markers: no echo is expected (lastword.py rule 4)."""
        with self._word_lock:
            self._word.echoes = False

    def _holds_possible(self) -> bool:
        return self._publisher.up and not self._markers_denied

    def _carry(self, rot: RotatorPort, kind: str, what: str, hold: int | None = None) -> None:
        """A stop or a lock ON, into the mailbox (under the word lock: lastword.py's decision
        and the put are one step)."""
        if kind == "stop":
            rot.submit(Stop(Source.MQTT), what, hold=hold)
        else:
            rot.set_lock(True, hold=hold, save=False)

    def _send_marker(self, n: int) -> None:
        self._publisher.publish_marker(self.topics.bridge_fence, self._word.marker(n))
        self._arm_resend()

    def _arm_resend(self) -> None:
        """One timer at most looks again in RESEND_S while a hold is out."""
        with self._word_lock:
            if self._resend_timer is not None or not self._word.holding:
                return
            timer = self._resend_timer = threading.Timer(RESEND_S, self._resend_marker)
        timer.daemon = True
        timer.start()

    def _resend_marker(self) -> None:
        """lastword.py rule 5: a marker the broker dropped is sent again (a new number)."""
        with self._word_lock:
            self._resend_timer = None
        self._resend_marker_if_due()
        self._arm_resend()

    def _resend_marker_if_due(self) -> None:
        with self._word_lock:
            n = self._word.resend_due(self._clock())
        if n is None:
            return
        if n < 0:  # lastword.py rule 5: the broker drops them
            problem = (
                f"the bridge's own markers on {self.topics.bridge_fence} do not come back "
                "(does the broker's ACL deny that topic?): a stop from the stop lane can no "
                "longer hold back a target published before it"
            )
            log.error("%s", problem)
            self.markers_denied()
            if self._on_problem is not None:
                self._on_problem(self.topics.bridge_fence, problem)
            return
        log.info("a marker of the stop lane did not come back; sending another")
        self._publisher.publish_marker(self.topics.bridge_fence, self._word.marker(n))

    def _marker_back(self, payload: bytes) -> None:
        with self._word_lock:
            n, released = self._word.marker_back(payload)
            for rid in released:
                rot = self._rotators.get(rid)
                if rot is not None:
                    rot.release(n)

    def on_lane_marker(self, payload: bytes) -> None:
        """The lane read its marker (lastword.py rule 4)."""
        with self._word_lock:
            self._word.lane_marker_back(payload)

    def _replayed_halt(self, rot: RotatorPort, topic: str, kind: str, payload: bytes) -> None:
        """lastword.py rule 6 under MQTT 3.1.1: a replayed retained stop or lock ON, once."""
        what = pl.describe(kind, payload)
        with self._word_lock:
            if not self._word.retained_halt(topic, payload, replayed=True):
                log.debug("%s: retained %s on %s already carried out once", rot.id, kind, topic)
                return
            self._carry(rot, kind, what)
        if kind == "lock":
            rot.save_lock()
        self._report_retained_halt(rot, topic, kind, what)

    def _report_retained_halt(self, rot: RotatorPort, topic: str, kind: str, what: str) -> None:
        rot.report_refusal(
            f"{kind} on {topic} was published retained: executed (stopping is always safe), "
            "but clear it with an empty retained message",
            what,
        )

    def start(self) -> None:
        self._publisher.start()

    def stop(self) -> None:
        self._publisher.publish_offline_now(
            [self.topics.rotator(rid).availability for rid in self._rotators]
        )
        self._publisher.stop()

    # -- outbound (the lines thread) -------------------------------------------------------
    def publish_status(self, rotator_id: str, status: RotatorStatus) -> None:
        rot = self._rotators.get(rotator_id)
        if rot is None:
            return  # emitted before attach(): the first real status follows
        spec = rot.spec
        t = self.topics.rotator(rotator_id)
        pub = self._publisher.publish_retained
        if status.bearing_deg is not None:
            pub(t.bearing, pl.number(status.bearing_deg))
        if status.elevation_deg is not None:
            pub(t.elevation, pl.number(status.elevation_deg))
        pub(t.state, status.state.value)
        pub(t.availability, "online" if status.available else "offline")
        if status.version:
            pub(t.version, status.version)
        for name in spec.options:
            if name in status.options:
                pub(t.option_state(name), pl.switch(status.options[name]))
        pub(t.lock_state, pl.switch(status.locked))
        if rot.can_track:
            pub(t.tracking, pl.tracking_state(status))
        shows_raw = rot.pointing.shows_raw
        pub(t.status, pl.status_json(status, self._wall(), spec.has_elevation, shows_raw))
        for listener in self._status_listeners:
            listener(rotator_id, status)

    def publish_event(self, rotator_id: str, event: ErrorEvent) -> None:
        """Rule 4: rate-limited per rotator; the next one published counts those left out."""
        t = self.topics.rotator(rotator_id)
        if event.kind is not ErrorKind.REFUSED:  # a stall, a stop that did not take: always
            self._publisher.publish_event(
                t.error, json.dumps(event.as_dict(), separators=(",", ":"))
            )
            return
        left_out = self._limiter.admit(t.error)
        if left_out is None:
            return
        doc = event.as_dict()
        if left_out:
            doc["message"] = f"{doc['message']} ({left_out} more error(s) before this not shown)"
            doc["suppressed"] = left_out
        self._publisher.publish_event(t.error, json.dumps(doc, separators=(",", ":")))

    # -- inbound (paho's threads) -----------------------------------------------------------
    def on_lane_message(self, topic: str, payload: bytes, retain: bool) -> None:
        """The stop lane's messages (rule 5; lastword.py rules 2-4 and 6)."""
        if topic == self.topics.bridge_fence_lane:
            self.on_lane_marker(payload)
            return
        route = self.topics.route(topic)
        if route is None or (retain and not payload):
            return
        rotator_id, kind, _arg = route
        rot = self._rotators.get(rotator_id)
        if rot is None or kind not in ("stop", "lock"):
            return
        if kind == "lock" and not _switch_on(payload):
            if retain or not _switch_off(payload):
                return  # the main connection refuses or reports it
            with self._word_lock:  # lastword.py rule 3: the only word while it is down
                if self._publisher.up:
                    return
                rot.set_lock(False, save=False)
            rot.save_lock()
            return
        if retain and not self._retain_is_live:
            self._replayed_halt(rot, topic, kind, payload)
            return
        what = pl.describe(kind, payload)
        with self._word_lock:
            marker = self._word.lane_halt(rotator_id, kind, self._clock(), self._holds_possible())
            if marker is None:
                log.debug("%s: %s on the stop lane: already carried out", rotator_id, kind)
                return  # lastword.py rule 4: the echo of the main connection's copy
            self._carry(rot, kind, what, hold=marker or None)
        if kind == "lock":
            rot.save_lock()
        if marker:
            self._send_marker(marker)

    def on_message(self, topic: str, payload: bytes, retain: bool, *, gated: bool = False) -> None:
        """The main connection's messages, in the order the broker sent them (rule 5)."""
        route = self.topics.route(topic)
        if route is None:
            if topic == self.topics.bridge_fence:
                self._marker_back(payload)
                return
            for handler in self._handlers:
                if handler(topic, payload, retain):
                    return
            return
        self._resend_marker_if_due()
        rotator_id, kind, arg = route
        rot = self._rotators.get(rotator_id)
        if rot is None:
            return
        if retain and not payload:
            with self._word_lock:
                self._word.retained_halt(topic, payload, replayed=True)  # deleted: forgotten
            return  # a retained command being deleted (rule 1)
        what = pl.describe(kind if arg is None else f"option {arg}", payload)
        halt = kind == "stop" or (kind == "lock" and _switch_on(payload))
        if retain and halt and not self._retain_is_live:
            self._replayed_halt(rot, topic, kind, payload)
            return
        if retain and not halt:
            rot.report_refusal(
                f"retained command on {topic} ignored: commands must be published without the "
                "retain flag (clear it with an empty retained message)",
                what,
            )
            return
        if gated and not halt:  # rule 6
            rot.report_refusal(
                "not taken: the bridge is still checking that no other bridge runs on its base "
                "topic (its first look after connecting); send it again",
                what,
            )
            return
        if halt:
            with self._word_lock:  # lastword.py rule 1: carried out in order, noted for rule 4
                lane_marker = self._word.main_halt(rotator_id, kind)
                self._carry(rot, kind, what)
            if kind == "lock":
                rot.save_lock()
            if lane_marker is not None:
                marker = self._word.marker(lane_marker)
                self._publisher.publish_marker(self.topics.bridge_fence_lane, marker)
            if retain:  # published retained, live (MQTT 5): carried out, and reported
                self._report_retained_halt(rot, topic, kind, what)
            return
        if kind == "lock":
            try:
                pl.parse_switch(payload)
            except pl.PayloadError as exc:
                rot.report_refusal(str(exc), what)
                return
            with self._word_lock:
                if not self._word.main_lock_off(rotator_id):  # lastword.py rule 8
                    log.info("%s: lock OFF published before a lock ON: the ON stands", rotator_id)
                    return
                rot.set_lock(False, save=False)
            rot.save_lock()
            return
        try:
            if kind == "target":
                aim = pl.parse_aim(payload)
                if isinstance(aim, pl.Place):
                    lat, lon = aim.latitude_deg, aim.longitude_deg
                    if lat is None or lon is None:
                        rot.take_path(aim.long_path, Source.MQTT, what)
                        return
                    rot.go_toward(
                        lat,
                        lon,
                        Source.MQTT,
                        what,
                        locator=aim.locator,
                        long_path=aim.long_path,
                    )
                else:
                    rot.submit(Target(aim[0], aim[1], Source.MQTT), what)
            elif kind == "preset":
                rot.go_to_preset(pl.parse_name(payload, "preset"), Source.MQTT, what)
            elif kind == "park":
                rot.park(Source.MQTT, what)
            elif kind == "nudge":
                rot.nudge(*pl.parse_nudge(payload), Source.MQTT, what)
            elif kind == "track":
                name, tle = pl.parse_track(payload)
                rot.track(name, Source.MQTT, what, tle)
            elif kind == "target_elevation":
                rot.submit(Target(None, pl.parse_number(payload, "elevation"), Source.MQTT), what)
            elif kind == "option" and arg is not None:
                rot.submit(SetOption(arg, pl.parse_switch(payload), Source.MQTT), what)
        except pl.PayloadError as exc:
            rot.report_refusal(str(exc), what)
        except Refused:
            pass  # the rotator has reported it
