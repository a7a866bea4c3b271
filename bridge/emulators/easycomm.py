"""Easycomm II / III controller emulator (SatNOGS controllers, K3NG in Easycomm mode), sans-IO.

What the device is: a rotator controller that takes Easycomm commands on its serial port and
drives an azimuth rotor, 0..360, and on az/el controllers an elevation rotor, 0..180. This is a
controller, the thing the bridge drives; the bridge's own station-side Easycomm port (a program
driving the bridge) is another thing and lives elsewhere.

Frame: ASCII commands of two letters and a value, separated by a space, CR or LF; a line ends at
CR or LF. Only commands that ask something are answered; the answers of one line are sent
together, space separated, at its end, followed by `line_ending` (LF by default, CR LF on some
firmware):
  ``AZaaa.a`` ``ELeee.e``  turn to azimuth / elevation
  ``AZ`` ``EL``            answered ``AZaaa.a`` ``ELeee.e``
  ``SA`` ``SE``            stop azimuth / elevation;  ``RESET`` stop both
  ``ML MR MU MD``          turn until stopped;  ``PARK`` turn to 0/0
  ``VE``                   answered ``VExxx`` (the version)
Easycomm III adds ``VL VR VU VD`` with a speed in millidegrees per second (turn until stopped,
at that speed or the motor's top speed), ``GS`` answered ``GSn`` (status bits: 1 idle, 2 moving,
8 error) and ``GE`` answered ``GEn`` (error bits: 2 jam; 0 none). Unknown commands and radio
words (``UP DN UM DM UR DR``) are ignored: Easycomm has no error answer.

Source documents (written from these, never from bridge/protocols): the Easycomm II/III
descriptions shipped with Hamlib (easycomm.txt), the project's protocol sheet (SatNOGS at 19200,
K3NG at 9600; firmware that answers AZ and EL only when asked separately), Hamlib 4.5.4's easycomm
backend and its traffic seen with rotctl -m 202/204.

Rules:
1. Sans-IO: bytes in through receive(data, now), out through due_output(now), paced at line
   rate after `processing_delay_s` (base.PacedLine); `now` never goes back. An answer shows the
   rotor at the instant its line ended.
2. Variants are data (MODELS): the dialect (2 or 3), whether an elevation rotor is connected (on
   azimuth controllers ``EL`` values move nothing and ``EL`` reads 0.0), and whether the
   controller answers a position only when asked on a line of its own (``separate``: a line
   asking ``AZ EL`` is not answered at all). `decimals` (1, or 0 for whole degrees) and `spacing`
   (spaces between the answers of one line) give the reply forms firmware sends.
3. A value beyond the rotor's range (azimuth 0..360, elevation 0..180) or not a number is ignored
   and moves nothing (logged REFUSED); the other commands of its line still count.
4. A new bearing while turning re-targets at once (no brake).
5. Every command is logged once with its Outcome; motion is logged as MotionEvents.
   power_cycle() stops the motors, drops a half-received line and anything not yet sent; the
   rotors stay where they are.
"""

from __future__ import annotations

import enum
import re
from dataclasses import dataclass

from bridge.emulators.base import LoggedFrame, RotatorState
from bridge.emulators.physics import DRIVER_COMMAND
from bridge.emulators.twoaxes import EL_TOP_DEG, TwoAxes

__all__ = ["MODELS", "EasycommController", "EasycommModel", "EasycommState", "Outcome"]

AZ_TOP_DEG = 360.0
_MAX_LINE = 64
_VALUE = re.compile(r"(AZ|EL)([-+]?\d+(?:\.\d*)?)")
_VELOCITY = re.compile(r"(VL|VR|VU|VD)(\d{1,5})")
_RADIO = ("UP", "DN", "UM", "DM", "UR", "DR")


class Outcome(enum.StrEnum):
    MOVE = "move"  # AZaaa.a / ELeee.e taken
    QUERY = "query"  # AZ, EL answered
    UNANSWERED = "unanswered"  # a query a `separate` controller leaves unanswered
    STOP = "stop"  # SA, SE, RESET
    JOG = "jog"  # ML MR MU MD, VL VR VU VD
    PARK = "park"
    INFO = "info"  # VE, GS, GE answered
    IGNORED = "ignored"  # unknown commands, radio words
    REFUSED = "refused"  # a value out of range or not a number (rule 3)


@dataclass(frozen=True)
class EasycommModel:
    name: str
    dialect: int  # 2 or 3
    elevation: bool  # an elevation rotor is connected
    separate: bool  # answers AZ and EL only when asked on lines of their own


def _models() -> dict[str, EasycommModel]:
    out: dict[str, EasycommModel] = {}
    for dialect in (2, 3):
        name = f"easycomm{dialect}"
        out[name] = EasycommModel(name, dialect, True, False)
        out[f"{name}-az"] = EasycommModel(f"{name}-az", dialect, False, False)
        out[f"{name}-separate"] = EasycommModel(f"{name}-separate", dialect, True, True)
    return out


MODELS: dict[str, EasycommModel] = _models()


@dataclass(frozen=True)
class EasycommState(RotatorState):
    """RotatorState plus what only this controller has."""

    target_el_deg: float | None = None


class EasycommController(TwoAxes):
    """One Easycomm controller with its rotor(s). See the module rules."""

    def __init__(
        self,
        model: str = "easycomm2",
        *,
        baud: int = 19200,
        az_speed_deg_s: float = 6.0,
        el_speed_deg_s: float = 6.0,
        start_az_deg: float = 0.0,
        start_el_deg: float = 0.0,
        line_ending: bytes = b"\n",
        decimals: int = 1,
        spacing: int = 1,
        version: str = "2.0",
        processing_delay_s: float = 0.002,
        now: float = 0.0,
    ) -> None:
        if decimals not in (0, 1, 2) or not 0 <= spacing <= 4:
            raise ValueError("decimals must be 0..2 and spacing 0..4")
        axes = (start_az_deg, start_el_deg, az_speed_deg_s, el_speed_deg_s)
        line = (baud, line_ending, processing_delay_s)
        self.spec: EasycommModel = self._build(model, MODELS, AZ_TOP_DEG, axes, line, now)
        self.decimals = decimals
        self.spacing = spacing
        self.version = version

    # -- sans-IO surface ------------------------------------------------------------------------

    def receive(self, data: bytes, now: float) -> None:
        now = self._update(now)
        for line, too_long in self._lines(data, _MAX_LINE):
            if too_long:  # no line is this long
                self._log.append(LoggedFrame(now, line, Outcome.REFUSED.value))
            else:
                self._line(line, now)

    # -- ground truth ---------------------------------------------------------------------------

    def state(self, now: float) -> EasycommState:
        now = self._update(now)
        return EasycommState(
            **self._truth(now),
        )

    # -- front panel and faults -----------------------------------------------------------------

    def power_cycle(self, now: float) -> None:
        now = self._update(now)
        self._halt(now, "power off")
        self._rx_line.clear()
        self._tx.clear()
        self._event(now, "power on")

    # -- internals ------------------------------------------------------------------------------

    def _line(self, line: bytes, now: float) -> None:
        words = line.decode("latin-1").upper().split()
        queries = [w for w in words if w in ("AZ", "EL")]
        quiet = self.spec.separate and len(queries) > 1  # rule 2: asked both at once
        answers: list[str] = []
        skip = False
        for i, word in enumerate(words):
            if skip:  # the mode word after a radio word (UP000 XXX)
                skip = False
                outcome = Outcome.IGNORED
            elif word.startswith(_RADIO):
                skip = i + 1 < len(words) and words[i + 1].isalpha()
                outcome = Outcome.IGNORED
            elif word in ("AZ", "EL"):
                outcome = Outcome.UNANSWERED if quiet else Outcome.QUERY
                if not quiet:
                    answers.append(self._reading(word))
            else:
                outcome, answer = self._command(word, now)
                if answer:
                    answers.append(answer)
            self._log.append(LoggedFrame(now, word.encode(), outcome.value))
        if answers:
            text = (" " * self.spacing).join(answers)
            self._tx.send(text.encode() + self.line_ending, now)

    def _command(self, word: str, now: float) -> tuple[Outcome, str]:
        if m := _VALUE.fullmatch(word):
            return self._move(m.group(1), float(m.group(2)), now), ""
        if word in ("SA", "SE"):
            self._halt(now, f"serial {word}", "az" if word == "SA" else "el")
            return Outcome.STOP, ""
        if word == "RESET":
            self._halt(now, "serial RESET")
            return Outcome.STOP, ""
        if word == "PARK":
            self._move("AZ", 0.0, now)
            if self.spec.elevation:
                self._move("EL", 0.0, now)
            return Outcome.PARK, ""
        if word in ("ML", "MR", "MU", "MD"):
            return self._jog(word[1], None, now)
        if self.spec.dialect == 3 and (m := _VELOCITY.fullmatch(word)):
            return self._jog(word[1], int(m.group(2)) / 1000.0, now)
        if word == "VE":
            return Outcome.INFO, f"VE{self.version}"
        if self.spec.dialect == 3 and word in ("GS", "GE"):
            return Outcome.INFO, self._register(word)
        return Outcome.IGNORED, ""

    def _move(self, axis_name: str, value: float, now: float) -> Outcome:
        top = AZ_TOP_DEG if axis_name == "AZ" else EL_TOP_DEG
        if not 0.0 <= value <= top:
            return Outcome.REFUSED  # rule 3
        if axis_name == "EL" and not self.spec.elevation:
            return Outcome.MOVE  # taken, and nothing hangs on it
        axis = self._az if axis_name == "AZ" else self._el
        axis.advance(now)
        axis.speed_deg_s = self._az_speed if axis_name == "AZ" else self._el_speed  # after a jog
        if axis.start_move(value, now, driver=DRIVER_COMMAND):
            self._event(now, "move", f"{axis_name.lower()} to {value:g}")
        return Outcome.MOVE

    def _jog(self, letter: str, speed_deg_s: float | None, now: float) -> tuple[Outcome, str]:
        if letter in "UD" and not self.spec.elevation:
            return Outcome.IGNORED, ""
        axis, full, to = {
            "R": (self._az, self._az_speed, AZ_TOP_DEG),
            "L": (self._az, self._az_speed, 0.0),
            "U": (self._el, self._el_speed, EL_TOP_DEG),
            "D": (self._el, self._el_speed, 0.0),
        }[letter]
        axis.advance(now)
        axis.speed_deg_s = full if not speed_deg_s else min(full, speed_deg_s)
        if axis.start_move(to, now):
            self._event(now, "move", f"jog {letter}")
        return Outcome.JOG, ""

    def _register(self, word: str) -> str:
        moving = self._az.is_moving or self._el.is_moving
        jammed = self._az.is_jammed or self._el.is_jammed
        if word == "GS":
            return f"GS{(2 if moving else 1) | (8 if jammed else 0)}"
        return f"GE{2 if jammed else 0}"

    def _reading(self, word: str) -> str:
        if word == "AZ":
            value = self._az.position_deg
        else:
            value = self._el.position_deg if self.spec.elevation else 0.0
        return f"{word}{value:.{self.decimals}f}"
