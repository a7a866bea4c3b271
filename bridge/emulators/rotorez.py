"""Rotor-EZ / RotorCard / DCU-1 controller emulator (sans-IO).

What the device is: a rotator control box on an RS-232 line at 4800 8N1. Three models share the
"Rotor-EZ protocol": the Idiom Press Rotor-EZ (board for Hy-Gain rotors, which have a brake and a
five-second brake delay), the Idiom Press RotorCard (board for Yaesu rotors: no brake, no delay,
calibration letters K/k) and the Hy-Gain DCU-1 (a subset; it never transmits anything).

Frame: plain ASCII, case-sensitive, no echo, no CR/LF in replies.
  `AP1xxx;`  store target xxx        `AP1xxx<CR>`  store and execute      `AM1;`  execute
  `AI1;` or `AI1<CR>`  ask bearing -> `;xxx` (4 bytes, no terminator)      `AS1;`  stop (DCU-1)
  single bytes outside a command: `;` stop, `V` version, `E/e J/j O/o S/s` options (Rotor-EZ),
  `K/k` calibration (RotorCard). An invalid command makes the Idiom boards print the 18-byte
  banner `C2000 IDIOM V1.4S ` (trailing space); `V` prints the same text.

Source documents (the emulator is written from these, never from bridge/protocols):
  Idiom Press "Rotor-EZ Rotator Control Protocol" (command table, FAQ, analog note),
  Idiom Press's 2003 command reference letter to Hamlib,
  Hamlib's README.rotorez (0xE0 at power-on, the banner),
  Hamlib 4.5.4's rotorez backend on the wire. Where the FAQ swaps `V` and `AI1;`, the table wins.

Rules:
1. Sans-IO: bytes in through receive(data, now), bytes out through due_output(now); the caller
   owns the clock and may ask next_wakeup(now) when something will next be due.
2. Replies leave at line rate (10 bits per byte at `baud`) after `processing_delay_s`, behind
   anything already being sent; a reply reflects the state when its frame completed.
3. A command frame starts at `A` and ends at `;` or CR; a seventh byte without a terminator makes
   it invalid. Outside a frame each byte is a command of its own; CR and LF there are ignored.
4. Bearings are exactly three ASCII digits 000..360. Anything else, and any command the model
   does not have, is an invalid command: the banner on Rotor-EZ/RotorCard, silence on a DCU-1.
   An invalid command never changes motion, options or the stored target.
5. A bearing command (`AP1xxx;`, `AP1xxx<CR>`, `AM1;`) while the rotor turns stops the rotor
   and is otherwise ignored (not stored, no new move). During the brake delay it is ignored.
6. The brake delay (`brake_delay_s`: 5 s Rotor-EZ and DCU-1, 0 RotorCard) follows every end of
   motion: arrival (timed from the exact arrival instant), stop, re-target stop, brake paddle,
   end of a manual move. A zero-length move turns nothing and starts no delay.
7. `;` while turning stops silently; `;` while idle (brake delay included) is invalid.
8. `AI1` answers `;xxx` with the position rounded half up, 360 reported as 000. While the
   potentiometer is still (idle, or jammed) successive answers alternate between two values
   `jitter_deg` apart, starting with the true rounded value; while it turns they follow it.
9. Option letters exist on the Rotor-EZ only, take effect at once, and power_cycle() resets them
   to the jumpers. Power-on (construction, power_cycle) emits one 0xE0 byte if power_on_junk.
10. The DCU-1 transmits nothing at all: no answer, no banner, no version, no power-on byte.
11. Every complete frame is logged once with its outcome (`Outcome`); motion is logged as
    `MotionEvent`s. These are the ground truth tests assert on.
12. The rotor turns inside its travel and never past its stop. With `stop_at_south` (a Hy-Gain
    rotor's, rotorez_models.py rule 4: the demo and the command line ask for the model's own) a
    target turns the way that does not cross south, and 180, which names both ends, goes to the
    end nearer the rotor; without it (the default, which the test suite's long turns from 0 were
    written for) the travel ends at north and a turn never crosses it. Bearings in and out
    (commands, readings, `state`, motion events, the panel) are compass bearings 0..360 either way.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from bridge.emulators.base import LoggedFrame, MotionEvent, PacedLine, Recorder, RotatorState
from bridge.emulators.physics import DRIVER_COMMAND, Axis
from bridge.emulators.rotorez_models import (
    BEARING_OUTCOMES,
    DEFAULT_JUMPERS,
    MAX_FRAME_BODY_BYTES,
    MODELS,
    OPTION_LETTERS,
    POWER_ON_JUNK,
    ModelSpec,
    Outcome,
)

__all__ = [
    "BEARING_OUTCOMES",
    "DEFAULT_JUMPERS",
    "MODELS",
    "ModelSpec",
    "Outcome",
    "RotorEZ",
]


def _parse_bearing(digits: bytes) -> int | None:
    if len(digits) != 3 or not all(0x30 <= b <= 0x39 for b in digits):
        return None
    value = int(digits)
    return value if value <= 360 else None


class RotorEZ(Recorder):
    """One Rotor-EZ-family controller with its rotor. See the module rules."""

    def __init__(
        self,
        model: str = "rotorez",
        *,
        speed_deg_s: float = 6.0,
        start_az_deg: float = 0.0,
        brake_delay_s: float | None = None,
        jitter_deg: int = 1,
        baud: int = 4800,
        version: str = "1.4S",
        jumpers: Mapping[str, bool] | None = None,
        power_on_junk: bool = True,
        processing_delay_s: float = 0.002,
        stop_at_south: bool = False,
        now: float = 0.0,
    ) -> None:
        if model not in MODELS:
            raise ValueError(f"unknown model {model!r}; known: {', '.join(sorted(MODELS))}")
        if jitter_deg < 0:
            raise ValueError(f"jitter_deg must be >= 0, got {jitter_deg}")
        if brake_delay_s is not None and brake_delay_s < 0:
            raise ValueError(f"brake_delay_s must be >= 0, got {brake_delay_s}")
        unknown = set(jumpers or {}) - set(DEFAULT_JUMPERS)
        if unknown:
            raise ValueError(f"unknown jumpers {sorted(unknown)}; known: {sorted(DEFAULT_JUMPERS)}")
        self.spec: ModelSpec = MODELS[model]
        self.brake_delay_s: float = (
            self.spec.brake_delay_s if brake_delay_s is None else float(brake_delay_s)
        )
        self.jitter_deg: int = int(jitter_deg)
        self.version: str = version
        self.banner: bytes = f"C2000 IDIOM V{version} ".encode("ascii")
        self.power_on_junk: bool = power_on_junk
        self.jumpers: dict[str, bool] = {**DEFAULT_JUMPERS, **(jumpers or {})}
        if not 0.0 <= start_az_deg <= 360.0:
            raise ValueError(f"start_az_deg must be within 0..360, got {start_az_deg}")
        self._south: bool = stop_at_south  # rule 12
        low = 180.0 if self._south else 0.0
        self._axis = Axis(
            self._travel(start_az_deg, low),
            min_deg=low,
            max_deg=low + 360.0,
            speed_deg_s=speed_deg_s,
            now=now,
        )
        self._tx = PacedLine(baud, processing_delay_s=processing_delay_s)
        self._now_s: float = now
        self._log: list[LoggedFrame] = []
        self._events: list[MotionEvent] = []
        self._rx = bytearray()
        self._options: dict[str, bool] = {}
        self._stored_target_deg: int | None = None
        self._brake_until_s: float | None = None
        self._jitter_phase: int = 0
        self.calibrating: bool = False
        self._power_on(now)

    # -- sans-IO surface ------------------------------------------------------------------------

    def receive(self, data: bytes, now: float) -> None:
        """Bytes from the host, all arrived at `now`."""
        now = self._update(now)
        for value in data:
            self._feed(value, now)

    def due_output(self, now: float) -> bytes:
        """Bytes that have completely arrived at the host by `now`."""
        self._update(now)
        return self._tx.due(now)

    def next_wakeup(self, now: float) -> float | None:
        """The next instant something happens by itself (a byte due, arrival, brake set)."""
        self._update(now)
        times = [self._tx.next_due_s(), self._axis.arrival_time_s(), self._brake_until_s]
        pending = [t for t in times if t is not None]
        return min(pending) if pending else None

    # -- ground truth ---------------------------------------------------------------------------

    def state(self, now: float) -> RotatorState:
        now = self._update(now)
        target = self._axis.target_deg
        return RotatorState(
            time_s=now,
            az_deg=self._bearing(self._axis.position_deg),
            is_moving=self._axis.is_moving,
            is_jammed=self._axis.is_jammed,
            in_brake_delay=self._brake_until_s is not None,
            target_az_deg=None if target is None else self._bearing(target),
            stored_target_az_deg=(
                None if self._stored_target_deg is None else float(self._stored_target_deg)
            ),
            brake_delay_ends_s=self._brake_until_s,
            driver=self._axis.driver,
            options=dict(self._options),
        )

    def true_az_deg(self, now: float) -> float:
        self._update(now)
        return self._bearing(self._axis.position_deg)

    def is_moving(self, now: float) -> bool:
        self._update(now)
        return self._axis.is_moving

    def in_brake_delay(self, now: float) -> bool:
        self._update(now)
        return self._brake_until_s is not None

    @property
    def options(self) -> dict[str, bool]:
        return dict(self._options)

    def bearing_frames_in_brake_delay(self) -> list[LoggedFrame]:
        """Bearing commands that arrived while the brake delay ran (a client should send none)."""
        return self.frames(Outcome.IGNORED_BRAKE_DELAY)

    # -- front panel and faults -----------------------------------------------------------------

    def press_brake(self, now: float) -> bool:
        """The brake paddle: halts a rotation and cancels it. True if something was turning."""
        now = self._update(now)
        return self._halt(now, "brake paddle")

    def manual_rotate(self, az_deg: float, now: float) -> None:
        """The pointing control: turn to `az_deg`, overriding (cancelling) a serial rotation."""
        if not 0.0 <= az_deg <= 360.0:
            raise ValueError(f"az_deg must be within 0..360, got {az_deg}")
        now = self._update(now)
        was_moving = self._axis.is_moving
        self._brake_until_s = None  # the brake comes off to turn
        if self._axis.manual_move(self._travel(az_deg, self._axis.position_deg), now):
            self._event(now, "move", f"panel to {az_deg:g}")
        elif was_moving:
            self._event(now, "stopped", "panel override")
            self._begin_brake_delay(now)

    def jam(self, now: float) -> None:
        """The rotor sticks: the motor may run, the position stays."""
        now = self._update(now)
        self._axis.jam(now)
        self._event(now, "jammed")

    def unjam(self, now: float) -> None:
        now = self._update(now)
        self._axis.unjam(now)
        self._event(now, "unjammed")

    def power_cycle(self, now: float) -> None:
        """Off and on again: motor off at once, options back to the jumpers, junk byte."""
        now = self._update(now)
        if self._axis.stop(now):
            self._event(now, "stopped", "power off")
        self._power_on(now)

    # -- internals ------------------------------------------------------------------------------

    def _power_on(self, now: float) -> None:
        self._brake_until_s = None
        self._stored_target_deg = None
        self._rx.clear()
        self._tx.clear()
        self._jitter_phase = 0
        self.calibrating = False
        self._options = dict(self.jumpers) if self.spec.has_options else {}
        self._event(now, "power on")
        if self.power_on_junk:
            self._send(POWER_ON_JUNK, now)

    def _update(self, now: float) -> float:
        now = max(now, self._now_s)
        self._now_s = now
        arrival_s = self._axis.advance(now)
        if arrival_s is not None:
            self._event(arrival_s, "arrived")
            self._begin_brake_delay(arrival_s)
        if self._brake_until_s is not None and now >= self._brake_until_s:
            self._event(self._brake_until_s, "brake set")
            self._brake_until_s = None
        return now

    def _event(self, time_s: float, kind: str, detail: str = "") -> None:
        position = self._bearing(self._axis.position_deg_at(time_s))
        self._events.append(MotionEvent(time_s, kind, position, detail))

    def _begin_brake_delay(self, time_s: float) -> None:
        if self.brake_delay_s > 0:
            self._brake_until_s = time_s + self.brake_delay_s

    def _halt(self, now: float, reason: str) -> bool:
        if not self._axis.stop(now):
            return False
        self._event(now, "stopped", reason)
        self._begin_brake_delay(now)
        return True

    def _send(self, data: bytes, now: float) -> None:
        if self.spec.transmits:
            self._tx.send(data, now)

    def _record(self, frame: bytes, outcome: Outcome, now: float) -> None:
        self._log.append(LoggedFrame(now, frame, outcome.value))

    def _feed(self, value: int, now: float) -> None:
        rx = self._rx
        if rx:
            rx.append(value)
            if value in (0x3B, 0x0D):  # ';' or CR ends the frame
                frame = bytes(rx)
                rx.clear()
                self._dispatch_frame(frame, now)
            elif len(rx) > MAX_FRAME_BODY_BYTES:
                frame = bytes(rx)
                rx.clear()
                self._invalid(frame, now)
            return
        if value == 0x41:  # 'A' opens a frame
            rx.append(value)
        elif value not in (0x0D, 0x0A):
            self._single(value, now)

    def _single(self, value: int, now: float) -> None:
        frame = bytes([value])
        spec = self.spec
        if value == 0x3B and spec.semicolon_stops:
            if self._halt(now, "serial stop"):
                self._record(frame, Outcome.STOP, now)
            else:
                self._invalid(frame, now)
        elif value == ord("V") and spec.has_version:
            self._send(self.banner, now)
            self._record(frame, Outcome.VERSION, now)
        elif value in OPTION_LETTERS and spec.has_options:
            name, enabled = OPTION_LETTERS[value]
            self._options[name] = enabled
            self._record(frame, Outcome.OPTION, now)
        elif value in (ord("K"), ord("k")) and spec.has_calibration:
            self.calibrating = value == ord("K")
            self._record(frame, Outcome.CALIBRATION, now)
        else:
            self._invalid(frame, now)

    def _dispatch_frame(self, frame: bytes, now: float) -> None:
        body, on_cr = frame[:-1], frame.endswith(b"\r")
        spec = self.spec
        if body == b"AI1" and spec.has_query:
            self._send(b";%03d" % self._reading_deg(), now)
            self._record(frame, Outcome.QUERY, now)
        elif body == b"AM1" and not on_cr:
            self._bearing_command(frame, None, now)
        elif body == b"AS1" and not on_cr and spec.as1_stops:
            self._halt(now, "serial stop")
            self._record(frame, Outcome.STOP, now)
        elif body.startswith(b"AP1") and (not on_cr or spec.executes_on_cr):
            target = _parse_bearing(body[3:])
            if target is None:
                self._invalid(frame, now)
            else:
                self._bearing_command(frame, (target, on_cr), now)
        else:
            self._invalid(frame, now)

    def _bearing_command(self, frame: bytes, bearing: tuple[int, bool] | None, now: float) -> None:
        """`bearing` is (target, execute) for AP1, None for AM1 (execute the stored target)."""
        if self._axis.is_moving:
            self._halt(now, "re-target while turning")
            self._record(frame, Outcome.IGNORED_RETARGET, now)
            return
        if self._brake_until_s is not None:
            self._record(frame, Outcome.IGNORED_BRAKE_DELAY, now)
            return
        if bearing is not None:
            self._stored_target_deg, execute = bearing
            if not execute:
                self._record(frame, Outcome.STORED, now)
                return
        if self._stored_target_deg is None:
            self._record(frame, Outcome.IGNORED_NO_TARGET, now)
            return
        to = self._travel(self._stored_target_deg, self._axis.position_deg)
        if self._axis.start_move(to, now, driver=DRIVER_COMMAND):
            self._jitter_phase = 0
            self._event(now, "move", f"to {self._stored_target_deg:03d}")
        self._record(frame, Outcome.EXECUTED, now)

    def _travel(self, bearing_deg: float, near_deg: float) -> float:
        """Rule 12: where on the rotor's travel a compass bearing is; on a Hy-Gain rotor, 180 is
        either end: the one nearer ``near_deg`` (a place on the travel)."""
        if not self._south:
            return bearing_deg
        if bearing_deg == 180.0:
            return 180.0 if near_deg < 360.0 else 540.0
        return bearing_deg if bearing_deg > 180.0 else bearing_deg + 360.0

    def _bearing(self, travel_deg: float) -> float:
        """Rule 12: the compass bearing of a place on the rotor's travel."""
        return travel_deg - 360.0 if self._south and travel_deg >= 360.0 else travel_deg

    def _invalid(self, frame: bytes, now: float) -> None:
        self._send(self.banner, now)
        self._record(frame, Outcome.INVALID, now)

    def _reading_deg(self) -> int:
        """The bearing as the controller reads its potentiometer (rule 8), its jitter inside the
        travel (at an end, towards the other: rule 12)."""
        axis = self._axis
        true_deg = math.floor(axis.position_deg + 0.5)  # (on the travel)
        still = not axis.is_moving or axis.is_jammed
        if not still or self.jitter_deg == 0:
            self._jitter_phase = 0
            return int(self._bearing(true_deg)) % 360
        other_deg = true_deg + self.jitter_deg
        if other_deg > axis.max_deg:
            other_deg = true_deg - self.jitter_deg
        reading = true_deg if self._jitter_phase == 0 else other_deg
        self._jitter_phase ^= 1
        return int(self._bearing(min(axis.max_deg, max(axis.min_deg, reading)))) % 360
