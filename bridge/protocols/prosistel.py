"""Prosistel D (one rotor: azimuth or elevation) and Combi-Track (azimuth and elevation): the codec.

Device: Prosistel's rotator controllers. The D series (and the PRO series, which speaks the same)
drives one rotor in whole degrees, as unit A (azimuth, 0..360) or unit E (elevation, 0..90); a D
box set up as an azimuth box but fitted to an elevation rotor answers as unit A, in 0..90
(Hamlib's "D elevation CBOX az"). The Combi-Track drives an azimuth and an elevation rotor as
two units, A and B, in tenths of a degree. 9600 8N1, no flow control. Every frame starts with
STX (0x02) and ends with CR; a command is the unit's letter, the command's letter and its value
(``STX A G 123 CR``), and every command is answered by the unit, the command and what it says,
comma-separated (``STX A,?,123,B CR``). Some boxes send their position over and over unasked
(continuous position monitoring, CPM) until ``STX A S CR`` turns it off.
Sources: the project's protocol sheet (Prosistel's documents as gathered there); Hamlib 4.5.4's
prosistel backend (prosistel.c: models 1701 D azimuth, 1702 D elevation, 1703 Combi-Track, 1704
D elevation CBOX az, an elevation rotor on unit A; its commands, its unit letters, its stop
values and the reply examples in its comments) and its author's notes in Hamlib's tracker (the
D tried on a PST-61D; the three families).

Frames we send (STX written ``^B``):
  ``^BAG123\\r``            turn unit A to 123 (D: degrees; Combi-Track: ``^BAG1234\\r``, tenths),
                           without leading zeros, as Hamlib sends them to a PST-61D
  ``^BA?\\r``               ask unit A's position: ``^BA,?,123,R\\r`` (R: running, B: braked)
  ``^BAG999\\r``            stop at once (the hard stop; Combi-Track ``^BAG9999\\r`` per unit)
  ``^BAS\\r``               at open: no continuous position output (per unit)
The Combi-Track's units go one frame each: A, then B, for a target, a query, a stop. A D on an
elevation rotor is sent the same frames for unit E (or for unit A, a box set up as an azimuth
box: prosistel-el-a); its elevation is that rotator's bearing (the box has no azimuth), as with
one box of an az/el pair on two ports.
Not sent: the soft stop (``G997``, Combi-Track ``G9777``): with the box's PWM ramps on it slows
the rotor down over the ramp, so the rotor goes on turning after the user's STOP; the hard stop
stops it where it is (rule 4).

Rules:
1. Frames end at CR; what comes on a line before its last STX is line noise. The first line of a
   connection may have lost its head: a box that streams its position (rule 2) was mid-line when
   the port opened, and the open's flush (or the adapter, closed till then) took the line's STX
   and first bytes. Such a line, with no STX and the form of a position's tail (``50,B``,
   ``A,?,050,B``), is the box's chatter (never a reading; harmless while no junk follows it; a
   query it came in is not trusted, rule 3); any other first line is noise, as ever, and so is a
   line with no STX anywhere later. A position is ``STX u,?,n,s`` with n one to four digits and
   s a status letter; it is read only while a query is open and for a unit this model has, and
   the query is answered once every unit has said its position (two lines on the Combi-Track, in
   any order). A value past the top of the unit's range (azimuth 360, elevation 90) by at most
   its family's read slack is read as that end (base.py rule 10): a D's, POT_SLACK_DEG, a pot
   read in whole degrees (noise_deg 1; ``A,?,361`` at north, ``E,?,091`` at the zenith, as
   axes.py rule 2 reads a one-axis elevation box past its end); a Combi-Track's,
   TENTHS_SLACK_DEG, an encoder read in tenths (noise_deg 0.2; ``A,?,3601``, ``B,?,0901``)
   (attack 30: spoiled there, a box at rest at its end went offline for good, and one
   wandering a tenth either side of it was told as junk every 30 s). Further past is
   spoiled. A Combi-Track whose elevation is never turned nor read (a composite's azimuth
   box, axes.py rule 1) is judged by no elevation range (``elevation_unread``): unit B's
   four digits, whatever they say, are read as they read and spoil nothing of the azimuth
   (review 98, as a GS-232's ``EL=190``: spoiled, every reply was, the rotator offline for
   good, its azimuth never turned).
2. A position nobody asked for (the box's continuous output, or a unit's second line in one
   exchange) is the box's own chatter: harmless, never a reading, never a spoiler; but only a
   position this box can say (its unit, its width, in range or within rule 1's slack): any
   other is told, asked for or not (an attack pass: ``A,?,365,B`` or a Combi-Track's
   ``B,?,0950,B`` was dropped and asked again, and nobody was told). The bridge
   turns the output off at open; a box that streams anyway (power-cycled, say) costs nothing.
3. The answers to ``G`` and ``S`` are chatter too, whatever their payload; an answer that says
   ``E,<code>`` is the box's refusal or error (SPOILED, its code in the detail, not harmless).
   On a D, whose target is one ``G``, an error answering a ``G`` is the box's refusal of it
   (REFUSED, as the GS-232's ``?>``): a target it refuses that has not moved the rotor is
   dropped at once and said refused, not waited on until the stall check calls the rotor stuck
   (motion.py rule 8). On the Combi-Track a target is a ``G`` per unit and the other unit's may
   have turned its rotor: SPOILED, and the stall check judges the target.
   Any junk within an open query makes its reading UNTRUSTED (the engine asks again at once).
4. STOP is the hard stop (999; 9999 on the Combi-Track): a user's STOP and a lock stop the
   rotor where it is. Each lies outside its own family's targets, but not outside the other's:
   a Combi-Track set up as a D would read the D's 999 as a bearing, 99.9 degrees (rule 6 is
   how that set-up shows itself before anyone relies on its STOP).
5. Targets are whole degrees (D) or tenths (Combi-Track), rounded half up; outside azimuth
   0..360 or elevation 0..90 (a D elevation's bearing too) they are refused before anything is
   sent.
6. A D says its position in one to three digits (``A,?,290,R``), a Combi-Track in four, zero
   padded (``B,?,0900,R``). A position of the other family's width is a box set up as the
   wrong model: never a reading (a Combi-Track at 35.0 degrees read as 350), its detail says
   so, and the rotator never becomes available to be sent targets.
7. A query whose reply time ran out may still be answered (base.py rule 7): the lines of its
   units that had not said their position are owed late. A clean position of a unit this
   model has, in range, that comes with no query open while one is owed is one of them:
   UNSOLICITED, so that it spoils a reading held in the same exchange (rule 2's chatter does
   not), harmless, and never a reading. A line that comes while the next query is open is
   that query's, as ever. (A loaded host: a poll's answer and the next poll's came together,
   the older was taken as the newer poll's reading, and the newer, chatter, spoiled nothing:
   a Combi-Track turning at 6 degrees a second was shown 4 degrees behind where it was.)
8. A position's last letter says whether that unit's motor runs (``R``) or is braked (``B``;
   the protocol sheet; Hamlib reads past it): a reading drives a motor if any unit's says
   ``R``, none if every unit's says ``B`` (base.py rule 8), and says nothing of it where a unit
   gave another letter. (A box power-cycled mid-turn forgets its turn and says ``B``: read
   past, the rotor it left standing was called stalled 10 s later, and rotor health counted a
   stall.)
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from dataclasses import dataclass, replace
from typing import Any

from bridge.protocols.base import (
    POT_SLACK_DEG,
    TENTHS_SLACK_DEG,
    HamlibRotType,
    JunkReason,
    JunkReply,
    ModelSpec,
    OneQuery,
    PositionReply,
    Reply,
    RetargetPolicy,
    half_up,
    read_in_range,
)

STX = b"\x02"
AZ_MAX_DEG = 360
EL_MAX_DEG = 90
_MAX_LINE = 32
_POSITION = re.compile(rb"\x02(?P<unit>[A-Z]),\?,(?P<value>\d{1,4}),(?P<state>[A-Z])")
_DRIVING = {b"R": True, b"B": False}  # rule 8: running, braked; any other letter says neither
_ERROR = re.compile(rb"\x02(?P<unit>[A-Z]),(?P<cmd>.),E,(?P<code>\d*)")
_ANSWER = re.compile(rb"\x02(?P<unit>[A-Z]),(?P<cmd>[^?\r]),[^\r]*")
# what a healthy box emits besides replies (rules 2 and 3): blank lines, answers without an
# error, positions
_CHATTER = re.compile(rb"(?:[\r\n ]|\x02[A-Z],[^?\r],(?!E,)[^\r]*\r|\x02[A-Z],\?,\d{1,4},[A-Z]\r)*")
# rule 1: what a position line (``STX u,?,n,s CR``) can be once its head is cut off
_TAIL = re.compile(rb"(?:(?:(?:[A-Z]?,)?\?)?,\d{1,4}|\d{0,4}),[A-Z]\r|[A-Z]\r")


@dataclass(frozen=True)
class Family:
    """What a box of one family is on the wire: its units (the bridge's bearing first), the top
    of each unit's range in degrees, its scale (1: degrees, 10: tenths), its hard stop, how
    many digits its positions have (rule 6) and how far past a top a reading is that top
    (rule 1, base.py rule 10)."""

    units: tuple[str, ...]
    tops: tuple[int, ...]
    scale: int
    hard_stop: int
    digits: range
    slack: float


# rule 1: a D reads a pot in whole degrees, a Combi-Track an encoder in tenths
D_AZIMUTH = Family(("A",), (AZ_MAX_DEG,), 1, 999, range(1, 4), POT_SLACK_DEG)
# a D on an elevation rotor: its one unit, E, is the rotator's bearing (0..90)
D_ELEVATION = Family(("E",), (EL_MAX_DEG,), 1, 999, range(1, 4), POT_SLACK_DEG)
# ... and one set up as an azimuth box (Hamlib's "D elevation CBOX az"): the same, as unit A
D_ELEVATION_UNIT_A = Family(("A",), (EL_MAX_DEG,), 1, 999, range(1, 4), POT_SLACK_DEG)
COMBI_TRACK = Family(("A", "B"), (AZ_MAX_DEG, EL_MAX_DEG), 10, 9999, range(4, 5), TENTHS_SLACK_DEG)


def _value(deg: float, top: int, scale: int, axis: str) -> int:
    value = half_up(deg, scale)
    if not 0 <= value <= top * scale:
        raise ValueError(f"{axis} {deg:g} outside 0..{top}")
    return value


class ProsistelCodec(OneQuery):
    """Codec for one Prosistel box: a D on one rotor (unit A or E), or a Combi-Track's two."""

    BOX = "a Prosistel box"

    def __init__(self, family: Family = D_AZIMUTH) -> None:
        self.family = family
        self.elevation = len(family.units) == 2
        self._buf = bytearray()
        self._query_open = False
        self._noisy = False  # junk arrived since the query was opened
        self._said: dict[str, float] = {}  # what this exchange's units have said so far
        self._driving: dict[str, bool | None] = {}  # rule 8: and whether each drives its motor
        self._first = True  # rule 1: no line of this connection has ended yet
        self._cut = b""  # rule 1: the connection's first line, a position's tail
        self._el_unread = False  # rule 1: its elevation judged by no range (elevation_unread)

    # -- encoding -------------------------------------------------------------------------
    def wire_target(self, az_deg: float, el_deg: float | None = None) -> tuple[float, float | None]:
        scale, tops = self.family.scale, self.family.tops
        az = _value(az_deg, tops[0], scale, "azimuth" if tops[0] == AZ_MAX_DEG else "bearing")
        if not self.elevation:
            return az / scale, None
        return az / scale, _value(el_deg or 0.0, tops[1], scale, "elevation") / scale

    def encode_target(self, az_deg: float, el_deg: float | None = None) -> list[bytes]:
        values = [v for v in self.wire_target(az_deg, el_deg) if v is not None]
        return [
            STX + b"%sG%d\r" % (unit.encode(), round(v * self.family.scale))
            for unit, v in zip(self.family.units, values, strict=True)
        ]

    def encode_stop(self) -> bytes:
        return self._each(b"G%d" % self.family.hard_stop)

    def encode_query(self) -> bytes:
        self._open_query()
        self._said, self._driving = {}, {}
        return self._each(b"?")

    def encode_connect(self, now_unix: float) -> list[bytes]:
        return [self._each(b"S")]  # no continuous position output

    def expire_query(self) -> None:
        if self._query_open:  # rule 7: the units that had not answered may still
            self._owe_late(len(self.family.units) - len(self._said))
        super().expire_query()

    def harmless(self, junk: bytes) -> bool:
        if self._cut and junk.startswith(self._cut):  # rule 1: the connection's first line
            junk = junk[len(self._cut) :]
        if _CHATTER.fullmatch(junk) is None:
            return False
        # rule 2's positions are this box's own: one out of range or of the other family's
        # width, or of a unit it has not got, is told (rules 1 and 6)
        lines = _POSITION.finditer(junk)
        return all(self._misfit(m["unit"].decode(), m["value"]) is None for m in lines)

    def _junk(self, raw: bytes, reason: JunkReason, why: str, out: list[Reply]) -> None:
        self._cut = b""  # rule 1: excused only while nothing but chatter came after it
        super()._junk(raw, reason, why, out)

    def _each(self, command: bytes) -> bytes:
        return b"".join(STX + unit.encode() + command + b"\r" for unit in self.family.units)

    # -- decoding -------------------------------------------------------------------------
    def feed(self, data: bytes) -> list[Reply]:
        self._buf += data
        out: list[Reply] = []
        while (end := self._buf.find(b"\r")) != -1:
            line = bytes(self._buf[: end + 1])
            del self._buf[: end + 1]
            self._line(line, out)
        if len(self._buf) > _MAX_LINE:
            self._junk(bytes(self._buf), JunkReason.NOISE, "line too long", out)
            self._buf.clear()
            self._first = False
        return out

    def _line(self, raw: bytes, out: list[Reply]) -> None:
        start = raw.rfind(STX)
        first, self._first = self._first, False
        if start == -1 and first and _TAIL.fullmatch(raw):  # rule 1: cut by the port's opening
            self._cut = raw
            self._noisy = self._noisy or self._query_open  # (a query it came in is not trusted)
            out.append(JunkReply(raw, JunkReason.CHATTER, "a line the port's opening cut"))
            return
        if start == -1:
            if raw.strip(b"\r\n "):
                self._junk(raw, JunkReason.NOISE, "not a reply line", out)
            else:
                out.append(JunkReply(raw, JunkReason.CHATTER, "blank line"))
            return
        clean = not raw[:start].strip(b"\r\n ")
        if not clean:  # rule 1: noise in front of the frame
            self._junk(raw[:start], JunkReason.NOISE, "not a reply", out)
        frame = raw[start:]
        body = frame.rstrip(b"\r")
        if m := _ERROR.fullmatch(body):
            code, cmd = m.group("code").decode(), m.group("cmd").decode("latin-1")
            why = f"unit {m.group('unit').decode()} answered {cmd} with error {code}"
            # rule 3: a D's target is its one G: an error to it is the box's refusal
            refused = cmd == "G" and not self.elevation
            self._junk(frame, JunkReason.REFUSED if refused else JunkReason.SPOILED, why, out)
            if cmd == "G" and self.elevation:  # a Combi-Track's: that unit's axis is not driven
                first = m.group("unit").decode() == self.family.units[0]
                junk = out[-1]  # (the JunkReply just made)
                assert isinstance(junk, JunkReply)
                out[-1] = replace(junk, axis="azimuth" if first else "elevation")
        elif _ANSWER.fullmatch(body):
            out.append(JunkReply(frame, JunkReason.CHATTER, "the answer to a command"))
        elif m := _POSITION.fullmatch(body):
            self._position(frame, m, clean, out)
        else:
            self._junk(frame, JunkReason.NOISE, "not a reply line", out)

    def _misfit(self, unit: str, digits: bytes) -> tuple[JunkReason, str] | None:
        """Why a position line of ``unit`` saying ``digits`` is none of this box's (rules 1 and
        6); None if it is one."""
        units = self.family.units
        if unit not in units:
            return JunkReason.NOISE, f"a position of unit {unit}: is the model right?"
        if len(digits) not in self.family.digits:  # rule 6
            form = "tenths (a Combi-Track)" if len(digits) == 4 else "whole degrees (a D)"
            return JunkReason.NOISE, f"a position in {form}: is the model right?"
        if self._read(unit, digits) is None:  # rule 1
            return JunkReason.SPOILED, "position out of range"
        return None

    def _read(self, unit: str, digits: bytes) -> float | None:
        """Rule 1: the bearing ``unit`` says in ``digits``, a little past its top read as the
        top; None past its slack."""
        index = self.family.units.index(unit)
        if self._el_unread and index == 1:  # (a Combi-Track's unit B, never read)
            return int(digits) / self.family.scale
        top = self.family.tops[index]
        return read_in_range(int(digits) / self.family.scale, 0, top, self.family.slack)

    def elevation_unread(self) -> None:
        """Rule 1: the box's elevation is never turned nor read (a composite's azimuth box):
        whatever unit B says spoils nothing of the azimuth (base.ScalesElevation)."""
        self._el_unread = True

    def _position(self, frame: bytes, m: re.Match[bytes], clean: bool, out: list[Reply]) -> None:
        units, unit, digits = self.family.units, m["unit"].decode(), m["value"]
        if (misfit := self._misfit(unit, digits)) is not None:
            self._junk(frame, *misfit, out)
            return
        deg = self._read(unit, digits)
        assert deg is not None  # (_misfit said so)
        if clean and self._late_answer(frame, out):  # rule 7
            return
        if not self._query_open or unit in self._said:  # rule 2
            out.append(JunkReply(frame, JunkReason.CHATTER, "position output nobody asked for"))
            return
        self._said[unit] = deg
        self._driving[unit] = _DRIVING.get(m["state"])
        if len(self._said) < len(units):
            return  # the other unit's line is still to come
        self._query_open = False
        if self._noisy:
            out.append(JunkReply(frame, JunkReason.UNTRUSTED, "position after line noise"))
            return
        out.append(
            PositionReply(
                self._said[units[0]],
                self._said.get(units[-1]) if self.elevation else None,
                driving=_driving(self._driving.values()),
            )
        )


def _driving(flags: Iterable[bool | None]) -> bool | None:
    """Rule 8: the box drives a motor if any unit says so, none if every unit says it is
    braked; None if a unit says neither."""
    said = list(flags)
    if any(said):
        return True
    return None if None in said else False


def _spec(name: str, display: str, family: Family, **kw: Any) -> ModelSpec:
    combi = family is COMBI_TRACK
    digits = 4 if combi else 3
    top = float(family.tops[0])
    query = len(family.units) * len(b"\x02A?\r")
    reply = len(family.units) * len(b"\x02A,?,%s,B\r" % (b"0" * digits))
    defaults: dict[str, Any] = dict(
        manufacturer="Prosistel",
        codec_factory=lambda: ProsistelCodec(family),
        baud=9600,
        has_elevation=combi,
        retarget=RetargetPolicy.DIRECT,  # a new G while turning: the box turns to it
        az_min_deg=0.0,
        az_max_deg=top,
        el_min_deg=0.0,
        el_max_deg=float(EL_MAX_DEG) if combi else 0.0,
        az_wraps=top == AZ_MAX_DEG,  # 0 and 360 are one direction; 0 and 90 of a mast are not
        reply_timeout_s=0.5,
        noise_deg=0.2 if combi else 1.0,  # an encoder read in tenths; a pot in whole degrees
        nominal_speed_deg_s=6.0,
        nominal_el_speed_deg_s=3.0,
        whole_degrees=not combi,
        tenths=combi,  # rule 5
        query_bytes=query,
        reply_bytes=reply,
        hamlib_rot_type=HamlibRotType.AZEL if combi else HamlibRotType.AZ,
        hamlib_info=None,  # Hamlib's prosistel backend has no get_info
    )
    defaults.update(kw)
    return ModelSpec(name=name, display_name=display, **defaults)


# A D on an elevation rotor (either unit): Hamlib's 1702 and 1704 are El rotators, but this
# rotator's bearing is the elevation: the bridge's rotctld port answers it as an azimuth in 0..90,
# and says so in dump_state, so a client's view of the port is one that fits together
_ELEVATION_AS_BEARING: dict[str, Any] = dict(
    hamlib_rot_type=HamlibRotType.AZ,
    nominal_speed_deg_s=3.0,  # an elevation rotor's speed, as the bearing's
)

MODELS: dict[str, ModelSpec] = {
    "prosistel": _spec("prosistel", "D azimuth", D_AZIMUTH, hamlib_model=1701),
    "prosistel-el": _spec(
        "prosistel-el", "D elevation", D_ELEVATION, hamlib_model=1702, **_ELEVATION_AS_BEARING
    ),
    "prosistel-el-a": _spec(
        "prosistel-el-a",
        "D elevation (unit A)",
        D_ELEVATION_UNIT_A,
        hamlib_model=1704,
        **_ELEVATION_AS_BEARING,
    ),
    "prosistel-combi": _spec(
        "prosistel-combi", "Combi-Track az/el", COMBI_TRACK, hamlib_model=1703
    ),
}
