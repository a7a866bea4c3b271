"""Prosistel D and Combi-Track rotator controller emulator, sans-IO.

What the device is: Prosistel's controllers. A D box drives one rotor in whole degrees, as unit
A (an azimuth rotor, 0..360) or unit E (an elevation rotor, 0..90), or, set up as an azimuth box
on an elevation rotor, as unit A in 0..90; a Combi-Track drives an azimuth rotor as unit A and
an elevation rotor as unit B, in tenths of a degree. Each rotor has a brake the box sets when
the motor stops. A new bearing while turning is taken at once.

Frame: STX (0x02), the unit's letter, the command's letter, its value, CR. Every command is
answered by STX, the unit, the command and what it says, comma-separated, and CR:
  ``STX u ? CR``      position: ``STX u,?,nnn,s CR`` (D: three digits; Combi-Track: four,
                      tenths), s ``R`` while the motor runs, ``B`` when it is braked
  ``STX u G n CR``    turn to n (leading zeros optional), answered ``STX u,G,s CR``; n 997 (the
                      soft stop) or 999 (the hard stop) stops instead; on the Combi-Track 9777
                      and 9999
  ``STX u S CR``      continuous position output off, answered ``STX u,S,s CR``
A unit the box has not got is answered ``STX u,c,E,00003 CR``; a command it cannot carry out (an
unknown letter, a value out of range or not a number) ``STX u,c,E,00001 CR``. Bytes outside a
frame are ignored; an STX starts a frame afresh.

Source documents (written from these, never from bridge/protocols): the project's protocol
sheet (Prosistel's commands as gathered there) and Hamlib 4.5.4's prosistel backend (models
1701, 1702, 1703 and 1704 "D elevation CBOX az": the commands it sends, the unit letters, the
stop values, the answers quoted in its comments: ``A,?,290,R``, ``A,?,1000,R``, ``B,?,0900,R``,
``B,?,E,00003``) and its traffic seen with rotctl. Hamlib reads only the unit and the command
letter of an answer to ``G`` and ``S``: what follows them, and the error code 00001, are this
emulator's choice.

Rules:
1. Sans-IO: bytes in through receive(data, now), out through due_output(now), paced at line
   rate after `processing_delay_s` (base.PacedLine); `now` never goes back. An answer shows the
   rotor at the instant its command's CR arrived.
2. Variants are data (MODELS): the units, the scale (1 or 10 to the degree), the stop values.
3. `streaming` boxes send every unit's position line, unasked, every `stream_interval_s` from
   power-on until that unit's ``S``; a power cycle starts it again.
4. The hard stop stops the motor at once. The soft stop does too, unless `soft_stop_s` is set
   (the box's PWM ramps on): then the rotor goes on for that long before it stops.
5. Every complete frame is logged once with its Outcome; motion is logged as MotionEvents.
   power_cycle() stops the motors, drops a half-received frame and anything not yet sent; the
   rotors stay where they are.
"""

from __future__ import annotations

import enum
import math
import re
from dataclasses import dataclass

from bridge.emulators.base import LoggedFrame, MotionEvent, PacedLine, RotatorState
from bridge.emulators.physics import DRIVER_COMMAND, Axis
from bridge.emulators.twoaxes import TwoAxes

__all__ = ["MODELS", "Outcome", "Prosistel", "ProsistelModel", "ProsistelState"]

STX, CR = 0x02, 0x0D
AZ_TOP_DEG = 360.0
EL_TOP_DEG = 90.0
NO_SUCH_UNIT = b"E,00003"
CANNOT = b"E,00001"
_MAX_FRAME = 16
_G = re.compile(rb"G(\d{1,5})")


class Outcome(enum.StrEnum):
    MOVE = "move"  # G taken
    QUERY = "query"  # ? answered
    STOP = "stop"  # G997 / G999 (Combi-Track G9777 / G9999)
    OUTPUT_OFF = "output off"  # S
    REFUSED = "refused"  # answered with an error


@dataclass(frozen=True)
class ProsistelModel:
    name: str
    units: dict[str, str]  # unit letter -> "az" or "el"
    scale: int  # 1: whole degrees; 10: tenths
    soft_stop: int
    hard_stop: int


MODELS: dict[str, ProsistelModel] = {
    "prosistel": ProsistelModel("prosistel", {"A": "az"}, 1, 997, 999),
    "prosistel-el": ProsistelModel("prosistel-el", {"E": "el"}, 1, 997, 999),
    "prosistel-el-a": ProsistelModel("prosistel-el-a", {"A": "el"}, 1, 997, 999),
    "prosistel-combi": ProsistelModel("prosistel-combi", {"A": "az", "B": "el"}, 10, 9777, 9999),
}


@dataclass(frozen=True)
class ProsistelState(RotatorState):
    """RotatorState plus what only this box has."""

    target_el_deg: float | None = None
    streaming: tuple[str, ...] = ()  # the units sending their position unasked


class Prosistel(TwoAxes):
    """One Prosistel box with its rotor(s). See the module rules."""

    def __init__(
        self,
        model: str = "prosistel",
        *,
        baud: int = 9600,
        az_speed_deg_s: float = 6.0,
        el_speed_deg_s: float = 3.0,
        start_az_deg: float = 0.0,
        start_el_deg: float = 0.0,
        streaming: bool = False,
        stream_interval_s: float = 0.25,
        soft_stop_s: float = 0.0,
        processing_delay_s: float = 0.002,
        now: float = 0.0,
    ) -> None:
        if model not in MODELS:
            raise ValueError(f"unknown model {model!r}; known: {', '.join(sorted(MODELS))}")
        if stream_interval_s <= 0 or soft_stop_s < 0:
            raise ValueError("stream_interval_s must be > 0 and soft_stop_s >= 0")
        self.spec = MODELS[model]
        axes = set(self.spec.units.values())
        if ("az" not in axes and start_az_deg) or ("el" not in axes and start_el_deg):
            raise ValueError(f"{model} has no rotor to start there")
        self._az = Axis(start_az_deg, max_deg=AZ_TOP_DEG, speed_deg_s=az_speed_deg_s, now=now)
        self._el = Axis(start_el_deg, max_deg=EL_TOP_DEG, speed_deg_s=el_speed_deg_s, now=now)
        self.baud = int(baud)
        self._tx = PacedLine(self.baud, processing_delay_s=processing_delay_s)
        self._now_s = now
        self._rx: bytearray | None = None  # a frame since its STX
        self._log: list[LoggedFrame] = []
        self._events: list[MotionEvent] = []
        self.name, self.has_elevation = self.spec.name, "el" in axes  # (TwoAxes)
        self.stream_at_power_on = streaming
        self.stream_interval_s = float(stream_interval_s)
        self.soft_stop_s = float(soft_stop_s)
        self._streaming: set[str] = set()
        self._next_stream_s = math.inf
        self._start_streaming(now)
        self._event(now, "power on")

    # -- sans-IO surface ------------------------------------------------------------------------

    def receive(self, data: bytes, now: float) -> None:
        now = self._update(now)
        for value in data:
            if value == STX:
                self._rx = bytearray()  # a frame starts afresh
            elif self._rx is None:
                continue  # outside a frame
            elif value == CR:
                frame, self._rx = bytes(self._rx), None
                self._frame(frame, now)
            else:
                self._rx.append(value)
                if len(self._rx) > _MAX_FRAME:
                    frame, self._rx = bytes(self._rx), None
                    self._log.append(LoggedFrame(now, b"\x02" + frame, Outcome.REFUSED.value))

    def due_output(self, now: float) -> bytes:
        self._stream(self._update(now))
        return super().due_output(now)

    def next_wakeup(self, now: float) -> float | None:
        self._stream(self._update(now))
        times = [super().next_wakeup(now), self._next_stream_s if self._streaming else None]
        pending = [t for t in times if t is not None]
        return min(pending) if pending else None

    # -- ground truth ---------------------------------------------------------------------------

    def state(self, now: float) -> ProsistelState:
        now = self._update(now)
        return ProsistelState(**self._truth(now), streaming=tuple(sorted(self._streaming)))

    # -- front panel and faults -----------------------------------------------------------------

    @property
    def transmitting(self) -> bool:
        """Whether bytes are still to go out (a power cycle now would cut a frame short)."""
        return self._tx.pending() > 0

    def power_cycle(self, now: float) -> None:
        now = self._update(now)
        self._halt(now, "power off")
        self._rx = None
        self._tx.clear()
        self._start_streaming(now)
        self._event(now, "power on")

    # -- internals ------------------------------------------------------------------------------

    def _start_streaming(self, now: float) -> None:
        """Rule 3."""
        self._streaming = set(self.spec.units) if self.stream_at_power_on else set()
        self._next_stream_s = now + self.stream_interval_s

    def _stream(self, now: float) -> None:
        while self._streaming and self._next_stream_s <= now:
            t = self._next_stream_s
            for unit in sorted(self._streaming):
                self._tx.send(self._position(unit, t), t)
            self._next_stream_s = t + self.stream_interval_s

    def _axis(self, unit: str) -> Axis:
        return self._az if self.spec.units[unit] == "az" else self._el

    def _status(self, unit: str, now: float) -> bytes:
        axis = self._axis(unit)
        axis.advance(now)
        return b"R" if axis.is_moving else b"B"

    def _position(self, unit: str, now: float) -> bytes:
        value = round(self._axis(unit).position_deg_at(now) * self.spec.scale)
        digits = 4 if self.spec.scale == 10 else 3
        reading = b"%0*d" % (digits, value)
        return b"\x02%s,?,%s,%s\r" % (unit.encode(), reading, self._status(unit, now))

    def _frame(self, frame: bytes, now: float) -> None:
        unit, command = frame[:1].decode("latin-1"), frame[1:]
        head = b"\x02" + frame[:1] + b"," + command[:1] + b","
        if unit not in self.spec.units:
            outcome, answer = Outcome.REFUSED, head + NO_SUCH_UNIT + b"\r"
        elif command == b"?":
            outcome, answer = Outcome.QUERY, self._position(unit, now)
        elif command == b"S":
            self._streaming.discard(unit)
            outcome, answer = Outcome.OUTPUT_OFF, head + self._status(unit, now) + b"\r"
        elif (m := _G.fullmatch(command)) is not None and self._go(unit, int(m[1]), now):
            stop = int(m[1]) in (self.spec.soft_stop, self.spec.hard_stop)
            outcome = Outcome.STOP if stop else Outcome.MOVE
            answer = head + self._status(unit, now) + b"\r"
        else:
            outcome, answer = Outcome.REFUSED, head + CANNOT + b"\r"
        self._tx.send(answer, now)
        self._log.append(LoggedFrame(now, b"\x02" + frame + b"\r", outcome.value))

    def _go(self, unit: str, value: int, now: float) -> bool:
        """A ``G``: a stop or a bearing; False if it is neither (rule 4)."""
        axis, name = self._axis(unit), self.spec.units[unit]
        if value == self.spec.hard_stop or (value == self.spec.soft_stop and not self.soft_stop_s):
            self._halt(now, f"serial G{value}", name)
            return True
        if value == self.spec.soft_stop:  # the PWM ramp: on for a while, then stopped
            target = axis.target_deg
            if target is not None:
                on = math.copysign(axis.speed_deg_s * self.soft_stop_s, target - axis.position_deg)
                if abs(on) < abs(target - axis.position_deg):
                    axis.start_move(axis.position_deg + on, now)
            return True
        deg = value / self.spec.scale
        if deg > axis.max_deg:
            return False
        if axis.start_move(deg, now, driver=DRIVER_COMMAND):
            self._event(now, "move", f"{name} to {deg:g}")
        return True
