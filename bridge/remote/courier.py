"""The remote's PstRotator ports' way to a station rotator: their moves handed to a sender of
their own, so the loggers' one thread never waits for the station's broker on a move.

The remote's link answers a command only once the station's broker acknowledged it
(interfaces/mqtt/remote.py rule 7), a round trip. The loggers' ports are served by one thread
(interfaces/loggers/server.py), and PstRotator's protocol has no reply to a command
(loggers/commands.py rule 1): nobody waits for the acknowledgement but that thread. Sent from
it, a burst of targets from another program on the remote's computer (190 of them, within one
sender's budget) held the operator's STOP read after them one round trip per target, 3.9 s
with the station's broker on loopback, 10 s on a 25 ms link (attack 29); the station refused
every one of those targets as expired anyway.

Rules:
1. A move (a target, park, a place) is handed to the rotator's sender thread and the loggers'
   thread goes on at once. The sender sends them one at a time, in the order they came, each
   as before (``RemoteRotator.submit``: stamped with when it was seen, ``since``, its reader),
   and with the halt count read when it came (``asked``): a STOP or lock ON of any front end
   of this rotator that went out since refuses it up to its hand-off to the link, under the
   link's send lock (remote.py rule 9), as the console's queued moves are refused
   (interfaces/web/server.py rule 5).
2. A newer move replaces an older one of the same kind not yet sent (``kind``: a target's
   azimuth, its elevation, both, park, a place): only the newest counts at the station, and a
   queued one would go late, maybe refused there as expired. An elevation does not replace an
   azimuth (Hamlib's PstRotator client sends ``P 200 30`` as two datagrams: attack 17). So at
   most one move of each kind waits: a burst costs one round trip, not one a datagram.
3. A STOP or lock ON is never behind a move: it drops every move not yet sent (they came
   before it; each is reported stale, as the link would refuse it: remote.py rule 8) and is
   sent on the caller's thread at once, not queued (it waits for its own acknowledgement, one
   round trip, as before; its refusal, not delivered or kept for the reconnect, reaches the
   caller as before: loggers/commands.py rule 4). A move the sender is handing over meanwhile
   goes before it or not at all (rule 1's ``asked``); one already handed over is before it
   at the broker too. Whatever else never moves goes on the caller's thread too, after the
   moves before it have gone (its order kept).
4. A refusal on the sender's thread is the rotator's to report (remote/rotator.py rule 5, on
   its log) and goes no further: the datagram's sender gets no reply in any case.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Hashable
from dataclasses import dataclass

from bridge.core.errors import RefusalCode, Refused
from bridge.core.model import (
    Command,
    Lock,
    Origin,
    Park,
    RotatorStatus,
    Source,
    Stop,
    Target,
    Toward,
)
from bridge.pointing import Pointing
from bridge.protocols.base import ModelSpec
from bridge.remote.rotator import HALTED_SINCE, RemoteRotator

log = logging.getLogger(__name__)

IDLE_S = 5.0  # the sender's thread ends after this long with nothing to send (rule 1)


def kind(command: Command) -> Hashable:
    """Rule 2: what a newer move of the same kind replaces."""
    match command:
        case Target():
            return ("target", command.az_deg is not None, command.el_deg is not None)
        case Park():
            return "park"
        case Toward():
            return "place"
    return ("other", id(command))  # (never replaced)


def moves(command: Command) -> bool:
    return isinstance(command, (Target, Park, Toward))


def halts(command: Command) -> bool:
    return isinstance(command, Stop) or (isinstance(command, Lock) and command.on)


@dataclass
class _Move:
    command: Command
    described: str | None
    since: int | None
    seen_s: float | None
    reader: Hashable | None
    asked: int


class Courier:
    """Rules 1 to 4: what the loggers' endpoints take for the remote's rotator ``rot``."""

    def __init__(self, rot: RemoteRotator) -> None:
        self.rot = rot
        self._lock = threading.Condition()
        self._waiting: dict[Hashable, _Move] = {}  # in the order they came (rule 2)
        self._busy = False  # a move being handed over (rule 3: the next ones wait for it)
        self._thread: threading.Thread | None = None
        self._stopping = False
        self.replaced = 0  # rule 2: moves a newer one replaced (diagnostics, the tests)
        self.dropped = 0  # rule 3: moves a halt dropped

    # what the loggers read of the rotator (loggers/commands.py ``Rotator``)
    @property
    def id(self) -> str:
        return self.rot.id

    @property
    def spec(self) -> ModelSpec:
        return self.rot.spec

    @property
    def status(self) -> RotatorStatus:
        return self.rot.status

    @property
    def pointing(self) -> Pointing:
        return self.rot.pointing

    @property
    def last_halt_s(self) -> float:
        return self.rot.last_halt_s

    @property
    def halts(self) -> int:
        return self.rot.halts

    def halts_for(self, source: Source) -> int:
        return self.rot.halts_for(source)

    def report_refusal(
        self, message: str, command: str | None, *, origin: Origin | None = None
    ) -> None:
        self.rot.report_refusal(message, command, origin=origin)

    def submit(
        self,
        command: Command,
        described: str | None = None,
        *,
        since: int | None = None,
        seen_s: float | None = None,
        reader: Hashable | None = None,
        read_s: float | None = None,
    ) -> None:
        if moves(command):  # rule 1
            move = _Move(command, described, since, seen_s, reader, self.rot.halts)
            with self._lock:
                if self._stopping:
                    raise Refused(RefusalCode.OFFLINE, "the remote is stopping: not sent")
                key = kind(command)
                if self._waiting.pop(key, None) is not None:  # rule 2
                    self.replaced += 1
                self._waiting[key] = move
                self._lock.notify_all()
                if self._thread is None:
                    self._thread = threading.Thread(
                        target=self._run, name=f"pst-sender-{self.rot.id}", daemon=True
                    )
                    self._thread.start()
            return
        if halts(command):  # rule 3: the moves before it never go
            with self._lock:
                dropped = list(self._waiting.values())
                self._waiting.clear()
            self.dropped += len(dropped)
            for move in dropped:
                self.rot.report_refusal(HALTED_SINCE, move.described)
        else:  # rule 3: after the moves before it
            with self._lock:
                self._lock.wait_for(lambda: not self._waiting and not self._busy)
        self.rot.submit(command, described, seen_s=seen_s, reader=reader, read_s=read_s)

    def _run(self) -> None:
        while True:
            with self._lock:
                self._busy = False
                self._lock.notify_all()
                if not self._lock.wait_for(lambda: self._waiting or self._stopping, IDLE_S):
                    self._thread = None  # (idle: the next move starts another)
                    return
                if self._stopping:
                    self._thread = None
                    return
                key = next(iter(self._waiting))
                move = self._waiting.pop(key)
                self._busy = True
            try:
                self.rot.submit(
                    move.command,
                    move.described,
                    since=move.since,
                    seen_s=move.seen_s,
                    reader=move.reader,
                    asked=move.asked,
                )
            except Refused:
                pass  # rule 4: the rotator reported it
            except Exception:  # (a bug behind it: the next move is still sent)
                log.exception("sending %s to %s", move.described, self.rot.id)

    def stop(self) -> None:
        with self._lock:
            self._stopping = True
            self._waiting.clear()
            self._lock.notify_all()
