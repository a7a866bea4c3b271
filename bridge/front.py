"""What every front end sees of a rotator: one Protocol, the station's own (runtime/rotator.py)
and the remote's stand-ins for the station's (remote/rotator.py, remote/console.py) alike.

Rules:
1. A front end (MQTT, rotctld, GS-232, Easycomm, the loggers, the console, the DX cluster's
   aim) reaches the judge only through ``submit``: it parses what it read into one value of the
   ``Command`` union (core/model.py) and hands it over with the words the user sent
   (``described``, echoed on ``R/error`` and in the audit trail). ``submit`` raises Refused
   once the refusal is reported where the rotator's refusals go; the front end only renders it
   (an RPRT code, an alarm, an HTTP status).
2. ``report_refusal`` is for input that never became a command (a bad payload, a locator that
   does not parse): reported where the rotator's refusals go; with ``origin`` (who sent it) it
   is in the audit trail too, where the rotator keeps one.
3. A front end that needs more of a rotator (rotctld's limits, the console's last halt) says so
   in a Protocol of its own that extends this one. One that submits a move a while after it
   was asked, or after a look at the last halt, extends ``HaltCounted``: the count of the
   rotator's STOPs and lock ONs (the station's judge's, runtime/rotator.py ``halts``; the
   remote's, of its own front ends, remote/rotator.py), the count a command of ``source``
   asked now hands to ``submit`` as ``since`` (``halts_for``), and ``submit`` taking it.
   ``submit`` takes ``seen_s`` too: when the command's bytes were seen (the monotonic clock),
   where the front end can say (a TCP port's or a pty's look, interfaces/tcplines.py rule 9;
   a datagram's arrival, interfaces/loggers/server.py rule 9), a stop's as a move's. The
   remote stamps what it sends with it (remote/rotator.py rule 7: a STOP the station took
   another way after the bytes came refuses the move there); the station's judge needs no
   time (its halt count says what came before a halt: mailbox.py rule 10) and ignores it.
   With it goes ``reader``: the connection, pty or port that read the bytes (it orders its
   own): the remote lifts a move's stamp to the stamp of a halt read by the same reader
   alone, never to another front end's (remote/rotator.py rule 7). ``seen_s`` is a lower
   bound (the reader's last look that found nothing waiting), and two readers' lower bounds
   do not order their bytes; so a stop (or lock ON) takes ``read_s`` too: the latest its
   bytes can have come, where the front end knows it better than the moment it hands the
   stop over (the kernel's datagram stamp, interfaces/loggers/commands.py rule 8; None: that
   moment). The remote sends a move after another reader's halt only if the move was seen
   after the halt's ``read_s`` (interfaces/mqtt/remote.py rule 8); after its own reader's,
   if seen no earlier than the halt.
"""

from __future__ import annotations

from collections.abc import Hashable
from typing import Protocol

from bridge.core.model import Command, Origin, RotatorStatus, Source
from bridge.protocols.base import ModelSpec


class FrontRotator(Protocol):
    @property
    def id(self) -> str: ...
    @property
    def spec(self) -> ModelSpec: ...
    @property
    def status(self) -> RotatorStatus: ...
    def submit(self, command: Command, described: str | None = None) -> None: ...
    def report_refusal(
        self, message: str, command: str | None, *, origin: Origin | None = None
    ) -> None: ...


class HaltCounted(FrontRotator, Protocol):
    """Rule 3: a rotator that counts its halts for a front end's ``since``."""

    @property
    def halts(self) -> int: ...
    def halts_for(self, source: Source) -> int: ...
    def submit(
        self,
        command: Command,
        described: str | None = None,
        *,
        since: int | None = None,
        seen_s: float | None = None,
        reader: Hashable | None = None,
        read_s: float | None = None,
    ) -> None: ...
