"""One open serial connection and its line discipline. Used only by its rotator's worker thread.

What it does: writes frames, keeps the controller's replies in order, decides when the line may
carry the next frame, polls, holds back junk until the line is quiet, and says when it next
needs the worker's attention. What it does not do: decide anything about motion or commands
(worker.py) or parse bytes (the model's codec).

Rules:
1. A reply is owed when the codec says so after a write; its deadline is the model's reply
   timeout. An owed reply that does not come is given up at its deadline (the worker decides).
   A slew's report (a controller silent while it moves) is owed until twice the travel time at
   the rotor's speeds plus SLEW_MARGIN_S; a stop written during the slew brings that deadline
   forward to one reply time: a stopped controller reports at once, or the stop was lost, or
   the slew had already ended (and its report was lost).
2. Silence is counted from the last valid reply, or from the end of a wait for a slew's report
   (a controller that was silent for a whole slew was not "not answering").
3. On a half-duplex line (``spec.full_duplex`` False) nothing is written while a reply is owed,
   except a stop on a controller that takes one at any time (``spec.stop_interrupts``).
4. A poll is sent only when due, when nothing is owed and no stop is waiting.
5. Junk is judged once the line has been quiet for JUNK_QUIET_S, so a banner paced byte by byte
   is judged whole (by the codec: it knows what its controller emits besides replies).
"""

from __future__ import annotations

import logging
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, replace

import serial

from bridge.model import Source
from bridge.protocols.base import Codec, ModelSpec

log = logging.getLogger(__name__)

JUNK_QUIET_S = 0.05
SLEW_TIME_FACTOR = 2.0  # a slew's report is waited for twice the travel time at the set speeds...
SLEW_MARGIN_S = 5.0  # ...plus this (relays, start-up, the report itself at 9600 baud)
_JUNK_KEEP = 4096  # a run of banners (a STOP pressed again and again on an idle Rotor-EZ) fits


@dataclass(frozen=True)
class Slew:
    """A move on a controller that is silent until it ends: what we know to estimate it."""

    start_t: float
    from_az_deg: float | None
    from_el_deg: float | None
    to_az_deg: float
    to_el_deg: float | None
    source: Source = Source.MQTT
    stops: int = 0  # stops written during the slew
    attempt: int = 1  # 2: the same target sent again after its report did not come

    def travel_s(
        self, az_speed_deg_s: float, el_speed_deg_s: float, az_span_deg: float, el_span_deg: float
    ) -> float:
        """How long the slew takes at these speeds: the slower axis decides. Where the start is
        unknown, the whole span; the azimuth travels linearly between its stops."""
        az_travel = _travel(self.from_az_deg, self.to_az_deg, az_span_deg)
        el_travel = _travel(self.from_el_deg, self.to_el_deg, el_span_deg)
        return max(az_travel / az_speed_deg_s, el_travel / el_speed_deg_s)

    def estimate(
        self, now: float, az_speed_deg_s: float, el_speed_deg_s: float
    ) -> tuple[float | None, float | None]:
        """Where the rotor should be, in whole degrees, moving at the nominal speeds."""
        dt = now - self.start_t
        return (
            _toward(self.from_az_deg, self.to_az_deg, az_speed_deg_s * dt),
            _toward(self.from_el_deg, self.to_el_deg, el_speed_deg_s * dt),
        )


def _travel(start: float | None, end: float | None, span: float) -> float:
    if end is None:
        return 0.0
    return span if start is None else abs(end - start)


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
        self.quiet_from_t = now  # silence counts from here when no reply came since
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
            self.reply_deadline = self._clock() + self.spec.reply_timeout_s

    def write_stop(self, now: float) -> None:
        """Write the stop. During a slew the report now comes within one reply time, or the
        stop was lost, or the controller had already stopped (the worker decides)."""
        self.outbox.clear()
        self.write(self.codec.encode_stop())
        if self.slew is not None:
            self.slew = replace(self.slew, stops=self.slew.stops + 1)
            self.reply_deadline = now + self.spec.reply_timeout_s

    def begin_slew(self, slew: Slew, travel_s: float) -> None:
        """The target just sent starts a slew expected to take ``travel_s``: its report is owed
        until twice that, plus SLEW_MARGIN_S."""
        self.slew = slew
        self.reply_deadline = slew.start_t + SLEW_TIME_FACTOR * travel_s + SLEW_MARGIN_S

    def send(self, frames: list[bytes], now: float) -> None:
        """The first frame now, the rest spaced by the model's inter-frame gap (all now if
        there is none: a stop that came between them would cancel the second alone)."""
        self.write(frames[0])
        for i, frame in enumerate(frames[1:], start=1):
            self.outbox.append((now + i * self.spec.inter_frame_gap_s, frame))
        self.flush_outbox(now)

    def flush_outbox(self, now: float) -> None:
        while self.outbox and self.outbox[0][0] <= now:
            self.write(self.outbox.popleft()[1])

    def free(self, for_stop: bool = False) -> bool:
        if self.spec.full_duplex or self.reply_deadline is None:
            return True
        return for_stop and self.spec.stop_interrupts

    # -- replies ------------------------------------------------------------------------------
    def reply_overdue(self, now: float) -> bool:
        return self.reply_deadline is not None and now >= self.reply_deadline

    def give_up_reply(self, now: float) -> None:
        """Stop waiting for the owed reply (and for a slew's report: the slew is over)."""
        self.codec.expire_query()
        self.reply_deadline = None
        self.end_slew(now)

    def end_slew(self, now: float) -> bool:
        """The slew (if any) is over without a reading: silence counts from now (rule 2).
        True if there was one."""
        if self.slew is None:
            return False
        self.slew = None
        self.quiet_from_t = now
        return True

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
        heard = self.last_reply_t if self.last_reply_t is not None else self.quiet_from_t
        return now - max(heard, self.quiet_from_t)

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
