"""SPID Rot2Prog, Rot1Prog and MD-01/02 (in ROT2 mode) az/el controllers: the codec.

Device: Alfa SPID controllers for az/el rotators (satellite, EME). 8N1, no flow control; Rot2Prog
600 baud, Rot1Prog 1200, MD-01/02 whatever the controller is set to. Binary frames.
Sources: Hamlib 4.5.4's spid backend (spid.c, spid.txt) and its traffic on the wire, seen with
rotctl; the rot2prog package on PyPI (its frame and resolution tables, its simulator).

Frames we send, 13 bytes: ``57 H1 H2 H3 H4 PH V1 V2 V3 V4 PV K 20`` with ASCII digits;
K = 0x0F stop, 0x1F status, 0x2F set. For stop and status every byte but S, K and END is 0x00.
Replies, 12 bytes (Rot1Prog: 5): ``57 H1 H2 H3 H4 PH V1 V2 V3 V4 PV 20`` with RAW digits 0..9:
az = 100*H1 + 10*H2 + H3 + H4/10 - 360, el likewise; PH/PV = pulses per degree (1, 2, 4, 10).

Rules:
1. Set: pulses = floor(PH * (360 + angle)) as four ASCII digits (Hamlib truncates the same way,
   so a target snaps down to the controller's grid); Rot1Prog: three digits of 360 + az, then
   ASCII '0' and six zero bytes. The floor is of the angle meant, not of its binary rounding:
   a step missed by a millionth of a pulse is that step (true 251.2 less an offset of -4.9 is
   256.09999999999997, which is 256.1 at 10 pulses per degree, not 256.0). The resolution is
   learned from status replies; without one, ``encode_target`` refuses (a guessed resolution
   would point the antenna elsewhere). The engine sends targets only after a reading, so this
   never bites in practice.
2. Stop and status are answered with a position frame; a set is answered only by an MD-01.
   ``awaiting_reply`` says whether a frame is still owed.
3. A reply frame starts with 0x57, ends with 0x20, carries raw digits (0..9) and a known
   resolution; anything else is junk and the parser resynchronises on the next 0x57. MD-01 debug
   lines (``<digits>: text`` CR LF) are skipped whole, never read as a position; a line ends at
   its LF or where a well-formed frame starts, so a torn line costs no reply.
4. Only frames that answer something we sent become readings.
5. The resolutions are what every target is counted in, the azimuth's in PH and the
   elevation's in PV (Hamlib sets them apart, ``az_resolution`` and ``el_resolution``): read
   wrong, a target turns the rotor to its end stops (20 degrees at 10 pulses per degree for 2
   is 3800 pulses: azimuth 540). They are taken from a reply that is a reading (it answers us,
   no noise before it). The first such reply of a connection sets them; a later one that says
   another for either axis is not trusted (asked again) unless the reply before it said the
   same: a controller whose resolution was changed at its panel is believed on its second
   word, a bit flipped once never; and they count from when the engine takes that reply as a
   reading (``taken``: a well-formed glitch a second reply spoils teaches nothing). A
   connection's first resolution is confirmed so too: two readings taken that say the same
   (until then no target is counted: ``NotReady``, and the engine asks first). A reading
   of an azimuth the controller cannot turn to (-180..540) is spoiled (the elevation's counter
   of a controller with no elevation rotor may read anything).
6. A reading is in tenths, the grid may be finer (0.25 degrees: 44.25 reads 44.2; a
   controller that rounds would read 44.3): an axis to be kept where it reads (a composite's
   box, axes.py rules 1 and 2) is asked for at the step nearest the reading, half a pulse
   above it so that rule 1's floor lands on that step, not the one below (``held``).
7. A frame owed when the engine gave up waiting (``expire_query``: a status's, a stop's, an
   MD-01's set's) may still come (base.py rule 7): a position frame that comes while none is
   owed, but one given up is, is that late answer: UNSOLICITED (it still spoils a reading held
   in the same exchange) but harmless, never told on R/error, and never a reading. One that comes
   while a frame is owed again is that frame's, as ever. (A loaded host: a status's answer
   came after its reply time, the next status or the stop after it took it, and its own
   answer was told on R/error as 'controller sent 12 bytes that are no valid reply'.)
"""

from __future__ import annotations

import math
import re
from typing import Any

from bridge.protocols.base import (
    HamlibRotType,
    JunkReason,
    JunkReply,
    LateAnswers,
    ModelSpec,
    NotReady,
    Plain,
    PositionReply,
    Reply,
    RetargetPolicy,
)

START, END = 0x57, 0x20
K_STOP, K_STATUS, K_SET = 0x0F, 0x1F, 0x2F
RESOLUTIONS = (1, 2, 4, 10)
AZ_RANGE = (-180.0, 540.0)  # rule 5: what the controller turns
_MAX_DEBUG_LINE = 200
_GRID_SLACK = 1e-6  # rule 1: of a pulse, far below any step, far above a double's rounding
_DEBUG_LINES = re.compile(rb"(\d+:[^\n]*\n)+")


def _frame(k: int, body: bytes = bytes(10)) -> bytes:
    return bytes([START]) + body + bytes([k, END])


def _pulses(per: int, deg: float) -> int:
    """Rule 1: the pulses a set counts for ``deg`` at ``per`` pulses per degree."""
    return math.floor(per * (360 + deg) + _GRID_SLACK)


class SpidCodec(Plain, LateAnswers):
    BOX = "a SPID controller"

    def __init__(self, variant: str = "rot2prog") -> None:
        if variant not in ("rot2prog", "rot1prog", "md01"):
            raise ValueError(f"unknown SPID variant {variant!r}")
        self.variant = variant
        self._reply_len = 5 if variant == "rot1prog" else 12
        self.resolution: int | None = None  # PH: the azimuth's pulses per degree (rule 5)
        self.el_resolution: int | None = None  # PV: the elevation's
        self._owed = 0  # replies still owed by the controller
        self._buf = bytearray()
        self._noisy = False  # junk (not a debug line) arrived while a reply was owed
        self._said: tuple[int, int] | None = None  # rule 5: what the last reading said
        self._resolutions: list[tuple[PositionReply, tuple[int, int]]] = []  # fed, not taken
        self._first: tuple[int, int] | None = None  # rule 5: the first one taken, unconfirmed

    # -- encoding -------------------------------------------------------------------------
    def encode_query(self) -> bytes:
        self._owed += 1
        self._noisy = False
        return _frame(K_STATUS)

    def encode_stop(self) -> bytes:
        self._owed += 1
        return _frame(K_STOP)

    def expire_query(self) -> None:
        self._owe_late(self._owed)  # rule 7: they may still come
        self._owed = 0

    def awaiting_reply(self) -> bool:
        return self._owed > 0

    def harmless(self, junk: bytes) -> bool:
        junk = self._unsaid(junk)  # rule 7: a late answer
        return not junk or bool(_DEBUG_LINES.fullmatch(junk))

    def wire_target(self, az_deg: float, el_deg: float | None = None) -> tuple[float, float | None]:
        if self.variant == "rot1prog":
            return _pulses(1, az_deg) - 360.0, None
        ph, pv = self._need_resolution()
        az = _pulses(ph, az_deg) / ph - 360
        el = None if el_deg is None else _pulses(pv, el_deg) / pv - 360
        return az, el

    def encode_target(self, az_deg: float, el_deg: float | None = None) -> list[bytes]:
        if self.variant == "rot1prog":
            h = _pulses(1, az_deg)
            if not 0 <= h <= 999:
                raise ValueError(f"azimuth {az_deg} outside the frame's range")
            body = b"%03d" % h + b"0" + bytes(6)
            return [_frame(K_SET, body)]
        ph, pv = self._need_resolution()
        h = _pulses(ph, az_deg)
        v = _pulses(pv, el_deg or 0.0)
        if not (0 <= h <= 9999 and 0 <= v <= 9999):
            raise ValueError(f"target {az_deg}/{el_deg} outside the frame's range")
        body = b"%04d" % h + bytes([ph]) + b"%04d" % v + bytes([pv])
        if self.variant == "md01":
            self._owed += 1  # the MD-01 answers a set with its position
        return [_frame(K_SET, body)]

    def held(self, deg: float, axis: str) -> float:
        """Rule 6: what to ask for to keep ``axis`` ("azimuth" or "elevation") at the step it
        read as ``deg``."""
        per = self.el_resolution if axis == "elevation" else self.resolution
        if per is None or self.variant == "rot1prog":
            return deg  # (no target is counted without one: rule 5)
        return (round(per * (360 + deg)) + 0.5) / per - 360

    def _need_resolution(self) -> tuple[int, int]:
        if self.resolution is None or self.el_resolution is None:
            raise NotReady("controller resolution not confirmed yet (rule 5)")
        return self.resolution, self.el_resolution

    # -- decoding -------------------------------------------------------------------------
    def feed(self, data: bytes) -> list[Reply]:
        self._buf += data
        out: list[Reply] = []
        buf = self._buf
        junk = bytearray()
        i = 0
        while i < len(buf):
            b = buf[i]
            if b == START:
                if len(buf) - i < self._reply_len:
                    break
                frame = bytes(buf[i : i + self._reply_len])
                if self._well_formed(frame):
                    if junk:
                        self._junk_seen()  # before decoding: this frame is not trusted
                        out.append(JunkReply(bytes(junk), JunkReason.NOISE, "not a reply frame"))
                        junk.clear()
                    reply = self._decode(frame)
                    assert reply is not None
                    out.append(reply)
                    i += self._reply_len
                    continue
            elif 0x30 <= b <= 0x39:  # possibly an MD-01 debug line "<digits>: text\r\n"
                end = buf.find(b"\n", i)
                colon = buf.find(b":", i, i + 12)
                if colon == -1 and buf[i:].isdigit() and len(buf) - i < 12:
                    break  # digits so far: the colon may still come
                if colon != -1 and buf[i:colon].isdigit():
                    # the line ends at its newline, or where a reply frame starts: a line whose
                    # end was lost must not swallow the replies after it
                    frame_at = self._frame_start(buf, colon + 1, end)
                    if frame_at == -1:
                        break
                    if frame_at is not None:
                        end = frame_at - 1
                    elif end == -1:
                        if len(buf) - i < _MAX_DEBUG_LINE:
                            break  # wait for the rest of the line
                        end = i + _MAX_DEBUG_LINE - 1
                    if junk:
                        self._junk_seen()
                        out.append(JunkReply(bytes(junk), JunkReason.NOISE, "not a reply frame"))
                        junk.clear()
                    line = bytes(buf[i : end + 1])
                    out.append(JunkReply(line, JunkReason.CHATTER, "controller debug line"))
                    i = end + 1
                    continue
            junk.append(b)
            i += 1
        del buf[:i]
        if junk:
            self._junk_seen()
            out.append(JunkReply(bytes(junk), JunkReason.NOISE, "not a reply frame"))
        return out

    def _junk_seen(self) -> None:
        if self._owed > 0:
            self._noisy = True

    def _frame_start(self, buf: bytearray, start: int, end: int) -> int | None:
        """Where a well-formed reply frame starts in buf[start:end] (end -1: to the end);
        -1 if one may start there but its bytes have not all arrived."""
        stop = len(buf) if end == -1 else end
        j = buf.find(START, start, stop)
        while j != -1:
            if len(buf) - j < self._reply_len:
                return -1  # a frame may be starting here (it may even hold a LF): wait for it
            if self._well_formed(buf[j : j + self._reply_len]):
                return j
            j = buf.find(START, j + 1, stop)
        return None

    def _well_formed(self, frame: bytes | bytearray) -> bool:
        if frame[0] != START or frame[-1] != END:
            return False
        if self.variant == "rot1prog":
            return all(d <= 9 for d in frame[1:4])
        return (
            all(d <= 9 for d in frame[1:5] + frame[6:10])
            and frame[5] in RESOLUTIONS
            and frame[10] in RESOLUTIONS
        )

    def _decode(self, frame: bytes) -> Reply | None:
        if not self._well_formed(frame):
            return None
        if self.variant == "rot1prog":
            digits = frame[1:4]
            whole_az = 100 * digits[0] + 10 * digits[1] + digits[2] - 360
            return self._answer(frame, float(whole_az), None)
        h, ph, v, pv = frame[1:5], frame[5], frame[6:10], frame[10]
        az = 100 * h[0] + 10 * h[1] + h[2] + h[3] / 10 - 360
        el = 100 * v[0] + 10 * v[1] + v[2] + v[3] / 10 - 360
        return self._answer(frame, round(az, 1), round(el, 1), (ph, pv))

    def _answer(
        self, frame: bytes, az: float, el: float | None, res: tuple[int, int] | None = None
    ) -> Reply:
        if self._owed <= 0:
            late: list[Reply] = []
            if self._late_answer(frame, late):  # rule 7
                return late[0]
            return JunkReply(frame, JunkReason.UNSOLICITED, "position frame nobody asked for")
        self._owed -= 1
        if self._noisy:
            # line noise inside this exchange: the frame may be spliced from two (the engine
            # asks again instead of publishing it)
            self._noisy = False
            return JunkReply(frame, JunkReason.UNTRUSTED)
        if not AZ_RANGE[0] <= az <= AZ_RANGE[1]:  # rule 5
            return JunkReply(frame, JunkReason.SPOILED, "azimuth outside the controller's")
        reply = PositionReply(az, el)
        if res is not None:  # rule 5
            said, self._said = self._said, res
            known = (self.resolution, self.el_resolution)
            if self.resolution is not None and res != known and said != res:
                return JunkReply(frame, JunkReason.UNTRUSTED, "another resolution, said once")
            if res != known:  # taken with the reading (``taken``), not before
                self._resolutions = [*self._resolutions[-3:], (reply, res)]
        return reply

    def taken(self, reply: PositionReply) -> None:
        """Rule 5: the engine took ``reply`` as a reading (link.py rule 9: not a glitch a
        second reply spoiled): the resolution it said counts from now, the connection's first
        once a second reading taken says it too."""
        for i, (fed, res) in enumerate(self._resolutions):
            if fed is reply:
                del self._resolutions[: i + 1]
                if self.resolution is not None or self._first == res:
                    self.resolution, self.el_resolution = res
                else:
                    self._first = res
                return


def _spec(name: str, display: str, **kw: Any) -> ModelSpec:
    baud = int(kw.pop("baud"))
    frame_s = 25 * 10 / baud  # one exchange: 13-byte command + 12-byte reply
    defaults: dict[str, Any] = dict(
        manufacturer="SPID (Alfa Radio)",
        baud=baud,
        has_elevation=True,
        retarget=RetargetPolicy.DIRECT,
        az_min_deg=-180.0,
        az_max_deg=540.0,
        el_min_deg=-20.0,
        el_max_deg=210.0,
        az_wraps=False,
        cuts_down=True,  # to its pulses per degree (one, at the coarsest)
        full_duplex=False,
        reply_timeout_s=frame_s + 0.3,
        noise_deg=0.0,
        nominal_speed_deg_s=1.0,
        query_bytes=13,
        reply_bytes=12,
        hamlib_rot_type=HamlibRotType.AZEL,
        hamlib_info=None,  # Hamlib's spid backend has no get_info
    )
    defaults.update(kw)
    return ModelSpec(name=name, display_name=display, **defaults)


MODELS: dict[str, ModelSpec] = {
    "rot2prog": _spec(
        "rot2prog",
        "Rot2Prog",
        baud=600,
        codec_factory=lambda: SpidCodec("rot2prog"),
        hamlib_model=901,
    ),
    "rot1prog": _spec(
        "rot1prog",
        "Rot1Prog",
        baud=1200,
        has_elevation=False,
        el_min_deg=0.0,
        el_max_deg=0.0,
        codec_factory=lambda: SpidCodec("rot1prog"),
        reply_bytes=5,
        hamlib_model=902,
        hamlib_rot_type=HamlibRotType.AZ,
    ),
    "md01": _spec(
        "md01",
        "MD-01/02",
        baud=115200,
        codec_factory=lambda: SpidCodec("md01"),
        hamlib_model=903,
    ),
}
