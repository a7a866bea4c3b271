"""Easycomm II and III controllers (SatNOGS rotator controllers, K3NG in Easycomm mode): the codec.

This is the controller side: the bridge drives a box that speaks Easycomm. The other direction, a
program speaking Easycomm II to the bridge (``easycomm_port``), lives in bridge/interfaces/gs232/.

Device: a rotator controller taking Easycomm commands on a serial line, SatNOGS controllers at
19200 8N1, K3NG's firmware at 9600 8N1. Commands are two letters and a value, separated by a
space, CR or LF; only commands that ask something are answered, by the command's letters and the
value, and a line end (LF, or CR LF). Easycomm III adds velocities, a status and an error register
and configuration registers.
Sources: the Easycomm II/III descriptions shipped with Hamlib (easycomm.txt), Hamlib 4.5.4's and
its newer easycomm backend (models 202, 204: what they send and how they read the answers), the
project's protocol sheet, and our emulator's traffic with rotctl.

Frames we send (each ends in LF):
  ``AZ123.4 EL45.0``  turn to azimuth and elevation, tenths of a degree (az/el models)
  ``AZ123.4``         turn to azimuth (azimuth models)
  ``AZ EL``           ask both, answered ``AZ123.4 EL45.0`` on one line (azimuth models too)
  ``AZ`` LF ``EL``    ask each on its own line (the ``-separate`` models: controllers that answer
                      AZ and EL only when asked separately), answered ``AZ123.4`` and ``EL45.0``
  ``SA SE``           stop azimuth and elevation (also to an azimuth controller: SE is harmless;
                      a SatNOGS answers it with the position, rule 9)
  ``VE``              ask the version, once at connect (Easycomm III), answered ``VExxx``
Not sent: ``VL VR VU VD`` (velocities) and ``CR``/``CW`` (configuration registers) are the
controller's own settings; ``ML MR MU MD`` (turn until stopped) have no place in a bridge that
sends bearings; ``GS``/``GE`` (status, errors) are not polled: the position shows what the
bridge needs. ``UP DN`` (radio words) belong to a radio, not a rotator.

Rules:
1. Replies are lines ended by CR or LF; blank lines are harmless chatter, never a reading.
   ``ALxxx`` is the controller's alarm (a refusal, a fault): never a reading and no spoiler of
   one (CHATTER, its text in the detail), but not harmless either, so the user is told.
2. A position is read only while a query is open, from lines of the form ``AZ<n>``, ``EL<n>``
   or ``AZ<n> EL<n>`` (spaces optional, and only spaces: a tab or a form feed is junk, rule 3;
   decimals optional, a sign allowed, radio words after ignored). The query is answered once
   every axis the model reads has a value, whether they came on one line or two; an azimuth
   model ignores an elevation on the line. A value past an end of its axis's range (azimuth
   0..360, elevation -90..180) by at most READ_SLACK_DEG, half a degree, is read as that end
   (base.py rule 10: a sensor read in tenths, noise_deg 0.1): a SatNOGS controller's encoder is
   zeroed at its home switch and its PID rests anywhere within 0.2 of the target, so turned to
   north it may say ``AZ-0.1`` (review 39; Hamlib reads it), and flipped up to 180,
   ``EL180.2``. Further past is spoiled. A box whose elevation is never turned nor read (a
   composite's azimuth box, axes.py rule 1) is judged by no elevation range
   (``elevation_unread``): its ``EL`` spoils nothing of the azimuth (review 98: ``EL181.0``
   spoiled every reply, the rotator offline for good, its azimuth never turned).
3. A line with junk in front of the reply, or junk anywhere in the exchange, makes its reading
   UNTRUSTED (the engine asks again at once); a reply nobody asked for is UNSOLICITED. An
   azimuth model's elevation line (harmless, rule 2) with junk in front is noise, not
   chatter: it is the tail of a reply a stray line end tore (``AZ15`` LF ``0.0 EL0.0`` from a
   rotor at 150), and it must spoil the reading its head made (an attack pass: ``AZ15`` stood
   as a clean reading, shown at start-up, and a nudge turned the rotor from 150 to 25).
4. ``VExxx`` is the controller's version whenever it comes.
5. Targets are tenths of a degree, rounded half up; outside azimuth 0..360 or elevation 0..180
   they are refused before anything is sent.
6. A line longer than 80 bytes (its CR or LF not counted) is noise, whole or not, and is never
   matched, however the reads split it (an 81-byte line was read when it came in one read and
   noise when a read ended before its LF: a box's version came or not by chance); a reply line is
   read one way only (no pattern that backtracks: an attack pass, ``AZ1`` and 32 ``UP`` words
   in one read held the serial-lines thread 3 s, its every rotator and stop with it, and 126
   bytes longer than two minutes).
7. K3NG's firmware in its default build answers a bare ``AZ`` or ``EL`` with the value alone,
   always signed (``+123.4``, ``-1.5``), and ends each answer with the byte that ended the
   question: ``AZ EL`` LF is answered ``+123.4 +45.0`` LF, and on an azimuth build
   ``+123.4 ?`` (it has no ``EL``). Such a line's values fill the open query's axes in order,
   the azimuth first; the ``?`` is read only by an azimuth model, to which a ``?`` alone is
   harmless too (its answer to the stop's ``SE``: the stop stays ``SA SE``, the one stop the
   SatNOGS firmware knows), and so are up to STOP_FRAMES such lines in one quiet spell, each
   ``?`` on a line of its own: one STOP may put that many ``SA SE`` on the wire (the stop
   express's, the stop lane's and the main connection's copy, or a stop and its repeat:
   session/stops.py rule 1), each refused. More are refusals of something else, and told. (An
   attack pass: a STOP's two refusals came in one quiet spell, judged together, and STOPs to
   such a box were told on R/error as 'controller sent 6 bytes that are no valid reply'.)
   Without its sign a bare number is never a reply.
8. Every model asks ``AZ EL`` on one line but the ``-separate`` ones, an azimuth model too:
   the SatNOGS firmware reads any other line that begins ``AZ`` as a target, a bare ``AZ`` as
   "turn to 0" (and answers nothing), so a bare ``AZ`` is never sent to a controller of
   unknown firmware as a question. (The ``-separate`` models ask ``AZ`` and ``EL`` alone, as
   Hamlib does: never for a SatNOGS controller, which docs/controllers.md says.)
9. The SatNOGS firmware answers ``SA SE`` with the position; others answer nothing. A whole
   position line that comes after a stop before the next query, or after it once this
   controller was seen to answer a stop, is that answer: harmless chatter, never a reading
   (nor a reply nobody asked for, told on R/error at every stop). Once it was seen to, a
   whole position line with no query open is taken for the answer to a stop this codec did
   not send (the stop express writes its own copy, ``ModelSpec.stop_anytime``). Before, such
   a line is a reply nobody asked for (UNSOLICITED: it spoils a reading held, as a second
   reply must; nothing yet tells it from one), but when the controller is first seen to
   answer a stop of the codec's own, the whole lines that came so within the last
   UNASKED_POLLS polls (UNASKED_KEEP at most) are taken for the express's answers to the same
   STOP (its frame goes first): harmless, not told (but where the line was quiet for
   link.py's JUNK_QUIET_S between the two answers: that junk was judged, and told, before).
   (An attack pass: the first STOP of every connection to a SatNOGS was told on R/error as
   'controller sent 28 bytes that are no valid reply', the express's answer with the
   codec's own.) A stop written while a query is open (the line is full duplex) is answered
   after it: the query's answer comes first and is the query's, and only a line after it can
   be the stop's. (A review: the poll's answer in flight was taken for the stop's, on a
   controller that answers no stop; the poll waited out its reply time, the codec took the
   controller for one that answers stops, so the repeat of a double STOP ate the next poll's
   answer too, and 1 s without a reading put the rotator offline.)
10. A query whose reply time ran out may still be answered: its answer's lines (one, or the
   ``-separate`` models' two, less those that came in time) are owed late, at most
   LATE_LINES_MAX of them (base.py rule 7). A position line with no query open while some are
   owed is one of them, ahead of any stop's answer (the controller answers in the order asked):
   UNSOLICITED, so that it still spoils a reading held in the same exchange (link.py rule 9),
   but harmless, never told on R/error, and never a reading. While any is owed, a line taken
   for a stop's answer does not show that this controller answers stops (it may be the late
   one). A line that comes while the next query is open is that query's, as ever: which of
   the two it answers no line says, and a late answer that never comes must not eat the
   next poll's. Whatever else comes (junk, a line with junk in front, a position no query
   owes) is told as before. (A CI run at load 23: a poll's answer came after its reply time,
   the next poll took it, and that poll's own answer, one line later, was told on R/error as
   bytes that are no reply; and a poll given up before a stop had its late answer taken for
   the stop's, teaching that this controller answers stops.)
11. The connection's first stop (base.py rule 9) goes behind whatever half frame an unplug or
   a cut write left in the box, which reads the two as one line: ``S`` then ``SA SE`` is
   ``SSA SE``, the elevation's stop alone (attack 22: the azimuth turned on 2 s until the
   stop went again). So it is ``SA SE`` twice, one write: the first takes the half frame in
   (what the box makes of that line, the second stops), the second is whole. Never a bare
   line end first: a cut poll's ``AZ`` ended alone is "turn to 0" on a SatNOGS box (rule 8),
   a cut ``AZ18`` a move. Each ``SA SE`` is answered as ever (rules 7 and 9: a SatNOGS box's
   position, an azimuth model's ``?``). The connection's first poll goes right behind it,
   before the codec can know whether this box answers stops, so the two position lines a
   SatNOGS box answers come ahead of the poll's own: one that comes while the poll is open
   is read as its answer (the box's position then), and two lines are owed as late answers
   are (rule 10): harmless, never told, never readings (review 71: "28 bytes that are no
   valid reply" after a replug whose stop took). On a box that answers no stop they stay
   owed, and two unasked position lines later on go untold.
"""

from __future__ import annotations

import re
from typing import Any

from bridge.protocols.base import (
    TENTHS_SLACK_DEG,
    HalfLine,
    HamlibRotType,
    JunkReason,
    JunkReply,
    ModelSpec,
    OneQuery,
    PositionReply,
    Reply,
    RetargetPolicy,
    VersionReply,
    read_in_range,
    tenths_pair,
)

AZ_MAX_DEG = 360
EL_MAX_DEG = 180
EL_READ_MIN_DEG = -90  # a reading below the horizon is a reading (a rotor parked at -0.5)
READ_SLACK_DEG = TENTHS_SLACK_DEG  # rule 2: a SatNOGS at rest within its dead zone past an end
_MAX_LINE = 80
_NUM = rb"[-+]?\d{1,3}(?:\.\d*)?"  # 123.4, 123, 5.
# a reply at the end of its line, with whatever came before it on that line in "pre"
_SP = rb"[\r\n ]"  # what parts a line: a space (and its own line end), never a tab or a form feed
_RADIO = rb"(?:UP|DN|UM|DM|UR|DR)"
# (a radio word's mode is no radio word: ``UP UP`` reads one way only, rule 6)
_REPLY = re.compile(
    rb"(?P<pre>.*?)(?:AZ%(sp)s*(?P<az>%(num)s))?%(sp)s*(?:EL%(sp)s*(?P<el>%(num)s))?"
    rb"(?P<radio>(?:%(sp)s+%(radio)s\S*(?:%(sp)s+(?!%(radio)s)[A-Z]{2,3})?)*)%(sp)s*"
    % {b"sp": _SP, b"num": _NUM, b"radio": _RADIO},
    re.DOTALL,
)
# K3NG's default build (rule 7): +123.4, +123.4 +45.0, +123.4 -1.5, on an azimuth build +123.4 ?
_K3NG = re.compile(
    rb"%(sp)s*(?P<a>[-+]\d{1,3}(?:\.\d*)?)(?: +(?:(?P<b>[-+]\d{1,3}(?:\.\d*)?)|(?P<q>\?)))?%(sp)s*"
    % {b"sp": _SP}
)
_VERSION = re.compile(rb"%(sp)s*VE(?P<v>[ -~]*?)%(sp)s*" % {b"sp": _SP})
_ALARM = re.compile(rb"%(sp)s*AL(?P<a>[ -~]*?)%(sp)s*" % {b"sp": _SP})
_CHATTER = re.compile(_SP + rb"*")
_NO_SE = re.compile(rb"%(sp)s*\?%(sp)s*" % {b"sp": _SP})  # rule 7
# rule 7: the SA SE one STOP puts on the wire: the express's, the session's two (a stop and
# its repeat 0.1 s apart, or a connection's first stop, twice in one write: rule 11)
STOP_FRAMES = 3
# rule 7: up to STOP_FRAMES refusals, one to a line (read one way only, rule 6)
_NO_SES = re.compile(rb"(?:[\r\n ]*\? *[\r\n]){1,%d}[\r\n ]*" % STOP_FRAMES)
UNASKED_POLLS = 2  # rule 9: the poll the express's stop's answer came in, the re-poll it asked
UNASKED_KEEP = 2  # rule 9: whole lines nobody asked for kept as maybe the express's stop's answers


class EasycommCodec(OneQuery):
    """Codec for one Easycomm controller: ``version`` 2 or 3, ``elevation`` whether it drives an
    elevation rotor, ``separate`` whether it is asked AZ and EL on lines of their own."""

    BOX = "an Easycomm controller"

    def __init__(self, version: int = 2, *, elevation: bool = True, separate: bool = False) -> None:
        if version not in (2, 3):
            raise ValueError(f"unknown Easycomm version {version!r}")
        self.version = version
        self.elevation = elevation
        self.separate = separate and elevation
        self._buf = bytearray()
        self._query_open = False
        self._noisy = False  # junk arrived since the query was opened
        self._az: float | None = None  # what this exchange has said so far
        self._el: float | None = None
        self._stop_open = False  # rule 9: a stop sent, its answer (if it has one) still due
        self._stop_behind = False  # rule 9: that stop went while a query was open: after it
        self._answers_stop = False  # rule 9: this controller was seen to answer one
        self._polls = 0  # rule 9: queries opened, to age ``_unasked``
        self._unasked: list[tuple[int, bytes]] = []  # rule 9: lines maybe the express's stop's
        self._el_unread = False  # rule 2: its elevation judged by no range (elevation_unread)

    # -- encoding -------------------------------------------------------------------------
    def wire_target(self, az_deg: float, el_deg: float | None = None) -> tuple[float, float | None]:
        return tenths_pair(az_deg, el_deg, AZ_MAX_DEG, EL_MAX_DEG if self.elevation else None)

    def encode_target(self, az_deg: float, el_deg: float | None = None) -> list[bytes]:
        az, el = self.wire_target(az_deg, el_deg)
        if el is None:
            return [b"AZ%.1f\n" % az]
        return [b"AZ%.1f EL%.1f\n" % (az, el)]

    def encode_stop(self) -> bytes:
        self._stop_open = True  # rule 9
        self._stop_behind = self._query_open  # rule 9: the query's answer comes first
        return b"SA SE\n"

    def encode_stop_after(
        self, half: HalfLine, axes: bytes | None = None, ready: bytes | None = None
    ) -> bytes:
        """Rule 11 (base.py rule 9): the connection's first stop, behind a half frame."""
        stop = self.encode_stop()
        if half is HalfLine.NONE:
            return stop
        self._owe_late(2)  # (a SatNOGS box's two answers, ahead of the first poll's)
        return stop + stop

    def expire_query(self) -> None:
        if self._query_open:  # rule 10: its answer may still come, what is left of it
            due = 1 if not self.separate or self._az is not None or self._el is not None else 2
            self._owe_late(due)
        super().expire_query()

    def encode_query(self) -> bytes:
        self._open_query()
        self._polls += 1
        self._az = self._el = None
        self._stop_open = self._stop_open and self._answers_stop  # rule 9
        self._stop_behind = False  # (this query went after the stop)
        return b"AZ\nEL\n" if self.separate else b"AZ EL\n"  # rule 8

    def encode_version(self) -> bytes | None:
        return b"VE\n" if self.version == 3 else None

    def encode_connect(self, now_unix: float) -> list[bytes]:
        return [b"VE\n"] if self.version == 3 else []

    def harmless(self, junk: bytes) -> bool:
        junk = self._unsaid(junk)  # rule 9: a SatNOGS's answer to a stop; rule 10: a late one
        if not self.elevation and _NO_SES.fullmatch(junk):  # rule 7: K3NG's ``SE`` refused
            return True
        return _CHATTER.fullmatch(junk) is not None  # an alarm is not (rule 1)

    # -- decoding -------------------------------------------------------------------------
    def feed(self, data: bytes) -> list[Reply]:
        self._buf += data
        out: list[Reply] = []
        while True:
            ends = [i for i in (self._buf.find(b"\r"), self._buf.find(b"\n")) if i != -1]
            if not ends:
                if len(self._buf) > _MAX_LINE:
                    self._junk(bytes(self._buf), JunkReason.NOISE, "line too long", out)
                    self._buf.clear()
                return out
            end = min(ends)
            line = bytes(self._buf[: end + 1])
            del self._buf[: end + 1]
            self._line(line, out)

    def _line(self, raw: bytes, out: list[Reply]) -> None:
        if len(raw) > _MAX_LINE + 1:  # rule 6: raw ends in its one CR or LF, not counted
            self._junk(raw, JunkReason.NOISE, "line too long", out)
            return
        if _CHATTER.fullmatch(raw):
            out.append(JunkReply(raw, JunkReason.CHATTER, "blank line"))
            return
        if not self.elevation and _NO_SE.fullmatch(raw):  # rule 7
            out.append(JunkReply(raw, JunkReason.CHATTER, "SE refused (an azimuth build)"))
            return
        if m := _ALARM.fullmatch(raw):
            alarm = m.group("a").decode("ascii", "replace")
            out.append(JunkReply(raw, JunkReason.CHATTER, f"controller alarm: {alarm}"))
            return
        if m := _VERSION.fullmatch(raw):
            out.append(VersionReply(m.group("v").decode("ascii")))
            return
        if k := _K3NG.fullmatch(raw):  # rule 7
            if k.group("q") and self.elevation:
                self._junk(raw, JunkReason.NOISE, "no elevation from an az/el model", out)
                return
            pre = b""
            values = [float(v) for v in k.group("a", "b") if v is not None]
            first = self._az is None or not self._query_open  # unasked: read as a whole answer
            az = values.pop(0) if first else None
            el = values.pop(0) if values else None
        else:
            m = _REPLY.fullmatch(raw)
            if m is None or (m.group("az") is None and m.group("el") is None):
                self._junk(raw, JunkReason.NOISE, "not a reply line", out)
                return
            pre = m.group("pre")
            az = None if m.group("az") is None else float(m.group("az"))
            el = None if m.group("el") is None else float(m.group("el"))
        if not self.elevation and az is not None:
            el = None  # rule 2: an azimuth model ignores it, out of range or not
        # rule 2: a little past an end is that end, further is no reading
        az_read = None if az is None else read_in_range(az, 0, AZ_MAX_DEG, READ_SLACK_DEG)
        el_read = None if el is None else self._el_read(el)
        if (az is not None and az_read is None) or (el is not None and el_read is None):
            self._junk(raw, JunkReason.SPOILED, "position out of range", out)
            return
        az, el = az_read, el_read
        if not self.elevation and az is None:
            if pre.strip(b"\r\n "):  # rule 3: a reply torn by a stray line end, its tail
                self._junk(raw, JunkReason.NOISE, "junk in front of an elevation", out)
                return
            out.append(JunkReply(raw, JunkReason.CHATTER, "an elevation from an azimuth model"))
            return
        whole = az is not None and (el is not None or not self.elevation)
        clean = not pre.strip(b"\r\n ")
        if clean and (whole or self.separate) and self._late_answer(raw, out):  # rule 10
            return
        stop_first = self._stop_open and not (self._stop_behind and self._query_open)  # rule 9
        stop_answer = stop_first or (self._answers_stop and not self._query_open)
        if stop_answer and whole and clean:  # rule 9
            self._stop_open = False
            if not self._answers_stop and not self._late_lines:  # rule 10: else it may be late
                self._answers_stop = True
                for n, said in self._unasked:  # rule 9: the express's answers to this STOP
                    if self._polls - n <= UNASKED_POLLS:
                        self._say(said)
            self._unasked.clear()
            self._say(raw)
            out.append(JunkReply(raw, JunkReason.CHATTER, "the controller's answer to SA SE"))
            return
        if not self._query_open:
            if whole and clean and not self._answers_stop:  # rule 9: the express's stop's?
                self._unasked = [*self._unasked, (self._polls, raw)][-UNASKED_KEEP:]
            out.append(JunkReply(raw, JunkReason.UNSOLICITED, "position nobody asked for"))
            return
        if pre.strip(b"\r\n "):
            self._noisy = True
        self._az = self._az if az is None else az
        self._el = self._el if el is None else el
        if self._az is None or (self.elevation and self._el is None):
            return  # the other axis's line is still to come (rule 2)
        self._query_open = False
        if self._noisy:
            out.append(JunkReply(raw, JunkReason.UNTRUSTED, "position after line noise"))
            return
        out.append(PositionReply(self._az, self._el if self.elevation else None))

    def _el_read(self, el: float) -> float | None:
        """Rule 2: the elevation a reply says as ``el``, a little past an end read as the end;
        None past the slack, but on a box whose elevation is never read, as it reads."""
        if self._el_unread:
            return el
        return read_in_range(el, EL_READ_MIN_DEG, EL_MAX_DEG, READ_SLACK_DEG)

    def elevation_unread(self) -> None:
        """Rule 2: the box's elevation is never turned nor read (a composite's azimuth box):
        whatever it says there spoils nothing of the azimuth (base.ScalesElevation)."""
        self._el_unread = True


def _spec(name: str, display: str, version: int, *, elevation: bool, separate: bool) -> ModelSpec:
    query = b"AZ\nEL\n" if separate else b"AZ EL\n"  # rule 8
    # the longest answer (the width varies with the value): AZ359.9 EL180.0 LF, or on two lines;
    # an azimuth box answers EL0.0 (a SatNOGS used for azimuth alone: a few bytes more)
    reply = b"AZ359.9 EL180.0\n" if elevation else b"AZ359.9 EL0.0\n"
    defaults: dict[str, Any] = dict(
        # and others speaking the protocol; a bare AZ turns a SatNOGS to 0 (rule 8)
        manufacturer="K3NG" if separate else "SatNOGS, K3NG",
        codec_factory=lambda: EasycommCodec(version, elevation=elevation, separate=separate),
        baud=19200,  # SatNOGS controllers; K3NG's firmware runs at 9600 (set baud)
        has_elevation=elevation,
        has_version=version == 3,
        retarget=RetargetPolicy.DIRECT,  # a new bearing is taken while turning
        az_min_deg=0.0,
        az_max_deg=360.0,
        el_min_deg=0.0,
        el_max_deg=180.0 if elevation else 0.0,
        az_wraps=True,
        reply_timeout_s=0.4,  # Hamlib waits 200 ms; an Arduino's loop may be busy stepping
        noise_deg=0.1,  # encoders or steps counted, read in tenths
        # a poll's EL is one bit from ML (a jog), the space of AZ EL from 0 (rule 8: every
        # model asks AZ EL, an azimuth one too)
        unasked_moves="stop",
        nominal_speed_deg_s=6.0,
        nominal_el_speed_deg_s=6.0,
        whole_degrees=False,
        tenths=True,  # rule 5
        stop_anytime=True,  # SA SE waits for no reply (a SatNOGS answers it: rule 9)
        query_bytes=len(query),
        reply_bytes=len(reply),
        least_reply_bytes=len(b"AZ0.0 EL0.0\n"),  # (the shortest: at 0, either form)
        hamlib_model=204 if version == 3 else 202,
        hamlib_rot_type=HamlibRotType.OTHER,  # what Hamlib's easycomm backend declares
        hamlib_info="EasycommIII" if version == 3 else "EasycommII",
    )
    return ModelSpec(name=name, display_name=display, **defaults)


def _family(version: int) -> dict[str, ModelSpec]:
    box = "Easycomm " + "I" * version
    name = f"easycomm{version}"
    return {
        name: _spec(name, f"{box} controller", version, elevation=True, separate=False),
        f"{name}-az": _spec(
            f"{name}-az", f"{box} azimuth controller", version, elevation=False, separate=False
        ),
        f"{name}-separate": _spec(
            f"{name}-separate",
            f"{box} controller (AZ and EL asked separately)",
            version,
            elevation=True,
            separate=True,
        ),
    }


MODELS: dict[str, ModelSpec] = {**_family(2), **_family(3)}
