"""Shared pieces of the device emulators: the responder contract, ground truth, the paced line.

What this is: the seam between a controller emulator (sans-IO, one module per controller
family: rotorez.py, spid.py, satel.py) and the pty layer (pty.py) that puts any of them
on a pseudo-terminal. Nothing here knows a protocol.

Frame: none of its own. A responder takes raw bytes in (`receive`) and hands raw bytes out when
they have finished "arriving" on the wire (`due_output`).

Source documents: the controllers' own documents (emulators are written from those, never from
our codecs, and Hamlib's rotctl judges them) and Hamlib 4.5.4 on a socat pty pair (how a client
drives a fake device on a pty).

Rules:
1. Responders are sans-IO: no clock, no threads, no file descriptors. Every method that depends
   on time takes `now` (float seconds on any monotonic origin) from the caller.
2. A responder never goes back in time: a `now` earlier than one already seen is treated as the
   latest one seen.
3. Bytes leave at line rate: a byte takes `bits_per_byte / baud` seconds (10 bits: start, 8 data,
   stop) and starts only when the previous byte has finished (`PacedLine`).
4. Ground truth (`RotatorState`, the frame log and the motion events, kept by `Recorder`) is
   what tests assert on; it is never what the device would report over the wire (that one is
   noisy, rounded, maybe silent).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Protocol

#: Bits on the wire per byte for 8N1 framing: start bit, 8 data bits, stop bit.
BITS_PER_BYTE_8N1 = 10


@dataclass(frozen=True)
class LoggedFrame:
    """One complete command frame as the controller understood it."""

    time_s: float
    data: bytes
    outcome: str


@dataclass(frozen=True)
class MotionEvent:
    """Something the rotor did: "move", "arrived", "stopped", "brake set", "jammed", ..."""

    time_s: float
    kind: str
    az_deg: float
    detail: str = ""


@dataclass(frozen=True)
class RotatorState:
    """Ground truth of an emulated rotator at `time_s` (no jitter, no rounding)."""

    time_s: float
    az_deg: float
    is_moving: bool
    is_jammed: bool
    in_brake_delay: bool
    target_az_deg: float | None = None
    stored_target_az_deg: float | None = None
    brake_delay_ends_s: float | None = None
    driver: str | None = None
    options: Mapping[str, bool] = field(default_factory=dict)
    el_deg: float | None = None


class Responder(Protocol):
    """What the pty layer needs from a controller emulator (see rule 1)."""

    def receive(self, data: bytes, now: float) -> None: ...

    def due_output(self, now: float) -> bytes: ...

    def next_wakeup(self, now: float) -> float | None: ...

    def state(self, now: float) -> RotatorState: ...

    @property
    def log(self) -> list[LoggedFrame]: ...

    # Front panel and faults: every rotator controller has a power switch, some manual control,
    # a way to stop, and a motor that can stall.
    def power_cycle(self, now: float) -> None: ...

    def press_brake(self, now: float) -> bool: ...

    def manual_rotate(self, az_deg: float, now: float) -> None: ...

    def jam(self, now: float) -> None: ...

    def unjam(self, now: float) -> None: ...


class Recorder:
    """Rule 4: what a box keeps for tests, the frames it understood (with their outcomes) and
    what its rotor did; the box's own class fills ``_log`` and ``_events``."""

    _log: list[LoggedFrame]
    _events: list[MotionEvent]

    @property
    def log(self) -> list[LoggedFrame]:
        return self._log

    @property
    def events(self) -> list[MotionEvent]:
        return self._events

    def frames(self, *outcomes: str) -> list[LoggedFrame]:
        """Logged frames; only those with one of ``outcomes`` if any are named."""
        wanted = set(outcomes)
        return [f for f in self._log if not wanted or f.outcome in wanted]


class PacedLine:
    """A UART transmitter: queued bytes become due one byte time after another (rule 3)."""

    def __init__(
        self,
        baud: int,
        *,
        processing_delay_s: float = 0.0,
        bits_per_byte: int = BITS_PER_BYTE_8N1,
    ) -> None:
        if baud <= 0:
            raise ValueError(f"baud must be positive, got {baud}")
        if processing_delay_s < 0:
            raise ValueError(f"processing_delay_s must be >= 0, got {processing_delay_s}")
        self.byte_time_s: float = bits_per_byte / baud
        self.processing_delay_s: float = processing_delay_s
        self._queue: deque[tuple[float, int]] = deque()
        self._line_free_at_s: float = float("-inf")

    def send(self, data: bytes, now: float) -> float:
        """Queue `data`, composed at `now`; return when its last byte will have arrived."""
        start_s = max(now + self.processing_delay_s, self._line_free_at_s)
        due_s = start_s
        for value in data:
            due_s += self.byte_time_s
            self._queue.append((due_s, value))
        if data:
            self._line_free_at_s = due_s
        return due_s

    def due(self, now: float) -> bytes:
        """Pop every byte that has completely arrived by `now`."""
        out = bytearray()
        while self._queue and self._queue[0][0] <= now:
            out.append(self._queue.popleft()[1])
        return bytes(out)

    def next_due_s(self) -> float | None:
        return self._queue[0][0] if self._queue else None

    def pending(self) -> int:
        return len(self._queue)

    def clear(self) -> None:
        self._queue.clear()
        self._line_free_at_s = float("-inf")
