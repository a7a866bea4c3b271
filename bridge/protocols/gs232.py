"""Yaesu GS-232A and GS-232B (and the boxes that speak them: K3NG, ERC, ARS): the codec.

Device: the computer interface of Yaesu's rotator controllers (G-450 to G-2800, G-5500) and of
many clones. 9600 8N1, no flow control. ASCII commands ending in CR; every command is answered:
by a CR where it returns nothing, by data and CR LF where it returns data (CR alone on some
clones); K3NG's firmware sends blank lines after answering ``W``.
Sources: Yaesu's GS-232A/B command tables as gathered on the project's protocol sheet; Hamlib
4.5.4's gs232a backend (gs232a.c, gs232b.c: models 601, 603, 609, 611) and its traffic on the
wire, seen with rotctl against our emulator.

Frames we send:
  ``Mxxx\\r``      turn to azimuth xxx (azimuth-only models)
  ``Wxxx yyy\\r``  turn to azimuth xxx and elevation yyy (az/el models)
  ``C\\r``         ask the azimuth: GS-232A ``+0xxx``, GS-232B ``AZ=xxx``
  ``C2\\r``        ask both: GS-232A ``+0xxx+0yyy``, GS-232B ``AZ=xxx  EL=yyy`` (two spaces on
                  Yaesu's boxes, one or none on some clones)
  ``S\\r``         stop both axes (``A`` and ``E`` stop one axis: AXIS_STOPS, not used by the
                  engine, which always stops everything)
  ``Xn\\r``        the speed setting ``speed``, n = 1 (slowest) .. 4 (fastest), answered by a CR
Not sent: ``P36``/``P45`` (the box's range) is the controller's own setting; ``R L U D`` (turn
until stopped) have no place in a bridge that sends bearings.

Rules:
1. Replies are lines ended by CR or LF; the LF right after a line's CR ends that line with it
   (a CR LF is one end, not a blank line after it: no junk, nothing for the engine to wait out
   at every reading); blank lines (the CR answering ``M W S``, K3NG's blank lines after ``W``)
   are the controller's chatter, never a reading.
2. Only a line of this model's reply form (A or B, three digits a value) is a bearing, only
   while a query is open, and only with values in range (azimuth 0..450, elevation 0..180),
   or past an end by at most READ_SLACK_DEG, read as that end (base.py rule 10: a pot read in
   whole degrees, noise_deg 2, set by hand at the box): K3NG's forms of an elevation up to 3
   degrees below 0, ``EL=00-1`` in the B form and ``-0000`` or ``-000-1`` in the A form, read
   as 0, the horizon (review 39); ``EL=181`` as 180, a G-5500 flipped up to its end (attack
   30); ``AZ=451`` as 450 on a 450-degree model at its end (attack 30). Further past is
   "position out of range", spoiled.
   A reply of the other form names the other model in its detail (a box set up as the wrong
   model). A reply with junk in front of it on its line is not trusted (UNTRUSTED: the engine
   asks again at once).
   An azimuth past the top of this model's scale (360 on the 360-degree models) is the box set
   to the other range, P45 (a 450-degree rotor's G-800DXA, G-1000DXA, G-2800DXA): MISFIT,
   never a reading, and its words (told on R/error once such replies persist: a lone one is
   doubted as line noise, controller.py rule 6) name the model to configure or the box's
   P36. Up to READ_SLACK_DEG past it is a pot calibrated a little short of its end, read as
   the end, as K3NG's elevation below the horizon is read as the horizon. (Attack 12: ``AZ=400``
   was read on a gs232b-az as 40, nothing said, and a target of 50 went out as ``M050``: the
   rotor ran 350 degrees the long way round.) A 450-degree model whose box says only 0..360
   (K3NG's, which reports its azimuth modulo 360) reads as ever. A box whose azimuth is never
   turned (a composite's elevation box, axes.py rules 2 and 5) is judged by no scale but the
   widest (``azimuth_unturned``): that channel is no antenna's (review 49: a G-5500's box at
   P45 whose azimuth rested at 400 was a MISFIT at every reply, the rotator offline and its
   elevation never turned). Likewise a box whose elevation is never turned nor read (a
   composite's azimuth box, axes.py rule 1) is judged by no elevation range
   (``elevation_unread``): whatever three digits its ``EL=`` says, the azimuth is read
   (review 98: a G-5500's box whose elevation input read ``EL=190`` was spoiled at every
   reply, the rotator offline for good as "garbled replies", its azimuth never turned).
3. ``?>`` (the box refused a command) is junk of its own reason (REFUSED), whenever it comes and
   whether or not a CR follows; it never closes a query (its reply, if any, still may come).
4. Targets are whole degrees, rounded half up, three digits; outside 0..450 (azimuth) or
   0..180 (elevation) they are refused before anything is sent.
5. A query whose reply time ran out may still be answered (base.py rule 7): its one line is
   owed late. A reply line of this model's form, in range and clean, that comes with no query
   open while one is owed is that answer: UNSOLICITED (it still spoils a reading held in the
   same exchange, link.py rule 9), but harmless, never told on R/error, and never a reading.
   A line that comes while the next query is open is that query's, as ever. Whatever else
   comes (junk, a line with junk in front, a position no query owes) is told as before. (A
   loaded host: the poll that went out with a STOP was answered after its reply time, the
   next poll took that answer, and its own, a line later, was told on R/error as bytes that
   are no reply.)
6. The connection's first stop (base.py rule 9) goes behind whatever half frame an unplug or
   a cut write left in the box, which reads the two as one command: ``S`` then ``S`` CR is
   ``SS``, refused (attack 22: the rotor turned on 2 s until the stop went again). Where no
   target may have been cut it is a line end and the stop (CR ``S`` CR): a cut ``S`` is ended
   as the stop it was, and taken first, a cut ``C`` or ``C2`` as the poll; on a line with
   nothing in it the box may answer the empty line ``?>`` (interfaces/mqtt/express.py rule
   9), which is then no refusal: harmless, until the box answers anything else or a target
   is written. A cut poll so ended is answered with a position line the connection's first
   poll did not ask: one such line is owed as a late answer is (rule 5), harmless, never
   told (review 71: "16 bytes that are no valid reply" after a replug whose stop took; the
   first of the two lines answers that poll, the second is the one owed). Where a target may
   have been cut it is the stop twice (``S`` CR ``S`` CR): a
   cut ``M18`` takes the first (``M18S``, refused, and told: the box did refuse a command),
   never a line end that would carry it out, and the second is whole.
"""

from __future__ import annotations

import re
from typing import Any

from bridge.core.model import SettingValue
from bridge.protocols.base import (
    POT_SLACK_DEG,
    HalfLine,
    HamlibRotType,
    JunkReason,
    JunkReply,
    ModelSpec,
    OneQuery,
    PositionReply,
    Reply,
    RetargetPolicy,
    SendWhen,
    Setting,
    SettingKind,
    half_up,
    read_in_range,
)

AZ_MAX_DEG = 450  # the widest range the commands carry (the 450-degree models)
AZ_SCALE_DEG = 360  # the 360-degree models' scale: the box at P36
READ_SLACK_DEG = POT_SLACK_DEG  # rule 2 (base.py rule 10): past an end by a pot's calibration
EL_MAX_DEG = 180
REFUSED = b"?>"
AXIS_STOPS = {"az": b"A\r", "el": b"E\r"}
_MAX_LINE = 64
_NUM = rb"(\d{3})"  # three digits, zero-padded, as the documents and every box send them
# a reply at the end of its line; group "pre" is whatever came before it on that line
# K3NG pads an elevation a little below the horizon (calibration drift) as EL=00-1 in the B
# form and -000-1 in the A form (-0000 for less than half a degree below); further below is no
# horizon but a pot that is broken or far off: no reading
_B_EL = rb"(\d{3}|0{0,2}-[1-3])"
_A_EL = rb"(?:\+0(?=\d{3})|-0(?=000|00-[1-3]))" + _B_EL  # K3NG: -0000, -000-1 only
_A_FORM = re.compile(rb"(?P<pre>.*?)\+0" + _NUM + rb"(?:\s*" + _A_EL + rb")?\s*$", re.DOTALL)
_B_FORM = re.compile(
    rb"(?P<pre>.*?)AZ=\s*" + _NUM + rb"(?:\s*EL=\s*" + _B_EL + rb")?\s*$", re.DOTALL
)
# what a healthy box emits besides replies: blank lines (rule 1)
_CHATTER = re.compile(rb"[\r\n ]*")


def _degrees(value: float, top: int, axis: str) -> int:
    whole = half_up(value, 1)
    if not 0 <= whole <= top:
        raise ValueError(f"{axis} {value:g} outside 0..{top}")
    return whole


class Gs232Codec(OneQuery):
    """Codec for one GS-232 box: ``variant`` "a" or "b" (its reply form), ``elevation`` whether
    an elevation rotor hangs on it (``W``/``C2``, else ``M``/``C``), ``az_top_deg`` the top of
    its model's azimuth scale (360, or AZ_MAX_DEG for the 450-degree models: rule 2)."""

    BOX = "the GS-232"

    def __init__(
        self, variant: str = "b", *, elevation: bool = True, az_top_deg: int = AZ_MAX_DEG
    ) -> None:
        if variant not in ("a", "b"):
            raise ValueError(f"unknown GS-232 variant {variant!r}")
        if az_top_deg not in (AZ_SCALE_DEG, AZ_MAX_DEG):
            raise ValueError(f"a GS-232 box's scale is 360 or 450 degrees, not {az_top_deg}")
        self.variant = variant
        self.elevation = elevation
        self.az_top_deg = az_top_deg
        self._own, self._other = (_A_FORM, _B_FORM) if variant == "a" else (_B_FORM, _A_FORM)
        self._buf = bytearray()
        self._after_cr = False  # rule 1: the last line ended with a CR (its LF may follow)
        self._query_open = False
        self._noisy = False  # junk arrived since the query was opened
        self._line_end = False  # rule 6: a bare line end went, its ?> may come
        self._el_unread = False  # rule 2: its elevation judged by no range (elevation_unread)

    # -- encoding -------------------------------------------------------------------------
    def wire_target(self, az_deg: float, el_deg: float | None = None) -> tuple[float, float | None]:
        az = float(_degrees(az_deg, AZ_MAX_DEG, "azimuth"))
        if not self.elevation:
            return az, None
        return az, float(_degrees(el_deg or 0.0, EL_MAX_DEG, "elevation"))

    def encode_target(self, az_deg: float, el_deg: float | None = None) -> list[bytes]:
        az, el = self.wire_target(az_deg, el_deg)
        self._line_end = False  # rule 6: a ?> from now on may be the target's refusal
        if el is None:
            return [b"M%03d\r" % az]
        return [b"W%03d %03d\r" % (az, el)]

    def encode_stop(self) -> bytes:
        return b"S\r"

    def encode_stop_after(
        self, half: HalfLine, axes: bytes | None = None, ready: bytes | None = None
    ) -> bytes:
        """Rule 6 (base.py rule 9): the connection's first stop, written behind a half frame."""
        if half is HalfLine.MOVE:  # (S CR S CR: a cut M18 takes the first S, refused)
            return b"S\rS\r"
        if half is HalfLine.HARMLESS:  # (a cut S, C or C2 ended as itself: S then S CR)
            self._line_end = True
            self._owe_late(1)  # (a cut C or C2 ended so is answered: one more position line)
            return b"\rS\r"
        return b"S\r"

    def encode_query(self) -> bytes:
        self._open_query()
        return b"C2\r" if self.elevation else b"C\r"

    def expire_query(self) -> None:
        if self._query_open:  # rule 5: its answer may still come
            self._owe_late(1)
        super().expire_query()

    def harmless(self, junk: bytes) -> bool:
        return _CHATTER.fullmatch(self._unsaid(junk)) is not None  # rule 5: a late answer

    # -- decoding -------------------------------------------------------------------------
    def feed(self, data: bytes) -> list[Reply]:
        self._buf += data
        out: list[Reply] = []
        while True:
            if self._after_cr and self._buf:  # rule 1: a CR LF's LF, in this read or the next
                self._after_cr = False
                if self._buf[0] == 0x0A:
                    del self._buf[0]
                    continue
            refused = self._buf.find(REFUSED)
            ends = [i for i in (self._buf.find(b"\r"), self._buf.find(b"\n")) if i != -1]
            end = min(ends) if ends else -1
            if refused != -1 and (end == -1 or refused < end):
                if refused:  # what came before it on its line
                    self._line(bytes(self._buf[:refused]), out)
                del self._buf[: refused + len(REFUSED)]
                if self._line_end and not refused:  # rule 6: the empty line's answer
                    self._line_end = False
                    self._say(REFUSED)
                    why = "the answer to the line end written before a stop"
                    out.append(JunkReply(REFUSED, JunkReason.CHATTER, why))
                    continue
                why = "the controller refused a command (?>)"
                self._junk(REFUSED, JunkReason.REFUSED, why, out)
                continue
            if end == -1:
                if len(self._buf) > _MAX_LINE:
                    self._junk(bytes(self._buf), JunkReason.NOISE, "line too long", out)
                    self._buf.clear()
                return out
            line = bytes(self._buf[: end + 1])
            del self._buf[: end + 1]
            self._after_cr = line[-1] == 0x0D
            self._line(line, out)

    def _line(self, raw: bytes, out: list[Reply]) -> None:
        self._line_end = False  # rule 6: the box answered past the line end
        if _CHATTER.fullmatch(raw):
            out.append(JunkReply(raw, JunkReason.CHATTER, "blank line"))
            return
        own = self._own.fullmatch(raw)
        if own is None:
            other = self._other.fullmatch(raw)
            form = "GS-232B" if self.variant == "a" else "GS-232A"
            why = f"a {form} reply: is the model right?" if other else "not a reply line"
            self._junk(raw, JunkReason.NOISE, why, out)
            return
        az, el = int(own.group(2)), own.group(3)
        # rule 2: K3NG's "00-1" (and the A form's "-0000"), the antenna at the horizon with its
        # pot a degree off, reads as the horizon, as 181 at the top reads as 180
        el_deg = None if el is None else int(el.lstrip(b"0") or b"0")
        el_read = None if el_deg is None else self._el_read(el_deg)
        if read_in_range(az, 0, AZ_MAX_DEG, READ_SLACK_DEG) is None or (
            el_deg is not None and el_read is None
        ):
            self._junk(raw, JunkReason.SPOILED, "position out of range", out)
            return
        if self.elevation and el_read is None:
            self._junk(raw, JunkReason.SPOILED, "no elevation in the reply", out)
            return
        az_read = read_in_range(az, 0, self.az_top_deg, READ_SLACK_DEG)
        if az_read is None:  # rule 2: the box set to the other range
            self._junk(raw, JunkReason.MISFIT, self._misfit(az), out)
            return
        clean = not own.group("pre").strip(b"\r\n ")
        if clean and self._late_answer(raw, out):  # rule 5
            return
        if not self._query_open:
            out.append(JunkReply(raw, JunkReason.UNSOLICITED, "position nobody asked for"))
            return
        self._query_open = False
        if not clean or self._noisy:
            out.append(JunkReply(raw, JunkReason.UNTRUSTED, "position after line noise"))
            return
        if self.elevation and el_read is not None:
            out.append(PositionReply(float(az_read), float(el_read)))
        else:
            out.append(PositionReply(float(az_read)))  # an azimuth box that says EL: dropped

    def azimuth_unturned(self) -> None:
        """Rule 2: the box's azimuth is never turned (a composite's elevation box): its scale
        is no model's to judge, and a reading past 360 is no misfit (base.ScalesAzimuth)."""
        self.az_top_deg = AZ_MAX_DEG

    def _el_read(self, el: int) -> float | None:
        """Rule 2: the elevation a reply says as ``el``, a little past an end read as the end;
        None past the slack, but on a box whose elevation is never read, as it reads."""
        if self._el_unread:
            return float(el)
        return read_in_range(el, 0, EL_MAX_DEG, READ_SLACK_DEG)

    def elevation_unread(self) -> None:
        """Rule 2: the box's elevation is never turned nor read (a composite's azimuth box):
        whatever it says there spoils nothing of the azimuth (base.ScalesElevation)."""
        self._el_unread = True

    def _misfit(self, az: int) -> str:
        """Rule 2's words: what a reading of ``az`` past this model's scale says."""
        model = f"gs232{self.variant}{'' if self.elevation else '-az'}-450"
        return (
            f"the GS-232 box reads azimuth {az}, past {self.az_top_deg}, the top of this "
            f"model's scale: the box seems set up as the 450-degree model (P45); configure "
            f'model = "{model}", or set the box to 360 degrees (P36); not read as a bearing'
        )


def encode_speed(level: SettingValue) -> bytes:
    """``X1``..``X4``: the box's speed, 1 the slowest (Yaesu's table; Hamlib's gs232a
    set_level SPEED sends the same)."""
    return b"X%s\r" % str(level).encode("ascii")


# The box takes X at any time and applies it to the turn in progress; it is back at its own
# speed after a power-off, so it is sent again. The factors (a quarter per step, X4 full speed)
# are an estimate: Yaesu's documents name the steps, not their speeds.
SPEED = Setting(
    "speed",
    "Speed (1 slowest, 4 fastest)",
    encode_speed,
    kind=SettingKind.CHOICE,
    choices=("1", "2", "3", "4"),
    when=SendWhen.ANYTIME,
    resend=True,
    speed_factors={"1": 0.25, "2": 0.5, "3": 0.75, "4": 1.0},
)


def _spec(name: str, display: str, variant: str, *, elevation: bool, **kw: Any) -> ModelSpec:
    a = variant == "a"
    if elevation:
        reply = b"+0123+0045\r\n" if a else b"AZ=123  EL=045\r\n"
    else:
        reply = b"+0123\r\n" if a else b"AZ=123\r\n"
    az_top = int(kw.get("az_max_deg", AZ_SCALE_DEG))  # rule 2: the scale the box is set to
    defaults: dict[str, Any] = dict(
        manufacturer="Yaesu",
        codec_factory=lambda: Gs232Codec(variant, elevation=elevation, az_top_deg=az_top),
        baud=9600,
        has_elevation=elevation,
        retarget=RetargetPolicy.DIRECT,  # the box takes a new bearing while turning
        az_min_deg=0.0,
        az_max_deg=360.0,
        el_min_deg=0.0,
        el_max_deg=180.0 if elevation else 0.0,
        az_wraps=True,
        # K3NG's OPTION_DELAY_C_CMD_OUTPUT answers C and C2 400 ms late (for Ham Radio Deluxe)
        reply_timeout_s=1.0,
        noise_deg=2.0,  # a potentiometer read by an ADC, whole degrees
        # a Yaesu G-1000DXC or the G-5500's azimuth at full speed; the G-5500's elevation
        nominal_speed_deg_s=6.0,
        nominal_el_speed_deg_s=2.5,
        whole_degrees=True,
        stop_anytime=True,  # S is answered by a CR, a blank line the codec skips (rule 1)
        query_bytes=3 if elevation else 2,  # C2\r, C\r
        reply_bytes=len(reply),
        refusal_bytes=len(REFUSED) + 1,  # ?> CR (rule 3)
        hamlib_rot_type=HamlibRotType.AZEL if elevation else HamlibRotType.AZ,
        hamlib_info=None,  # Hamlib's gs232a backend has no get_info
        settings=(SPEED,),
    )
    defaults.update(kw)
    return ModelSpec(name=name, display_name=display, **defaults)


def _family(variant: str, hamlib_azel: int, hamlib_az: int) -> dict[str, ModelSpec]:
    box = f"GS-232{variant.upper()}"
    name = f"gs232{variant}"
    return {
        name: _spec(name, box, variant, elevation=True, hamlib_model=hamlib_azel),
        # an az/el box whose azimuth turns 450 degrees with the box set to P45 (the G-5500's
        # azimuth, say): the overlap is real on this axis too
        f"{name}-450": _spec(
            f"{name}-450",
            f"{box} az/el 450",
            variant,
            elevation=True,
            az_max_deg=float(AZ_MAX_DEG),
            az_wraps=False,
            hamlib_model=hamlib_azel,
        ),
        f"{name}-az": _spec(
            f"{name}-az", f"{box} azimuth", variant, elevation=False, hamlib_model=hamlib_az
        ),
        # the 450-degree rotors (G-800DXA, G-1000DXA, G-2800DXA) with the box set to P45: the
        # overlap is real, 10 and 370 are the same direction on two different cable wraps
        f"{name}-az-450": _spec(
            f"{name}-az-450",
            f"{box} azimuth 450",
            variant,
            elevation=False,
            az_max_deg=float(AZ_MAX_DEG),
            az_wraps=False,
            hamlib_model=hamlib_az,
        ),
    }


MODELS: dict[str, ModelSpec] = {**_family("a", 601, 609), **_family("b", 603, 611)}
