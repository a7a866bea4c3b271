"""``rotor-bridge remote``: connect to the station's broker, learn its rotators, serve the local
endpoints until SIGINT or SIGTERM.

Rules:
1. Nothing is served before the station has described every endpoint's rotator (``R/info``):
   a rotator that does not show within ``info_wait_s`` is a start-up error that names the topic
   looked at and the likely cause (a wrong base_topic or rotator id, the bridge not running).
   A refused login or a failed TLS handshake ends the start at once, in one line that says
   which (mqtt/remote.py rule 5).
2. A rotator named ``X`` is found at ``B/X`` (a station with several rotators) or, when the
   station has one rotator and publishes under ``B`` itself, there; an endpoint without a
   rotator takes ``B``, and is told the ids when the station has several.
3. One line per endpoint goes to stdout at start:
   ``DL1ABC -> host: tower (rotorez, 0..360) on rotctld 127.0.0.1:4533``.
4. The station's topics read before a connection drops are forgotten when it does: the next
   connection's retained messages are the station's word again (the rotator's description,
   read at start, is kept).
"""

from __future__ import annotations

import logging
import signal
import threading
import time
from dataclasses import dataclass, field
from types import FrameType
from typing import TYPE_CHECKING

from bridge.mqtt.remote import RemoteLink
from bridge.mqtt.topics import RotatorTopics, StationTopics
from bridge.remote.rotator import Info, InfoError, RemoteRotator, StationView
from bridge.remote.settings import Endpoint, RemoteSettings
from bridge.rotctld import RotctldServer
from bridge.settings import ConfigError

if TYPE_CHECKING:
    pass

log = logging.getLogger(__name__)

ONE_ROTATOR_GRACE_S = 0.5  # rule 2: B/X/info may come just after B/info in one burst


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
    servers: list[RotctldServer] = field(default_factory=list)
    link: RemoteLink | None = None

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
        )
        self.link.start()
        try:
            lines = []
            for ep in s.endpoints:
                rot = self._find(ep)
                server = RotctldServer(rot, ep.rotctld_port, ep.rotctld_bind)
                server.start()  # OSError naming the address and the setting
                self.rotators.append(rot)
                self.servers.append(server)
                spec, (lo, hi) = rot.spec, rot.pointing.target_range()
                host, port = server.address
                lines.append(
                    f"{s.operator} -> {s.mqtt.host}: {rot.id} ({spec.name}, {_g(lo)}..{_g(hi)}) "
                    f"on rotctld {host}:{port}"
                )
            return lines
        except BaseException:
            self.stop()
            raise

    def stop(self) -> None:
        for server in self.servers:
            server.stop()
        self.servers.clear()
        if self.link is not None:
            self.link.stop()
            self.link = None

    def _on_link(self) -> None:
        """Rule 4: what the broker held before a drop is not kept across it."""
        if self.link is not None and not self.link.up:
            self.view.clear()

    def _on_message(self, topic: str, payload: bytes, retain: bool) -> None:
        self.view.put(topic, payload)

    def _find(self, ep: Endpoint) -> RemoteRotator:
        """Rules 1 and 2."""
        s, view = self.settings, self.view
        own = self.station.rotator(ep.rotator) if ep.rotator else None
        one = self.station.rotator(None)
        deadline = time.monotonic() + s.info_wait_s
        single_seen: float | None = None
        while True:
            now = time.monotonic()
            topics = None
            if own is not None and view.get(own.info) is not None:
                topics = own
            elif view.get(one.info) is not None:
                single_seen = single_seen or now
                if own is None or now - single_seen >= ONE_ROTATOR_GRACE_S:
                    topics = one
            if topics is not None:
                return self._rotator(ep, topics)
            if now >= deadline or (self.link is not None and self.link.fatal):
                raise StartError(self._missing(ep, own))
            view.wait(min(deadline - now, ONE_ROTATOR_GRACE_S))

    def _rotator(self, ep: Endpoint, topics: RotatorTopics) -> RemoteRotator:
        s = self.settings
        raw = self.view.get(topics.info) or b""
        try:
            info = Info.parse(raw)
        except InfoError as exc:
            raise StartError(f"{topics.info}: {exc}") from None
        except (ValueError, KeyError, TypeError, IndexError) as exc:
            raise StartError(f"{topics.info} is not the station's description: {exc}") from None
        rid = ep.rotator or info.name
        one = topics == self.station.rotator(None)
        if one and ep.rotator is not None and ep.rotator != info.name:
            log.warning(
                "the station has one rotator, %r: endpoints.rotator %r is taken to be it",
                info.name,
                ep.rotator,
            )
        assert self.link is not None
        return RemoteRotator(
            rid,
            topics,
            self.station.bridge_state,
            info,
            self.view,
            self.link,
            s.operator,
            s.command_expiry_s,
            s.moving_max_age_s,
        )

    def _missing(self, ep: Endpoint, own: RotatorTopics | None) -> str:
        s = self.settings
        where = f"{s.mqtt.host}:{s.mqtt.port}"
        assert self.link is not None
        if not self.link.up:  # mqtt/remote.py rule 5: why, in this one line
            return (
                f"cannot reach the station's broker at {where}: {self.link.failure or 'no answer'}"
            )
        ids = self.station.described(list(self.view.topics()))
        looked = (own or self.station.rotator(None)).info
        hint = (
            f"; the station has rotators {', '.join(ids)}: name one in endpoints.rotator"
            if ids
            else "; is base_topic the station's, and its bridge running?"
        )
        return (
            f"no description of the station's rotator on {looked} within {s.info_wait_s:g} s{hint}"
        )


def run(settings: RemoteSettings) -> int:
    """Serve until SIGINT or SIGTERM; StartError when it cannot start."""
    stopping = threading.Event()

    def on_signal(signum: int, frame: FrameType | None) -> None:
        stopping.set()

    signal.signal(signal.SIGINT, on_signal)
    signal.signal(signal.SIGTERM, on_signal)
    remote = Remote(settings)
    for line in remote.start():
        print(line, flush=True)
    try:
        while not stopping.wait(1.0):  # a bounded wait: signals are handled between waits
            pass
    finally:
        remote.stop()
    return 0
