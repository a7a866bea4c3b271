"""What the MQTT front end (service.py, halts.py) sees of a rotator and of the broker."""

from __future__ import annotations

from typing import Protocol

from bridge.core.model import Command, Origin, RotatorStatus
from bridge.front import FrontRotator
from bridge.pointing import Pointing
from bridge.protocols.base import ModelSpec


class RotatorPort(FrontRotator, Protocol):
    """A rotator as the service sees it: every command through ``submit`` (front.py rule 1),
    with the stop lane's hold and echo (halts.py)."""

    id: str
    name: str  # as dashboards show it
    spec: ModelSpec
    pointing: Pointing
    can_track: bool  # a station and a controller that reports where it points

    @property
    def halted(self) -> tuple[float, float | None]: ...  # the last halt's send time,

    # monotonic, and its stamp on the station's clock if it had one (runtime/rotator.py;
    # service.py rule 9)

    @property
    def halts(self) -> int: ...  # the halt count now (runtime/rotator.py; mailbox.py rule 10)

    @property
    def status(self) -> RotatorStatus: ...
    @property
    def can_follow(self) -> bool: ...  # [wsjtx] on and a station: R/follow (session/follow.py)
    def submit(
        self,
        command: Command,
        described: str | None = None,
        *,
        hold: int | None = None,
        echo: bool = False,
        since: int | None = None,
        ticket: int | None = None,
    ) -> None: ...
    def audit_refusal(self, message: str, command: str, origin: Origin) -> None: ...
    def ticket(self) -> int: ...  # a place in the order of commands (mailbox.py rule 10a)
    def check_motion(self, origin: Origin) -> None: ...  # the lock, wind, lease now (Refused)
    def release(self, marker: int, *, clear: bool = False) -> None: ...


class Publisher(Protocol):
    """The broker connection as the service uses it (bridge.interfaces.mqtt.client.MqttClient).

    ``publish_retained`` with ``only_if_changed`` sends nothing when the payload equals the last
    one for that topic (rule 3). ``publish_offline_now`` marks retained topics ``offline`` and
    waits until the broker has them (shutdown). ``publish_event`` with ``lapses`` (an error) is
    dropped while the broker is away, not held for its return (client.py rule 3).
    ``publish_marker`` sends a message to the
    bridge itself, at QoS 0, now or never (lastword.py); ``up``: a connection is accepted.
    """

    def publish_retained(
        self, topic: str, payload: str | bytes, *, only_if_changed: bool = True
    ) -> None: ...
    def publish_event(self, topic: str, payload: str | bytes, *, lapses: bool = False) -> None: ...
    def publish_marker(self, topic: str, payload: str) -> None: ...
    def publish_offline_now(
        self, topics: list[str], last: dict[str, str] | None = None
    ) -> None: ...

    @property
    def up(self) -> bool: ...
    @property
    def hears(self) -> bool: ...
    def start(self) -> None: ...
    def stop(self) -> None: ...
