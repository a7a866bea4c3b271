"""What the console asks of a rotator: the station's own (engine/rotator.py) or one far away
(remote/console.py, over the station's broker). server.py, commands.py and view.py are typed
against this and nothing else.

Rules:
1. Every command goes to the rotator's judge, which raises Refused (and reports it where the
   rotator's refusals go) or takes it; the console never decides a refusal itself.
2. ``last_halt_s`` is when the rotator last carried out (or sent on) a STOP or lock ON, on the
   monotonic clock (commands.py rule 5): from any interface on the station; on the remote,
   from any of the remote's own (a STOP given at the station is not seen there).
3. ``report_refusal`` shows a refusal the console found itself (a bad body, a stale command)
   where the rotator's own refusals go.
"""

from __future__ import annotations

from typing import Protocol

from bridge.model import Command, Source
from bridge.pointing import Pointing
from bridge.protocols.base import ModelSpec


class ConsoleRotator(Protocol):
    @property
    def id(self) -> str: ...
    @property
    def name(self) -> str: ...
    @property
    def spec(self) -> ModelSpec: ...
    @property
    def pointing(self) -> Pointing: ...
    @property
    def can_track(self) -> bool: ...
    @property
    def last_halt_s(self) -> float: ...

    def submit(self, command: Command, described: str | None = None) -> None: ...
    def set_lock(self, locked: bool) -> None: ...
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
    def take_path(self, long_path: bool, source: Source, described: str) -> None: ...
    def go_to_preset(self, name: str, source: Source, described: str) -> None: ...
    def park(self, source: Source, described: str) -> None: ...
    def nudge(self, d_az: float, d_el: float | None, source: Source, described: str) -> None: ...
    def track(self, name: str, source: Source, described: str) -> None: ...
    def report_refusal(self, message: str, command: str | None) -> None: ...
