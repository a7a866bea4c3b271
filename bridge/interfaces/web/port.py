"""What the console asks of a rotator: the station's own (runtime/rotator.py) or one far away
(remote/console.py, over the station's broker). server.py, commands.py and view.py are typed
against this and nothing else.

Rules:
1. Every command goes to the rotator's judge, which raises Refused (and reports it where the
   rotator's refusals go) or takes it; the console never decides a refusal itself.
2. ``last_halt_s`` is when the rotator last carried out (or sent on) a STOP or lock ON, on the
   monotonic clock (commands.py rule 5): from any interface on the station; on the remote,
   from any of the remote's own (a STOP given at the station is not seen there).
2a. ``halts`` counts the STOPs and lock ONs the rotator carried out (sent on): read before the
   console judges a command stale, and handed to ``submit`` (``since``), it refuses the command
   if one came in between, on any thread (runtime/rotator.py; the remote counts its own).
2b. On the remote, ``halts`` counts those of the remote's other front ends alone (its rotctld,
   the loggers; remote/console.py): the console carries out a far rotator's commands on a
   thread of their own, in the order they came (server.py rule 5), so the page's own STOP,
   then its target, both go, while a STOP another front end sent after the target was posted
   refuses it, up to the moment it is handed to the remote's link (remote/rotator.py
   ``submit``). The station's own rotator counts every front end's: the console carries out
   its commands at once, so none of its own can come in between.
3. ``report_refusal`` shows a refusal the console found itself (a bad body, a stale command)
   where the rotator's own refusals go.
4. Every command carries who sent it (``origin``: ``web`` and the browser's address, the audit
   trail and the control lease judge by it); the remote's rotator takes it and sends its own
   operator instead (remote/console.py).
"""

from __future__ import annotations

from typing import Protocol

from bridge.core.model import Command
from bridge.front import FrontRotator
from bridge.pointing import Pointing


class ConsoleRotator(FrontRotator, Protocol):
    """Rule 1: every command through ``submit`` (front.py rule 1)."""

    @property
    def name(self) -> str: ...
    @property
    def pointing(self) -> Pointing: ...
    @property
    def can_track(self) -> bool: ...
    @property
    def last_halt_s(self) -> float: ...
    @property
    def halts(self) -> int: ...
    def submit(
        self, command: Command, described: str | None = None, *, since: int | None = None
    ) -> None: ...
    def on_its_way(self) -> bool:
        """A motion command taken that the status does not show yet: a command made from the
        status waits for it (server.py rule 10); never, where ``commands_block``."""
        ...

    @property
    def commands_block(self) -> bool:
        """Carrying out a command may wait for a round trip far away (the remote's rotator
        waits for its broker's acknowledgement): the console runs it off its loop."""
        ...
