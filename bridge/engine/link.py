"""One open serial connection and its line discipline. Used only by its rotator's worker thread.

What it does: writes frames, keeps the controller's replies in order, decides when the line may
carry the next frame, polls, holds back junk until the line is quiet, and says when it next
needs the worker's attention. What it does not do: decide anything about motion or commands
(worker.py) or parse bytes (the model's codec).

Rules:
1. A reply is owed when the codec says so after a write; its deadline is the codec's reply
   timeout for what was sent. An owed reply that does not come is given up at its deadline.
2. On a half-duplex line (``spec.full_duplex`` False) nothing is written while a reply is owed,
   except a stop on a controller that takes one at any time (``spec.stop_interrupts``).
3. A poll is sent only when due, when nothing is owed and no stop is waiting.
4. Junk is judged once the line has been quiet for JUNK_QUIET_S, so a banner paced byte by byte
   is judged whole (by the codec: it knows what its controller emits besides replies).
"""

from __future__ import annotations

import logging
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

import serial

from bridge.protocols.base import Codec, ModelSpec

log = logging.getLogger(__name__)

JUNK_QUIET_S = 0.05
_JUNK_KEEP = 4096  # a run of banners (a STOP pressed again and again on an idle Rotor-EZ) fits


@dataclass(frozen=True)
class Slew:
    """A move on a controller that is silent until it ends: what we know to estimate it."""

    start_t: float
    from_az_deg: float | None
    from_el_deg: float | None
    to_az_deg: float
    to_el_deg: float | None

    def estimate(
        self, now: float, az_speed_deg_s: float, el_speed_deg_s: float
    ) -> tuple[float | None, float | None]:
        """Where the rotor should be, in whole degrees, moving at the nominal speeds."""
        dt = now - self.start_t
        return (
            _toward(self.from_az_deg, self.to_az_deg, az_speed_deg_s * dt),
            _toward(self.from_el_deg, self.to_el_deg, el_speed_deg_s * dt),
        )


def _toward(start: float | None, end: float | None, step: float) -> float | None:
    if start is None or end is None:
        return end
    if abs(end - start) <= step:
        return end
    return float(round(start + step * (1 if end > start else -1)))


class Link:
    def __init__(
        self,
        port: serial.Serial,
        codec: Codec,
        spec: ModelSpec,
        now: float,
        clock: Callable[[], float],
        name: str,
    ) -> None:
        self.port = port
        self.codec = codec
        self.spec = spec
        self.opened_t = now
        self._clock = clock
        self._name = name
        self.reply_deadline: float | None = None
        self.next_poll = now
        self.last_reply_t: float | None = None
        self.answering = False
        self.silence_reported = False
        self.stop_due = False
        self.options_due: set[str] = set()
        self.options_sent_t = 0.0
        self.outbox: deque[tuple[float, bytes]] = deque()
        self.slew: Slew | None = None
        self.enable_due = False
        self._junk = bytearray()
        self._junk_t = 0.0

    # -- writing ----------------------------------------------------------------------------
    def write(self, frame: bytes) -> None:
        self.port.write(frame)
        log.debug("%s: -> %r", self._name, frame)
        if self.reply_deadline is None and self.codec.awaiting_reply():
            timeout_s = self.codec.reply_timeout_s(self.spec.reply_timeout_s)
            self.reply_deadline = self._clock() + timeout_s

    def send(self, frames: list[bytes], now: float) -> None:
        """The first frame now, the rest spaced by the model's inter-frame gap."""
        self.write(frames[0])
        for i, frame in enumerate(frames[1:], start=1):
            self.outbox.append((now + i * self.spec.inter_frame_gap_s, frame))

    def flush_outbox(self, now: float) -> None:
        while self.outbox and self.outbox[0][0] <= now:
            self.write(self.outbox.popleft()[1])

    def free(self, for_stop: bool = False) -> bool:
        if self.spec.full_duplex or self.reply_deadline is None:
            return True
        return for_stop and self.spec.stop_interrupts

    # -- replies ------------------------------------------------------------------------------
    def expire_reply(self, now: float) -> bool:
        """Give up an owed reply whose deadline passed; True if one was given up."""
        if self.reply_deadline is not None and now >= self.reply_deadline:
            self.codec.expire_query()
            self.reply_deadline = None
            return True
        return False

    def got_reading(self, now: float) -> None:
        if not self.codec.awaiting_reply():
            self.reply_deadline = None
        self.last_reply_t = now

    def ask_again(self, now: float) -> None:
        """The reply was not usable: close it and poll at once."""
        self.codec.expire_query()
        self.reply_deadline = None
        self.next_poll = now

    def poll(self, now: float, interval_s: float) -> None:
        if self.reply_deadline is not None or self.stop_due or now < self.next_poll:
            return
        query = self.codec.encode_query()
        if query:
            self.write(query)
            self.next_poll = now + interval_s

    def silent_for(self, now: float) -> float:
        return now - (self.last_reply_t if self.last_reply_t is not None else self.opened_t)

    # -- junk ---------------------------------------------------------------------------------
    def add_junk(self, data: bytes, now: float) -> None:
        if len(self._junk) < _JUNK_KEEP:
            self._junk += data[: _JUNK_KEEP - len(self._junk)]
        self._junk_t = now

    def quiet_junk(self, now: float) -> tuple[bytes, bool] | None:
        """Junk held back until the line went quiet, and whether the codec calls it harmless."""
        if not self._junk or now - self._junk_t < JUNK_QUIET_S:
            return None
        data, self._junk = bytes(self._junk), bytearray()
        return data, self.codec.harmless(data)

    # -- scheduling ---------------------------------------------------------------------------
    def wakeups(self) -> list[float]:
        times: list[float] = []
        if self.outbox:
            times.append(self.outbox[0][0])
        if self._junk:
            times.append(self._junk_t + JUNK_QUIET_S)
        if self.spec.can_report_position:
            times.append(self.reply_deadline or self.next_poll)
        return times
