"""M2 RC2800 rotator controller emulator, sans-IO.

What the device is: M2 Antenna Systems' RC2800 controller, driving an azimuth rotor, 0..360, and
on the az/el version an elevation rotor, 0..180. One axis is selected at a time: a command names
its axis, and ``S`` stops the one selected.

Frame: ASCII lines ending in CR (a LF is taken as an end too; empty lines are ignored). Every
command is answered by one line (`line_ending`, CR by default; LF CR as a box in Hamlib's
issue 451 ends them) of the axis it selected:
``A P= 98.1 S=9 MV`` (position, the speed setting 1..9, ``MV`` moving or ``ST`` stopped).
  ``A``  ``E``           select the axis and answer its line
  ``A123.4`` ``E45``     select the axis and turn it to that bearing (tenths or whole degrees)
  ``S``                  stop the axis selected
A command it does not know, or a bearing out of range, is answered ``A ERR=n`` (``E`` for the
elevation): n 1 for an unknown command, 2 for a bearing out of range or an axis it lacks (the
box's own numbers are not known here; Hamlib reads any n).

Source documents (written from these, never from bridge/protocols): the project's protocol
sheet (M2 RC2800: 9600 8N1, CR, the reply form, echo and streaming, 200 ms between the axes)
and Hamlib's m2 backend (rc2800.c, model 1001: what it sends, the reply forms it reads, its
reading again after an echo, its stop as the axis selected then ``S``) and its traffic seen
with rotctl -m 1001.

Rules:
1. Sans-IO: bytes in through receive(data, now), out through due_output(now), paced at line
   rate after `processing_delay_s` (base.PacedLine); `now` never goes back. An answer shows
   the rotor at the instant its command's line ended.
2. Variants are data (MODELS): whether an elevation rotor is connected (on the azimuth box
   ``E`` reads 0.0, a bearing or a stop for it is answered ``E ERR=2`` and moves nothing).
3. ``echo`` sends every command line back (with CR) before its answer, as some boxes do.
   ``stream_s`` makes the box send every axis's line unasked once the line has been quiet
   (no command, nothing streamed) for that long, as some boxes stream their position.
4. A new bearing while turning re-targets at once (no brake).
5. A command to one axis less than AXIS_GAP_S (200 ms) after a command to the other is still
   taken, and counted (``too_soon`` in the state): the box's rule, for a test to hold a client
   to; ``S`` is a command to the axis selected.
6. Every complete line is logged once with its Outcome; motion is logged as MotionEvents.
   power_cycle() stops the motors, drops a half-received line and anything not yet sent; the
   rotors stay where they are and the azimuth is selected.
"""

from __future__ import annotations

import enum
import re
from dataclasses import dataclass

from bridge.emulators.base import LoggedFrame, RotatorState
from bridge.emulators.physics import DRIVER_COMMAND
from bridge.emulators.twoaxes import EL_TOP_DEG, TwoAxes

__all__ = ["AXIS_GAP_S", "MODELS", "Outcome", "Rc2800", "Rc2800Model", "Rc2800State"]

AZ_TOP_DEG = 360.0
AXIS_GAP_S = 0.2
# rule 5: "about 200 ms", timed from the end of one command line to the end of the next, so a
# shorter line after a longer one ends sooner by a few byte times (9600 baud: 1 ms a byte)
_GAP_SLACK_S = 0.01
SPEED_SETTING = 9  # the box's speed knob, 1..9: full speed
_MAX_LINE = 32
_COMMAND = re.compile(r"([AE])(\d{1,3}(?:\.\d*)?)?")


class Outcome(enum.StrEnum):
    MOVE = "move"  # A123.4 / E45 taken
    QUERY = "query"  # A, E answered
    STOP = "stop"  # S
    REFUSED = "refused"  # answered ERR (unknown, out of range, no such axis)


@dataclass(frozen=True)
class Rc2800Model:
    name: str
    elevation: bool  # an elevation rotor is connected


MODELS: dict[str, Rc2800Model] = {
    "rc2800": Rc2800Model("rc2800", True),
    "rc2800-az": Rc2800Model("rc2800-az", False),
}


@dataclass(frozen=True)
class Rc2800State(RotatorState):
    """RotatorState plus what only this box has."""

    target_el_deg: float | None = None
    selected: str = "A"
    too_soon: int = 0  # commands that came within the axis gap after the other axis's


class Rc2800(TwoAxes):
    """One RC2800 with its rotor(s). See the module rules."""

    def __init__(
        self,
        model: str = "rc2800",
        *,
        baud: int = 9600,
        az_speed_deg_s: float = 6.0,
        el_speed_deg_s: float = 3.0,
        start_az_deg: float = 0.0,
        start_el_deg: float = 0.0,
        echo: bool = False,
        stream_s: float | None = None,
        line_ending: bytes = b"\r",
        processing_delay_s: float = 0.002,
        now: float = 0.0,
    ) -> None:
        if stream_s is not None and stream_s <= 0:
            raise ValueError(f"stream_s must be positive, got {stream_s}")
        axes = (start_az_deg, start_el_deg, az_speed_deg_s, el_speed_deg_s)
        line = (baud, line_ending, processing_delay_s)
        self.spec: Rc2800Model = self._build(model, MODELS, AZ_TOP_DEG, axes, line, now)
        self.echo = echo
        self.stream_s = stream_s
        self._selected = "A"
        self._axis_t = {"A": float("-inf"), "E": float("-inf")}  # last command to each axis
        self._too_soon = 0
        self._quiet_since_s = now  # rule 3: the stream waits for a quiet line

    # -- sans-IO surface ------------------------------------------------------------------------

    def receive(self, data: bytes, now: float) -> None:
        now = self._update(now)
        self._stream(now)
        for line, too_long in self._lines(data, _MAX_LINE):
            if too_long:  # no command is this long
                self._answer(b"%c ERR=1" % ord(self._selected), now)
                self._log.append(LoggedFrame(now, line, Outcome.REFUSED.value))
            else:
                self._command(line, now)

    def due_output(self, now: float) -> bytes:
        self._stream(self._update(now))
        return super().due_output(now)

    def next_wakeup(self, now: float) -> float | None:
        times = [super().next_wakeup(now), self._next_stream_s()]
        pending = [t for t in times if t is not None]
        return min(pending) if pending else None

    # -- ground truth ---------------------------------------------------------------------------

    def state(self, now: float) -> Rc2800State:
        now = self._update(now)
        return Rc2800State(**self._truth(now), selected=self._selected, too_soon=self._too_soon)

    # -- front panel and faults -----------------------------------------------------------------

    def power_cycle(self, now: float) -> None:
        now = self._update(now)
        self._halt(now, "power off")
        self._rx_line.clear()
        self._tx.clear()
        self._selected = "A"
        self._quiet_since_s = now
        self._event(now, "power on")

    # -- internals ------------------------------------------------------------------------------

    def _answer(self, data: bytes, now: float) -> None:
        self._tx.send(data + self.line_ending, now)
        self._quiet_since_s = now

    def _axis_line(self, letter: str, at: float) -> bytes:
        axis = self._az if letter == "A" else self._el
        value = axis.position_deg_at(at) if letter == "A" or self.spec.elevation else 0.0
        state = b"MV" if axis.is_moving else b"ST"
        return b"%c P=%6.1f S=%d %s" % (ord(letter), value, SPEED_SETTING, state)

    def _next_stream_s(self) -> float | None:
        return None if self.stream_s is None else self._quiet_since_s + self.stream_s

    def _stream(self, now: float) -> None:
        """Rule 3: every axis's line, unasked, for each quiet stretch that has passed."""
        while (due := self._next_stream_s()) is not None and due <= now:
            for letter in "AE" if self.spec.elevation else "A":
                self._tx.send(self._axis_line(letter, due) + self.line_ending, due)
            self._quiet_since_s = due

    def _command(self, line: bytes, now: float) -> None:
        text = line.decode("latin-1").strip().upper()
        if self.echo:
            self._tx.send(line.strip() + b"\r", now)  # rule 3
        outcome = self._dispatch(text, now)
        if outcome is Outcome.REFUSED:
            code = 2 if text == "S" or _COMMAND.fullmatch(text) else 1
            self._answer(b"%c ERR=%d" % (ord(self._selected), code), now)
        else:
            self._answer(self._axis_line(self._selected, now), now)
        self._log.append(LoggedFrame(now, line, outcome.value))

    def _dispatch(self, text: str, now: float) -> Outcome:
        m = _COMMAND.fullmatch(text)
        letter = self._selected if text == "S" else m.group(1) if m else None
        if letter is None:
            return Outcome.REFUSED
        if now - self._axis_t["E" if letter == "A" else "A"] < AXIS_GAP_S - _GAP_SLACK_S:
            self._too_soon += 1  # rule 5
        self._axis_t[letter] = now
        self._selected = letter
        if letter == "E" and not self.spec.elevation and text != "E":
            return Outcome.REFUSED  # rule 2
        if text == "S":
            self._halt(now, "serial S", "az" if letter == "A" else "el")
            return Outcome.STOP
        assert m is not None
        value = m.group(2)
        if value is None:
            return Outcome.QUERY
        bearing = float(value)
        top = AZ_TOP_DEG if letter == "A" else EL_TOP_DEG
        if bearing > top:
            return Outcome.REFUSED
        axis = self._az if letter == "A" else self._el
        if axis.start_move(bearing, now, driver=DRIVER_COMMAND):
            self._event(now, "move", f"{'az' if letter == 'A' else 'el'} to {bearing:g}")
        return Outcome.MOVE
