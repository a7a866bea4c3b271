"""What every controller family provides: a sans-IO codec and a model spec that is pure data.

Rules:
1. A codec turns typed commands into bytes and bytes into typed replies. It never touches a
   port, a clock, a thread or a sleep; timing values live on the ModelSpec as data.
2. ``feed()`` accepts any slicing of the byte stream (whole buffers, one byte at a time, junk
   around the frames) and yields the same replies. Junk is reported, never turned into a reading.
3. A position reply is only accepted while a reply is awaited (a query, or a command the
   controller answers with its position); ``awaiting_reply`` says so, ``expire_query`` gives up
   on it after the engine's reply timeout. Anything else is junk, but for a controller that
   streams its position unasked (RC2800: a well-formed line of every axis is a reading).
   ``OneQuery`` keeps that bookkeeping for the codecs that ask one question at a time.
4. The engine, the MQTT topics and Home Assistant ask the spec's capabilities; nothing offers
   what the model cannot do.
5. What the bytes mean is the codec's to say, as a type: the engine acts on a reply's type and
   a JunkReason (UNTRUSTED: ask again; POWER_ON: the controller forgot its options; MISFIT:
   the box set up otherwise than configured, its detail told to the user), never on the bytes
   themselves.
6. A controller setting (an option, a speed) is data: a ``Setting`` in the spec's ``settings``
   says its kind (bool, number with range/step/unit, choice of named values), when it may be
   sent, whether the controller forgets it at power-off, what it does to the rotor's speed,
   and names the codec's function that turns a value into bytes. ``Setting.read`` is the one
   judge of a value: anything outside the declaration is refused with words a user can act
   on, and nothing is sent. A new setting is one encoder in its codec and one spec entry.
7. A query given up (``expire_query``) may still be answered: ``LateAnswers`` (OneQuery's, and
   any codec's that says ``awaiting_reply``) counts the lines of its answer still owed (the
   codec says how many, ``_owe_late``; at most LATE_LINES_MAX in all: more than the polls a
   link gives up in a default silence timeout, 3 s at the shortest reply time, 0.25 s, so that
   an adapter that stalls once for 2-3 s and then hands over every answer it held is told
   nowhere; an attack pass: with four, a 2.5 s stall mid-turn was told on R/error as
   'controller sent 25 bytes that are no valid reply' on an RT-21). A clean reply line of
   the controller's form while no reply is awaited and some are owed is one of them
   (``_late_answer``): UNSOLICITED (it spoils a reading held in the same exchange, link.py
   rule 9), never a reading (but rc2800.py rule 6's, before any other exchange: that box's
   stream), and harmless (the codec's ``harmless`` discounts the lines it
   said, ``_unsaid``, each as often as it said it: a second line of the same text that no
   query owes is told). A line that comes while the next query is open is that query's, as
   ever (no line says which poll it answers, and a late answer that never comes must not eat
   the next poll's). (easycomm.py rule 10, gs232.py rule 5, rt21.py rule 5, spid.py rule 7,
   prosistel.py rule 7, rc2800.py rule 6, rotorez.py rule 7: a busy host gave a poll up, the
   next poll took its answer, and that poll's own answer a line later was told on R/error as
   bytes that are no reply, or passed as chatter that spoiled nothing, the older reading
   standing.) Such a line's JunkReply says so (``late``): the engine learns from it how late
   its controller answers (session/link.py rule 12); ``owes_late`` says whether any is owed.
8. A reading says whether the controller drives a motor (``PositionReply.driving``) where its
   reply carries a flag for it (Prosistel's ``R``/``B``, an RC2800's ``MV``/``ST``): True if it
   drives any axis it reads, False if it says of every one that it drives none, None where a
   reply does not say. The engine ends a turn the controller gave up on that flag
   (session/controller.py rule 12), never on a flag alone.
9. A stop is written where the line left off (``StopsOnTheLine``). The first frame of a
   connection lands behind whatever half frame the one before left in the box (an adapter
   pulled mid-frame, a frame a full tty buffer cut short: runtime/port.py rule 6), and the
   box reads the two as one command: a GS-232's ``S`` then ``S`` CR is ``SS``, refused
   (``?>``); an Easycomm's ``S`` then ``SA SE`` is ``SSA SE``, the elevation's stop alone; an
   RC2800's ``A`` then ``A`` CR ``S`` CR is ``AA``, and the ``S`` stops the axis still
   selected (attack 22: the azimuth turned on until the stop was sent again 2 s later). Such
   a codec writes that stop so that no half frame eats it (``HalfLine``): the stop after a
   throwaway frame that takes the half frame in (refused or partial; the stop itself, or on
   an RC2800 the axis's selection, twice), or, where no move can have been cut (no target
   whose bytes may not all have reached the box), after a bare line end, which ends a cut
   stop or poll as the command it was (a GS-232's ``S`` then CR: the stop, taken first). A
   bare line end is never written where a move may have been cut: it would carry out
   ``M18`` of ``M180`` (interfaces/mqtt/express.py rule 9). On a line that carried a frame
   already the stop is the plain one (``HalfLine.NONE``). A Rotor-EZ's ``;`` ends an open
   ``A`` frame (``AI`` then ``;``: invalid, no stop), so it goes twice too (rotorez.py rule
   8), and so does an RT-21's, whose ``;`` ends every command it takes (a cut ``BI1`` or a
   target's ``AP1200.0`` CR takes the lone ``;`` as its end: rt21.py rule 6; review 71). A
   codec that does not say how is sent ``encode_stop``, as before: the DCU-1 (every stop
   twice 0.1 s apart already, session/stops.py rule 6), the SPID (fixed
   13-byte frames; the fact sheet's simulator drops a frame short of them 0.1 s after its
   last byte, and no source says what the box does), the SatEL and the Prosistel (STX
   framed): none of them looked at closely here.
10. A reading a little past an end of its axis's range is that end (``read_in_range``): a
   healthy box at rest at an end may say a little more than it, and a reading spoiled there
   is spoiled at every poll, the rotator offline for good and no target ever turning it back
   (attack 30: a GS-232 450-degree model at 451, a G-5500 at elevation 181, a Prosistel at
   361, 091, 3601 or 0901, an RC2800 at -0.2 or 360.2; review 39's Easycomm at ``AZ-0.1``;
   review 49's RT-21 at 181, axes.py rule 2). How far is the model's read slack, at least its
   ``noise_deg`` (how far a still rotor's readings wander: resting at an end, that far past
   it): POT_SLACK_DEG for a potentiometer read in whole degrees (a GS-232, a Prosistel D: set
   by hand at the box, a degree or two off with the weather, a coast past the end; K3NG's own
   forms say up to 3 below the horizon), TENTHS_SLACK_DEG for a sensor read in tenths (an
   Easycomm box, a Combi-Track, an RC2800: its noise and a PID's dead zone, and under a
   degree, so that a reading a whole degree past, ``A P= 361.0``, is still told). A one-axis
   box turning a composite's elevation is read with a pot's slack past the elevation's ends
   whatever its resolution (axes.py rule 2, EL_READ_SLACK_DEG: an RT-21's pot a degree off,
   review 49). Past the slack a reading is no bearing the box can have: spoiled (or a MISFIT
   where it says the box is set up otherwise, gs232.py rule 2; axes.py rule 2), as before.
   An axis the box never turns nor reads for the antenna is judged by no range: a
   composite's azimuth box's own elevation (``ScalesElevation``, axes.py rule 1), as its
   elevation box's own azimuth by no model's scale (``ScalesAzimuth``), and as a SPID's
   unused elevation counter (spid.py rule 5): what it reads spoils nothing of the axis used
   (review 98: a GS-232's ``EL=190``, an Easycomm's ``EL181.0``, spoiled the whole reply,
   its azimuth too, and the rotator went offline for good, told as garbled replies).
"""

from __future__ import annotations

import enum
import math
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import ClassVar, Protocol, runtime_checkable

from bridge.core.model import SettingValue
from bridge.core.text import shown_past


@dataclass(frozen=True)
class PositionReply:
    az_deg: float
    el_deg: float | None = None
    motion_enabled: bool | None = None  # controllers with an automatic-motion switch (SatEL)
    controller_time: str | None = None  # the controller's own clock, as it prints it
    # rule 8: whether the controller says it drives a motor now (Prosistel's R or B, an
    # RC2800's MV or ST); None where its reply does not say
    driving: bool | None = None


@dataclass(frozen=True)
class VersionReply:
    version: str


class NotReady(ValueError):
    """A codec cannot count a target yet (``wire_target``, ``encode_target``): what it needs
    from its controller has not been read, or not confirmed (SPID's resolution, spid.py rule
    5; a composite's box its own other axis, axes.py). The engine asks first and sends the
    target after the answer (session/targets.py ``decide``), never sends a guess."""


class JunkReason(enum.StrEnum):
    """Why bytes are no reading. The engine acts on UNTRUSTED and POWER_ON, tells MISFIT's
    detail; the rest it logs."""

    NOISE = "noise"  # bytes that form no reply: line garbage, a torn frame, a banner
    CHATTER = "chatter"  # text a healthy controller prints besides replies (a debug line)
    UNSOLICITED = "unsolicited"  # a well-formed reply nobody is waiting for (a late answer)
    SPOILED = "spoiled"  # a reply that cannot be read; nothing was waiting on it
    # a reply that looked right but came after line noise in the same exchange (or a spoiled
    # report that ended a slew): not a reading; ask again at once
    UNTRUSTED = "untrusted"
    # the controller announced that it was switched on: it has forgotten its options
    POWER_ON = "power_on"
    # the controller answered a command with its refusal (GS-232's ``?>``): a target that went
    # out and has not moved the rotor is dropped and reported, not waited on until a stall
    REFUSED = "refused"
    # a well-formed reply the box as configured cannot give, one set up otherwise can (a
    # GS-232 at P45 configured as a 360-degree model; an elevation box reading past an
    # elevation's scale): never a reading, and its detail, words a user acts on (what to
    # configure or set on the box), is told on R/error (session/controller.py rule 6)
    MISFIT = "misfit"


LATE_ANSWER = "a poll's answer after its time"  # rule 7: the detail of a line owed late


@dataclass(frozen=True)
class JunkReply:
    """Bytes that are no valid reply (power-on noise, a banner, line garbage)."""

    data: bytes
    reason: JunkReason
    detail: str = ""  # the codec's words, for a log line or a test
    # the axis ("azimuth", "elevation") whose own frame of a target the controller refused,
    # where a target is a frame per axis (an RC2800's az/el box, a Combi-Track): that axis is
    # not driven to it (session/motion.py rule 3: not judged stalled on its own)
    axis: str | None = None

    @property
    def late(self) -> bool:
        """Rule 7: a line of an answer owed by a query given up (the engine learns from it
        how late its controller answers: link.py rule 12)."""
        return self.reason is JunkReason.UNSOLICITED and self.detail == LATE_ANSWER


Reply = PositionReply | VersionReply | JunkReply

UNTRUSTED = JunkReason.UNTRUSTED  # the name the engine used before JunkReason existed


class RetargetPolicy(enum.StrEnum):
    # The controller stops on a new bearing while turning and ignores bearings during its brake
    # delay (Rotor-EZ FAQ): stop, wait for stillness plus the brake delay, then send the target.
    STOP_AND_WAIT = "stop_and_wait"
    # The controller takes a new target at any time (SPID).
    DIRECT = "direct"


class Codec(Protocol):
    def encode_target(self, az_deg: float, el_deg: float | None) -> list[bytes]: ...
    # a list: frames to the controller's axes in turn, paced by ModelSpec.axis_gap_s (RC2800)
    def encode_stop(self) -> bytes | list[bytes]: ...
    def encode_query(self) -> bytes | list[bytes] | None: ...
    def expire_query(self) -> None: ...
    def encode_version(self) -> bytes | None: ...
    def encode_option(self, name: str, enabled: bool) -> bytes:
        """An on/off option's bytes (ValueError where the model has none). The engine sends
        every setting through its declaration's encoder (rule 6), which may call this."""
        ...

    def feed(self, data: bytes) -> list[Reply]: ...
    def awaiting_reply(self) -> bool: ...
    def harmless(self, junk: bytes) -> bool:
        """Is this non-reply text something a healthy controller emits (a banner, a log line)?"""
        ...

    def encode_enable(self) -> bytes | None:
        """Switch automatic motion on (SatEL ``g``); None where there is no such switch."""
        ...

    def encode_connect(self, now_unix: float) -> list[bytes]:
        """Frames to send right after the port opens (identify, version, clock, enable)."""
        ...

    def wire_target(self, az_deg: float, el_deg: float | None) -> tuple[float, float | None]:
        """The position the controller will actually be sent (after its rounding)."""
        ...


class HalfLine(enum.Enum):
    """Rule 9: what the box may hold in its line buffer when a stop is written."""

    NONE = "none"  # a frame went on this connection already: its end ended any half frame
    HARMLESS = "harmless"  # the connection's first frame; what the last cut is no move
    MOVE = "move"  # the connection's first frame; a target of the last may have been cut


@runtime_checkable
class StopsOnTheLine(Protocol):
    """Rule 9: a codec whose stop depends on what the line carried before it: ``half`` what
    the box may hold; ``axes``, where the stop is a frame to each axis, the order they go in
    (their ``ModelSpec.axis_prefixes``; None: the codec's own order); ``ready``, the axes whose
    stop frame the line would write at once, no axis gap to wait (session/link.py rule 10;
    None: every axis, or no gap kept). It opens the stop's exchange as ``encode_stop``."""

    def encode_stop_after(
        self, half: HalfLine, axes: bytes | None = None, ready: bytes | None = None
    ) -> bytes | list[bytes]: ...


@runtime_checkable
class PacedConnect(Protocol):
    """A codec whose connect frames owe their replies from their own writes, not from
    ``encode_connect`` (session/link.py rule 14: each is written when the line takes it, on a
    half-duplex line only once the one before was answered): told of each as it is written."""

    def connect_written(self, frame: bytes) -> None: ...


@runtime_checkable
class WatchesWrites(Protocol):
    """A codec told of every frame as it is written (session/link.py ``write``), not only as
    it is encoded: a frame encoded may wait and be dropped unwritten (link.py rule 10: a
    target's second axis, behind the axis gap, when a stop comes). An RC2800 orders its stop
    by the axes the bridge has just set turning (rc2800.py rule 9)."""

    def frame_written(self, frame: bytes) -> None: ...


@runtime_checkable
class TakesReadings(Protocol):
    """A codec told which of its positions the engine took as readings (link.py rule 9: a
    position whose exchange a second reply spoiled is none). A composite's elevation box sends
    back the azimuth of a reading taken, never of a glitch dropped (axes.py rule 2)."""

    def taken(self, reply: PositionReply) -> None: ...


@runtime_checkable
class ScalesAzimuth(Protocol):
    """A codec that judges its azimuth against the scale of the model configured (gs232.py
    rule 2: past it, a MISFIT), told when its box's azimuth is never turned (a composite's
    elevation box, axes.py rules 2 and 5: that channel reads whatever it reads, within what
    the codec can read at all, and is never the antenna's)."""

    def azimuth_unturned(self) -> None: ...


@runtime_checkable
class ScalesElevation(Protocol):
    """A codec that judges its elevation against its axis's range (rule 10: past the slack,
    the whole reply spoiled, its azimuth too), told when its box's elevation is never turned
    nor read (a composite's azimuth box, axes.py rule 1): that channel reads whatever the
    reply's form carries, spoils nothing, and is never the antenna's (review 98: a G-5500's
    box whose elevation input read 190 gave no azimuth reading at all, the rotator offline
    for good; the mirror of ScalesAzimuth)."""

    def elevation_unread(self) -> None: ...


@runtime_checkable
class HoldsOnGrid(Protocol):
    """A codec whose targets snap to a grid its readings do not show exactly (a Rot2Prog at
    0.25 degrees reads 44.25 as 44.2, and a target 44.2 snaps down to 44.0): what to ask for
    to keep an axis where the controller said it is (axes.py rules 1 and 2: the axis of a
    composite's box that is never turned)."""

    def held(self, deg: float, axis: str) -> float: ...


class SettingKind(enum.StrEnum):
    BOOL = "bool"  # on or off (ON/OFF on its topic): a Home Assistant switch
    NUMBER = "number"  # a value in a range, on a step, in a unit: a Home Assistant number
    CHOICE = "choice"  # one of named values: a Home Assistant select


class SendWhen(enum.StrEnum):
    """When the engine may write a setting (session/options.py rule 1)."""

    # only with the rotor at rest and settled, no target waiting (a controller that takes no
    # input while turning, or stops on it: the Rotor-EZ)
    AT_REST = "at_rest"
    # whenever the line is free, turning or not (a controller that takes any command at any
    # time and applies it to the move in progress: the GS-232's speed); never during a silent
    # slew or before a stop that is due
    ANYTIME = "anytime"


@dataclass(frozen=True)
class Setting:
    """One controller setting, as data (rule 6)."""

    name: str  # the topic's last part (R/option/<name>), the state file's key
    label: str  # what a user reads (Home Assistant's entity name, the docs)
    encode: Callable[[SettingValue], bytes]  # the codec's: a value already ``read``, as bytes
    kind: SettingKind = SettingKind.BOOL
    minimum: float = 0.0  # NUMBER: the range, inclusive
    maximum: float = 0.0
    step: float = 1.0  # NUMBER: values are minimum + n * step
    unit: str = ""  # NUMBER: e.g. "deg/s"
    choices: tuple[str, ...] = ()  # CHOICE: the named values, in the order a user sees them
    when: SendWhen = SendWhen.AT_REST
    # the controller forgets it at power-off: sent again after every (re)connect, a power-on
    # byte and while idle every OPTIONS_REFRESH_S (session/options.py); False: sent once when set
    resend: bool = True
    # what it changes in the motion model: the rotor's speeds, both axes, are the configured
    # (or nominal) ones times the factor of the value in effect (a choice's name or a number
    # as text, "ON"/"OFF" for a bool); a value not named leaves them as they are
    speed_factors: dict[str, float] = field(default_factory=dict)

    def read(self, value: SettingValue) -> SettingValue:
        """``value`` (typed, or text as a user sent it) as this setting's own type, or
        ValueError with words a user can act on (rule 6)."""
        if self.kind is SettingKind.BOOL:
            return _read_bool(self.name, value)
        if self.kind is SettingKind.CHOICE:
            text = str(value).strip() if not isinstance(value, bool) else ""
            for choice in self.choices:
                if text.casefold() == choice.casefold():
                    return choice
            raise ValueError(
                f"{self.name}: {str(value)[:20]!r} is not one of {', '.join(self.choices)}"
            )
        return self._read_number(value)

    def _read_number(self, value: SettingValue) -> float:
        try:
            if isinstance(value, bool):
                raise ValueError
            number = float(value)
        except ValueError:
            raise ValueError(f"{self.name}: expected a number, got {str(value)[:20]!r}") from None
        unit = f" {self.unit}" if self.unit else ""
        span = f"{self.minimum:g}..{self.maximum:g}{unit}"
        if not math.isfinite(number) or not self.minimum <= number <= self.maximum:
            shown = shown_past(number, self.minimum, self.maximum)  # (4.0000001: not "4")
            raise ValueError(f"{self.name}: {shown} is outside {span}")
        steps = (number - self.minimum) / self.step
        if abs(steps - round(steps)) > 1e-6:
            raise ValueError(f"{self.name}: {number:g} is not on a step of {self.step:g} in {span}")
        return number

    def speed_factor(self, value: SettingValue) -> float:
        """What ``value`` does to the rotor's speeds (1.0: nothing)."""
        if isinstance(value, bool):
            key = "ON" if value else "OFF"
        else:
            key = f"{value:g}" if isinstance(value, float | int) else value
        return self.speed_factors.get(key, 1.0)


def _read_bool(name: str, value: SettingValue) -> bool:
    if isinstance(value, bool):
        return value
    text = str(value).strip().lower()
    if text in ("on", "1", "true"):
        return True
    if text in ("off", "0", "false"):
        return False
    raise ValueError(f"{name}: expected ON or OFF, got {str(value)[:20]!r}")


class Plain:
    """What most codecs send nothing for: no version query, no options, no motion switch,
    nothing at connect (RT-21, GS-232, Easycomm, SPID, RC2800, Prosistel). The codec names its
    controller in ``BOX``; a codec that has one of them writes its own."""

    BOX: ClassVar[str]

    def encode_version(self) -> bytes | None:
        return None

    def encode_option(self, name: str, enabled: bool) -> bytes:
        raise ValueError(f"{self.BOX} has no options the bridge switches")

    def encode_enable(self) -> bytes | None:
        return None

    def encode_connect(self, now_unix: float) -> list[bytes]:
        return []


LATE_LINES_MAX = 16  # rule 7: the polls given up in a silence timeout (a 3 s adapter stall)
SAID_KEEP = LATE_LINES_MAX  # rule 7: every line owed late, come in one quiet spell


class LateAnswers(ABC):
    """Rule 7's bookkeeping of answers owed after their reply time, for any codec that says
    whether a reply is awaited (``awaiting_reply``, its own): OneQuery's codecs, and those that
    count what is owed their own way (SPID, RC2800, Rotor-EZ)."""

    _late_lines: int = 0  # rule 7: lines of answers to queries given up that may still come
    _harmless_lines: tuple[bytes, ...] = ()  # rule 7: late answers (and the codec's own)

    @abstractmethod
    def awaiting_reply(self) -> bool: ...

    @property
    def owes_late(self) -> bool:
        """Rule 7: lines of an answer to a query given up may still come."""
        return self._late_lines > 0

    def _owe_late(self, lines: int) -> None:
        """Rule 7: the query open is given up; ``lines`` of its answer may still come."""
        self._late_lines = min(LATE_LINES_MAX, self._late_lines + lines)

    def _late_answer(self, raw: bytes, out: list[Reply]) -> bool:
        """Rule 7: ``raw``, a clean reply line, is one owed by a query given up (True: said as
        such in ``out``); False while a reply is awaited or none is owed."""
        if self.awaiting_reply() or not self._late_lines:
            return False
        self._late_lines -= 1
        self._say(raw)
        out.append(JunkReply(raw, JunkReason.UNSOLICITED, LATE_ANSWER))
        return True

    def _say(self, raw: bytes) -> None:
        """Rule 7: ``raw`` was told harmless (the last SAID_KEEP such lines are kept)."""
        self._harmless_lines = (*self._harmless_lines, raw)[-SAID_KEEP:]

    def _unsaid(self, junk: bytes) -> bytes:
        """Rule 7: ``junk`` without the lines told harmless, each as often as it was told."""
        for said in self._harmless_lines:
            junk = junk.replace(said, b"", 1)
        return junk


class OneQuery(Plain, LateAnswers):
    """Rule 3's bookkeeping for a controller asked one question at a time (GS-232, Easycomm,
    RT-21, Prosistel): the query open and whether junk came within it. The codec calls
    ``_open_query`` from encode_query and ``_junk`` for bytes that are no reply."""

    _query_open: bool = False
    _noisy: bool = False  # junk arrived since the query was opened

    def _open_query(self) -> None:
        self._query_open = True
        self._noisy = False

    def expire_query(self) -> None:
        self._query_open = False

    def awaiting_reply(self) -> bool:
        return self._query_open

    def _junk(self, raw: bytes, reason: JunkReason, why: str, out: list[Reply]) -> None:
        if self._query_open:
            self._noisy = True
        out.append(JunkReply(raw, reason, why))


POT_SLACK_DEG = 3  # rule 10: a potentiometer read in whole degrees, set by hand at the box
TENTHS_SLACK_DEG = 0.5  # rule 10: a sensor read in tenths; under a whole degree


def read_in_range(value: float, low: float, high: float, slack: float) -> float | None:
    """Rule 10: a reading ``value`` of an axis whose range is ``low``..``high``: as it is within
    it, the end it passed by at most ``slack``, None (no reading) past that."""
    if low - slack <= value < low:
        return float(low)
    if high < value <= high + slack:
        return float(high)
    return float(value) if low <= value <= high else None


def half_up(value_deg: float, per_deg: int) -> int:
    """``value_deg`` in steps of 1/``per_deg`` degree (1: whole degrees, 10: tenths), rounded
    half up: what a controller that takes whole degrees or tenths is sent, one formula for
    every codec and for the judge that checks what they send (pointing.py rule 4)."""
    return math.floor(value_deg * per_deg + 0.5)


def half_up_step(value_deg: float, step_deg: int) -> int:
    """``value_deg`` rounded half up to a multiple of ``step_deg`` whole degrees: what a
    controller whose rotors stop only at such steps is sent (a SatEL's ten, satel.py rule 7),
    the same for its codec and the judge (pointing.py rule 4)."""
    return half_up(value_deg / step_deg, 1) * step_deg


def tenths(value_deg: float, top_deg: float, axis: str) -> float:
    """``value_deg`` rounded half up to tenths of a degree; outside 0..``top_deg`` a ValueError
    that names the ``axis``."""
    value = half_up(value_deg, 10)
    if not 0 <= value <= top_deg * 10:
        raise ValueError(f"{axis} {value_deg:g} outside 0..{top_deg:g}")
    return value / 10


def tenths_pair(
    az_deg: float, el_deg: float | None, az_top_deg: float, el_top_deg: float | None
) -> tuple[float, float | None]:
    """A target in tenths (``tenths``): the azimuth, and the elevation (0 when none is named)
    on a controller with one (``el_top_deg`` not None), else None."""
    az = tenths(az_deg, az_top_deg, "azimuth")
    if el_top_deg is None:
        return az, None
    return az, tenths(el_deg or 0.0, el_top_deg, "elevation")


class HamlibRotType(enum.StrEnum):
    """Hamlib's ``rot_type`` of a model, as its rotctld prints it in ``dump_state``."""

    AZ = "Az"
    EL = "El"
    AZEL = "AzEl"
    OTHER = "Other"  # what Hamlib's rotorez backend calls its Rotor-EZ family


# Idle polling takes at most this share of the line (half duplex: of its time), but is never
# more frequent than MIN_IDLE_POLL_S: a still rotor's bearing need not be fresher than that.
IDLE_LINE_SHARE = 0.045  # at most 5 % of the line, with room for how it is measured
MIN_IDLE_POLL_S = 1.0


@dataclass(frozen=True)
class ModelSpec:
    """Everything the bridge needs to know about one controller model, as data."""

    name: str  # registry key, used in the configuration
    display_name: str
    manufacturer: str
    codec_factory: Callable[[], Codec]
    baud: int
    bytesize: int = 8
    parity: str = "N"
    stopbits: int = 1
    can_report_position: bool = True
    has_elevation: bool = False
    turns_azimuth: bool = True  # False: a composite's elevation box (axes.py rule 2)
    has_version: bool = False
    settings: tuple[Setting, ...] = ()  # the controller's own settings, as data (rule 6)
    brake_delay_s: float = 0.0
    retarget: RetargetPolicy = RetargetPolicy.DIRECT
    az_min_deg: float = 0.0
    az_max_deg: float = 360.0
    el_min_deg: float = 0.0
    el_max_deg: float = 0.0
    az_wraps: bool = True  # 0 and 360 are the same direction
    # on a scale that wraps, 0 and 360 are the two ends of the rotor's travel, its stop at north
    # (a Yaesu rotor's, as a GS-232 or a RotorCard turns it; an Easycomm, Prosistel, RC2800 or
    # SatEL box's 0..360): False where north is the middle of the travel (a Hy-Gain rotor's
    # stop is at south: Rotor-EZ, DCU-1) or the box is never sent 360 and picks the way itself
    # (RT-21, whose north is 000.0). A nudge across north stops at an end (pointing.py rule 6)
    az_ends_at_north: bool = True
    # the rotor's stop is at south, raw 180, and the box turns it the one way its travel allows
    # (a Hy-Gain rotor behind a Rotor-EZ or a DCU-1): every turn between east and west passes
    # north (pointing.py rule 4); not an RT-21's, which may drive either kind of rotor
    stop_at_south: bool = False
    reply_timeout_s: float = 0.3
    inter_frame_gap_s: float = 0.0  # pause between the frames of one multi-frame command
    # the controller needs this long between commands to its two axes (RC2800): no frame goes
    # sooner after the one before it to the other axis, a command's frames go this far apart,
    # a stop's first too (the azimuth's: at once, or when the gap ends; session/link.py rule 10)
    axis_gap_s: float = 0.0
    # it turns its two axes one after the other, not together (the axis waiting its turn does
    # not move): movement on either counts as progress for both (session/motion.py rule 3).
    # None of the families here does (each fact sheet and emulator: both axes turn at once)
    axes_in_turn: bool = False
    # how a frame names the axis it is for (its first bytes: RC2800 b"A", b"E"): frames to the
    # same axis need no axis gap between them
    axis_prefixes: tuple[bytes, ...] = ()
    full_duplex: bool = True  # may a command be written while a reply is still coming?
    stop_interrupts: bool = False  # a stop may go out while a (slew) reply is owed
    # the stop frame may reach the controller at any moment, between any two frames the session
    # writes, and what the controller answers to it (nothing, a blank line, a banner) the codec
    # takes unasked: the stop express may write it ahead of the session (interfaces/mqtt/express.py)
    stop_anytime: bool = False
    # its connect's frames begin with its stop (SatEL: satel.py rule 2): a replug stops a turn
    # the port dropped (session/controller.py rule 13)
    connect_stops: bool = False
    reports_while_moving: bool = True  # False: silent until the after-move report (SatEL)
    nominal_el_speed_deg_s: float = 1.0
    # the controller takes whole degrees, rounded half up (False: finer, or learned at run time)
    whole_degrees: bool = False
    # ... and turns to a multiple of this many degrees, the nearest to the value sent (a SatEL's
    # rotors move in ten-degree steps: its codec sends what it reaches, satel.py rule 7)
    steps_deg: int = 1
    tenths: bool = False  # it takes tenths of a degree, rounded half up (``tenths``)
    cuts_down: bool = False  # it cuts a value down to its resolution, learned from its replies
    # a composite's elevation box's (whole_degrees, tenths, cuts_down, steps_deg); None: as the
    # four above, which are then the azimuth box's (pointing.py rule 4: each axis by its box)
    el_rounding: tuple[bool, bool, bool, int] | None = None
    noise_deg: float = 0.0  # analog jitter of a still rotor's readings
    # what becomes of a turn nobody asked for by default (session/controller.py rule 10):
    # "follow"; "stop" where a poll one flipped bit makes a command that turns the rotor
    # (Easycomm's EL, ML), or one stray byte does (an RC2800's A CR, A5 CR); "after-stop"
    # where it makes one that turns it to its last target's bearing (a Rotor-EZ's AI1; read
    # as AM1;)
    unasked_moves: str = "follow"
    # the same on a composite's elevation box of this model (its azimuth channel turns nothing):
    # "follow", but "stop" where a poll of the elevation one stray byte makes a target (an
    # RC2800's E CR, E5 CR)
    el_unasked_moves: str = "follow"
    # typical speeds, until the user sets the real ones (az_speed_deg_s, el_speed_deg_s): travel
    # estimates without feedback (DCU-1), a silent slew's estimate and bound (SatEL)
    nominal_speed_deg_s: float = 6.0
    # one position poll on the wire: the query frame and the controller's reply to it, in bytes
    # (0 and 0 for a controller that cannot be asked); the default idle poll interval comes
    # from these (default_idle_poll_interval_s)
    query_bytes: int = field(kw_only=True)
    reply_bytes: int = field(kw_only=True)
    # the shortest reply a poll can get where its width varies with the value (0: reply_bytes,
    # the longest): what session/link.py rule 11 measures an answer torn past any form against
    least_reply_bytes: int = 0
    # the bytes a controller refuses a target with (GS-232's ``?>`` CR: 3), 0 if it never does:
    # no poll goes out before such a refusal can have come (session/link.py rule 4)
    refusal_bytes: int = 0
    # what Hamlib knows this model as (rotctld's dump_state, dump_caps and get_info)
    hamlib_model: int = field(kw_only=True)  # Hamlib's rotator model number (rotctl -m)
    hamlib_rot_type: HamlibRotType = field(kw_only=True)
    # get_info's text; None where Hamlib's backend has no get_info (rotctld then says "None")
    hamlib_info: str | None = field(default=None, kw_only=True)
    # Hamlib's backend reads the controller's 360 as 0 (the Rotor-EZ family's ``;360``, the
    # RT-21's ``360.0;``); the others pass it on as 360 (GS-232, Easycomm, SatEL, Prosistel,
    # RC2800): rotctld's ``p`` answers as Hamlib's would (interfaces/rotctld/commands.py)
    hamlib_folds_360: bool = field(default=False, kw_only=True)

    @property
    def options(self) -> tuple[str, ...]:
        """The names of the controller's settings (R/option/<name>), in declared order."""
        return tuple(s.name for s in self.settings)

    def setting(self, name: str) -> Setting | None:
        return next((s for s in self.settings if s.name == name), None)

    @property
    def reading_step_deg(self) -> float:
        """The step its readings move in, as the bridge counts it: a whole degree where it
        takes whole degrees, else a tenth (the settle time and the try more allow for it)."""
        return 1.0 if self.whole_degrees else 0.1

    def speeds_deg_s(
        self, az_deg_s: float | None = None, el_deg_s: float | None = None
    ) -> tuple[float, float]:
        """The rotor's (azimuth, elevation) speeds: the user's where set, else this model's
        nominal ones. The one place a speed default comes from."""
        return (
            self.nominal_speed_deg_s if az_deg_s is None else az_deg_s,
            self.nominal_el_speed_deg_s if el_deg_s is None else el_deg_s,
        )

    def exchange_time_s(self, baud: int | None = None) -> float:
        """How long one position poll (query and reply) occupies the line at ``baud``
        (start, data, parity and stop bits of every byte; the model's default rate if None)."""
        bits = 1 + self.bytesize + (0 if self.parity == "N" else 1) + self.stopbits
        return (self.query_bytes + self.reply_bytes) * bits / (baud or self.baud)

    def default_idle_poll_interval_s(self, baud: int | None = None) -> float:
        """The idle poll interval that leaves the line at least 95 % free (IDLE_LINE_SHARE),
        never below MIN_IDLE_POLL_S; rounded up to a tenth of a second."""
        interval = self.exchange_time_s(baud) / IDLE_LINE_SHARE
        return max(MIN_IDLE_POLL_S, math.ceil(interval * 10 - 1e-9) / 10)
