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
7. ``received`` keeps the last RECEIVED reads from the client, always: ``(t, due of the last
   byte, bytes)``, ``t`` when we read them (time.monotonic: on Linux CLOCK_MONOTONIC, the clock
   of a benchmark's publish stamps and of the emulators' frame logs). ``ahead_of(t)`` says from
   it what the line still carried at ``t`` of bytes read before ``t`` (``wire_ahead``): the
   line's own floor for a byte the client writes at ``t``, which no client can shorten (bytes
   handed to a UART are not recalled). The due times are the line's, not our deliveries (a
   late delivery is the relay's error, rule 4, and is not taken for the line's floor).
   ``read_between(t0, t1)``: the bytes read from ``t0`` to ``t1`` (what came after a publish).
8. ``stamp_late(t, byte)``: how long after the line delivered ``byte`` (its due time) the
   controller stamped a frame ending in it at ``t``: the instrument's own wait (the relay's and
   the emulator's threads waiting for a core or the interpreter lock; a real controller stamps
   nothing and waits for nothing), kept beside every latency so that a figure taken with the
   instrument raised (harness.py rule 6) and one without compare. From the last RECEIVED chunks
   handed on (``handed``: ``(t handed, due of each byte, bytes)``, always kept).
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
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

_CHUNK = 4096
RECEIVED = 256  # reads kept in ``received`` (rule 7): seconds of polls on a busy line
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


def name_thread(tid: int | None, name: str) -> None:
    """A thread of this process named for the kernel too (its ``comm``, 15 bytes), so that
    per-thread scheduling read from outside (/proc, perf) names the instrument's threads."""
    with contextlib.suppress(OSError):
        Path(f"/proc/self/task/{tid}/comm").write_text(name[:15])


@dataclass(frozen=True)
class Ahead:
    """What a line still carried at a moment of bytes it had read before it (rule 7)."""

    s: float  # how long after the moment the line stayed busy with them (0: it was idle)
    data: bytes  # the reads those bytes came in, whole (b"" if none)


def wire_ahead(received: Iterable[tuple[float, float, bytes]], t: float) -> Ahead:
    """From a line's reads ``(t read, due of its last byte, bytes)`` (rule 7): how long after
    ``t`` the line was busy with bytes read before ``t``, and the reads they came in. A read
    whose last byte is due after ``t`` has bytes still on the line at ``t`` (sent in part, or
    waiting behind others); the line is free when the last of them is due."""
    busy_until = t
    data = bytearray()
    for t_read, due_last, chunk in received:
        if t_read < t < due_last:
            busy_until = max(busy_until, due_last)
            data += chunk
    return Ahead(busy_until - t, bytes(data))


def stamp_late(
    handed: Iterable[tuple[float, tuple[float, ...], bytes]], t: float, byte: bytes
) -> float | None:
    """From a line's chunks handed on ``(t handed, due of each byte, bytes)`` (rule 8): ``t``
    (a frame's stamp) less the due time of ``byte`` in the last chunk handed on by ``t`` that
    holds it (its first such byte: the frame ended there); None if none did. A relay hands a
    chunk on only once the controller took the one before (rule 5), so that chunk is the
    frame's."""
    for t_out, dues, data in reversed(tuple(handed)):
        if t_out <= t and byte in data:
            return max(0.0, t - dues[data.index(byte)])
    return None


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
        self.received: deque[tuple[float, float, bytes]] = deque(maxlen=RECEIVED)
        self.handed: deque[tuple[float, tuple[float, ...], bytes]] = deque(maxlen=RECEIVED)
        self._received_lock = threading.Lock()
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

    @property
    def thread_id(self) -> int | None:
        """The relay thread's native id (its kernel thread)."""
        return self._thread.native_id

    def _run(self) -> None:
        fds = [self._master, self._device, self._wake_r]
        while not self._stop:
            now = time.monotonic()
            if self._queue and self._queue[0][0] <= now:
                self.lateness_s.append(now - self._queue[0][0])
                first_due = self._queue[0][0]
                out = bytearray()
                dues: list[float] = []
                while self._queue and self._queue[0][0] <= now:
                    due, byte = self._queue.popleft()
                    out += byte
                    dues.append(due)
                with self._received_lock:
                    self.handed.append((time.monotonic(), tuple(dues), bytes(out)))
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
                        t_read = time.monotonic()
                        due = max(t_read, self._line_free_s)
                        for i in range(len(data)):
                            due += self.byte_time_s
                            self._queue.append((due, data[i : i + 1]))
                        self._line_free_s = due
                        with self._received_lock:
                            self.received.append((t_read, due, data))
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

    def ahead_of(self, t: float) -> Ahead:
        """What the line still carried at ``t`` (time.monotonic) of bytes read before it."""
        with self._received_lock:
            received = tuple(self.received)
        return wire_ahead(received, t)

    def read_between(self, t0: float, t1: float) -> bytes:
        """The bytes read from the client from ``t0`` to ``t1`` (time.monotonic)."""
        with self._received_lock:
            return b"".join(data for t, _, data in self.received if t0 <= t <= t1)

    def stamp_late(self, t: float, byte: bytes) -> float | None:
        """Rule 8, from what this line handed on."""
        with self._received_lock:
            handed = tuple(self.handed)
        return stamp_late(handed, t, byte)

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
