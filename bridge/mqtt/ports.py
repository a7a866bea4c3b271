"""What the MQTT front end (service.py, halts.py) sees of a rotator and of the broker."""

from __future__ import annotations

from typing import Protocol

from bridge.model import Origin, RotatorStatus, SetOption, Source, Stop, Target
from bridge.pointing import Pointing
from bridge.protocols.base import ModelSpec


class LeasePort(Protocol):
    """A rotator's control lease (engine/operators.py): claim or release, Refused if not."""

    def claim(
        self, operator: object, minutes: object, origin: Origin, described: str
    ) -> object: ...
    def release(self, origin: Origin, described: str) -> object: ...


class RotatorPort(Protocol):
    id: str
    name: str  # as dashboards show it
    spec: ModelSpec
    pointing: Pointing
    can_track: bool  # a station and a controller that reports where it points
    last_halt_s: float  # when a STOP or lock ON was last put in (monotonic; engine/rotator.py)

    @property
    def operators(self) -> LeasePort: ...

    @property
    def status(self) -> RotatorStatus: ...
    @property
    def can_follow(self) -> bool: ...  # [wsjtx] on and a station: R/follow (engine/follow.py)
    def follow(
        self,
        on: bool,
        source: Source,
        described: str,
        *,
        long_path: bool = False,
        origin: Origin | None = None,
    ) -> None: ...
    def submit(
        self,
        command: Target | Stop | SetOption,
        described: str | None = None,
        *,
        hold: int | None = None,
        echo: bool = False,
    ) -> None: ...
    def set_lock(
        self,
        locked: bool,
        *,
        hold: int | None = None,
        origin: Origin | None = None,
        echo: bool = False,
    ) -> None: ...
    def release(self, marker: int, *, clear: bool = False) -> None: ...
    def report_refusal(
        self, message: str, command: str | None, *, origin: Origin | None = None
    ) -> None: ...
    def reset_health(self) -> None: ...
    def go_to_preset(
        self, name: str, source: Source, described: str, *, origin: Origin | None = None
    ) -> None: ...
    def park(self, source: Source, described: str, *, origin: Origin | None = None) -> None: ...
    def take_path(
        self, long_path: bool, source: Source, described: str, *, origin: Origin | None = None
    ) -> None: ...
    def nudge(
        self,
        d_az: float,
        d_el: float | None,
        source: Source,
        described: str,
        *,
        origin: Origin | None = None,
    ) -> None: ...
    def track(
        self,
        name: str,
        source: Source,
        described: str,
        tle: tuple[str, str, str] | None = None,
        *,
        origin: Origin | None = None,
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
        origin: Origin | None = None,
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
