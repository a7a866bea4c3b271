"""M2 RC2800 (azimuth, or azimuth and elevation): the codec.

Device: M2 Antenna Systems' RC2800 rotator controller, one box driving an azimuth rotor and, on
the az/el versions, an elevation rotor. 9600 8N1, no flow control. ASCII commands ending in CR,
each to one axis: a letter selects the axis (``A`` azimuth, ``E`` elevation) and the box answers
with that axis's line, like ``A P= 98.1 S=9 MV`` (position, speed, moving or stopped). Some
boxes echo every command before answering it; some stream their position lines unasked. The box
needs about 200 ms between commands to its two axes.
Sources: the project's protocol sheet (M2 RC2800), Hamlib's m2 backend (rc2800.c: model 1001,
its reply forms ``A P= 98.1 S=9 MV``, ``E=43.7 S=9 M`` and ``A ERR=5``, its echo handling, its
200 ms between the axes, its stop as the axis selected then ``S``), and our emulator's traffic
with rotctl -m 1001.

Frames we send (each a list the link paces by the spec's ``axis_gap_s``, 200 ms on az/el):
  ``A123.4\\r`` then ``E45.0\\r``      turn to azimuth and elevation, tenths of a degree
  ``A\\r`` then ``E\\r``               ask each axis; answered by its line
  ``A\\rS\\r`` then ``E\\rS\\r``         stop: select each axis, stop it (first the axis that
                                   runs or was just sent a bearing, one the axis gap lets
                                   go at once before one it holds: rule 9)
The azimuth model sends only the azimuth's frames.

Rules:
1. Replies are lines ended by CR or LF. A position line is ``A`` or ``E``, then ``P=`` (after a
   space) or ``=``, a number, optionally the speed ``S=n`` and a one- or two-letter state; only
   such a whole line is read. A line longer than _MAX_LINE (its end not counted) is noise,
   however the bytes came: given up once that much has come without its end, the rest of it,
   up to its end, is noise too, no line of its own. An exchange it came in is spoiled (rule 2);
   it ends with its answer (untrusted) or at its deadline, not with the noise: the box may
   still be answering, and a query written then would take that answer for its own.
   The first line of a connection may have lost its head: a box that streams its position
   was mid-line when the port opened, and the open's flush (or the adapter, closed till then)
   took the line's first bytes. Such a line, one that an axis's head (``A=``, ``A P``, ...) in
   front would make a position line (``0.0 S=9 ST``), is the box's chatter: never a reading,
   harmless while no noise follows it, but an exchange it came in is spoiled as by noise (it
   may be a mangled line). Any other line is read as below.
   A line shaped like a command (``A``, ``E45``, ``S``) is the box's echo: harmless
   chatter, never a reply. ``A ERR=n`` is the box's error: no reading, reported. On the
   azimuth box it is the box's refusal (REFUSED, as the GS-232's ``?>``): a target it answers
   that has not moved the rotor is dropped at once, not waited on until a stall (motion.py
   rule 8). On the az/el box it is not: a target is a frame for each axis, each answered for
   its own, and the other axis's frame may have turned its rotor (a review: ``E ERR=2`` to the
   elevation's frame was taken for the target's refusal, reported so, the target dropped,
   while the azimuth turned 190 degrees to it); the stall check judges that target.
2. A query (or a stop, whose axis selections are answered too) waits for a line of each axis it
   asked, in order; when the last has come, they are one reading (UNTRUSTED if any noise came
   in the exchange: the engine asks again). An axis's line while nothing is asked is kept; a
   reading is made of it once every axis the model reads has had a line since the last reading
   (the box's own stream, or its answers to a target's frames): a well-formed line updates the
   bearing, anything else changes nothing. A query is answered by the same count too: a line
   of each axis since the last reading, none older than the exchange before it (a line that
   loses the azimuth's answer to one poll and the elevation's to the next still gives a
   reading, at the azimuth's line, and a reading is never staler than that). That poll's own
   elevation line, if it comes, is read as it comes and carried no further (else each poll of
   a clean line after it was read at its azimuth with the poll before's elevation, for good);
   a line of an exchange that had line noise is never carried (it may be a mangled one).
3. A value past an end of its axis's range (azimuth 0..360, elevation -90..180) by at most
   READ_SLACK_DEG is read as that end (base.py rule 10: a pot read in tenths, noise_deg 0.5;
   attack 30: a rotor at rest at north saying ``A P=  -0.2`` or ``A P= 360.2`` was spoiled at
   every poll, offline for good, as an Easycomm box's ``AZ-0.1`` was before review 39). Further
   past it is spoiled and no reading, and never harmless, asked for or not (an attack pass:
   ``A P= 361.0`` was dropped and nobody told). A box whose elevation is never turned nor
   read (a composite's azimuth box, axes.py rule 1) is judged by no elevation range
   (``elevation_unread``): its ``E`` line, whatever it says, is read as it reads and spoils
   nothing of the azimuth (review 98, as a GS-232's ``EL=190``: spoiled, every exchange was,
   the rotator offline for good, its azimuth never turned).
4. Targets are tenths of a degree, rounded half up; outside azimuth 0..360 or elevation 0..180
   they are refused before anything is sent. A new bearing while turning goes straight out.
5. The 200 ms between the axes is the link's to keep (``ModelSpec.axis_gap_s``): this codec
   only splits each command into its axes' frames, in the order they must go.
6. An exchange given up (``expire_query``) may still be answered (base.py rule 7): the lines
   it still waited for are owed late. A well-formed line of an axis this model reads that
   comes while nothing is asked and some are owed late (and is not the line rule 2's early
   reading still waits for) is one of them: UNSOLICITED (it spoils a reading held in the same
   exchange), harmless, never a reading and never kept for one (rule 2's stream). A line that
   comes while the next exchange is open is that exchange's, as ever. (A loaded host: a
   poll's answer and the next poll's came together, the older made the newer poll's reading
   and the newer, kept as the box's stream, spoiled nothing: the bearing was published 6
   degrees behind the rotor turning at 6 degrees a second.) But a line owed late that comes
   before any other exchange is opened (a poll, a stop) is the newest the box has said: no
   longer owed, and kept as rule 2's stream (a review: a box always a little later than its
   reply time, polled every 2 s, gave no reading at all, and the rotator went offline, its
   turn stopped short, while it answered every poll).
7. A position line's state word says whether that axis's motor runs (``MV``, or ``M`` as in
   Hamlib's example) or not (``ST``, or ``S``); a reading drives a motor if the latest line of
   any axis it is made of says so, none if each says stopped (base.py rule 8), and says
   nothing of it where a line has no state word or another. (A box power-cycled mid-turn
   forgets its turn and says ``ST``: read past, the rotor it left standing was called stalled
   10 s later, and rotor health counted a stall.)
8. A turn nobody asked for is stopped by default (``unasked_moves = "stop"``, as on an
   Easycomm box and the SatEL: session/controller.py rule 10). A poll is the axis letter alone
   (``A`` CR) and a target the letter and a bearing (``A5`` CR): one stray byte on the line (a
   digit) makes a poll a target the box takes at once (an attack pass: an azimuth at rest at
   150, ``az_min_deg`` 30, ran to 5 past its limit, followed, nothing said: the motion watches a
   limit on the way only while a target of the bridge's is out, and a wrapping azimuth's not
   at all, motion.py rule 10). The cost: a turn from the box's front panel (its buttons, its
   presets) is stopped too, 5 degrees from where the rotor rested, four times at most for a
   button held on, and a bridge started while the rotor turns stops it; an owner who turns it
   there sets ``unasked_moves = "follow"``. Holding the limits for every turn nobody asked for
   instead, on every model, was not taken: a hand at a panel turning past a soft limit on
   purpose would be fought, and the limits of an azimuth that wraps are not watched on the way.
   The same holds for an RC2800 that turns a composite's elevation (``E`` CR, ``E5`` CR), where
   other models' elevation boxes follow (settings ``unasked_moves_of``).
9. A stop begins with the azimuth (``A`` CR ``S`` CR), the elevation's frame the gap after
   it; the link writes the first as soon as the box's 200 ms between its axes allows: at
   once after a frame to the azimuth or once the gap since the last ``E`` frame is over, else
   when that gap ends (session/link.py rule 10). (Attack 22: a stop's ``A`` 2 ms after an
   ``E`` CR poll broke that gap. Helper-590 then began the stop with the axis the last frame
   named, ``E`` CR ``S`` CR at once, but that put the azimuth's stop a whole gap after the
   STOP however long ago the ``E`` went (review 71: up to 200 ms later, 1.2 degrees more
   coast at 6 degrees a second). The axis stopped first is one whose motor runs by its last
   line (rule 7) or that a drive frame (``A200.0`` CR) went to since that line; where both
   are, one whose stop the link writes at once (no axis gap to wait: the last frame was its
   own, or the gap since the other axis's is over; link.py rule 10 tells it, ``ready``) before
   one that must wait, then the one with the most recent such frame; the azimuth where both or
   neither are and no such frame went: the other's stop goes the gap after it, up to two gaps
   after the STOP. (Review 78: ranked by the drive frame alone, an ``E60.0`` whose answer came
   late, or garbled, stayed counted past the next ``A`` CR poll, and a STOP then began with
   the elevation behind the gap: the turning azimuth, running by its line, was stopped 0.4 s
   after the STOP, 2.4 degrees more at 6 degrees a second, where at once was allowed.)
   (Review 74: always the azimuth first, an RC2800 that turns a composite's elevation, its
   azimuth never driven, stopped its elevation 0.35 s after a STOP 50 ms after an ``E`` CR
   poll, where at once was allowed. Attack 24: by the lines alone, a STOP within ~30 ms of an
   ``A200`` frame, the dish elevating, began with the elevation, the azimuth just set turning
   stopped 0.4 s after the STOP; at rest, a STOP right after ``E60`` began with the idle
   azimuth.) A drive frame counts from its write (base.py ``WatchesWrites``: one encoded and
   dropped unwritten, a target's second axis behind the gap when the STOP came, never
   counts) until that axis's first line owed to no frame written before it (a poll's answer
   still on its way when the frame went says nothing of it), an ``ERR`` too; an exchange
   given up forgets the lines owed (a lost one would keep the frame counted for good), and
   the axis's own stop frame ends it. A repeat of a stop whose
   frames still wait (``axes``: the order they go in) keeps them where they are and adds the
   frames of the axes whose stop already went after them; the exchange waits for the axes'
   lines in the order the frames go (rule 2).
10. The connection's first stop (base.py rule 9) goes behind whatever half frame an unplug or
   a cut write left in the box: ``A`` then ``A`` CR is ``AA``, answered ``ERR``, and the
   ``S`` stops the axis still selected (attack 22). So its first axis is selected twice
   (``A`` CR ``A`` CR ``S`` CR): the first selection takes the half frame in (``AA``, ``SA``,
   ``A12A``: none is a command the box takes), the second is whole and the ``S`` stops that
   axis. Never a bare line end first: it would carry out a cut ``A12`` of ``A123.4``. A
   clean line answers the extra selection with one more line of that axis, read as the
   exchange's (rule 2); a half frame taken in is answered ``A ERR=1`` (``E ERR=1``): the
   answer the stop provokes, so one such line in that stop's exchange is harmless, never
   told on R/error (review 71: "8 bytes that are no valid reply" after a replug whose stop
   took). A second, or one in any other exchange, is told as ever.
"""

from __future__ import annotations

import re

from bridge.protocols.base import (
    TENTHS_SLACK_DEG,
    Codec,
    HalfLine,
    HamlibRotType,
    JunkReason,
    JunkReply,
    LateAnswers,
    ModelSpec,
    Plain,
    PositionReply,
    Reply,
    RetargetPolicy,
    read_in_range,
    tenths_pair,
)

AZ_MAX_DEG = 360
EL_MAX_DEG = 180
EL_READ_MIN_DEG = -90  # a pot a little below the horizon is still a reading
READ_SLACK_DEG = TENTHS_SLACK_DEG  # rule 3 (base.py rule 10): a pot read in tenths
AXIS_GAP_S = 0.2  # between commands to the two axes (Hamlib's rc2800.c waits as long)
_MAX_LINE = 64
_POSITION = re.compile(
    rb"\s*(?P<axis>[AE])(?: P=|=)\s*(?P<deg>-?\d{1,3}(?:\.\d+)?)"
    rb"(?:\s+S=\d+)?(?:\s+(?P<state>[A-Z]{1,2}))?\s*"
)
# rule 7: the state word, moving (the sheet's MV; Hamlib's own example says M) or stopped (ST;
# Hamlib's example S); any other says neither
_DRIVING = {b"MV": True, b"M": True, b"ST": False, b"S": False}
_ERROR = re.compile(rb"\s*[AE] ERR=(?P<code>\d+)\s*")
_DRIVE = re.compile(rb"[AE]\d")  # rule 9: a frame that sets an axis turning (``A200.0``)
_ECHO = re.compile(rb"\s*(?:[AE](?:\d{1,3}(?:\.\d*)?)?|S)\s*")  # what we send, echoed
_LINES = re.compile(rb"[^\r\n]*[\r\n]")
# rule 1: what an axis's line may have lost at the port's opening, from its head to its end
_HEADS = (b"A", b"A ", b"A P", b"A=", b"A=1", b"A=1 ", b"A=1 S", b"A=1 S=")


class Rc2800Codec(Plain, LateAnswers):
    """Codec for one RC2800: ``elevation`` whether an elevation rotor hangs on it."""

    BOX = "the RC2800"

    def __init__(self, *, elevation: bool = True) -> None:
        self.elevation = elevation
        self._axes = b"AE" if elevation else b"A"
        self._buf = bytearray()
        self._rest = False  # rule 1: the rest of a line too long is still to come
        self._want: list[int] = []  # rule 2: the axes' lines the open exchange waits for
        self._noisy = False  # junk arrived since the exchange was opened
        self._seen: set[int] = set()  # rule 2: axes heard since the last reading
        self._heard: set[int] = set()  # rule 2: axes heard since the last exchange opened
        self._query = False  # the open exchange is a query (one line an axis)
        self._owed: set[int] = set()  # rule 2: axes a query read early owes, read as they come
        self._deg: dict[int, float] = {}  # each axis's latest value
        self._driving: dict[int, bool | None] = {}  # rule 7: and whether its motor runs
        self._written = 0  # rule 9: drive frames written on this connection
        self._driven: dict[int, int] = {}  # rule 9: an axis's drive frame since its last line
        self._before: dict[int, int] = {}  # rule 9: ... and its lines owed from before it
        self._owing: dict[int, int] = {}  # rule 9: each axis's lines owed for frames written
        self._first = True  # rule 1: no line of this connection has ended yet
        self._cut = b""  # rule 1: the connection's first line, a position line's tail
        self._late_newest = False  # rule 6: lines owed late, and no exchange opened since
        self._taken_in = False  # rule 10: the extra selection's ERR may come in this exchange
        self._el_unread = False  # rule 3: its elevation judged by no range (elevation_unread)

    # -- encoding -------------------------------------------------------------------------
    def wire_target(self, az_deg: float, el_deg: float | None = None) -> tuple[float, float | None]:
        return tenths_pair(az_deg, el_deg, AZ_MAX_DEG, EL_MAX_DEG if self.elevation else None)

    def encode_target(self, az_deg: float, el_deg: float | None = None) -> list[bytes]:
        az, el = self.wire_target(az_deg, el_deg)
        frames = [b"A%.1f\r" % az]
        return frames if el is None else [*frames, b"E%.1f\r" % el]

    def encode_stop(self) -> list[bytes]:
        return self.encode_stop_after(HalfLine.NONE)

    def encode_stop_after(
        self, half: HalfLine, axes: bytes | None = None, ready: bytes | None = None
    ) -> list[bytes]:
        """Rules 9 and 10 (base.py rule 9): each axis's stop, in the order ``axes`` go
        (``ready``: the axes whose stop the line writes at once, rule 9)."""
        at_once = self._axes if ready is None else ready
        first = sorted(self._axes, key=lambda axis: self._stop_rank(axis, axis in at_once))
        order = bytes(a for a in axes or bytes(first) if a in self._axes) or self._axes
        self._open(2, order)  # each axis answers its selection and its stop
        frames = [b"%c\rS\r" % axis for axis in order]
        if half is not HalfLine.NONE:  # rule 10: a selection to take a half frame in
            frames[0] = b"%c\r" % order[0] + frames[0]
            self._taken_in = True
        return frames

    def _stop_rank(self, axis: int, at_once: bool) -> tuple[bool, bool, int]:
        """Rule 9: an axis whose motor runs by its last line, or that a drive frame went to
        since, before one that neither; of those, one whose stop goes at once (``at_once``:
        no axis gap to wait) before one that must wait, then the most recent drive frame
        first (stable: A, E)."""
        driven = self._driven.get(axis, 0)
        runs = bool(driven or self._driving.get(axis))
        return not runs, runs and not at_once, -driven

    def frame_written(self, frame: bytes) -> None:
        """Rule 9 (base.py WatchesWrites): a drive frame marks its axis as just set turning
        until a line the box said after it; a stop frame ends the mark."""
        axis = frame[0] if frame else 0
        if axis not in self._axes:
            return
        if _DRIVE.match(frame):
            self._written += 1
            self._driven[axis] = self._written
            self._before[axis] = self._owing.get(axis, 0)
        elif frame.endswith(b"S\r"):
            self._driven.pop(axis, None)
        self._owing[axis] = self._owing.get(axis, 0) + frame.count(b"\r")  # a line a command

    def _answered(self, axis: int) -> None:
        """Rule 9: a line of ``axis`` came: one owed fewer, and the drive frame's mark ends at
        the first line owed to no frame written before it."""
        self._owing[axis] = max(0, self._owing.get(axis, 0) - 1)
        if axis not in self._driven:
            return
        if self._before.get(axis):
            self._before[axis] -= 1
        else:
            del self._driven[axis]

    def encode_query(self) -> list[bytes]:
        self._open(1)
        return [b"%c\r" % axis for axis in self._axes]

    def _open(self, lines_per_axis: int, axes: bytes | None = None) -> None:
        self._want = [axis for axis in axes or self._axes for _ in range(lines_per_axis)]
        self._query = lines_per_axis == 1
        # rule 2: no older than the exchange before this one, and none of one with line noise
        self._seen = set() if self._noisy else self._seen & self._heard
        self._noisy = False
        self._heard = set()
        self._owed = set()
        self._late_newest = False  # (rule 6: a line owed late may be this one's now)
        self._taken_in = False  # (rule 10: the stop's exchange is over)

    def expire_query(self) -> None:
        self._owe_late(len(self._want))  # rule 6: they may still come
        self._owing.clear()  # rule 9: (given up: a line lost must not keep a mark for good)
        self._before.clear()
        self._late_newest = self._late_newest or bool(self._want)
        self._want = []

    def awaiting_reply(self) -> bool:
        return bool(self._want)

    def harmless(self, junk: bytes) -> bool:
        """Echoes, blank lines, well-formed position lines in range (rules 1 and 3) and the tail
        of the connection's first line the opening cut (rule 1); an error is not."""
        if self._cut and junk.startswith(self._cut):  # rule 1: the connection's first line
            junk = junk[len(self._cut) :]
        junk = self._unsaid(junk)  # rule 10: the extra selection's ERR
        lines = re.split(rb"[\r\n]", junk)
        return all(
            not line.strip() or _ECHO.fullmatch(line) or self._in_range(line) for line in lines
        )

    # -- decoding -------------------------------------------------------------------------
    def feed(self, data: bytes) -> list[Reply]:
        self._buf += data
        out: list[Reply] = []
        while (m := _LINES.match(self._buf)) is not None:
            line = bytes(m.group())
            del self._buf[: m.end()]
            if self._rest:  # rule 1: the end of a line already given up as too long
                self._rest = False
                self._junk(line, JunkReason.NOISE, "the rest of a line too long", out)
            elif len(line) > _MAX_LINE + 1:  # (its end came in the same read)
                self._junk(line, JunkReason.NOISE, "line too long", out)
            else:
                self._line(line, out)
        if len(self._buf) > _MAX_LINE or (self._rest and self._buf):
            if not self._rest:
                self._junk(bytes(self._buf), JunkReason.NOISE, "line too long", out)
            self._buf.clear()
            self._rest, self._first = True, False
        return out

    def _line(self, raw: bytes, out: list[Reply]) -> None:
        first, self._first = self._first, False
        if first and self._cut_by_opening(raw):
            self._cut = raw
            if self._want or self._owed:  # (it may be a mangled line: the exchange is spoiled)
                self._noisy, self._owed = True, set()
            out.append(JunkReply(raw, JunkReason.CHATTER, "a line the port's opening cut"))
            return
        if not raw.strip() or _ECHO.fullmatch(raw):
            out.append(JunkReply(raw, JunkReason.CHATTER, "echo" if raw.strip() else "blank"))
            return
        if (m := _ERROR.fullmatch(raw)) and raw.strip()[0] in self._axes:
            self._answered(raw.strip()[0])  # rule 9: a frame's answer (a target refused)
        if m and self._taken_in:  # rule 10: the stop provoked it
            self._taken_in = False
            self._say(raw)
            why = "the answer to the selection that took a half frame in"
            out.append(JunkReply(raw, JunkReason.CHATTER, why))
            return
        if m:
            code = m.group("code").decode()
            # rule 1: a target's refusal only where a target is one frame
            reason = JunkReason.CHATTER if self.elevation else JunkReason.REFUSED
            refused = None  # (the az/el box: the axis whose frame it refused, if a bearing's)
            if self.elevation:
                refused = "elevation" if raw.lstrip().startswith(b"E") else "azimuth"
            out.append(JunkReply(raw, reason, f"controller error {code}", refused))
            return
        m = _POSITION.fullmatch(raw)
        if m is None:
            self._junk(raw, JunkReason.NOISE, "not a reply line", out)
            return
        axis, value = m.group("axis")[0], self._read(m)
        if value is None:  # rule 3
            self._junk(raw, JunkReason.SPOILED, "position out of range", out)
            return
        if axis not in self._axes:
            out.append(JunkReply(raw, JunkReason.CHATTER, "an elevation from an azimuth model"))
            return
        if axis not in self._owed and self._late_lines and self._late_newest:
            self._late_lines -= 1  # rule 6: the newest word, with no exchange since: the stream
        elif axis not in self._owed and self._late_answer(raw, out):  # rule 6
            return
        self._deg[axis] = value
        self._driving[axis] = _DRIVING.get(m["state"] or b"")
        self._answered(axis)  # rule 9
        self._seen.add(axis)
        self._heard.add(axis)
        if self._want:
            if axis == self._want[0]:
                self._want.pop(0)
            if self._want and not (self._query and len(self._seen) == len(self._axes)):
                return  # the exchange's other lines are still to come (rule 2)
            self._owed, self._want = set() if self._noisy else set(self._want), []
            if self._noisy:
                self._seen.clear()
                out.append(JunkReply(raw, JunkReason.UNTRUSTED, "position after line noise"))
                return
        elif axis in self._owed:  # rule 2: this poll's own line, after its early reading
            self._owed.discard(axis)
        elif len(self._seen) < len(self._axes):
            out.append(JunkReply(raw, JunkReason.CHATTER, "one axis's position, kept"))
            return
        self._seen.clear()
        flags = [self._driving.get(axis) for axis in self._axes]
        driving = True if any(flags) else None if None in flags else False  # rule 7
        out.append(PositionReply(self._deg[ord("A")], self._deg.get(ord("E")), driving=driving))

    def elevation_unread(self) -> None:
        """Rule 3: the box's elevation is never turned nor read (a composite's azimuth box):
        whatever its ``E`` line says spoils nothing of the azimuth (base.ScalesElevation)."""
        self._el_unread = True

    def _in_range(self, line: bytes) -> bool:
        """Rules 1 and 3: ``line`` is a position line whose value is in its axis's range (or
        within its slack)."""
        m = _POSITION.fullmatch(line)
        return m is not None and self._read(m) is not None

    def _read(self, m: re.Match[bytes]) -> float | None:
        """Rule 3: the value of position line ``m``, a little past an end read as the end;
        None past the slack; an elevation never read, as it reads."""
        if self._el_unread and m.group("axis") == b"E":
            return float(m.group("deg"))
        return _read(m)

    @staticmethod
    def _cut_by_opening(raw: bytes) -> bool:
        """Rule 1: ``raw``, no line of its own, is the tail of an axis's position line."""
        if not raw.strip() or _ECHO.fullmatch(raw) or _ERROR.fullmatch(raw):
            return False
        if _POSITION.fullmatch(raw):
            return False
        return any(_POSITION.fullmatch(head + raw) for head in _HEADS)

    def _junk(self, raw: bytes, reason: JunkReason, why: str, out: list[Reply]) -> None:
        self._cut = b""  # rule 1: excused only while no noise came after it
        if self._want or self._owed:
            self._noisy = True
            self._owed = set()  # (a line after noise is none of the early reading's)
        out.append(JunkReply(raw, reason, why))


def _read(m: re.Match[bytes]) -> float | None:
    """Rule 3: the value of position line ``m``, a little past an end read as the end; None
    past the slack."""
    low, top = (0, AZ_MAX_DEG) if m.group("axis") == b"A" else (EL_READ_MIN_DEG, EL_MAX_DEG)
    return read_in_range(float(m.group("deg")), low, top, READ_SLACK_DEG)


def _spec(name: str, display: str, *, elevation: bool) -> ModelSpec:
    line = len(b"A P= 123.4 S=9 MV\r")  # one axis's answer
    return ModelSpec(
        name=name,
        display_name=display,
        manufacturer="M2",
        codec_factory=lambda: Rc2800Codec(elevation=elevation),
        baud=9600,
        has_elevation=elevation,
        retarget=RetargetPolicy.DIRECT,  # a new bearing is taken while turning
        axis_gap_s=AXIS_GAP_S if elevation else 0.0,
        axis_prefixes=(b"A", b"E"),
        az_min_deg=0.0,
        az_max_deg=float(AZ_MAX_DEG),
        el_min_deg=0.0,
        el_max_deg=float(EL_MAX_DEG) if elevation else 0.0,
        az_wraps=True,
        # a poll (A CR) is one stray digit from a target (A5 CR): rule 8
        unasked_moves="stop",
        el_unasked_moves="stop",  # rule 8: E CR, E5 CR, on a composite's elevation box
        # Hamlib waits up to a second; the elevation's answer comes 200 ms after the azimuth's
        reply_timeout_s=1.0,
        noise_deg=0.5,  # potentiometers read in tenths
        nominal_speed_deg_s=6.0,
        nominal_el_speed_deg_s=3.0,
        whole_degrees=False,
        tenths=True,  # rule 4
        query_bytes=4 if elevation else 2,  # A CR, E CR
        reply_bytes=2 * line if elevation else line,
        hamlib_model=1001,
        hamlib_rot_type=HamlibRotType.AZEL if elevation else HamlibRotType.AZ,
        hamlib_info=None,  # Hamlib's m2 backend has no get_info
    )


MODELS: dict[str, ModelSpec] = {
    "rc2800": _spec("rc2800", "RC2800 az/el", elevation=True),
    "rc2800-az": _spec("rc2800-az", "RC2800 azimuth", elevation=False),
}

_check: type[Codec] = Rc2800Codec  # Rc2800Codec satisfies the Codec protocol
