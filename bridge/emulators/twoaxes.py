"""What an emulated box with an azimuth and an elevation axis (and no brake) does with them,
whatever its protocol: the panel, a jam, time passing, a stop, its lines in (gs232.py,
easycomm.py, rc2800.py, prosistel.py); the frame log is base.Recorder's.

Rules:
1. Time only goes forward (``_update``): each axis advances to ``now`` and an arrival is an
   event at the moment it happened, not when it was noticed.
2. Turning by hand (``manual_rotate``) takes the box's whole range: azimuth 0..``az_top_deg``,
   elevation 0..``el_top_deg`` on a box with an elevation rotor; anything else is a ValueError.
3. A stop (``_halt``) stops the axes it names and is one event, if anything was moving.
4. A line protocol's commands (``_lines``: GS-232, Easycomm, RC2800) come as lines ended by CR
   or LF; lines of nothing but spaces are no command.
5. At power-on (``_build``) the box is its model's variant (an unknown model, a line ending
   other than CR, LF, CR LF or LF CR, or an elevation start on a box without one is a ValueError),
   both axes at their start, nothing on the line. An elevation started below 0 (a pot set a
   little below the horizon: Easycomm and RC2800 boxes read so) can turn back down to it.
6. A line the box sends on its own (``transmit``: an Easycomm III box's ``VE`` lines) goes on
   the line behind what it is sending already, as a UART sends it: never inside a reply (the
   pty's ``inject`` writes at once, the junk of a broken line).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from typing import Any

from bridge.emulators.base import MotionEvent, PacedLine, Recorder
from bridge.emulators.physics import Axis

EL_TOP_DEG = 180.0


class TwoAxes(Recorder):
    """The axes' part of a box; the protocol's class sets the attributes below."""

    _az: Axis
    _el: Axis
    _az_speed: float  # full speed of each axis
    _el_speed: float
    baud: int
    line_ending: bytes
    _now_s: float
    _rx_line: bytearray  # a line still coming
    _tx: PacedLine  # the box's replies, paced at its line rate
    name: str  # the model, for errors
    has_elevation: bool

    def _build(
        self,
        model: str,
        models: Mapping[str, Any],
        az_top_deg: float,
        axes: tuple[float, float, float, float],
        line: tuple[int, bytes, float],
        now: float,
    ) -> Any:
        """Rule 5: the box at power-on, ``models[model]`` (its variant) returned; ``axes`` its
        start azimuth, elevation and their full speeds, ``line`` its baud, line ending and
        processing delay."""
        start_az_deg, start_el_deg, az_speed_deg_s, el_speed_deg_s = axes
        baud, line_ending, processing_delay_s = line
        if model not in models:
            raise ValueError(f"unknown model {model!r}; known: {', '.join(sorted(models))}")
        if line_ending not in (b"\r", b"\n", b"\r\n", b"\n\r"):
            raise ValueError(f"line_ending must be CR, LF, CR LF or LF CR, got {line_ending!r}")
        spec = models[model]
        if not spec.elevation and start_el_deg != 0.0:
            raise ValueError(f"{model} has no elevation rotor")
        self.name, self.has_elevation = spec.name, spec.elevation
        self.line_ending = line_ending
        self._az_speed, self._el_speed = float(az_speed_deg_s), float(el_speed_deg_s)
        self._az = Axis(start_az_deg, max_deg=az_top_deg, speed_deg_s=self._az_speed, now=now)
        low = min(0.0, start_el_deg)  # rule 5: a pot set a little below the horizon reads so
        self._el = Axis(
            start_el_deg, min_deg=low, max_deg=EL_TOP_DEG, speed_deg_s=self._el_speed, now=now
        )
        self.baud = int(baud)
        self._tx = PacedLine(self.baud, processing_delay_s=processing_delay_s)
        self._now_s = now
        self._rx_line = bytearray()
        self._log, self._events = [], []
        self._event(now, "power on")
        return spec

    @property
    def az_top_deg(self) -> float:
        """Rule 2: the azimuth range the box is set to now."""
        return self._az.max_deg

    @property
    def el_top_deg(self) -> float:
        """Rule 2: the elevation rotor's travel."""
        return self._el.max_deg

    def press_brake(self, now: float) -> bool:
        """No brake on these: letting go of the turn switch, or a hand on the stop switch,
        stops the motors."""
        return self._halt(self._update(now), "panel stop")

    def manual_rotate(self, az_deg: float, now: float, *, el_deg: float | None = None) -> None:
        now = self._update(now)
        top = self.az_top_deg
        if not 0.0 <= az_deg <= top:
            raise ValueError(f"az {az_deg} outside 0..{top:g}")
        if el_deg is not None and (not self.has_elevation or not 0.0 <= el_deg <= self.el_top_deg):
            raise ValueError(f"el {el_deg} not possible on {self.name}")
        if self._az.manual_move(az_deg, now):
            self._event(now, "move", f"panel az to {az_deg:g}")
        if el_deg is not None and self._el.manual_move(el_deg, now):
            self._event(now, "move", f"panel el to {el_deg:g}")

    def jam(self, now: float) -> None:
        now = self._update(now)
        self._az.jam(now)
        self._el.jam(now)
        self._event(now, "jammed")

    def unjam(self, now: float) -> None:
        now = self._update(now)
        self._az.unjam(now)
        self._el.unjam(now)
        self._event(now, "unjammed")

    def transmit(self, data: bytes, now: float) -> None:
        """Rule 6: ``data``, sent on the box's own, after whatever is on the line."""
        self._update(now)
        self._tx.send(data, now)

    def due_output(self, now: float) -> bytes:
        self._update(now)
        return self._tx.due(now)

    def next_wakeup(self, now: float) -> float | None:
        self._update(now)
        times = [self._tx.next_due_s(), self._az.arrival_time_s(), self._el.arrival_time_s()]
        pending = [t for t in times if t is not None]
        return min(pending) if pending else None

    def _lines(self, data: bytes, max_line: int) -> Iterator[tuple[bytes, bool]]:
        """Rule 4: the lines ``data`` completes, each with False, and a line that grew past
        ``max_line`` (dropped where it stood) with True."""
        for value in data:
            if value in (0x0D, 0x0A):
                line, self._rx_line = bytes(self._rx_line), bytearray()
                if line.strip():
                    yield line, False
                continue
            self._rx_line.append(value)
            if len(self._rx_line) > max_line:
                line, self._rx_line = bytes(self._rx_line), bytearray()
                yield line, True

    def _truth(self, now: float) -> dict[str, Any]:
        """The ground truth both axes give (RotatorState's fields), at ``now``, for the box's own
        state class to add to."""
        el = self._el if self.has_elevation else None
        return {
            "time_s": now,
            "az_deg": self._az.position_deg,
            "el_deg": None if el is None else el.position_deg,
            "is_moving": self._az.is_moving or self._el.is_moving,
            "is_jammed": self._az.is_jammed,
            "in_brake_delay": False,
            "target_az_deg": self._az.target_deg,
            "target_el_deg": None if el is None else el.target_deg,
            "driver": self._az.driver or self._el.driver,
        }

    def _update(self, now: float) -> float:
        """Rule 1."""
        now = max(now, self._now_s)
        self._now_s = now
        for name, axis in self._named():
            arrival_s = axis.advance(now)
            if arrival_s is not None:
                self._event(arrival_s, "arrived", f"{name} at {axis.position_deg:g}")
        return now

    def _event(self, time_s: float, kind: str, detail: str = "") -> None:
        self._events.append(MotionEvent(time_s, kind, self._az.position_deg_at(time_s), detail))

    def _halt(self, now: float, reason: str, axes: str = "az el") -> bool:
        """Rule 3."""
        stopped = [axis.stop(now) for name, axis in self._named() if name in axes]
        if any(stopped):
            self._event(now, "stopped", reason)
        return any(stopped)

    def _named(self) -> list[tuple[str, Axis]]:
        return [("az", self._az), ("el", self._el)]
