"""Yaesu GS-232A / GS-232B computer interface emulator (and the K3NG firmware), sans-IO.

What the device is: the serial interface of a Yaesu rotator controller (G-450 to G-2800, the
G-5500 az/el pair) or a clone speaking its commands (K3NG's Arduino controller, ERC, ARS). It
drives an azimuth rotor, 0..360 or 0..450 (the box's P36/P45 setting), and on az/el boxes an
elevation rotor, 0..180, each at one of four speeds (X1 slowest .. X4 fastest).

Frame: ASCII lines ending in CR (a LF is taken as an end too; empty lines are ignored). Every
command is answered: a command that returns nothing by a CR, one that returns data by the data
and `line_ending` (CR LF by default, as Yaesu's documents say and Hamlib's gs232a backend waits
for; CR alone on some clones, Green Heron's GS-232B mode); an unknown or malformed command by
``?>`` and `line_ending`.
  ``Mxxx``         turn to azimuth xxx              ``Wxxx yyy``  azimuth xxx, elevation yyy
  ``C``            azimuth: A ``+0xxx``, B ``AZ=xxx``
  ``C2``           both: A ``+0xxx+0yyy``, B ``AZ=xxx  EL=yyy`` (``spacing`` spaces between)
  ``B``            elevation: A ``+0yyy``, B ``EL=yyy``
  ``S`` all stop, ``A`` azimuth stop, ``E`` elevation stop
  ``R L U D``      turn right/left/up/down until stopped
  ``X1``..``X4``   speed;  ``P36`` ``P45`` 360 or 450 degree azimuth range

Source documents (written from these, never from bridge/protocols): the project's protocol
sheet (Yaesu's command table for the GS-232A/B, K3NG's blank lines after ``W``) and Hamlib
4.5.4's gs232a backend (gs232a.c, gs232b.c) and its traffic seen with rotctl -m 601/603.

Rules:
1. Sans-IO: bytes in through receive(data, now), out through due_output(now), paced at line
   rate after `processing_delay_s` (base.PacedLine); `now` never goes back. A reply shows the
   rotor at the instant its command's line ended.
2. Variants are data (MODELS): the reply form ("a" or "b"), whether an elevation rotor is
   connected (on azimuth boxes ``W``'s elevation moves nothing and reads 000) and the azimuth
   range at power-on (P36 or P45). ``blank_lines_after_w`` adds K3NG's blank lines after the
   answer to ``W``.
3. A bearing beyond the box's range (azimuth above 360 in P36, above 450 in P45; elevation
   above 180) or with other than three digits is refused with ``?>`` and moves nothing.
4. A new ``M``/``W`` while turning re-targets at once (no brake delay on these rotors).
5. Speeds: X4 is `az_speed_deg_s` / `el_speed_deg_s`, X3 three quarters, X2 half, X1 a
   quarter; the box starts at X4. A new speed applies to the moves in progress.
6. Every complete line is logged once with its Outcome; motion is logged as MotionEvents.
   power_cycle() stops the motors, drops a half-received line and anything not yet sent; the
   range goes back to the model's and the speed to X4; the rotors stay where they are.
"""

from __future__ import annotations

import enum
import re
from dataclasses import dataclass

from bridge.emulators.base import LoggedFrame, RotatorState
from bridge.emulators.physics import DRIVER_COMMAND
from bridge.emulators.twoaxes import EL_TOP_DEG, TwoAxes

__all__ = ["MODELS", "Gs232", "Gs232Model", "Gs232State", "Outcome"]

AZ_TOP_DEG = 450.0  # the azimuth rotor's travel on a 450-degree model
REFUSAL = b"?>"
_MAX_LINE = 32
_THREE = r"(\d{3})"
_M = re.compile(rf"M{_THREE}")
_W = re.compile(rf"W{_THREE} {_THREE}")


class Outcome(enum.StrEnum):
    MOVE = "move"  # M or W taken
    QUERY = "query"  # C, C2, B answered
    STOP = "stop"  # S, A, E
    JOG = "jog"  # R L U D
    SPEED = "speed"  # X1..X4
    RANGE = "range"  # P36, P45
    REFUSED = "refused"  # answered ?> (unknown, malformed, out of range)


@dataclass(frozen=True)
class Gs232Model:
    name: str
    form: str  # "a": +0xxx replies; "b": AZ=xxx
    elevation: bool  # an elevation rotor hangs on the box
    az_range_deg: float  # 360 (P36) or 450 (P45) at power-on


MODELS: dict[str, Gs232Model] = {
    "gs232a": Gs232Model("gs232a", "a", True, 360.0),
    "gs232b": Gs232Model("gs232b", "b", True, 360.0),
    "gs232a-az": Gs232Model("gs232a-az", "a", False, 360.0),
    "gs232b-az": Gs232Model("gs232b-az", "b", False, 360.0),
    "gs232a-450": Gs232Model("gs232a-450", "a", True, 450.0),
    "gs232b-450": Gs232Model("gs232b-450", "b", True, 450.0),
    "gs232a-az-450": Gs232Model("gs232a-az-450", "a", False, 450.0),
    "gs232b-az-450": Gs232Model("gs232b-az-450", "b", False, 450.0),
}


@dataclass(frozen=True)
class Gs232State(RotatorState):
    """RotatorState plus what only this box has."""

    target_el_deg: float | None = None
    speed_level: int = 4
    az_range_deg: float = 360.0


class Gs232(TwoAxes):
    """One GS-232 box with its rotor(s). See the module rules."""

    def __init__(
        self,
        model: str = "gs232b",
        *,
        baud: int = 9600,
        az_speed_deg_s: float = 6.0,
        el_speed_deg_s: float = 2.5,
        start_az_deg: float = 0.0,
        start_el_deg: float = 0.0,
        line_ending: bytes = b"\r\n",
        spacing: int = 2,
        blank_lines_after_w: int = 0,
        processing_delay_s: float = 0.002,
        now: float = 0.0,
    ) -> None:
        if not 0 <= spacing <= 4 or blank_lines_after_w < 0:
            raise ValueError("spacing must be 0..4 and blank_lines_after_w >= 0")
        axes = (start_az_deg, start_el_deg, az_speed_deg_s, el_speed_deg_s)
        line = (baud, line_ending, processing_delay_s)
        self.spec: Gs232Model = self._build(model, MODELS, AZ_TOP_DEG, axes, line, now)
        self.spacing = spacing
        self.blank_lines_after_w = blank_lines_after_w
        self._range_deg: float = self.spec.az_range_deg
        self._level = 4

    # -- sans-IO surface ------------------------------------------------------------------------

    def receive(self, data: bytes, now: float) -> None:
        now = self._update(now)
        for line, too_long in self._lines(data, _MAX_LINE):
            if too_long:  # no command is this long
                self._answer(REFUSAL, now)
                self._log.append(LoggedFrame(now, line, Outcome.REFUSED.value))
            else:
                self._command(line, now)

    # -- ground truth ---------------------------------------------------------------------------

    def state(self, now: float) -> Gs232State:
        now = self._update(now)
        return Gs232State(
            **self._truth(now),
            speed_level=self._level,
            az_range_deg=self._range_deg,
        )

    # -- front panel and faults -----------------------------------------------------------------

    def power_cycle(self, now: float) -> None:
        now = self._update(now)
        self._halt(now, "power off")
        self._rx_line.clear()
        self._tx.clear()
        self._range_deg = self.spec.az_range_deg
        self._set_level(4, now)
        self._event(now, "power on")

    @property
    def az_top_deg(self) -> float:
        """twoaxes.py rule 2: 360 or 450 as the box is set now (P36, P45)."""
        return self._range_deg

    # -- internals ------------------------------------------------------------------------------

    def _answer(self, data: bytes, now: float) -> None:
        self._tx.send(data + self.line_ending if data else b"\r", now)  # rule 1 of the frame

    def _command(self, line: bytes, now: float) -> None:
        text = line.decode("latin-1").strip().upper()
        outcome, reply = self._dispatch(text, now)
        self._answer(reply, now)
        if outcome is Outcome.MOVE and text.startswith("W"):
            for _ in range(self.blank_lines_after_w):  # K3NG (rule 2)
                self._tx.send(self.line_ending, now)
        self._log.append(LoggedFrame(now, line, outcome.value))

    def _dispatch(self, text: str, now: float) -> tuple[Outcome, bytes]:
        if m := _M.fullmatch(text):
            return self._move(float(m.group(1)), None, now)
        if m := _W.fullmatch(text):
            return self._move(float(m.group(1)), float(m.group(2)), now)
        if text in ("C", "C2", "B"):
            return Outcome.QUERY, self._reading(text)
        if text in ("S", "A", "E"):
            axes = {"S": "az el", "A": "az", "E": "el"}[text]
            self._halt(now, f"serial {text}", axes)
            return Outcome.STOP, b""
        if text in ("R", "L", "U", "D"):
            return self._jog(text, now)
        if text in ("X1", "X2", "X3", "X4"):
            self._set_level(int(text[1]), now)
            return Outcome.SPEED, b""
        if text in ("P36", "P45"):
            self._range_deg = 360.0 if text == "P36" else 450.0
            return Outcome.RANGE, b""
        return Outcome.REFUSED, REFUSAL

    def _move(self, az: float, el: float | None, now: float) -> tuple[Outcome, bytes]:
        if az > self._range_deg or (el is not None and el > EL_TOP_DEG):
            return Outcome.REFUSED, REFUSAL  # rule 3
        if self._az.start_move(az, now, driver=DRIVER_COMMAND):
            self._event(now, "move", f"az to {az:g}")
        if el is not None and self.spec.elevation and self._el.start_move(el, now):
            self._event(now, "move", f"el to {el:g}")
        return Outcome.MOVE, b""

    def _jog(self, letter: str, now: float) -> tuple[Outcome, bytes]:
        if letter in "UD" and not self.spec.elevation:
            return Outcome.REFUSED, REFUSAL
        axis, to = {
            "R": (self._az, self._range_deg),
            "L": (self._az, 0.0),
            "U": (self._el, EL_TOP_DEG),
            "D": (self._el, 0.0),
        }[letter]
        if axis.start_move(to, now):
            self._event(now, "move", f"jog {letter}")
        return Outcome.JOG, b""

    def _set_level(self, level: int, now: float) -> None:
        self._level = level
        for axis, full in ((self._az, self._az_speed), (self._el, self._el_speed)):
            target = axis.target_deg
            axis.advance(now)
            axis.speed_deg_s = full * level / 4
            if target is not None:  # rule 5: the move goes on at the new speed
                axis.start_move(target, now, driver=axis.driver or DRIVER_COMMAND)

    def _reading(self, text: str) -> bytes:
        az = round(self._az.position_deg)
        el = round(self._el.position_deg) if self.spec.elevation else 0
        if self.spec.form == "a":
            return {
                "C": b"+0%03d" % az,
                "C2": b"+0%03d+0%03d" % (az, el),
                "B": b"+0%03d" % el,
            }[text]
        gap = b" " * self.spacing
        return {
            "C": b"AZ=%03d" % az,
            "C2": b"AZ=%03d" % az + gap + b"EL=%03d" % el,
            "B": b"EL=%03d" % el,
        }[text]
