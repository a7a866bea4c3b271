"""One thread per rotator: the only code that touches that rotator's serial port. I/O only.

The loop: open the port (back-off on failure), then select() on the port and the mailbox pipe.
Whatever happens (bytes, commands, time) goes into the rotator's session (session.py, where
every decision is made) and the actions it hands back are carried out: bytes written, statuses
and error events handed to the listeners (the second and last hand-off point, ARCHITECTURE.md
rule 3).

Rules:
1. Any serial error closes the port, tells the session the link is down and retries with
   back-off (``reconnect_min_s`` doubling up to ``reconnect_max_s``); the thread never dies of
   one. Commands are still taken while the port is closed (they are refused with a reason).
2. Everything the port has is read in one go and handed to the session as one chunk; while the
   session says a reply cannot be complete yet (link.py rule 7) only the mailbox is watched.
3. Listeners (MQTT, rotctld, Home Assistant) are called from this thread only, and a listener
   that raises is logged once per kind of failure and otherwise ignored (``contained``): a
   display problem never closes, reopens or delays the line to the controller.
"""

from __future__ import annotations

import logging
import os
import select
import threading
import time
from collections.abc import Callable
from typing import TypeVar

import serial

from bridge.engine.actions import Action, Publish, Report, Write
from bridge.engine.config import WorkerConfig
from bridge.engine.mailbox import Mailbox
from bridge.engine.port import PortError, open_port
from bridge.engine.session import RotatorSession
from bridge.model import ErrorEvent, ErrorKind, RotatorStatus
from bridge.protocols.base import ModelSpec

__all__ = ["Worker", "WorkerConfig", "contained"]

log = logging.getLogger(__name__)
T = TypeVar("T")


def contained(listener: Callable[[T], None], what: str) -> Callable[[T], None]:
    """``listener`` with its failures logged (once per exception type) and never raised."""
    seen: set[type[BaseException]] = set()

    def call(value: T) -> None:
        try:
            listener(value)
        except Exception as exc:
            if type(exc) not in seen:
                seen.add(type(exc))
                log.exception("%s failed (logged once; the rotator goes on)", what)

    return call


def _read_all(fd: int) -> bytes:
    """Everything the port has now (select said it has something)."""
    try:
        data = os.read(fd, 4096)
    except BlockingIOError:
        return b""
    if not data:
        raise serial.SerialException("port readable but no data (adapter unplugged?)")
    return data


def _write(port: serial.Serial, data: bytes) -> None:
    """A frame fits the port's buffer: one write() (pyserial's would select() after it too)."""
    try:
        done = os.write(port.fileno(), data)
    except BlockingIOError:
        done = 0
    if done < len(data):
        port.write(data[done:])  # the rest the way pyserial waits for room


class Worker:
    def __init__(
        self,
        cfg: WorkerConfig,
        mailbox: Mailbox,
        on_status: Callable[[RotatorStatus], None],
        on_event: Callable[[ErrorEvent], None],
        *,
        options: dict[str, bool] | None = None,
        locked: bool = False,
        clock: Callable[[], float] = time.monotonic,
        wall: Callable[[], float] = time.time,
        port_opener: Callable[[str, ModelSpec, int], serial.Serial] = open_port,
    ) -> None:
        self.cfg = cfg
        self.session = RotatorSession(cfg, options=options, locked=locked)
        self._mailbox = mailbox
        self._on_status = contained(on_status, f"{cfg.rotator_id}: status listener")
        self._on_event = contained(on_event, f"{cfg.rotator_id}: event listener")
        self._clock = clock
        self._wall = wall
        self._open = port_opener
        self._stopping = threading.Event()
        self._thread = threading.Thread(target=self._run, name=f"rotator-{cfg.rotator_id}")
        self._backoff_s = cfg.reconnect_min_s

    # -- public, any thread -----------------------------------------------------------------
    @property
    def status(self) -> RotatorStatus:
        return self.session.status

    def start(self) -> None:
        self._thread.start()

    def stop(self, timeout_s: float = 3.0) -> bool:
        """Stop the thread; True once it has ended."""
        self._stopping.set()
        self._mailbox.wake()
        if self._thread.is_alive():
            self._thread.join(timeout_s)
        return not self._thread.is_alive()

    # -- the thread ---------------------------------------------------------------------------
    def _run(self) -> None:
        self._do(self.session.start(self._clock()), None)
        while not self._stopping.is_set():
            try:
                self._cycle()
            except Exception:  # a bug must not end the thread
                log.exception("%s: unexpected error in the rotator worker", self.cfg.rotator_id)
                self._stopping.wait(1.0)

    def _cycle(self) -> None:
        """One attempt: open the port, serve it until it fails, then wait out the back-off."""
        try:
            port = self._open(self.cfg.port, self.cfg.spec, self.cfg.baud)
        except PortError as exc:
            self._do(self.session.open_failed(str(exc), self._clock()), None)
            self._idle_offline(self._backoff_s)
            self._backoff_s = min(self._backoff_s * 2, self.cfg.reconnect_max_s)
            return
        log.info("%s: opened %s", self.cfg.rotator_id, self.cfg.port)
        self._backoff_s = self.cfg.reconnect_min_s
        reason, kind = None, ErrorKind.SERIAL
        try:
            self._serve(port)
        except (serial.SerialException, OSError) as exc:
            reason = f"serial link to {self.cfg.port} lost: {exc}"
        except Exception:  # a bug must not kill the rotator: log it, reconnect
            log.exception("%s: unexpected error, reconnecting", self.cfg.rotator_id)
            reason = "unexpected error in the rotator worker (see the log)"
            kind = ErrorKind.INTERNAL
        finally:
            try:
                port.close()
            except Exception:  # closing a yanked port may fail too
                pass
        self._do(self.session.link_down(reason, self._clock(), kind), None)
        if not self._stopping.is_set():
            self._idle_offline(self._backoff_s)

    def _idle_offline(self, wait_s: float) -> None:
        """Wait for the next reconnect attempt, still taking commands from the mailbox."""
        deadline = self._clock() + wait_s
        while not self._stopping.is_set():
            now = self._clock()
            if now >= deadline:
                return
            readable, _, _ = select.select([self._mailbox], [], [], deadline - now)
            if readable:
                self._do(self.session.commands(self._mailbox.take(), self._clock()), None)

    def _serve(self, port: serial.Serial) -> None:
        session, mailbox = self.session, self._mailbox
        fd, box = port.fileno(), mailbox.fileno()
        self._do(session.link_up(self._clock(), self._wall()), port)
        while not self._stopping.is_set():
            now = self._clock()
            until, hold = session.next_wakeup(), session.hold_reads_until()
            watch = [fd, box] if now >= hold else [box]  # rule 2
            if now < hold:
                until = min(until, hold)
            readable, _, _ = select.select(watch, [], [], max(0.0, until - now))
            held, now = fd not in watch, self._clock()
            acted = False
            if box in readable:
                batch = mailbox.take()
                if batch:
                    self._do(session.commands(batch, now), port)
                    acted = True
            # a hold that just ended: the reply is due, read without asking select first
            if fd in readable or (held and not readable and now >= hold):
                data = _read_all(fd)
                if data:
                    actions = session.bytes_received(data, now)
                    acted = acted or bool(actions)
                    self._do(actions, port)
            if not acted and now >= session.next_wakeup():
                self._do(session.tick(now), port)

    def _do(self, actions: list[Action], port: serial.Serial | None) -> None:
        for action in actions:
            if isinstance(action, Write):
                if port is not None:
                    _write(port, action.data)
                    log.debug("%s: -> %r", self.cfg.rotator_id, action.data)
            elif isinstance(action, Publish):
                self._on_status(action.status)
            elif isinstance(action, Report):
                event = ErrorEvent(action.kind, action.message, action.command, self._wall())
                self._on_event(event)
