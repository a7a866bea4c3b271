"""SPID Rot2Prog / Rot1Prog / MD-01/02 (ROT2 mode) controller emulator (sans-IO).

What the device is: an Alfa/SPID rotator controller on a serial line, 8N1, driving an azimuth and
(except the Rot1Prog) an elevation motor at the same time. Rot2Prog 600 baud, Rot1Prog 1200 baud,
MD-01/02 at a configurable rate (spid_models.py).

Frame: every command is 13 bytes `57 H1 H2 H3 H4 PH V1 V2 V3 V4 PV K 20`, K = 0x0F stop,
0x1F status, 0x2F set, 0x14 move (MD-01/02). Set digits are ASCII: az = H/PH - 360 (Rot2Prog,
MD-01; PH is the controller's own resolution, the command's PH/PV bytes are ignored) or, on a
Rot1Prog, az = 100*H1 + 10*H2 + H3 - 360 with H4 = ASCII '0'. Replies carry RAW digits 0..9:
`57 H1 H2 H3 H4 PH V1 V2 V3 V4 PV 20` in tenths + 360 (12 bytes) or `57 H1 H2 H3 20` in whole
degrees + 360 (Rot1Prog, 5 bytes). MD-01 debug lines are `<digits>: <text>\r\n`.

Source documents (the emulator is written from these, never from bridge/protocols):
  Hamlib 4.5.4's spid backend (spid.c, spid.txt) and its traffic seen with rotctl,
  the rot2prog package's PyPI page (frame tables, resolution table, examples).

Rules:
1. Sans-IO: bytes in through receive(data, now), bytes out through due_output(now); the caller
   owns the clock. Replies leave at line rate behind anything already queued (base.PacedLine)
   and reflect the state at the instant their command frame completed.
2. Framing resynchronises: a frame starts at 0x57 and is taken when its 13th byte is 0x20. If the
   13th byte is anything else, only the leading 0x57 is dropped and the other twelve bytes are
   scanned again, so junk of any content before a frame never costs that frame. Bytes outside a
   frame are junk; each run of junk is logged as one "invalid" frame when the next 0x57 arrives
   or when the run reaches 13 bytes. (The real Rot2Prog reads 13 bytes blindly; a client's stray
   byte would then shift every later frame, which helps no test.)
3. Status (0x1F) and stop (0x0F) answer the position on every model; set (0x2F) answers nothing
   on a Rot2Prog/Rot1Prog and the position (before the new move starts) on an MD-01/02; move
   (0x14) answers nothing. Bytes other than S, K, END of status/stop frames are ignored.
4. A set with a non-ASCII digit in a field the model reads (H1..H4 and V1..V4; Rot1Prog H1..H3,
   and H4 must be ASCII '0') is invalid and changes nothing. Any other K is invalid; invalid
   frames get no reply (as the rot2prog simulator does).
5. A set target beyond the mechanical limits is clamped to the limit (the motor runs to the limit
   switch, physics.Axis rule 2) and logged "set: clamped"; Hamlib and the PyPI client never send
   one, so seeing that outcome means the client skipped its own range check.
6. Az and el move together at `az_speed_deg_s` / `el_speed_deg_s`. A set while moving re-targets
   at once (SPID has no brake-delay rule). Stop halts both axes and reports the exact position
   (with `coast_deg`, rule 11, the position at the instant the stop came).
7. Move (MD-01/02, H1 = direction bits 0x01 left, 0x02 right, 0x04 up, 0x08 down, combinations
   of one az and one el bit allowed) runs the named axes towards their limits until a stop or a
   new set; an axis not named stops (the controller replaces its motion; Hamlib 4.6 ORs the
   running direction in for that reason). H2..H4, PH, V1..V4, PV are ignored (Hamlib leaves PH/PV
   uninitialised). Zero, contradictory or unknown direction bits are invalid.
8. Reported angles are the true angle rounded to the resolution grid (nearest pulse), then
   written in tenths rounded down (0.25 deg steps: 123.25 reads 123.2, as the rot2prog
   simulator does); PH = PV = the configured resolution, never 0. Rot1Prog: nearest degree.
9. MD-01/02 debug lines (`debug_lines="before"|"after"`, or emit_debug_line()) are queued on the
   same paced line, so they fall between frames, never inside one. The digits are milliseconds
   since power-on.
10. Every complete frame (and every junk run) is logged once with its Outcome; motion is logged as
    MotionEvents. power_cycle() stops the motors, drops a half-received frame and anything not
    yet transmitted; the rotor stays where it is.
11. Coasting (`coast_deg`, default 0: stops dead): spid.txt says the stop reply is the current
    position, "often off by a degree or two", because the rotor is still coming to rest. With
    coast_deg > 0 an axis whose motor is cut while turning (a serial stop, the panel stop, a
    move that leaves the axis out, power off) runs on up to coast_deg further the way it was
    turning, never past a limit, decelerating to rest in `coast_s` (physics.Axis rule 6). The
    stop reply carries the position at the instant the stop frame completed; status replies
    during the coast show it going on; truth's is_moving is True until it rests ("coasted"
    event). A set or a move during a coast starts from where the rotor is then. Both axes use
    the same coast_deg (a stop of a jammed axis does not coast).
"""

from __future__ import annotations

from dataclasses import dataclass

from bridge.emulators.base import LoggedFrame, MotionEvent, PacedLine, Recorder, RotatorState
from bridge.emulators.physics import DRIVER_COMMAND, Axis
from bridge.emulators.spid_models import (
    COMMAND_BYTES,
    DEBUG_LINE_MODES,
    DIR_DOWN,
    DIR_LEFT,
    DIR_RIGHT,
    DIR_UP,
    END,
    K_MOVE,
    K_SET,
    K_STATUS,
    K_STOP,
    MAX_ENCODABLE_DEG,
    MIN_ENCODABLE_DEG,
    MODELS,
    MOTION_OUTCOMES,
    START,
    ModelSpec,
    Outcome,
    decode_reply,
    position_reply,
    set_targets,
)

__all__ = ["MODELS", "MOTION_OUTCOMES", "ModelSpec", "Outcome", "Spid", "SpidState"]


@dataclass(frozen=True)
class SpidState(RotatorState):
    """RotatorState plus what only a two-axis controller has."""

    target_el_deg: float | None = None
    resolution_ppd: int = 1


class Spid(Recorder):
    """One SPID controller with its az/el rotator. See the module rules."""

    def __init__(
        self,
        model: str = "rot2prog",
        *,
        resolution_ppd: int | None = None,
        baud: int | None = None,
        az_speed_deg_s: float = 1.0,
        el_speed_deg_s: float = 0.5,
        start_az_deg: float = 0.0,
        start_el_deg: float = 0.0,
        az_min_deg: float | None = None,
        az_max_deg: float | None = None,
        el_min_deg: float | None = None,
        el_max_deg: float | None = None,
        debug_lines: str = "off",
        coast_deg: float = 0.0,
        coast_s: float = 0.8,
        processing_delay_s: float = 0.002,
        now: float = 0.0,
    ) -> None:
        if model not in MODELS:
            raise ValueError(f"unknown model {model!r}; known: {', '.join(sorted(MODELS))}")
        spec = MODELS[model]
        ppd = spec.default_resolution_ppd if resolution_ppd is None else resolution_ppd
        if ppd not in spec.resolutions_ppd:
            raise ValueError(f"{model} resolution_ppd must be one of {spec.resolutions_ppd}")
        if debug_lines not in DEBUG_LINE_MODES:
            raise ValueError(f"debug_lines must be one of {DEBUG_LINE_MODES}, got {debug_lines!r}")
        if not (coast_deg >= 0 and coast_s > 0):
            raise ValueError(f"coast_deg must be >= 0 and coast_s > 0, got {coast_deg}, {coast_s}")
        if debug_lines != "off" and not spec.has_debug_lines:
            raise ValueError(f"{model} prints no debug lines (only the MD-01/02 does)")
        az_min = spec.az_min_deg if az_min_deg is None else float(az_min_deg)
        az_max = spec.az_max_deg if az_max_deg is None else float(az_max_deg)
        limits = [az_min, az_max]
        if spec.has_elevation:
            el_min = spec.el_min_deg if el_min_deg is None else float(el_min_deg)
            el_max = spec.el_max_deg if el_max_deg is None else float(el_max_deg)
            limits += [el_min, el_max]
        elif (el_min_deg, el_max_deg, start_el_deg) != (None, None, 0.0):
            raise ValueError(f"{model} has no elevation axis")
        if not all(MIN_ENCODABLE_DEG <= v <= MAX_ENCODABLE_DEG for v in limits):
            raise ValueError(
                f"limits must lie within {MIN_ENCODABLE_DEG:g}..{MAX_ENCODABLE_DEG:g} deg"
                " (what the frames can carry)"
            )
        self.spec: ModelSpec = spec
        self.resolution_ppd: int = ppd
        self.debug_lines: str = debug_lines
        self.coast_deg: float = float(coast_deg)
        self.coast_s: float = float(coast_s)
        self._az = Axis(
            start_az_deg, min_deg=az_min, max_deg=az_max, speed_deg_s=az_speed_deg_s, now=now
        )
        self._el: Axis | None = None
        if spec.has_elevation:
            self._el = Axis(
                start_el_deg, min_deg=el_min, max_deg=el_max, speed_deg_s=el_speed_deg_s, now=now
            )
        self.baud: int = spec.baud if baud is None else int(baud)
        self._tx = PacedLine(self.baud, processing_delay_s=processing_delay_s)
        self._now_s: float = now
        self._powered_on_s: float = now
        self._log: list[LoggedFrame] = []
        self._events: list[MotionEvent] = []
        self._rx = bytearray()
        self._junk = bytearray()
        self._event(now, "power on")

    # -- sans-IO surface ------------------------------------------------------------------------

    def receive(self, data: bytes, now: float) -> None:
        """Bytes from the host, all arrived at `now` (rule 2 for the framing)."""
        now = self._update(now)
        queue = bytearray(data)
        i = 0
        while i < len(queue):
            value = queue[i]
            i += 1
            rx = self._rx
            if not rx:
                if value == START:
                    self._flush_junk(now)
                    rx.append(value)
                else:
                    self._junk.append(value)
                    if len(self._junk) >= COMMAND_BYTES:
                        self._flush_junk(now)
                continue
            rx.append(value)
            if len(rx) < COMMAND_BYTES:
                continue
            frame = bytes(rx)
            rx.clear()
            if frame[-1] == END:
                self._dispatch(frame, now)
            else:  # not a frame start after all: keep its W as junk, rescan the rest
                self._junk.append(frame[0])
                queue[i:i] = frame[1:]

    def due_output(self, now: float) -> bytes:
        """Bytes that have completely arrived at the host by `now`."""
        self._update(now)
        return self._tx.due(now)

    def next_wakeup(self, now: float) -> float | None:
        """The next instant something happens by itself (a byte due, an axis arriving)."""
        self._update(now)
        times = [self._tx.next_due_s()]
        for axis in self._axes():
            times += [axis.arrival_time_s(), axis.coast_end_s()]
        pending = [t for t in times if t is not None]
        return min(pending) if pending else None

    # -- ground truth ---------------------------------------------------------------------------

    def state(self, now: float) -> SpidState:
        now = self._update(now)
        el = self._el
        drivers = [axis.driver for axis in self._axes() if axis.driver is not None]
        return SpidState(
            time_s=now,
            az_deg=self._az.position_deg,
            el_deg=None if el is None else el.position_deg,
            is_moving=any(axis.is_moving or axis.is_coasting for axis in self._axes()),
            is_jammed=any(axis.is_jammed for axis in self._axes()),
            in_brake_delay=False,
            target_az_deg=self._az.target_deg,
            target_el_deg=None if el is None else el.target_deg,
            driver=drivers[0] if drivers else None,
            resolution_ppd=self.resolution_ppd,
        )

    def reported_position(self, now: float) -> tuple[float, float | None]:
        """What a status reply sent at `now` would say, decoded (rule 8)."""
        self._update(now)
        return decode_reply(self.spec, self._position_frame())

    # -- front panel, faults, debug output ------------------------------------------------------

    def press_brake(self, now: float) -> bool:
        """The front-panel stop: halt both axes. True if something was turning."""
        now = self._update(now)
        return self._halt(now, "panel stop")

    def manual_rotate(self, az_deg: float, now: float, *, el_deg: float | None = None) -> None:
        """The front panel's pointing control: move to az (and el, if given)."""
        now = self._update(now)
        wanted = [(self._az, az_deg, "az")]
        if el_deg is not None:
            if self._el is None:
                raise ValueError(f"{self.spec.name} has no elevation axis")
            wanted.append((self._el, el_deg, "el"))
        for axis, target, name in wanted:
            if not axis.min_deg <= target <= axis.max_deg:
                raise ValueError(f"{name} {target} outside {axis.min_deg:g}..{axis.max_deg:g}")
        for axis, target, name in wanted:
            if axis.manual_move(target, now):
                self._event(now, "move", f"panel {name} to {target:g}")

    def jam(self, now: float) -> None:
        """Both axes stick: motors may run, positions stay."""
        now = self._update(now)
        for axis in self._axes():
            axis.jam(now)
        self._event(now, "jammed")

    def unjam(self, now: float) -> None:
        now = self._update(now)
        for axis in self._axes():
            axis.unjam(now)
        self._event(now, "unjammed")

    def power_cycle(self, now: float) -> None:
        """Off and on again (rule 10)."""
        now = self._update(now)
        self._halt(now, "power off")
        self._rx.clear()
        self._junk.clear()
        self._tx.clear()
        self._powered_on_s = now
        self._event(now, "power on")

    def emit_debug_line(self, now: float, text: str = "debug") -> bytes:
        """Queue one MD-01 debug line now (rule 9); return its bytes."""
        if not self.spec.has_debug_lines:
            raise ValueError(f"{self.spec.name} prints no debug lines (only the MD-01/02 does)")
        if "\r" in text or "\n" in text or not text.isascii():
            raise ValueError("a debug line's text must be ASCII without CR or LF")
        now = self._update(now)
        millis = int((now - self._powered_on_s) * 1000)
        line = f"{millis}: {text}\r\n".encode("ascii")
        self._tx.send(line, now)
        return line

    # -- internals ------------------------------------------------------------------------------

    def _axes(self) -> list[Axis]:
        return [self._az] if self._el is None else [self._az, self._el]

    def _update(self, now: float) -> float:
        now = max(now, self._now_s)
        self._now_s = now
        for axis, name in ((self._az, "az"), (self._el, "el")):
            if axis is not None:
                coast_end_s = axis.coast_end_s()
                arrival_s = axis.advance(now)
                if arrival_s is not None:
                    self._event(arrival_s, "arrived", f"{name} at {axis.position_deg:g}")
                if coast_end_s is not None and not axis.is_coasting:
                    self._event(coast_end_s, "coasted", f"{name} at rest at {axis.position_deg:g}")
        return now

    def _event(self, time_s: float, kind: str, detail: str = "") -> None:
        self._events.append(MotionEvent(time_s, kind, self._az.position_deg_at(time_s), detail))

    def _stop_axis(self, axis: Axis, now: float) -> bool:
        """Cut one axis's motor, coasting as rule 11 says; True if it was running."""
        return axis.stop(now, coast_deg=self.coast_deg, coast_s=self.coast_s)

    def _halt(self, now: float, reason: str) -> bool:
        stopped = [self._stop_axis(axis, now) for axis in self._axes()]
        if any(stopped):
            self._event(now, "stopped", reason)
        return any(stopped)

    def _flush_junk(self, now: float) -> None:
        if self._junk:
            self._log.append(LoggedFrame(now, bytes(self._junk), Outcome.INVALID.value))
            self._junk.clear()

    def _dispatch(self, frame: bytes, now: float) -> None:
        command = frame[11]
        position: bytes | None = None  # the reply, composed when the frame completed (rule 1)
        if command == K_STATUS:
            outcome, position = Outcome.STATUS, self._position_frame()
        elif command == K_STOP:
            self._halt(now, "serial stop")
            outcome, position = Outcome.STOP, self._position_frame()
        elif command == K_SET:
            targets = set_targets(self.spec, frame, self.resolution_ppd)
            if targets is None:
                outcome = Outcome.INVALID
            else:
                if self.spec.replies_to_set:  # the position before the new move starts
                    position = self._position_frame()
                outcome = self._set(targets, now)
        elif command == K_MOVE and self.spec.has_move:
            outcome = self._move(frame[1], now)
        else:
            outcome = Outcome.INVALID
        if self.debug_lines == "before":
            self.emit_debug_line(now, f"cmd {outcome.value}")
        if position is not None:
            self._tx.send(position, now)
        if self.debug_lines == "after":
            self.emit_debug_line(now, f"cmd {outcome.value}")
        self._log.append(LoggedFrame(now, frame, outcome.value))

    def _set(self, targets: tuple[float, float | None], now: float) -> Outcome:
        clamped = False
        for axis, target, name in ((self._az, targets[0], "az"), (self._el, targets[1], "el")):
            if axis is None or target is None:
                continue
            clamped |= axis.clamp(target) != target
            if axis.start_move(target, now, driver=DRIVER_COMMAND):
                self._event(now, "move", f"{name} to {axis.target_deg:g} (asked {target:g})")
        return Outcome.SET_CLAMPED if clamped else Outcome.SET

    def _move(self, direction: int, now: float) -> Outcome:
        az_bits, el_bits = direction & (DIR_LEFT | DIR_RIGHT), direction & (DIR_UP | DIR_DOWN)
        if direction == 0 or direction > 0x0F or az_bits == 0x03 or el_bits == 0x0C:
            return Outcome.INVALID
        if el_bits and self._el is None:
            return Outcome.INVALID
        plan = [(self._az, az_bits, DIR_LEFT, "az")]
        if self._el is not None:
            plan.append((self._el, el_bits, DIR_DOWN, "el"))
        for axis, bits, down_bit, name in plan:
            if not bits:
                if self._stop_axis(axis, now):
                    self._event(now, "stopped", f"{name}: not in the move direction")
                continue
            limit_deg = axis.min_deg if bits == down_bit else axis.max_deg
            if axis.start_move(limit_deg, now, driver=DRIVER_COMMAND):
                self._event(now, "move", f"{name} towards {limit_deg:g} until stop")
        return Outcome.MOVE

    def _position_frame(self) -> bytes:
        el_deg = 0.0 if self._el is None else self._el.position_deg
        return position_reply(self.spec, self._az.position_deg, el_deg, self.resolution_ppd)
