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
6. ``firmware`` picks whose reading of the protocol this box has: ``generic`` (the rules above),
   or two real ones, written from their sources:
   - ``satnogs``: the SatNOGS rotator firmware's easycomm.h. A line beginning ``AZ EL`` is
     answered ``AZaaa.a ELeee.e``; any other line beginning ``AZ`` is a target, its azimuth the
     number after the letters read as C's atof (nothing there is 0: a bare ``AZ`` turns the
     rotor to 0), then an ``EL`` word the same way, unanswered. ``SA SE`` is answered with the
     position and stops both. ``VE`` is answered; anything else (``EL`` alone) does nothing.
   - ``k3ng``: K3NG's rotator controller in Easycomm mode, its default build. Each word is
     carried out when a space, CR or LF ends it, and answered at once with what it says and
     that same byte: a bare ``AZ`` ``+aaa.a``, a bare ``EL`` ``+eee.e`` (``-`` below 0; ``?``
     on an azimuth build), a target or a stop nothing, anything it cannot read ``?``, ``VE``
     ``VE002``. So ``AZ EL`` LF is answered ``+aaa.a +eee.e`` LF.
"""

from __future__ import annotations

import enum
import re
from dataclasses import dataclass

from bridge.emulators.base import LoggedFrame, RotatorState
from bridge.emulators.physics import DRIVER_COMMAND
from bridge.emulators.twoaxes import EL_TOP_DEG, TwoAxes

__all__ = [
    "FIRMWARE",
    "MODELS",
    "EasycommController",
    "EasycommModel",
    "EasycommState",
    "Outcome",
]

AZ_TOP_DEG = 360.0
_MAX_LINE = 64
_VALUE = re.compile(r"(AZ|EL)([-+]?\d+(?:\.\d*)?)")
_VELOCITY = re.compile(r"(VL|VR|VU|VD)(\d{1,5})")
_RADIO = ("UP", "DN", "UM", "DM", "UR", "DR")
FIRMWARE = ("generic", "satnogs", "k3ng")  # rule 6
_ATOF = re.compile(r"\s*([-+]?(?:\d+\.?\d*|\.\d+))")  # the number C's atof reads, if any
_K3NG_VALUE = re.compile(r"(AZ|EL)\d{1,3}\.\d")  # AZx.x AZxx.x AZxxx.x


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
        firmware: str = "generic",
        processing_delay_s: float = 0.002,
        now: float = 0.0,
    ) -> None:
        if decimals not in (0, 1, 2) or not 0 <= spacing <= 4:
            raise ValueError("decimals must be 0..2 and spacing 0..4")
        if firmware not in FIRMWARE:
            raise ValueError(f"firmware must be one of {', '.join(FIRMWARE)}")
        axes = (start_az_deg, start_el_deg, az_speed_deg_s, el_speed_deg_s)
        line = (baud, line_ending, processing_delay_s)
        self.spec: EasycommModel = self._build(model, MODELS, AZ_TOP_DEG, axes, line, now)
        self.decimals = decimals
        self.spacing = spacing
        self.version = version
        self.firmware = firmware

    # -- sans-IO surface ------------------------------------------------------------------------

    def receive(self, data: bytes, now: float) -> None:
        now = self._update(now)
        if self.firmware == "k3ng":
            self._k3ng_bytes(data, now)
            return
        for line, too_long in self._lines(data, _MAX_LINE):
            if too_long:  # no line is this long
                self._log.append(LoggedFrame(now, line, Outcome.REFUSED.value))
            elif self.firmware == "satnogs":
                self._satnogs_line(line, now)
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

    # -- rule 6: the firmware of two real boxes ---------------------------------------------------

    def _position(self) -> str:
        el = self._el.position_deg if self.spec.elevation else 0.0
        return f"AZ{self._az.position_deg:.1f} EL{el:.1f}"

    def _satnogs_line(self, line: bytes, now: float) -> None:
        text = line.decode("latin-1")
        if text.startswith("AZ EL"):
            self._log.append(LoggedFrame(now, line, Outcome.QUERY.value))
            self._tx.send(self._position().encode() + self.line_ending, now)
        elif text.startswith("AZ"):
            words = text.split(" ")
            outcome = self._satnogs_value("AZ", words[0][2:12], now)
            if len(words) > 1 and words[1].startswith("EL"):
                self._satnogs_value("EL", words[1][2:12], now)
            self._log.append(LoggedFrame(now, line, outcome.value))
        elif text.startswith("SA SE"):
            self._tx.send(self._position().encode() + self.line_ending, now)
            self._halt(now, "serial SA SE")
            self._log.append(LoggedFrame(now, line, Outcome.STOP.value))
        elif text.startswith("VE"):
            self._tx.send(f"VESatNOGS-{self.version}".encode() + self.line_ending, now)
            self._log.append(LoggedFrame(now, line, Outcome.INFO.value))
        else:
            self._log.append(LoggedFrame(now, line, Outcome.IGNORED.value))

    def _satnogs_value(self, axis: str, data: str, now: float) -> Outcome:
        if any(c.isalpha() for c in data):  # its isNumber: letters only are refused
            return Outcome.REFUSED
        m = _ATOF.match(data)
        return self._move(axis, float(m.group(1)) if m else 0.0, now)

    def _k3ng_bytes(self, data: bytes, now: float) -> None:
        for value in data:
            if value not in (0x20, 0x0D, 0x0A):
                if len(self._rx_line) < _MAX_LINE:
                    self._rx_line.append(value)
                continue
            word, self._rx_line = bytes(self._rx_line).decode("latin-1"), bytearray()
            if len(word) < 2:  # its buffer must hold two characters to be carried out
                continue
            outcome, answer = self._k3ng_word(word, now)
            self._log.append(LoggedFrame(now, word.encode(), outcome.value))
            self._tx.send(answer.encode() + bytes([value]), now)

    def _k3ng_word(self, word: str, now: float) -> tuple[Outcome, str]:
        elevation = self.spec.elevation
        if word == "AZ":
            return Outcome.QUERY, f"+{self._az.position_deg:.1f}"
        if word == "EL" and elevation:
            el = self._el.position_deg
            return Outcome.QUERY, f"{'+' if el >= 0 else ''}{el:.1f}"
        if _K3NG_VALUE.fullmatch(word) and (word[0] == "A" or elevation):
            outcome = self._move(word[:2], float(word[2:]), now)
            return outcome, "" if outcome is Outcome.MOVE else "?"
        if word[0] == "S" and (word[1] == "A" or (word[1] == "E" and elevation)):
            self._halt(now, f"serial {word[:2]}", "az" if word[1] == "A" else "el")
            return Outcome.STOP, ""
        if word[0] == "M" and (word[1] in "LR" or (word[1] in "UD" and elevation)):
            return self._jog(word[1], None, now)
        if word.startswith("VE"):
            return Outcome.INFO, "VE002"
        return Outcome.REFUSED, "?"
