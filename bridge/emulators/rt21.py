"""Green Heron RT-21 rotator controller emulator (one box, one rotor: azimuth), sans-IO.

What the device is: Green Heron's digital controller for one rotor (Hy-Gain, Yaesu and others),
0..360 degrees, read and set in tenths. An az/el system is two boxes on two serial ports. It
takes a new heading while turning and handles its rotor's brake and ramps by itself.

Frame: plain ASCII at 4800 8N1, a superset of the Hy-Gain DCU-1's commands. A command starts
with a letter and ends at ``;``; inside a set command a CR executes it at once.
  ``AP1ddd.d<CR>;``  turn to ddd.d now          ``AP1ddd;`` / ``AP1ddd.d;``  store a heading
  ``AM1;``           turn to the stored heading ``AS1;`` or ``;`` alone       stop
  ``BI1;``           bearing in tenths, ``reply_padding`` "space" (the default) as Hamlib
                     describes the box: ``20.0;`` as seen on the wire, `` 5.0;`` padded to
                     four characters, ``123.4;``; "none": ``5.0;``; "zero": ``005.0;`` as the
                     protocol sheet writes it
  ``AI1;``           bearing in whole degrees: ``;020``
Outside a command CR, LF and spaces are ignored. Nothing else is answered: an unknown or
malformed command, or a heading outside 0..360, is dropped and moves nothing.

Source documents (written from these, never from bridge/protocols): the project's protocol
sheet (Green Heron's command set as gathered there) and Hamlib 4.5.4's rotorez backend (model
405) with its traffic on the wire as users posted it in Hamlib's issues 1257-1259.

Rules:
1. Sans-IO: bytes in through receive(data, now), out through due_output(now), paced at line
   rate after `processing_delay_s` (base.PacedLine); `now` never goes back. A reply shows the
   rotor at the instant its command's ``;`` arrived.
2. ``AP1...<CR>`` starts the move at the CR; the ``;`` that follows only closes the command (it
   is not a stop); any other byte after the CR closes it too and is read afresh (a client that
   sends the Rotor-EZ's ``AP1ddd<CR>`` alone). A command longer than 16 bytes without its ``;``
   is dropped as malformed.
3. A new heading while turning re-targets at once (the box ramps and reverses by itself).
4. Every complete command is logged once with its Outcome; motion is logged as MotionEvents.
   power_cycle() stops the motor, drops a half-received command, anything not yet sent and the
   stored heading; the rotor stays where it is.
"""

from __future__ import annotations

import enum
import re

from bridge.emulators.base import LoggedFrame, MotionEvent, PacedLine, Recorder, RotatorState
from bridge.emulators.physics import DRIVER_COMMAND, Axis

__all__ = ["PADDINGS", "Outcome", "Rt21"]

TOP_DEG = 360.0
PADDINGS = ("none", "space", "zero")
_MAX_COMMAND = 16
_HEADING = re.compile(rb"AP1(\d{3}(?:\.\d)?)")


class Outcome(enum.StrEnum):
    MOVE = "move"  # AP1..<CR>; or AM1; taken
    STORE = "store"  # AP1..; without CR: heading stored
    QUERY = "query"  # BI1; AI1; answered
    STOP = "stop"  # ; or AS1;
    REFUSED = "refused"  # unknown, malformed or out of range: dropped silently


class Rt21(Recorder):
    """One RT-21 box with its rotor. See the module rules."""

    def __init__(
        self,
        *,
        baud: int = 4800,
        az_speed_deg_s: float = 6.0,
        start_az_deg: float = 0.0,
        reply_padding: str = "space",
        processing_delay_s: float = 0.002,
        now: float = 0.0,
    ) -> None:
        if reply_padding not in PADDINGS:
            raise ValueError(f"reply_padding must be one of {', '.join(PADDINGS)}")
        self.reply_padding = reply_padding
        self._az = Axis(start_az_deg, max_deg=TOP_DEG, speed_deg_s=az_speed_deg_s, now=now)
        self.baud = int(baud)
        self._tx = PacedLine(self.baud, processing_delay_s=processing_delay_s)
        self._now_s = now
        self._rx = bytearray()
        self._executed = False  # the command in _rx was run by its CR (rule 2)
        self._stored: float | None = None
        self._log: list[LoggedFrame] = []
        self._events: list[MotionEvent] = []
        self._event(now, "power on")

    # -- sans-IO surface ------------------------------------------------------------------------

    def receive(self, data: bytes, now: float) -> None:
        now = self._update(now)
        for value in data:
            byte = bytes((value,))
            if self._executed and byte != b";":  # rule 2: a CR-run command without its ;
                self._close(now)
            if not self._rx:
                if byte == b";":
                    self._halt(now, "serial ;")
                    self._log.append(LoggedFrame(now, byte, Outcome.STOP.value))
                elif byte.isalpha():
                    self._rx += byte
                continue  # CR, LF, spaces and stray bytes between commands
            if byte == b";":
                self._close(now, b";")
                continue
            if byte == b"\r":
                self._executed = True
                self._execute(bytes(self._rx), now)
                continue
            self._rx += byte
            if len(self._rx) > _MAX_COMMAND:  # rule 2
                self._log.append(LoggedFrame(now, bytes(self._rx), Outcome.REFUSED.value))
                self._rx, self._executed = bytearray(), False

    def _close(self, now: float, end: bytes = b"") -> None:
        command, self._rx = bytes(self._rx), bytearray()
        executed, self._executed = self._executed, False
        self._command(command, executed, end, now)

    def due_output(self, now: float) -> bytes:
        self._update(now)
        return self._tx.due(now)

    def next_wakeup(self, now: float) -> float | None:
        self._update(now)
        times = [self._tx.next_due_s(), self._az.arrival_time_s()]
        pending = [t for t in times if t is not None]
        return min(pending) if pending else None

    # -- ground truth ---------------------------------------------------------------------------

    def state(self, now: float) -> RotatorState:
        now = self._update(now)
        return RotatorState(
            time_s=now,
            az_deg=self._az.position_deg,
            is_moving=self._az.is_moving,
            is_jammed=self._az.is_jammed,
            in_brake_delay=False,
            target_az_deg=self._az.target_deg,
            stored_target_az_deg=self._stored,
            driver=self._az.driver,
        )

    # -- front panel and faults -----------------------------------------------------------------

    def power_cycle(self, now: float) -> None:
        now = self._update(now)
        self._halt(now, "power off")
        self._rx.clear()
        self._executed = False
        self._stored = None
        self._tx.clear()
        self._event(now, "power on")

    def press_brake(self, now: float) -> bool:
        """The front panel's stop."""
        return self._halt(self._update(now), "panel stop")

    def manual_rotate(self, az_deg: float, now: float) -> None:
        now = self._update(now)
        if not 0.0 <= az_deg <= TOP_DEG:
            raise ValueError(f"az {az_deg} outside 0..{TOP_DEG:g}")
        if self._az.manual_move(az_deg, now):
            self._event(now, "move", f"panel to {az_deg:g}")

    def jam(self, now: float) -> None:
        now = self._update(now)
        self._az.jam(now)
        self._event(now, "jammed")

    def unjam(self, now: float) -> None:
        now = self._update(now)
        self._az.unjam(now)
        self._event(now, "unjammed")

    # -- internals ------------------------------------------------------------------------------

    def _update(self, now: float) -> float:
        now = max(now, self._now_s)
        self._now_s = now
        arrival_s = self._az.advance(now)
        if arrival_s is not None:
            self._event(arrival_s, "arrived", f"at {self._az.position_deg:g}")
        return now

    def _event(self, time_s: float, kind: str, detail: str = "") -> None:
        self._events.append(MotionEvent(time_s, kind, self._az.position_deg_at(time_s), detail))

    def _halt(self, now: float, reason: str) -> bool:
        stopped = self._az.stop(now)
        if stopped:
            self._event(now, "stopped", reason)
        return stopped

    @staticmethod
    def _heading(command: bytes) -> float | None:
        m = _HEADING.fullmatch(command)
        if m is None or float(m.group(1)) > TOP_DEG:
            return None
        return float(m.group(1))

    def _execute(self, command: bytes, now: float) -> None:
        """A CR inside a command: an ``AP1`` heading runs now; anything else waits for its ``;``
        to be judged (and is then refused)."""
        heading = self._heading(command)
        if heading is not None:
            self._move(heading, now)

    def _move(self, heading: float, now: float) -> None:
        if self._az.start_move(heading, now, driver=DRIVER_COMMAND):  # rule 3
            self._event(now, "move", f"to {heading:g}")

    def _command(self, command: bytes, executed: bool, end: bytes, now: float) -> None:
        outcome = self._dispatch(command, executed, now)
        shown = command + (b"\r" if executed else b"") + end
        self._log.append(LoggedFrame(now, shown, outcome.value))

    def _dispatch(self, command: bytes, executed: bool, now: float) -> Outcome:
        heading = self._heading(command)
        if heading is not None:
            if executed:
                return Outcome.MOVE  # already moving since its CR
            self._stored = heading
            return Outcome.STORE
        if executed:
            return Outcome.REFUSED
        if command == b"AM1" and self._stored is not None:
            self._move(self._stored, now)
            return Outcome.MOVE
        if command == b"AS1":
            self._halt(now, "serial AS1;")
            return Outcome.STOP
        if command in (b"BI1", b"AI1"):
            self._tx.send(self._reading(command), now)
            return Outcome.QUERY
        return Outcome.REFUSED

    def _reading(self, command: bytes) -> bytes:
        if command == b"AI1":
            return b";%03d" % int(self._az.position_deg + 0.5)
        tenths = int(self._az.position_deg * 10 + 0.5)
        text = b"%d.%d" % divmod(tenths, 10)
        if self.reply_padding == "space":
            text = text.rjust(4)
        elif self.reply_padding == "zero":
            text = text.rjust(5, b"0")
        return text + b";"
