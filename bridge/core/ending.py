"""The end of a process's main loop, asked for by a signal or by any thread, waited for by one.

Python runs a signal handler on the main thread, between two bytecodes of whatever it was doing:
inside ``threading.Event.wait`` too, while it holds the event's own lock (a plain, not re-entrant
``Lock``). A handler that set such an event waited for ever on a lock its own thread held, and
the service hung on ``systemctl stop`` until systemd killed it (no offline, no ordered stop).
A handler that raises instead (as Ctrl-C's KeyboardInterrupt does) can land in start-up, or
between two steps of ``Condition.wait`` that must not be parted, and leave a lock wrong.

So an end is a byte on a socket of its own, and the main thread sleeps in ``poll`` on it:
writing a byte takes no lock, and the byte stays until it is read, so an end asked for just
before the wait is not lost. ``signal.set_wakeup_fd`` points at the same socket: the signal's
low-level handler writes its byte at once on whichever thread the system delivered it, and the
main thread wakes even before Python runs the handler of ours. (Handing the Event's ``set`` to a
short-lived thread would have cost a thread per signal, started under threading's own locks.)

Rules:
1. ``end(reason)`` never blocks and takes no lock: a signal handler and any thread may call it,
   as often as they like. The first reason is kept (what ended it, said once); an end with
   none (``end()``: a failure that says its own words) keeps none.
2. One thread waits (``wait``): the main thread, or whichever thread runs the loop. ``wait``
   returns as soon as ``end`` was called, before its call or during it, whoever called it.
3. ``on_signals(...)`` routes the signals to ``end`` with the signal's name as the reason, for
   as long as its block lasts, then puts the handlers and the wake-up socket as they were. A
   signal again while the block is still on (a second Ctrl-C during the ordered shutdown) finds
   the end already asked for and changes nothing. Off the main thread (where Python allows no
   handler) it does nothing.
4. The handlers log nothing: a log line written from a handler can land inside the same
   stream's write on the same thread. The loop that waited says what ended it.
"""

from __future__ import annotations

import contextlib
import math
import signal
import socket
import threading
import time
from collections.abc import Iterator
from types import FrameType

from bridge.core.polling import POLLIN, new_poller

__all__ = ["Ending"]


class Ending:
    """An end asked for by ``end`` (any thread, a signal handler), waited for by ``wait``."""

    def __init__(self) -> None:
        self._reader, self._writer = socket.socketpair()
        self._reader.setblocking(False)
        self._writer.setblocking(False)  # set_wakeup_fd asks for it; a full socket is awake
        self._poll = new_poller()  # poll(): a descriptor above 1023 is fine too (polling.py)
        self._poll.register(self._reader, POLLIN)
        self._ended = False
        self.reason: str | None = None  # rule 1: the first

    def end(self, reason: str | None = None) -> None:
        """Rule 1: no lock, no wait; from a signal handler or any thread."""
        if self.reason is None:
            self.reason = reason
        self._ended = True
        # a full socket (bytes not yet read) already wakes the waiter; a closed one, nobody waits
        with contextlib.suppress(OSError):
            self._writer.send(b"\0")

    def is_set(self) -> bool:
        return self._ended

    def wait(self, timeout: float | None = None) -> bool:
        """Rule 2: True once ended, False when ``timeout`` seconds passed first."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while not self._ended:
            left_ms = None if deadline is None else (deadline - time.monotonic()) * 1000
            if left_ms is not None and left_ms <= 0:
                break
            # a handler that returns lets poll go on (PEP 475); its byte then ends the wait
            self._poll.poll(None if left_ms is None else math.ceil(left_ms))
            self._drain()
        return self._ended

    def _drain(self) -> None:
        with contextlib.suppress(OSError):  # BlockingIOError: all read
            while self._reader.recv(256):
                pass

    @contextlib.contextmanager
    def on_signals(self, *signums: signal.Signals) -> Iterator[None]:
        """Rule 3: ``signums`` end the loop while the block lasts."""
        if threading.current_thread() is not threading.main_thread():
            yield
            return

        def handler(signum: int, _frame: FrameType | None) -> None:
            self.end(signal.Signals(signum).name)

        previous = {sig: signal.signal(sig, handler) for sig in signums}
        wakeup = signal.set_wakeup_fd(self._writer.fileno(), warn_on_full_buffer=False)
        try:
            yield
        finally:
            signal.set_wakeup_fd(wakeup)
            for sig, old in previous.items():
                # None: a handler not set from Python, which Python cannot put back
                signal.signal(sig, signal.SIG_DFL if old is None else old)

    def close(self) -> None:
        """The socket given back; ``end`` afterwards is harmless (rule 1)."""
        self._reader.close()
        self._writer.close()
