"""MQTT front end: inbound topics become rotator commands, rotator statuses become topics.

It reaches the rotators only through the RotatorPort interface that app.py hands it.

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
"""

from __future__ import annotations

import json
import logging
import time
from collections.abc import Callable
from typing import Protocol

from bridge.errors import Refused
from bridge.model import ErrorEvent, RotatorStatus, SetOption, Source, Stop, Target
from bridge.mqtt import payloads as pl
from bridge.mqtt.client import MqttClient
from bridge.mqtt.topics import Topics
from bridge.protocols.base import ModelSpec
from bridge.settings import MqttSettings

log = logging.getLogger(__name__)


class RotatorPort(Protocol):
    id: str
    spec: ModelSpec

    @property
    def status(self) -> RotatorStatus: ...
    def submit(self, command: Target | Stop | SetOption, described: str | None = None) -> None: ...
    def set_lock(self, locked: bool) -> None: ...
    def report_refusal(self, message: str, command: str | None) -> None: ...


class MqttService:
    def __init__(
        self,
        settings: MqttSettings,
        topics: Topics,
        *,
        wall: Callable[[], float] = time.time,
    ) -> None:
        self.topics = topics
        self._wall = wall
        self._rotators: dict[str, RotatorPort] = {}
        self._handlers: list[Callable[[str, bytes, bool], bool]] = []
        self._status_listeners: list[Callable[[str, RotatorStatus], None]] = []
        self.client = MqttClient(
            settings,
            will_topic=topics.bridge_state,
            subscriptions=topics.subscriptions(),
            on_message=self._on_message,
        )

    def attach(self, rotator: RotatorPort) -> None:
        self._rotators[rotator.id] = rotator

    def add_feature(
        self,
        subscriptions: list[str],
        on_message: Callable[[str, bytes, bool], bool],
        on_status: Callable[[str, RotatorStatus], None] | None = None,
    ) -> None:
        """A feature (e.g. Home Assistant discovery) with topics of its own; before ``start()``.

        ``on_message`` gets every message that is not a rotator command and returns True when
        it was the feature's; ``on_status`` sees every status a rotator emits.
        """
        self.client.add_subscriptions(subscriptions)
        self._handlers.append(on_message)
        if on_status is not None:
            self._status_listeners.append(on_status)

    def start(self) -> None:
        self.client.start()

    def stop(self) -> None:
        self.client.publish_offline_now(
            [self.topics.rotator(rid).availability for rid in self._rotators]
        )
        self.client.stop()

    # -- outbound (worker threads) ----------------------------------------------------------
    def publish_status(self, rotator_id: str, status: RotatorStatus) -> None:
        rot = self._rotators.get(rotator_id)
        if rot is None:
            return  # emitted before attach(): the first real status follows
        spec = rot.spec
        t = self.topics.rotator(rotator_id)
        pub = self.client.publish_retained
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
        pub(t.status, pl.status_json(status, self._wall(), spec.has_elevation))
        for listener in self._status_listeners:
            listener(rotator_id, status)

    def publish_event(self, rotator_id: str, event: ErrorEvent) -> None:
        t = self.topics.rotator(rotator_id)
        self.client.publish_event(t.error, json.dumps(event.as_dict(), separators=(",", ":")))

    # -- inbound (paho's thread) ------------------------------------------------------------
    def _on_message(self, topic: str, payload: bytes, retain: bool) -> None:
        route = self.topics.route(topic)
        if route is None:
            for handler in self._handlers:
                if handler(topic, payload, retain):
                    return
            return
        rotator_id, kind, arg = route
        rot = self._rotators.get(rotator_id)
        if rot is None:
            return
        if retain and not payload:
            return  # a retained command being deleted (rule 1)
        what = pl.describe(kind if arg is None else f"option {arg}", payload)
        if retain and kind == "stop":
            rot.submit(Stop(Source.MQTT), what)
            rot.report_refusal(
                f"stop on {topic} was published retained: executed (stopping is always safe), "
                "but clear it with an empty retained message",
                what,
            )
            return
        if retain:
            rot.report_refusal(
                f"retained command on {topic} ignored: commands must be published without the "
                "retain flag (clear it with an empty retained message)",
                what,
            )
            return
        try:
            if kind == "stop":
                rot.submit(Stop(Source.MQTT), what)
            elif kind == "target":
                az, el = pl.parse_target(payload)
                rot.submit(Target(az, el, Source.MQTT), what)
            elif kind == "target_elevation":
                rot.submit(Target(None, pl.parse_number(payload, "elevation"), Source.MQTT), what)
            elif kind == "lock":
                rot.set_lock(pl.parse_switch(payload))
            elif kind == "option" and arg is not None:
                rot.submit(SetOption(arg, pl.parse_switch(payload), Source.MQTT), what)
        except pl.PayloadError as exc:
            rot.report_refusal(str(exc), what)
        except Refused:
            pass  # the rotator has reported it
