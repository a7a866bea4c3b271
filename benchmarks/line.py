"""A serial line at its real rate in both directions, between a client and an emulator's pty.

Why: the emulators pace what the controller sends (replies leave at the line rate), but a pty
hands whatever the host writes to the controller at once. Real UARTs do not: a 13-byte SPID frame
takes 217 ms at 600 baud, and a stop written right after a query waits in the UART behind it.
This relay puts a pacing UART in the host -> controller direction, so that every figure
(latency, freshness, line use) is what a real line at that rate would show.

Rules:
1. The client (the bridge, rotctld) opens `link`, a symlink to a pty slave we own. Bytes it writes
   are queued like a UART transmit buffer: each byte leaves when the line is free and reaches
   the controller `bits_per_byte / baud` later (bytes due by the time the relay wakes up are
   handed over together).
2. Bytes from the controller are passed on at once: the emulator already paced them.
3. We keep our slave descriptor open, so the master never sees EIO when a client closes.
4. `lateness` records how far behind its due time each chunk was delivered: the relay's own
   error, reported beside the results.
5. With ``deliver`` set (in-process emulators: rig.open_line's ``direct``), bytes due go to it
   (the emulator's ``inject(..., to="device")``) instead of through the emulator's pty: a pty
   hands written bytes to its reader from a kernel worker thread (the tty flip buffer's work,
   on the unbound workqueue, at nice 0), which on a busy machine waits for a CPU behind every
   other program, tens of ms at times; a real UART has no such hop. Replies still come back
   through the emulator's pty (rule 2).
6. With ``timeline`` set (a deque), every read from the client and every delivery to the
   controller is kept there, on our clock: ``("in", t, bytes, due of the last byte, sched)``
   and ``("out", t, bytes, due of the first byte, sched)``, sched being the relay thread's
   (ns on a CPU, ns runnable waiting for one) (where a slow byte waited: stop_trace.py).
"""

from __future__ import annotations

import contextlib
import os
import select
import termios
import threading
import time
import tty
from collections import deque
from collections.abc import Callable
from pathlib import Path
from typing import Any

_CHUNK = 4096
_lock = threading.Lock()
#: lateness of every delivery by every relay closed so far in this process (seconds)
ALL_LATENESS_S: list[float] = []


def thread_sched() -> tuple[int, int]:
    """(ns on a CPU, ns runnable but waiting for one) of the calling thread, from the kernel."""
    try:
        with open("/proc/thread-self/schedstat") as f:
            run, wait, _ = f.read().split()
        return int(run), int(wait)
    except (OSError, ValueError):
        return 0, 0


class PacedRelay:
    def __init__(
        self,
        device_path: str,
        link: Path,
        baud: int,
        bits_per_byte: int = 10,
        timeline: deque[tuple[Any, ...]] | None = None,
        deliver: Callable[[bytes], None] | None = None,
    ) -> None:
        self.byte_time_s = bits_per_byte / baud
        self.timeline = timeline
        self._deliver = deliver
        self.link = link
        self._master, self._slave = os.openpty()
        for fd in (self._master, self._slave):
            tty.setraw(fd)
        os.set_blocking(self._master, False)
        self._device = os.open(device_path, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
        tty.setraw(self._device)
        termios.tcflush(self._device, termios.TCIFLUSH)  # "a client opened the port"
        self._queue: deque[tuple[float, bytes]] = deque()
        self._line_free_s = 0.0
        self.lateness_s: list[float] = []
        self._stop = False
        self._wake_r, self._wake_w = os.pipe()
        os.set_blocking(self._wake_r, False)
        tmp = link.with_name(link.name + ".tmp")
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()
        os.symlink(os.ttyname(self._slave), tmp)
        os.replace(tmp, link)
        self._thread = threading.Thread(target=self._run, daemon=True, name=f"line-{link.name}")
        self._thread.start()

    def _run(self) -> None:
        fds = [self._master, self._device, self._wake_r]
        while not self._stop:
            now = time.monotonic()
            if self._queue and self._queue[0][0] <= now:
                self.lateness_s.append(now - self._queue[0][0])
                first_due = self._queue[0][0]
                out = bytearray()
                while self._queue and self._queue[0][0] <= now:
                    out += self._queue.popleft()[1]
                if self.timeline is not None:
                    event = ("out", time.monotonic(), bytes(out), first_due, *thread_sched())
                    self.timeline.append(event)
                if not self._hand_over(bytes(out)):
                    return
            timeout = None if not self._queue else max(0.0, self._queue[0][0] - time.monotonic())
            try:
                readable, _, _ = select.select(fds, [], [], timeout)
            except (OSError, ValueError):
                return
            if self._master in readable:
                with contextlib.suppress(BlockingIOError):
                    data = os.read(self._master, _CHUNK)
                    if data:
                        due = max(time.monotonic(), self._line_free_s)
                        for i in range(len(data)):
                            due += self.byte_time_s
                            self._queue.append((due, data[i : i + 1]))
                        self._line_free_s = due
                        if self.timeline is not None:
                            event = ("in", time.monotonic(), data, due, *thread_sched())
                            self.timeline.append(event)
            if self._device in readable:
                try:
                    data = os.read(self._device, _CHUNK)
                except BlockingIOError:
                    data = b""
                except OSError:
                    return  # the emulator went away
                if data:
                    self._write(self._master, data)
            if self._wake_r in readable:
                with contextlib.suppress(BlockingIOError):
                    os.read(self._wake_r, _CHUNK)

    def _hand_over(self, data: bytes) -> bool:
        """The bytes due to the controller: to ``deliver`` (rule 5), else through its pty."""
        if self._deliver is None:
            return self._write(self._device, data)
        try:
            self._deliver(data)
        except (RuntimeError, TimeoutError):  # the emulator closed (or stuck): the line ends
            return False
        return True

    @staticmethod
    def _write(fd: int, data: bytes) -> bool:
        view = memoryview(data)
        while view:
            try:
                view = view[os.write(fd, view) :]
            except BlockingIOError:
                select.select([], [fd], [], 0.1)
            except OSError:
                return False
        return True

    def close(self) -> None:
        self._stop = True
        with contextlib.suppress(OSError):
            os.write(self._wake_w, b"\0")
        self._thread.join(2)
        with contextlib.suppress(OSError):
            if os.readlink(self.link) == os.ttyname(self._slave):
                os.unlink(self.link)
        for fd in (self._master, self._slave, self._device, self._wake_r, self._wake_w):
            with contextlib.suppress(OSError):
                os.close(fd)
        with _lock:
            ALL_LATENESS_S.extend(self.lateness_s)


class FrameLog:
    """on_frame callback for emulators.start(): keeps frames and lets a thread wait for one.
    With ``sched``, each frame's (ns on a CPU, ns runnable waiting for one) of the emulator's
    thread when it logged the frame goes to ``sched`` too (its waits: stop_trace.py)."""

    def __init__(self, sched: bool = False) -> None:
        self.frames: list[Any] = []  # LoggedFrame
        self.sched: list[tuple[int, int]] | None = [] if sched else None
        self._cond = threading.Condition()

    def __call__(self, frame: Any) -> None:
        stat = thread_sched() if self.sched is not None else None
        with self._cond:
            if self.sched is not None and stat is not None:
                self.sched.append(stat)
            self.frames.append(frame)
            self._cond.notify_all()

    def mark(self) -> int:
        with self._cond:
            return len(self.frames)

    def since(self, start: int) -> list[Any]:
        with self._cond:
            return self.frames[start:]

    def wait(self, predicate: Callable[[Any], bool], start: int, timeout_s: float) -> Any:
        deadline = time.monotonic() + timeout_s
        with self._cond:
            i = start
            while True:
                while i < len(self.frames):
                    if predicate(self.frames[i]):
                        return self.frames[i]
                    i += 1
                left = deadline - time.monotonic()
                if left <= 0:
                    return None
                self._cond.wait(left)


class ByteCounter:
    """Counts bytes in both directions of an in-process emulator (wraps its sans-IO device)."""

    def __init__(self, port: Any) -> None:
        self.to_device = 0
        self.from_device = 0
        with port.lock:
            dev = port.device
            receive, due_output = dev.receive, dev.due_output

            def counted_receive(data: bytes, now: float) -> None:
                self.to_device += len(data)
                receive(data, now)

            def counted_output(now: float) -> bytes:
                out = due_output(now)
                self.from_device += len(out)
                return out

            dev.receive = counted_receive
            dev.due_output = counted_output

    def snapshot(self) -> tuple[int, int]:
        return self.to_device, self.from_device
