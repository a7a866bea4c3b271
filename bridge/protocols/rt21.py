"""Green Heron RT-21 (azimuth): the codec.

Device: Green Heron's digital rotator controller, one box per rotor (an az/el system is two
boxes on two serial ports, one per axis). 4800 8N1, no flow control. It speaks a superset of
Hy-Gain's DCU-1 commands: plain ASCII, every command and every reply ended by ``;``, bearings in
tenths of a degree.
Sources: the project's protocol sheet (Green Heron's command set as gathered there); Hamlib
4.5.4's rotorez backend (rotorez.c: model 405, RT-21) and its traffic on the wire as users
posted it in Hamlib's issue tracker (``BI1;`` answered ``20.0;``).

Frames we send:
  ``AP1ddd.d\\r;``  turn to ddd.d at once (the CR executes it; no ``AM1;`` as the DCU-1 needs)
  ``BI1;``          ask the bearing; answer one to three digits, a point, the tenth, ``;``
                    (``20.0;``; some firmware pads to five characters with leading spaces,
                    `` 20.0;``, and the protocol sheet writes ``ddd.d;``: all are read)
  ``;``             stop
Not sent: ``AP1ddd;`` + ``AM1;`` (the DCU-1's two-step form), ``AI1;`` (whole degrees, ``;ddd``)
and ``AS1;``: the RT-21 takes them, the bridge has no use for them.

Rules:
1. Replies end at ``;``. Only ``[spaces]d[dd].d`` before a ``;`` is a bearing, only while a
   query is open, and only in 0.0..360.0 (above it: SPOILED). A lone ``;`` or spaces are the
   box's chatter, never a reading.
2. Bytes that cannot begin a reply are reported as NOISE as soon as they arrive (they need not
   wait for a ``;``); once noise came within a query, the reply that follows is not trusted
   (UNTRUSTED: the engine asks again at once), and neither is one with junk in front of it.
3. What is left in the buffer when the next query is asked (digits a lost or flipped ``;``
   left, a late reply's first bytes, noise that could begin a bearing) begins no reply of the
   new exchange: the RT-21's replies have no head of their own, so ``3`` left by a glitch and
   then ``45.6;`` read as ``345.6``. It is dropped as NOISE, and the reply of that query is not
   trusted (asked again); spaces alone are the box's padding, dropped quietly.
4. Targets are rounded half up to tenths; outside 0..360 they are refused before anything is
   sent. North goes out as ``000.0``, never ``360.0``: the box takes headings in 0..359.9 (the
   protocol sheet's range, Hamlib's caps for model 405, whose ``rotctl`` refuses ``P 360``
   and sends ``AP1359.9`` for 359.9), so a target of 360, or one that rounds to it, is sent
   as 0, as the DCU-1's 360 is (rotorez.py rule 3). A new bearing while turning goes straight
   out: the box re-targets by itself, ramping down and holding its own brake as its settings
   say (the bridge keeps no brake time of it).
5. A query whose reply time ran out may still be answered (base.py rule 7): its one reply is
   owed late. A clean bearing in range that comes with no query open while one is owed is
   that answer: UNSOLICITED (it still spoils a reading held in the same exchange), but
   harmless, never told on R/error, and never a reading. One that comes while the next query
   is open is that query's, as ever. (A loaded host: a poll's answer came after its reply
   time, the next poll took it, and that poll's own answer, right behind it, was told on
   R/error as bytes that are no valid reply.)
6. The connection's first stop (base.py rule 9) goes behind whatever half frame an unplug or
   a cut write left in the box, and ``;``, the stop, is also what ends every command: a cut
   ``BI1`` (the poll without its ``;``) or ``AP1200.0`` CR (the target turning the rotor,
   its closing ``;`` lost) takes that ``;`` as its own end, and the rotor turns on until the
   stop goes again 2 s later (review 71: 12 degrees). So it is ``;`` twice, one write: the
   first ends the half frame, the second stops (a ``;`` with no command open is the stop; to
   a box with nothing open both are, and a still rotor answers neither). A cut ``BI1`` ends
   as the poll it was and is answered with a bearing: that one line is owed (rule 5's
   bookkeeping), harmless, never a reading. Never a bare line end or another byte first: any
   byte after a target's CR closes it and is read afresh (a letter would open a command that
   eats the ``;``).
"""

from __future__ import annotations

import re
from typing import Any

from bridge.protocols.base import (
    Codec,
    HalfLine,
    HamlibRotType,
    JunkReason,
    JunkReply,
    ModelSpec,
    OneQuery,
    PositionReply,
    Reply,
    RetargetPolicy,
    tenths,
)

AZ_MAX_DEG = 360.0
_MAX_PENDING = 32  # no reply is this long without its ';'
# a complete reply (everything before its ';'); "pre" is whatever came in front of it
_REPLY = re.compile(rb"(?P<pre>.*?) *(?P<deg>\d{1,3}\.\d)", re.DOTALL)
# what may still become a reply once more bytes come: the longest such tail of the buffer
_PARTIAL = re.compile(rb" *\d{0,3}(?:\.\d?)?\Z")
# what a healthy box emits besides replies (rule 1)
_CHATTER = re.compile(rb"[ ;]*")


def _tenths(az_deg: float) -> float:
    """The bearing the box is sent for ``az_deg``: tenths, rounded half up, and 360.0 (also
    359.95 and up, rounded) as 000.0 (rule 4)."""
    value = tenths(az_deg, AZ_MAX_DEG, "azimuth")
    return 0.0 if value == AZ_MAX_DEG else value


class Rt21Codec(OneQuery):
    """Codec for one RT-21 box (one axis: azimuth)."""

    BOX = "the RT-21"

    def __init__(self) -> None:
        self._buf = bytearray()
        self._query_open = False
        self._noisy = False  # junk arrived since the query was opened
        self._left = b""  # rule 3: bytes of before the query, reported at the next feed

    # -- encoding -------------------------------------------------------------------------
    def wire_target(self, az_deg: float, el_deg: float | None = None) -> tuple[float, None]:
        return _tenths(az_deg), None

    def encode_target(self, az_deg: float, el_deg: float | None = None) -> list[bytes]:
        return [b"AP1%05.1f\r;" % _tenths(az_deg)]

    def encode_stop(self) -> bytes:
        return b";"

    def encode_stop_after(
        self, half: HalfLine, axes: bytes | None = None, ready: bytes | None = None
    ) -> bytes:
        """Rule 6 (base.py rule 9): the connection's first stop, behind a half frame."""
        if half is HalfLine.NONE:
            return b";"
        self._owe_late(1)  # rule 6: a cut BI1 ended by the first ; answers its bearing
        return b";;"

    def encode_query(self) -> bytes:
        self._open_query()
        if self._buf.strip(b" "):  # rule 3
            self._left, self._noisy = bytes(self._buf), True
        self._buf.clear()
        return b"BI1;"

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
        if self._left:  # rule 3
            out.append(JunkReply(self._left, JunkReason.NOISE, "left before the query"))
            self._left = b""
        while (end := self._buf.find(b";")) != -1:
            segment = bytes(self._buf[:end])
            del self._buf[: end + 1]
            self._segment(segment, out)
        # (looked for in the last bytes only: from every start of a long run of spaces, a
        # pattern that fails at its end is a square of the run: an attack pass)
        tail = _PARTIAL.search(self._buf, max(0, len(self._buf) - _MAX_PENDING))
        start = tail.start() if tail is not None else len(self._buf)
        if start:  # rule 2: these bytes begin no reply, whatever follows
            self._junk(bytes(self._buf[:start]), JunkReason.NOISE, "not a reply", out)
            del self._buf[:start]
        if len(self._buf) > _MAX_PENDING:
            self._junk(bytes(self._buf), JunkReason.NOISE, "reply too long", out)
            self._buf.clear()
        return out

    def _segment(self, raw: bytes, out: list[Reply]) -> None:
        frame = raw + b";"
        if _CHATTER.fullmatch(raw):
            out.append(JunkReply(frame, JunkReason.CHATTER, "empty reply"))
            return
        m = _REPLY.fullmatch(raw)
        if m is None:
            self._junk(frame, JunkReason.NOISE, "not a reply", out)
            return
        if m.group("pre"):
            self._junk(m.group("pre"), JunkReason.NOISE, "not a reply", out)
        value = float(m.group("deg"))
        reading = m.group("deg") + b";"
        if value > AZ_MAX_DEG:
            self._junk(reading, JunkReason.SPOILED, "bearing out of range", out)
            return
        if not m.group("pre") and self._late_answer(reading, out):  # rule 5
            return
        if not self._query_open:
            out.append(JunkReply(reading, JunkReason.UNSOLICITED, "bearing nobody asked for"))
            return
        self._query_open = False
        if self._noisy:
            out.append(JunkReply(reading, JunkReason.UNTRUSTED, "bearing after line noise"))
            return
        out.append(PositionReply(value))


def _spec(**kw: Any) -> ModelSpec:
    return ModelSpec(
        name="rt21",
        display_name="RT-21",
        manufacturer="Green Heron",
        codec_factory=Rt21Codec,
        baud=4800,
        retarget=RetargetPolicy.DIRECT,  # rule 4: the box re-targets and brakes by itself
        az_min_deg=0.0,
        az_max_deg=AZ_MAX_DEG,
        az_wraps=True,
        az_ends_at_north=False,  # rule 4: never sent 360, the box turns its rotor its own way
        reply_timeout_s=0.3,
        # a potentiometer read in tenths: a still rotor's reading may wander a few tenths
        noise_deg=0.5,
        nominal_speed_deg_s=6.0,  # a Hy-Gain HAM-IV or a Yaesu G-1000 at full speed
        whole_degrees=False,
        tenths=True,  # rule 4
        query_bytes=4,  # BI1;
        reply_bytes=6,  # 123.4;
        hamlib_model=405,
        hamlib_rot_type=HamlibRotType.OTHER,  # as Hamlib's rotorez backend calls its family
        hamlib_info=None,  # Hamlib 4.5.4's RT-21 has no get_info
        hamlib_folds_360=True,  # rotorez.c's RT-21 reads 360.0 as 0
        **kw,
    )


MODELS: dict[str, ModelSpec] = {"rt21": _spec()}

_check: type[Codec] = Rt21Codec  # Rt21Codec satisfies the Codec protocol
