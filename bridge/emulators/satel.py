"""SatEL Az-El controller emulator (VE5FP-compatible, Hamlib model 2101), sans-IO.

What the device is: a microprocessor box driving an azimuth rotor (0..360, break at north) and an
elevation rotor (0..90) through relays, on RS-232 at 9600 8N1. It keeps a clock and up to 50
stored time/position points, and moves to them by itself when automatic motion is enabled.

Frame: ASCII, no echo, letters in upper or lower case. Single bytes: `?` identify -> `SatEL`;
`z` status (the 7-line report); `g` enable automatic motion; `s` stop the rotors and disable
automatic motion; `*` reset (= power cycle); `x` clear the memory; `u`/`d`/`r`/`l` jog el
up/down, az clockwise/counter-clockwise; `c` calibrate (a no-op on the SatEL); `cx` (lower case
only) setup calibration. Lines (`p` point, `t` clock, a stored point) are ended by CR or LF. How
bytes become commands and lines, the line forms, the report layout and the controller clock are
in satel_frames.py (pure), the two rotors and their slew in satel_rotors.py; this module decides.

Source documents (written from these, never from bridge/protocols):
  Hamlib 4.5.4's satel backend (satel.c and its author's notes, its traffic seen with rotctl),
  the SatEL Az-EL instruction manual, Appendix A and pages 12 and 15 (manualshive.com): 50
  stored points, excess lost; stored points and `p` do nothing while automatic motion is
  disabled; `*` = power cycle; the az/el values live in EEPROM.
Rotor speeds are not documented: by default az 8 deg/s, el 4 deg/s, so that a full slew (45 s,
22.5 s) fits inside Hamlib's 60 s read timeout, which its author sized to wait out a slew.

Rules:
1. Sans-IO, like rotorez.py: bytes in through receive(data, now), out through due_output(now),
   paced at line rate (base.PacedLine) after `processing_delay_s`. `now` never goes back.
2. A slew is a move started by `p` or by a stored point. While one runs the controller takes
   only `s` (stop) and `*` (reset), plus the one LF that follows the CR ending its `p` line.
   Every other byte is logged alone as "misuse: input while slewing" and dropped; with
   corrupt_on_misuse the first one also wedges the controller (rule 7). Jogs (u/d/r/l) are not
   slews: they run until told otherwise, so the controller listens during them.
3. `p` while automatic motion is disabled is ignored (manual). Otherwise both axes slew at their
   own speeds; when the last one arrives the status report is printed, composed at the exact
   arrival instant. A `p` to where the rotors already are reports at once. Values beyond the
   stops are clamped (the controller checks nothing; the rotors end at the stop).
4. `s` during a `p` slew ends it where the rotors are; the move routine then prints its report
   (showing Motion DISABLED) unless report_on_stop=False. Moves driven by stored points end
   silently. A reset ends any slew without a report.
5. Reset (`*`, power_cycle): rotors stop, automatic motion off, corruption cleared, half-typed
   line and unsent output dropped, clock back to its power-on reading `2001/00/00 00:00:00`
   (Hamlib's example), stored points forgotten (assumed RAM; unverified). The position stays
   (EEPROM). `*` is allowed during a slew: Hamlib uses it as its stop.
6. Stored points are kept in time order, at most `memory_limit`. When the controller clock
   reaches one (and no slew runs) it is consumed; if several are due only the latest counts. It
   moves the rotors only if automatic motion is enabled.
7. Corruption (corrupt_on_misuse=True, first misuse): the slew halts where it is, no report
   follows, automatic motion is off and `g`/`p` are ignored ("ignored: corrupted state") until
   a reset. Stored points are consumed without moving anything.
8. Unknown bytes and malformed lines (satel_frames.py rules 2 and 6) are logged "invalid" and
   get no reply.
9. The trailing empty lines leave at line rate too, so a reader that stops after 7 lines and
   flushes (Hamlib) may find them in front of its next reply: Hamlib 4.5.4 running `P az el p`
   in one session then reads 0.00 now and then (measured ~1 run in 10). That is the device as
   documented, kept on purpose; trailing_blank_lines=0 takes the race away.
10. step_deg: the rotors stop only at multiples of it: a `p` (or stored point) between them goes
   down to the one below (the manual: ``P0 34`` "would move to ... an elevation of 30 degrees
   because it moves in ten degree steps"; its one example cannot tell down from nearest, and
   `cx` drives each axis down to a 10-degree point). 1, the default, is every degree; the
   device as built (``as_built``) is 10.
"""

from __future__ import annotations

from bridge.emulators.base import LoggedFrame, MotionEvent, PacedLine, Recorder
from bridge.emulators.physics import DRIVER_COMMAND
from bridge.emulators.satel_frames import (
    MEMORY_LIMIT,
    ClockRead,
    ClockSet,
    ControllerClock,
    Framer,
    Outcome,
    PointLine,
    SatelState,
    StoredPoint,
    Token,
    parse_line,
    status_report,
)
from bridge.emulators.satel_rotors import Rotors

__all__ = ["MEMORY_LIMIT", "Outcome", "SatEL", "SatelState", "StoredPoint"]

DRIVER_EPHEMERIS = "ephemeris"
DRIVER_JOG = "jog"
_JOGS = {"u": ("el", 90.0), "d": ("el", 0.0), "r": ("az", 360.0), "l": ("az", 0.0)}


class SatEL(Recorder):
    """One SatEL controller with its two rotors. See the module rules."""

    def __init__(
        self,
        *,
        az_speed_deg_s: float = 8.0,
        el_speed_deg_s: float = 4.0,
        start_az_deg: float = 0.0,
        start_el_deg: float = 0.0,
        baud: int = 9600,
        line_ending: bytes = b"\r\n",
        corrupt_on_misuse: bool = False,
        report_on_stop: bool = True,
        trailing_blank_lines: int = 2,
        memory_limit: int = MEMORY_LIMIT,
        processing_delay_s: float = 0.002,
        step_deg: int = 1,
        now: float = 0.0,
    ) -> None:
        if step_deg < 1:
            raise ValueError(f"step_deg must be >= 1, got {step_deg}")
        if line_ending not in (b"\r\n", b"\n"):
            raise ValueError(f"line_ending must be b'\\r\\n' or b'\\n', got {line_ending!r}")
        if trailing_blank_lines < 0:
            raise ValueError(f"trailing_blank_lines must be >= 0, got {trailing_blank_lines}")
        if memory_limit < 0:
            raise ValueError(f"memory_limit must be >= 0, got {memory_limit}")
        self.line_ending: bytes = line_ending
        self.corrupt_on_misuse: bool = corrupt_on_misuse
        self.report_on_stop: bool = report_on_stop
        self.trailing_blank_lines: int = trailing_blank_lines
        self.memory_limit: int = memory_limit
        self._rotors = Rotors(start_az_deg, start_el_deg, az_speed_deg_s, el_speed_deg_s, now)
        self._step_deg = step_deg  # rule 10
        self._tx = PacedLine(baud, processing_delay_s=processing_delay_s)
        self._clock = ControllerClock(now)
        self._now_s: float = now
        self._log: list[LoggedFrame] = []
        self._events: list[MotionEvent] = []
        self._framer = Framer()
        self._motion_enabled = False
        self._corrupted = False
        self._memory: list[StoredPoint] = []
        self._event(now, "power on")

    # -- sans-IO surface ------------------------------------------------------------------------

    def receive(self, data: bytes, now: float) -> None:
        """Bytes from the host, all arrived at `now`."""
        now = self._update(now)
        for value in data:
            self._feed(value, now)

    def due_output(self, now: float) -> bytes:
        self._update(now)
        return self._tx.due(now)

    def next_wakeup(self, now: float) -> float | None:
        """The next instant something happens by itself (a byte due, a slew end, a point due)."""
        self._update(now)
        times = [self._tx.next_due_s(), self._next_internal_s()]
        pending = [t for t in times if t is not None]
        return min(pending) if pending else None

    # -- ground truth ---------------------------------------------------------------------------

    def state(self, now: float) -> SatelState:
        now = self._update(now)
        az, el, slew = self._rotors.az, self._rotors.el, self._rotors.slew
        flags = {
            "motion_enabled": self._motion_enabled,
            "slewing": slew is not None,
            "corrupted": self._corrupted,
        }
        return SatelState(
            time_s=now,
            az_deg=az.position_deg,
            el_deg=el.position_deg,
            is_moving=az.is_moving or el.is_moving,
            is_jammed=az.is_jammed or el.is_jammed,
            in_brake_delay=False,
            target_az_deg=slew.az_deg if slew else az.target_deg,
            target_el_deg=slew.el_deg if slew else el.target_deg,
            driver=az.driver or el.driver,
            options=flags,
            controller_time=self._clock.text(now),
            stored_points=tuple(self._memory),
            misuse_count=len(self.frames(Outcome.MISUSE)),
            **flags,
        )

    def misuse_frames(self) -> list[LoggedFrame]:
        """Bytes that arrived while the controller slewed (a client should send none)."""
        return self.frames(Outcome.MISUSE)

    # -- front panel and faults -----------------------------------------------------------------

    def power_cycle(self, now: float) -> None:
        self._reset(self._update(now), "power off")

    def press_brake(self, now: float) -> bool:
        """No brake on a SatEL: the box's stop acts like `s`. True if something was turning."""
        now = self._update(now)
        return self._stop(now, "panel stop")

    def manual_rotate(self, az_deg: float, now: float, *, el_deg: float | None = None) -> None:
        """Turn the rotors by hand (panel driver); a slew in progress ends as if stopped."""
        if not 0.0 <= az_deg <= 360.0 or (el_deg is not None and not 0.0 <= el_deg <= 90.0):
            raise ValueError(f"manual_rotate outside 0..360 / 0..90: {az_deg}, {el_deg}")
        now = self._update(now)
        if self._rotors.slew is not None:
            self._end_slew(now, "panel override", report=self.report_on_stop)
        self._rotors.az.manual_move(az_deg, now)
        if el_deg is not None:
            self._rotors.el.manual_move(el_deg, now)
        self._event(now, "move", f"panel to az {az_deg:g}, el {el_deg}")

    def jam(self, now: float) -> None:
        """Both rotors stick: motors may run, positions stay, a slew never ends."""
        now = self._update(now)
        self._rotors.jam(now)
        self._event(now, "jammed")

    def unjam(self, now: float) -> None:
        now = self._update(now)
        self._rotors.unjam(now)
        self._event(now, "unjammed")

    # -- time -----------------------------------------------------------------------------------

    def _next_internal_s(self) -> float | None:
        """The next slew end, or (when no slew runs) the next stored point due."""
        if self._rotors.slew is not None:
            return self._rotors.slew_end_s(self._now_s)
        if self._memory:
            return self._clock.instant_s(self._memory[0].when)
        return None

    def _update(self, now: float) -> float:
        """Play every internal event up to `now` in time order (rule 1)."""
        now = max(now, self._now_s)
        while (due_s := self._next_internal_s()) is not None and due_s <= now:
            at_s = max(due_s, self._now_s)
            self._advance_axes(at_s)
            self._now_s = at_s
            if self._rotors.slew is not None:
                self._end_slew(at_s, "arrived", report=True)
            else:
                self._fire_points(at_s)
        self._advance_axes(now)
        self._now_s = now
        return now

    def _advance_axes(self, now: float) -> None:
        for name in self._rotors.advance(now):
            if self._rotors.slew is None:
                self._event(now, "arrived", name)

    def _fire_points(self, now: float) -> None:
        due = [p for p in self._memory if self._clock.instant_s(p.when) <= now]
        del self._memory[: len(due)]
        point = due[-1]
        if self._motion_enabled:
            self._start_slew(DRIVER_EPHEMERIS, point.az_deg, point.el_deg, now)
        else:
            self._event(now, "point skipped", f"motion disabled: {point}")

    # -- motion ---------------------------------------------------------------------------------

    def _start_slew(self, kind: str, az_deg: float, el_deg: float, now: float) -> None:
        step = self._step_deg  # rule 10: down to a step
        if step > 1:
            az_deg, el_deg = az_deg // step * step, el_deg // step * step
        slew = self._rotors.start_slew(kind, az_deg, el_deg, now)
        self._event(now, "move", f"{kind} to {slew.az_deg:g} {slew.el_deg:g}")
        if not self._rotors.is_moving:
            self._end_slew(now, "arrived", report=True)

    def _end_slew(self, now: float, reason: str, *, report: bool) -> None:
        slew = self._rotors.end_slew(now)
        self._event(now, "stopped" if reason != "arrived" else reason, reason)
        if slew is not None and slew.kind == DRIVER_COMMAND and report:
            self._send(self._status_block(now), now)

    def _stop(self, now: float, reason: str) -> bool:
        """`s`: rotors stop (a `p` slew reports, rule 4), automatic motion is disabled."""
        self._motion_enabled = False
        if self._rotors.slew is not None:
            self._end_slew(now, reason, report=self.report_on_stop)
            return True
        stopped = self._rotors.stop(now)
        if stopped:
            self._event(now, "stopped", reason)
        return stopped

    def _reset(self, now: float, reason: str) -> None:
        if self._rotors.slew is not None:
            self._end_slew(now, reason, report=False)
        if self._rotors.stop(now):
            self._event(now, "stopped", reason)
        self._motion_enabled = self._corrupted = False
        self._framer.reset()
        self._tx.clear()
        self._clock.reset(now)
        self._memory.clear()
        self._event(now, "power on")

    # -- input ----------------------------------------------------------------------------------

    def _feed(self, value: int, now: float) -> None:
        token, data = self._framer.take(value, self._rotors.slew is not None)
        if token is Token.SINGLE:
            self._single(value, chr(value).lower() if value < 0x80 else "", now)
        elif token is Token.LINE:
            self._dispatch_line(data, now)
        elif token is Token.MISUSE:  # rule 2: only a stop or a reset gets through a slew
            self._misuse(value, now)
        elif token is Token.CX:
            self._log.append(LoggedFrame(now, data, Outcome.IGNORED_CX.value))

    def _single(self, value: int, letter: str, now: float) -> None:
        outcome = Outcome.INVALID
        if letter == "?":
            self._send_line(b"SatEL", now)
            outcome = Outcome.IDENTIFY
        elif letter == "z":
            self._send(self._status_block(now), now)
            outcome = Outcome.STATUS
        elif letter == "g":
            outcome = Outcome.IGNORED_CORRUPTED if self._corrupted else Outcome.MOTION_ENABLED
            self._motion_enabled = not self._corrupted
        elif letter == "s":
            self._stop(now, "serial stop")
            outcome = Outcome.STOP
        elif letter == "*":
            self._reset(now, "reset")
            outcome = Outcome.RESET
        elif letter == "x":
            self._memory.clear()
            outcome = Outcome.MEMORY_CLEARED
        elif letter in _JOGS:
            axis_name, end_deg = _JOGS[letter]
            axis = self._rotors.az if axis_name == "az" else self._rotors.el
            axis.start_move(end_deg, now, driver=DRIVER_JOG)
            self._event(now, "move", f"jog {letter}")
            outcome = Outcome.JOG
        elif letter == "c":
            outcome = Outcome.CALIBRATE
        self._record(value, outcome, now)

    def _dispatch_line(self, line: bytes, now: float) -> None:
        parsed = parse_line(line[:-1])
        outcome = Outcome.INVALID
        if isinstance(parsed, PointLine):
            if self._corrupted:
                outcome = Outcome.IGNORED_CORRUPTED
            elif not self._motion_enabled:
                outcome = Outcome.IGNORED_MOTION_DISABLED
            else:
                outcome = Outcome.SLEW
                self._start_slew(DRIVER_COMMAND, parsed.az_deg, parsed.el_deg, now)
        elif isinstance(parsed, ClockRead):
            self._send_line(self._clock.text(now).encode("ascii"), now)
            outcome = Outcome.TIME_READ
        elif isinstance(parsed, ClockSet):
            self._clock.set(parsed.when, now)
            outcome = Outcome.TIME_SET
        elif isinstance(parsed, StoredPoint):
            if len(self._memory) >= self.memory_limit:
                outcome = Outcome.IGNORED_MEMORY_FULL
            else:
                self._memory.append(parsed)
                self._memory.sort(key=lambda p: p.when)
                outcome = Outcome.POINT_STORED
        self._log.append(LoggedFrame(now, line, outcome.value))

    def _misuse(self, value: int, now: float) -> None:
        self._record(value, Outcome.MISUSE, now)
        if self.corrupt_on_misuse and not self._corrupted:
            self._corrupted = True
            self._motion_enabled = False
            self._end_slew(now, "corrupted by misuse", report=False)

    # -- output ---------------------------------------------------------------------------------

    def _status_block(self, now: float) -> bytes:
        az_deg, el_deg = self._rotors.positions_deg_at(now)
        return status_report(
            motion_enabled=self._motion_enabled,
            clock_text=self._clock.text(now),
            az_deg=az_deg,
            el_deg=el_deg,
            stored_points=len(self._memory),
            trailing_blank_lines=self.trailing_blank_lines,
            line_ending=self.line_ending,
        )

    def _send_line(self, text: bytes, now: float) -> None:
        self._send(text + self.line_ending, now)

    def _send(self, data: bytes, now: float) -> None:
        self._tx.send(data, now)

    def _record(self, value: int, outcome: Outcome, now: float) -> None:
        self._log.append(LoggedFrame(now, bytes([value]), outcome.value))

    def _event(self, time_s: float, kind: str, detail: str = "") -> None:
        az, el = self._rotors.positions_deg_at(time_s)
        self._events.append(MotionEvent(time_s, kind, az, f"{detail} el={el:g}".strip()))
