"""Put a controller emulator on a pseudo-terminal, with the faults a serial line really has.

What this is: the "cable" between a sans-IO responder (see base.Responder; rotorez.RotorEZ today)
and any serial client (the bridge, pyserial, Hamlib's rotctl). One daemon thread per port owns
the pty file descriptors; the responder itself is plain data guarded by a lock.

Frame: none; bytes pass through unchanged. The master side runs in packet mode (TIOCPKT) so the
thread also sees the client's input flushes, which is how an open by pyserial or Hamlib shows up.

Source documents: Hamlib 4.5.4 driven over a socat pty pair (every client flushes pending input
when it opens the port); the bridge opens ports by stable path, e.g. /dev/serial/by-id/...

Rules:
1. Only the device thread touches the pty descriptors. Calls from other threads (unplug, replug,
   inject, close) are queued to it and wait for it; the responder is used under `lock`.
2. We keep our own slave descriptor open, so the master never sees EIO when a client closes.
3. The thread sleeps in poll() until a byte arrives, a call is queued, or the responder's
   next_wakeup(); an idle port costs nothing. poll, not select: select refuses a descriptor
   above 1023, which ended the thread (the controller then never answered) in a process that
   holds that many (a test worker late in a long run, a demo with many clients).
4. `link` is an atomic symlink to the current slave: replaced with os.replace, removed on unplug
   and close (only if it still points at our pty), re-pointed by replug.
5. A fresh pty holds back its output until a client shows up (first input flush or first byte
   received). A client's open flushes pending input, so without this the power-on junk byte
   could never be seen by anyone; with it, the first client after a power-up sees it.
6. set_silent(True) drops everything the device transmits (its replies are lost); the device
   still hears and obeys, so its log shows what a client sent while it got no answer.
7. set_deaf(True) drops everything the client sends before the device hears it (a byte lost
   on the way in, a loose TX wire); `deaf_dropped` counts those bytes.
8. While unplugged the device lives on (a rotor keeps turning when the USB plug is pulled);
   what it transmits meanwhile is lost.
"""

from __future__ import annotations

import contextlib
import fcntl
import itertools
import math
import os
import select
import struct
import termios
import threading
import time
import tty
from collections import deque
from collections.abc import Callable
from concurrent.futures import Future
from typing import Generic, Literal, TypeVar

from bridge.emulators.base import LoggedFrame, Responder, RotatorState

R = TypeVar("R", bound=Responder)
T = TypeVar("T")

_TIOCPKT_DATA = 0x00
_TIOCPKT_FLUSHREAD = 0x01
_READ_CHUNK = 4096
_CALL_TIMEOUT_S = 10.0
_link_counter = itertools.count()


class EmulatedPort(Generic[R]):
    """A responder served on a pty at `.path` (and at `.link`, if given)."""

    def __init__(
        self,
        device: R,
        *,
        link: str | os.PathLike[str] | None = None,
        clock: Callable[[], float] = time.monotonic,
        hold_output_until_open: bool = True,
        on_frame: Callable[[LoggedFrame], None] | None = None,
        name: str = "emulator",
    ) -> None:
        self.device: R = device  # use under `lock`, or through call()
        self.lock = threading.RLock()
        self._changed = threading.Condition(self.lock)
        self._clock = clock
        self._hold_output = hold_output_until_open
        self._on_frame = on_frame
        self._link: str | None = os.path.abspath(os.fspath(link)) if link is not None else None
        self._master: int | None = None
        self._slave: int | None = None
        self._path: str = ""
        self._silent = False
        self._deaf = False
        self._deaf_dropped = 0
        self._closed = False
        self._client_seen = False
        self._held = bytearray()
        self._logged = len(device.log)
        self._flushes = 0
        self._iterations = 0
        self._requests: deque[tuple[Callable[[], object], Future[object]]] = deque()
        self._wake_r, self._wake_w = os.pipe()
        os.set_blocking(self._wake_r, False)
        os.set_blocking(self._wake_w, False)
        self._open_pty()
        self._thread = threading.Thread(target=self._run, name=f"{name}-pty", daemon=True)
        self._thread.start()

    # -- where to find it -----------------------------------------------------------------------

    @property
    def path(self) -> str:
        """The current slave device (changes on replug); "" while unplugged."""
        with self.lock:
            return self._path

    @property
    def link(self) -> str | None:
        return self._link

    @property
    def is_plugged(self) -> bool:
        with self.lock:
            return self._master is not None

    @property
    def flush_count(self) -> int:
        """Input flushes seen from clients: every pyserial or Hamlib open makes one."""
        with self.lock:
            return self._flushes

    @property
    def loop_iterations(self) -> int:
        """How often the device thread woke up (for checking that an idle port sleeps)."""
        with self.lock:
            return self._iterations

    # -- the device, thread-safely ----------------------------------------------------------------

    def call(self, fn: Callable[[R, float], T]) -> T:
        """Run fn(device, now) under the lock and let the thread re-plan its next wakeup."""
        with self.lock:
            result = fn(self.device, self._clock())
        self._wake()
        return result

    def state(self) -> RotatorState:
        return self.call(lambda device, now: device.state(now))

    def log(self) -> list[LoggedFrame]:
        with self.lock:
            return list(self.device.log)

    def frames(self, *outcomes: str) -> list[LoggedFrame]:
        wanted = set(outcomes)
        return [f for f in self.log() if not wanted or f.outcome in wanted]

    def wait_for(
        self, predicate: Callable[[RotatorState], bool], timeout_s: float = 5.0
    ) -> RotatorState:
        """Wait until predicate(state) holds; TimeoutError (with the last state) at the deadline."""
        return self.wait_until(lambda device, now: device.state(now), predicate, timeout_s)

    def wait_for_frame(
        self, data: bytes, outcome: str | None = None, timeout_s: float = 5.0
    ) -> LoggedFrame:
        """Wait until a frame equal to `data` (with `outcome`, if given) is in the log."""

        def find(device: R, _now: float) -> LoggedFrame | None:
            for frame in device.log:
                if frame.data == data and (outcome is None or frame.outcome == outcome):
                    return frame
            return None

        found = self.wait_until(find, lambda f: f is not None, timeout_s)
        assert found is not None
        return found

    def wait_until(
        self,
        probe: Callable[[R, float], T],
        predicate: Callable[[T], bool],
        timeout_s: float = 5.0,
    ) -> T:
        """Re-evaluate probe(device, now) on every device event (at least every 20 ms)."""
        deadline_s = time.monotonic() + timeout_s
        with self._changed:
            while True:
                value = probe(self.device, self._clock())
                if predicate(value):
                    return value
                remaining_s = deadline_s - time.monotonic()
                if remaining_s <= 0:
                    raise TimeoutError(f"condition not met within {timeout_s} s; last: {value!r}")
                self._changed.wait(min(remaining_s, 0.02))

    # -- front panel ----------------------------------------------------------------------------

    def press_brake(self) -> bool:
        return self.call(lambda device, now: device.press_brake(now))

    def manual_rotate(self, az_deg: float) -> None:
        self.call(lambda device, now: device.manual_rotate(az_deg, now))

    def jam(self) -> None:
        self.call(lambda device, now: device.jam(now))

    def unjam(self) -> None:
        self.call(lambda device, now: device.unjam(now))

    def power_cycle(self) -> None:
        self.call(lambda device, now: device.power_cycle(now))

    # -- line faults ----------------------------------------------------------------------------

    def set_silent(self, silent: bool) -> None:
        with self.lock:
            self._silent = silent

    def set_deaf(self, deaf: bool) -> None:
        with self.lock:
            self._deaf = deaf

    @property
    def deaf_dropped(self) -> int:
        with self.lock:
            return self._deaf_dropped

    def inject(self, data: bytes, *, to: Literal["host", "device"] = "host") -> None:
        """Garbage on the line: towards the client ("host") or into the controller ("device")."""
        if to == "host":
            self._on_thread(lambda: self._write(bytes(data)))
        elif to == "device":
            self._on_thread(lambda: self._deliver(bytes(data)))
        else:
            raise ValueError(f"inject(to=...) must be 'host' or 'device', got {to!r}")

    def unplug(self) -> None:
        """Yank the adapter: the pty goes away (client I/O fails), the link disappears."""
        self._on_thread(self._close_pty)

    def replug(self, *, power_cycle: bool = True) -> None:
        """A new pty, the link re-pointed; the rotor stays where it is (rule 7)."""

        def do() -> None:
            self._close_pty()
            if power_cycle:
                self.device.power_cycle(self._clock())
            self._open_pty()

        self._on_thread(do)

    def close(self) -> None:
        if self._closed:
            return

        def do() -> None:
            self._closed = True
            self._close_pty()

        self._on_thread(do)
        self._thread.join(_CALL_TIMEOUT_S)
        for fd in (self._wake_r, self._wake_w):
            with contextlib.suppress(OSError):
                os.close(fd)

    def __enter__(self) -> EmulatedPort[R]:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    # -- device thread --------------------------------------------------------------------------

    def _wake(self) -> None:
        with contextlib.suppress(BlockingIOError, OSError):
            os.write(self._wake_w, b"\0")

    def _on_thread(self, fn: Callable[[], object]) -> None:
        if self._closed:
            raise RuntimeError("the emulated port is closed")
        if threading.current_thread() is self._thread or not self._thread.is_alive():
            with self.lock:
                fn()
            return
        future: Future[object] = Future()
        with self.lock:
            self._requests.append((fn, future))
        self._wake()
        future.result(timeout=_CALL_TIMEOUT_S)

    def _run(self) -> None:
        while True:
            with self._changed:
                while self._requests:
                    fn, future = self._requests.popleft()
                    try:
                        future.set_result(fn())
                    except BaseException as exc:  # handed to the caller
                        future.set_exception(exc)
                if self._closed:
                    self._changed.notify_all()
                    return
                self._iterations += 1
                now = self._clock()
                self._pump(now)
                wake_at_s = self.device.next_wakeup(now)
                fds = [self._wake_r] if self._master is None else [self._wake_r, self._master]
                self._changed.notify_all()
            timeout_s = None if wake_at_s is None else max(0.0, wake_at_s - self._clock())
            waiting = select.poll()  # rule 3
            for fd in fds:
                waiting.register(fd, select.POLLIN)
            timeout_ms = None if timeout_s is None else math.ceil(timeout_s * 1000)
            readable = [fd for fd, _events in waiting.poll(timeout_ms)]
            if self._wake_r in readable:
                with contextlib.suppress(BlockingIOError):
                    os.read(self._wake_r, _READ_CHUNK)
            if self._master is not None and self._master in readable:
                with self.lock:
                    self._read_master()

    def _read_master(self) -> None:
        assert self._master is not None
        try:
            packet = os.read(self._master, _READ_CHUNK + 1)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:  # EIO cannot happen while we hold the slave (rule 2); be safe anyway
            return
        if not packet:
            return
        if packet[0] == _TIOCPKT_DATA:
            if self._deaf:
                self._client_arrived()
                self._deaf_dropped += len(packet) - 1
                with self._changed:
                    self._changed.notify_all()
                return
            self._deliver(packet[1:])
        elif packet[0] & _TIOCPKT_FLUSHREAD:
            self._flushes += 1
            self._client_arrived()

    def _deliver(self, data: bytes) -> None:
        self._client_arrived()
        self.device.receive(data, self._clock())
        log = self.device.log
        if self._on_frame is not None:
            for frame in log[self._logged :]:
                self._on_frame(frame)
        self._logged = len(log)

    def _client_arrived(self) -> None:
        if not self._client_seen:
            self._client_seen = True
            held, self._held = bytes(self._held), bytearray()
            if held and not self._silent:
                self._write(held)

    def _pump(self, now: float) -> None:
        out = self.device.due_output(now)
        if not out or self._silent or self._master is None:
            return
        if self._hold_output and not self._client_seen:
            self._held += out
            return
        self._write(out)

    def _write(self, data: bytes) -> None:
        view = memoryview(data)
        while view and self._master is not None:
            try:
                written = os.write(self._master, view)
            except (BlockingIOError, InterruptedError):
                return  # the client does not read: a real UART would overrun too
            except OSError:
                return
            view = view[written:]

    def _open_pty(self) -> None:
        master, slave = os.openpty()
        for fd in (master, slave):
            tty.setraw(fd)
        fcntl.ioctl(master, termios.TIOCPKT, struct.pack("i", 1))
        os.set_blocking(master, False)
        self._master, self._slave = master, slave
        self._path = os.ttyname(slave)
        self._client_seen = not self._hold_output
        self._held = bytearray()
        if self._link is not None:
            try:
                self._point_link(self._path)
            except OSError:
                self._close_pty()
                raise

    def _close_pty(self) -> None:
        if self._link is not None and self._path:
            with contextlib.suppress(OSError):
                if os.readlink(self._link) == self._path:
                    os.unlink(self._link)
        for fd in (self._master, self._slave):
            if fd is not None:
                with contextlib.suppress(OSError):
                    os.close(fd)
        self._master = self._slave = None
        self._path = ""
        self._held = bytearray()

    def _point_link(self, target: str) -> None:
        assert self._link is not None
        os.makedirs(os.path.dirname(self._link), exist_ok=True)
        temp = f"{self._link}.{os.getpid()}.{next(_link_counter)}.tmp"
        os.symlink(target, temp)
        os.replace(temp, self._link)
