"""One open serial connection's line discipline, sans-IO: frames out, timing in, no port.

What it does: queues the frames to write, keeps the controller's replies in order, decides when
the line may carry the next frame, polls, holds back junk until the line is quiet, and says when
it next needs attention. What it does not do: decide anything about motion or commands
(session.py), parse bytes (the model's codec) or touch a port (worker.py writes what ``output``
hands it).

Rules:
1. A reply is owed when the codec says so after a write; its deadline is the model's reply
   timeout. An owed reply that does not come is given up at its deadline (the session decides).
   A slew's report (a controller silent while it moves) is owed until twice the travel time at
   the rotor's speeds plus SLEW_MARGIN_S; a stop written during the slew brings that deadline
   forward to one reply time: a stopped controller reports at once, or the stop was lost, or
   the slew had already ended (and its report was lost).
2. Silence is counted from the last valid reply, or from the end of a wait for a slew's report
   (a controller that was silent for a whole slew was not "not answering"), or from the last
   garbled answer (rule 11; ``unread_for`` counts without those: controller.py rule 2 bounds
   them), but not from one torn past any form (rule 11: no reading can come from it; review 118:
   counted, a turn on a line that tore every byte ran 3 s longer unwatched; only the words count
   it, ``torn_since_heard``). Only the questions show it is the controller's
   (docs/architecture.md rule 15): ``asked_for_s`` reaches from the question the last valid
   reply answered to the last one asked. Where the clock has passed the silence's end and the
   questions have not (the last went out a reply time before the end, and was lost), the
   controller is asked once more then (``ask_verdict``): that reply, owed only until it can be
   whole (rule 7's hold, rule 9's quiet time) and VERDICT_SLACK_S, decides. (A review: a GS-232B
   whose line lost 2.6 s of every 3.6 s was called silent 3.2 s into a turn, and the turn
   stopped, just as the question that went next would have been answered.)
3. On a half-duplex line (``spec.full_duplex`` False) nothing is written while a reply is owed,
   except a stop on a controller that takes one at any time (``spec.stop_interrupts``).
4. A poll is sent only when due, when nothing is owed and no stop is waiting, and not before
   the controller's refusal of the target written last can have come (``spec.refusal_bytes``:
   the target and the refusal at the line rate, a byte time to turn round, and how late its
   replies are, rule 7): a refusal then answers the target, not a poll written after it
   (motion.py rule 8 gives a refusal to a target only when nothing was written after it).
   Likewise neither a poll nor a target is written before the refusal of the setting written
   last can have come (``write_setting``, ``setting_until``; session.py asks for the target),
   and such a setting is written only on a quiet line (``quiet``: no reply owed, nothing
   waiting to go), so that its refusal comes within that time: a GS-232's ``?>`` to a speed
   written in the same step as a new target was taken for the target's, and the rotor,
   turning to the one before, was stopped and the new target dropped (a cold review).
5. Junk is judged once the line has been quiet for JUNK_QUIET_S, so a banner paced byte by byte
   is judged whole (by the codec: it knows what its controller emits besides replies).
6. A stop cancels every frame still waiting for its inter-frame gap.
7. Bytes of a poll's reply are not worth a wake-up each: until the whole reply can have arrived
   at the line rate, plus one byte time for the controller to turn round (``hold_reads_until``),
   the worker leaves them in the port and reads them in one go. Only the mailbox (a stop) is
   watched meanwhile. If part of the reply is still missing then (a controller that takes its
   time), the hold starts again for the time the missing bytes take: a late reply costs a
   wake-up per chunk, not per byte. The hold's end may be met up to one quiet time of rule 9
   late (``hold_reads_latest``): a reply that came partly is then read in the wake-up that
   takes the readings of the replies that came whole (lines.py rule 7), not in one of its own.
   The hold also waits out how late this controller's replies have been whole (``late_s``:
   a turn-round longer than a byte time, a USB adapter that delivers in chunks), so that a
   controller that is always a little late has each reply read once, not once in part and
   again for the rest (and its reading taken in a wake-up of its own, after the others').
   How late a reply that took more than one read was whole is the earliest it can have been
   (the read that completed it, or, if that read came at the end of a hold, the bytes still
   missing at the read before, at the line rate with one of them on its way, whichever is
   sooner) plus a byte time. Two such replies in a row raise the hold to the less late of the
   two, by one quiet time of rule 9 at most per reply (an adapter always 16 ms late is learned
   in a few replies); a late reply after one whole in time raises nothing, so that a
   controller late now and then (a busy machine) does not hold every reply for its worst.
   Each reply whole at the hold's end lowers it by LATE_EASE of itself, so that a controller
   that got quicker holds the replies longer for a while, not for ever. It is at most
   LATE_MAX_S. A reply whose hold a stop ended (a read that found nothing before the hold's
   own end) teaches nothing, and a poll of several frames (RC2800's two axes, the second
   after the axis gap) neither learns nor waits: its hold counts both replies from the first
   frame. The reading is still taken only after the quiet time of rule 9 from the read. A
   stop due ends the hold: the port is read at once and watched, so a stop that waits for the
   reply on a half-duplex line (rule 3) goes the moment the reply is whole, not at the hold's
   end.
8. Polls keep to a grid of their interval on the monotonic clock (the next poll at the first
   multiple of the interval at least half an interval away): every rotator polling at the same
   interval polls at the same instants, so one thread serves a round of them with one wake-up
   (lines.py rule 1). A poll asked for at once (a new target) is off the grid; the next one is
   back on it, never less than half an interval later.
9. One exchange, one reading: a reading is held until the line has been quiet for SETTLE_BYTES
   byte times (SETTLE_MIN_S at least) and only then taken (``settled``); bytes that go on
   arriving hold it longer, up to a whole reply's bytes more (a frame that starts in the quiet
   time is judged whole). Bytes in that time that no healthy exchange has (a second reply,
   asked for or not, line noise; not the controller's own chatter, which its codec calls
   harmless) spoil it: the exchange is not trusted, the reading is dropped and the controller
   asked again (a glitch ``;359`` just before the real ``;180`` is neither published nor taken
   as a move). A reply owed is not overdue while its reading is held (nor does its deadline
   wake the session meanwhile). The quiet time is no reply still coming: a stop goes out at
   once (rule 3 does not hold it back once the reply is whole), and a stop ends the held
   exchange there, before it is written (``end_held``): its reading is taken if the reply is
   whole and no byte came after it, and dropped otherwise (bytes still coming may be the
   second reply that spoils it; the controller is asked again). What comes after the stop
   belongs to the stop's own exchange (its reply is a reading of its own, never a second reply
   that spoils the held one).
10. A controller that needs time between commands to its two axes (``spec.axis_gap_s``,
   RC2800; a frame's axis by its first bytes, ``spec.axis_prefixes``) gets it: a command's or
   a poll's frames (a list from the codec) go that far apart, and no frame goes sooner after
   one to the other axis, written or waiting. A target goes first to the axis last addressed
   (no wait), and the poll frames still waiting are dropped for it (its answers answer the
   poll); a poll waits while frames do and for the gap after any frame. A stop waits for
   nothing but that gap: its first frame (the codec's order: rc2800.py rule 9, which asks
   the frames written too, each told to a codec that ``WatchesWrites``, and is told which
   axes' stop the gap lets go at once, ``ready``) goes at
   once if the gap allows, else when the gap since the last frame to the other axis ends,
   its others the gap apart. (Attack 22: a stop's ``A`` 2 ms after an ``E`` CR poll broke the
   gap; review 71: starting with the axis last addressed instead put the azimuth's stop a
   whole gap after the STOP.) A stop's frames still waiting are kept, their times too, by a
   stop written meanwhile (a STOP's second copy, a repeat: stops.py rule 1): it adds only
   the frames of the axes whose stop already went, after them (review 71: the repeat had
   cancelled the azimuth's waiting frame and begun again, its stop 0.3 s after the STOP).
11. A garbled answer: bytes no healthy exchange has (rule 9's: not the controller's harmless
   chatter, nor a refusal) while a reply is owed and no slew. The controller answered (rule 2),
   but nothing of it is a reading. Its exchange, ended without one (at its deadline, or if the
   codec awaits no more, it took the garbled reply for the reply, once no byte at all has been
   read for JUNK_QUIET_S and no read is held back, rule 7: the rest of a garbled reply, good
   lines too, is still its own), is asked again at once, once: a garbled answer to that
   re-poll waits for the next poll (a line gone bad is not polled back to back). Only where a
   stop goes at any time (full duplex, or ``stop_interrupts``): on a half-duplex line the
   re-poll's reply would hold a stop back (rule 3). An exchange whose reading is not trusted
   (controller.py rule 5) is asked again at once on any line, but once so too. A poll's own
   right to a re-poll is lost only by being one, and given back by a valid answer: a target
   written before the re-poll takes its place, and a target that waits for a fresh reading
   asks at once only while the right holds (then at the moving rate).
   An attack pass: 0.3 % of bytes flipped garbled a SatEL's long reports two in a row, and
   it went offline 5-12 times in 20 minutes, dropping targets. A review: a SatEL report
   garbled in its second line was closed 50 ms after that line, the re-poll went onto the
   half-duplex line with 80 bytes still coming, their tail closed the re-poll's exchange and
   a report from before a point ended its slew: the next ``z`` went into the slew; one noise
   byte before every GS-232B answer had it polled 44 times a second.
   An answer torn past any form is garbled too: an exchange given up (``_tears``) with
   bytes read since its question, together with the one before TORN_SHARE of two of the
   shortest replies or more (``spec.least_reply_bytes``: review 118, half the longest, a line
   read at half rate, 7 of 14 bytes, or a GS-232A's 3 and 4 in turn, never counted), and none
   of them forming a
   reply of the controller's (``parsed``: any the codec makes but bytes that form none, NOISE
   or SPOILED not harmless; a reading, a version, an echo, a power-on byte, a late answer or a
   refusal is of its form), the second such in a row with no reply formed between, once per
   exchange however many its bytes; it ends no silence (rule 2). A line that garbles every
   byte, its line ends too (a
   failing RX level shifter, the wrong baud rate) leaves the codec waiting for a line end that
   never comes: such answers were silence, 'does not answer', and counted nothing toward
   controller.py rule 9's unwatched stop until the codec's buffer spilled (review 113: 22 s, a
   turn at the start 45 degrees past ``az_min_deg``; attack 30: the wrong baud rate told as a
   cable). The first of a run alone is not counted: an answer still arriving (in parts, late)
   forms its reply with its rest. The run goes on across a replug (``torn_run``: controller.py
   rule 9 counts so; review 118, begun anew with each link, an adapter that reset every 2 s
   never had one counted). A stray byte now and then is no answer (review 99: any byte
   counted kept an unwatched turn online 3 s longer, and one NUL as a box switched off was told
   as the wrong baud rate).
12. A controller that answers late: a line of the answer to the question given up last that
   comes before the next question (protocols/base.py rule 7: never a reading) says how long
   after that question it came (``answered_late``); from then on every answer is waited for
   that much past the reply time, and OVERDUE_SHARE of it more (JUNK_QUIET_S at least), up to
   one reply time more (``reply_wait_s``: at most twice the model's reply time, so that a lost
   reply still ends in time and, on a half-duplex line, a stop waits no longer than that, and
   the rest of an answer then arriving, for an answer under way). Each answer in the reply time
   gives back OVERDUE_EASE of it. So that such an answer can come before the next question
   (which would take it for its own: no line says which poll it answers), a poll (not a stop's
   or a target's exchange) given up with nothing read at all, the first since a valid reply,
   holds the next poll until twice the reply time from it, or until every line it owes came. A
   verdict's poll (rule 2) does not wait, nor does a poll after one of several frames (RC2800's
   two axes: as in rule 7, their timing is not one answer's). An answer whose bytes are
   arriving when its wait (or the hold) ends is let finish: given up (the next poll written)
   once the line has been quiet JUNK_QUIET_S, and no later than its whole reply's time at the
   line rate and that quiet time past the wait (``_overdue_t``, ``_late_hold_t``); on a
   half-duplex line a stop waits that much more at most. (An attack pass: an RT-21 answering
   0.585 s after each poll, whole just past the 0.6 s, had each answer given up with its ``;``
   on its way, which spoiled the next poll's; told as junk, then offline as 'answers only
   garbled replies: a noisy line?', the turn stopped short.) A controller later than the
   longest wait goes offline after its silence timeout as one that gives nothing, but the error
   says it answers, and how late (controller.py rule 2); where a poll went before its late
   answer came (the moving polls, a GS-232B's idle ones), that poll takes it, and the next the
   one after: online, a poll behind (docs/controllers.md's limit: no line says which poll it
   answers). (An RT-21 behind a serial server, 0.1 s past its 0.3 s, was offline from the
   start, 'does not answer'; a GS-232B 0.1 s past its 1 s, whose next poll went as the last was
   given up, had each poll take the one before's answer: its bearing published 5 degrees behind
   a turning rotor.)
13. The connection's first frame lands behind whatever half frame the connection before left
   in the box (an adapter pulled mid-frame; runtime/port.py rule 6 loses the link rather than
   leave a frame cut, so only a connection's end leaves one). A stop written as that first
   frame is the codec's stop behind a half line (protocols/base.py rule 9: ``HalfLine``),
   told whether a move may be what was cut: ``cut_move``, the controller's word on the
   connection before (``move_unsure``: a target was written there and no valid reply
   answered a question written after it, so its bytes may not all have reached the box; a
   bridge just started knows nothing and says it may). Any frame written ends the half line:
   stops after it are the plain ones. (Attack 22: a GS-232B's stop owed across an unplug was
   read as ``SS`` behind the ``S`` the unplug cut, refused, and the rotor turned on 2 s.)
14. The connect's frames (the codec's ``encode_connect``) keep these rules as every other frame
    does: each is written when the line takes it (rule 3: on a half-duplex line, not while the
    reply the one before owes is still coming; ``free``), and what it asks is owed from its
    write (protocols/base.py ``PacedConnect``), so a reply that is no reading (a version)
    closes its exchange when the codec awaits no more (``replied``). Until the last is written
    nothing else goes but a stop: no poll, target, setting or enable. A controller whose connect
    begins with its stop (``spec.connect_stops``: a SatEL, that takes no input but a stop while
    it slews, and may be slewing for a process before this one) gets slew.py rule 6 for it: the
    stop is followed by the stopped controller's report or written again, up to
    SLEW_STOP_TRIES, and only then does the rest go, once the line has been quiet JUNK_QUIET_S.
    Each stop's report is waited for as a verdict's reply (rule 2): until it can be whole, and
    VERDICT_SLACK_S (a stopped controller reports at once; most connects find it at rest, and a
    reply time a try would hold each of them 6 s). (Attack 22: ``s x ? t... g z`` went out in one
    breath: one noise burst on the ``s`` let the set-up into the slew, which wedged the box, shown
    idle with no error; and the clock line, ``g`` and ``z`` went while the box still answered
    ``?``.)
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from dataclasses import replace

from bridge.protocols.base import (
    Codec,
    HalfLine,
    JunkReason,
    JunkReply,
    LateAnswers,
    ModelSpec,
    PacedConnect,
    PositionReply,
    Reply,
    StopsOnTheLine,
    WatchesWrites,
)
from bridge.session.slew import SLEW_MARGIN_S, SLEW_STOP_TRIES, SLEW_TIME_FACTOR, Slew

JUNK_QUIET_S = 0.05
SETTLE_BYTES = 3  # rule 9: the next byte of a reply sent back to back comes after one
SETTLE_MIN_S = 0.005  # rule 9: at a high baud rate, a little longer than three byte times
LATE_MAX_S = 0.05  # rule 7: a USB adapter's latency timer (16 ms by default), and more
LATE_EASE = 1 / 256  # rule 7: of the learned lateness, given back per reply whole in time
VERDICT_SLACK_S = 0.2  # rule 2: a verdict's reply is owed this long after it can be whole
OVERDUE_SHARE = 0.25  # rule 12: a late answer's lateness past the reply time, waited on top
OVERDUE_EASE = 1 / 16  # rule 12: of the learned overdue time, given back per answer in time
TORN_SHARE = 0.5  # rule 11: of a reply's bytes, read with none formed: a torn answer
_FORMLESS = (JunkReason.NOISE, JunkReason.SPOILED)  # rule 11: bytes that form no reply
_JUNK_KEEP = 4096  # a run of banners (a STOP pressed again and again on an idle Rotor-EZ) fits

__all__ = ["JUNK_QUIET_S", "SLEW_MARGIN_S", "SLEW_TIME_FACTOR", "Link", "Slew"]


def _grid(now: float, interval_s: float) -> float:
    """Rule 8: the first multiple of ``interval_s`` at least half of it after ``now``."""
    return math.ceil((now + interval_s / 2) / interval_s) * interval_s


class Link:
    def __init__(self, codec: Codec, spec: ModelSpec, now: float, baud: int) -> None:
        self.codec = codec
        self.spec = spec
        # told of each frame written (protocols/base.py WatchesWrites: rc2800.py rule 9)
        self._watches = codec if isinstance(codec, WatchesWrites) else None
        self._byte_s = 10 / baud  # 8N1
        self._settle_s = max(SETTLE_MIN_S, SETTLE_BYTES * self._byte_s)  # rule 9
        # the model's reply timeout is for its default baud: a slower line needs longer
        slower_s = max(0.0, spec.exchange_time_s(baud) - spec.exchange_time_s())
        self.reply_timeout_s = spec.reply_timeout_s + slower_s
        self._hold_until = 0.0
        self._hold_bytes = 0  # of the polled reply, not read yet (rule 7)
        self._hold_base = 0.0  # rule 7: when the polled reply can be whole at the line rate
        self._hold_reads = 0  # rule 7: reads of the polled reply so far
        self._late_seen = 0.0  # rule 7: when it can be whole at the earliest, by the last read
        self._last_late = 0.0  # rule 7: how late the last polled reply was (0: in time)
        self._learns = False  # rule 7: the poll was one frame
        self.late_s = 0.0  # rule 7: how late this controller's replies have been whole
        self.overdue_s = 0.0  # rule 12: waited past the reply time for a controller's answer
        self._given_up_t = -math.inf  # rule 12: when the question given up last went out
        self._late_answer: tuple[float, float] | None = None  # rule 12: when, how long after
        self._late_hold_until = -math.inf  # rule 12: no poll before then (an answer late)
        self._polled_t = -math.inf  # rule 12: when the last poll went out
        self._quiet_from_t = now  # silence counts from here when no reply came since
        self._answered_t = now  # rule 2: when the question the last valid reply answered went out
        self._verdict = False  # rule 2: the next poll is a verdict
        self._reply_deadline: float | None = None
        self._next_poll = now
        self._refusal_until = -math.inf  # rule 4: a target's refusal can come until then
        self.setting_until = -math.inf  # rule 4: a setting's refusal can come until then
        self._last_reply_t: float | None = None
        self._heard_t = -math.inf  # ``heard``: the last reply whose reading was doubted
        self._stop_due = False
        # when, frame, a poll's, a stop's (rule 10)
        self._outbox: deque[tuple[float, bytes, bool, bool]] = deque()
        self._output: list[bytes] = []
        self._slew: Slew | None = None
        self._junk = bytearray()
        self._junk_t = 0.0
        self._held: PositionReply | None = None  # rule 9: a reading, until the line is quiet
        self._held_until = 0.0
        self._held_cap = 0.0  # rule 9: bytes after it hold it no longer than this
        self._held_after = False  # rule 9: bytes were read after the held reading
        self._last_write_t = -math.inf  # rule 10
        self._asked_t = -math.inf  # rule 2: the last frame written that awaits a reply
        self._first_asked_t = -math.inf  # ... the first of them since the last valid reply
        self._last_axis: bytes | None = None
        self._garbled = False  # rule 11: the reply owed now came garbled
        self.poll_garbled = False  # ... the exchange closed last was a poll's, answered garbled
        self._garbled_t = -math.inf  # rule 11: the last garbled answer
        self._torn_t = -math.inf  # rule 11: the last answer torn past any form (no silence's end)
        self._repoll_due = False  # rule 11: the next poll asks again for a garbled answer
        self._repolled = False  # rule 11: the last poll did
        self._read_t = -math.inf  # rule 11: the last bytes read
        self._formed_t = -math.inf  # rule 11: the last reply of the controller's form
        self._torn = 0  # rule 11: the bytes of the exchange given up last, none formed (0: not)
        self._asked_bytes = 0  # rule 11: bytes read since the last frame that awaits a reply
        self._fresh = True  # rule 13: no frame written on this connection yet
        self.cut_move = True  # rule 13: a move the connection before wrote may have been cut
        self._move_t = -math.inf  # rule 13: when the last target's last frame goes
        self._whole_t = -math.inf  # rule 13: the last question a valid reply answered
        self._connecting: deque[bytes] = deque()  # rule 14: the connect's frames still to go
        self._connect_stops = 0  # rule 14: the connect's stops written
        self._connect_wait: float | None = None  # rule 14: its stop's report awaited until then

    # -- what the session reads -------------------------------------------------------------
    @property
    def slew(self) -> Slew | None:
        return self._slew

    @property
    def last_reply_t(self) -> float | None:
        return self._last_reply_t

    @property
    def reply_owed(self) -> bool:
        return self._reply_deadline is not None

    @property
    def stop_due(self) -> bool:
        return self._stop_due

    def hold_reads_until(self) -> float:
        """Rule 7: bytes arriving before this time can wait in the port (none while a stop
        is due)."""
        if self._reply_deadline is None or self._stop_due:
            return 0.0
        return self._hold_until

    def hold_reads_latest(self) -> float:
        """Rule 7: the latest the held bytes are read, one quiet time after the hold ends."""
        if self._reply_deadline is None or self._stop_due or not self._hold_until:
            return 0.0
        return self._hold_until + self._settle_s

    def got_bytes(self, count: int, now: float) -> None:
        """``count`` bytes were read (none: the port had nothing at the hold's end): hold again
        for what the polled reply still lacks, and note how late it is (rule 7)."""
        if not count:  # the port is watched for the reply from now on
            if now < self._hold_until:  # a stop ended the hold: its timing tells nothing
                self._learns = False
            elif self._hold_bytes:  # the read that completes it comes as the bytes do
                self._hold_reads += 1
                self._late_seen = math.inf
            return
        self._read_t = now  # rule 11
        self._asked_bytes += count
        if self._hold_bytes:
            self._hold_reads += 1
            missing = max(0, self._hold_bytes - count)
            if missing:  # whole no sooner than the rest at the line rate (one on its way)
                self._late_seen = now + (missing - 1) * self._byte_s
            self._hold_bytes = missing
        self._hold_until = now + self._hold_bytes * self._byte_s if self._hold_bytes else 0.0
        if self._held is not None:  # rule 9: the line is not quiet yet
            self._held_after = True
            self._held_until = min(self._held_cap, max(self._held_until, now + self._settle_s))

    def parsed(self, replies: Sequence[Reply], now: float) -> None:
        """Rule 11: what the codec made of the bytes read now: a reply of the controller's
        form (a reading, a version, an echo, a power-on byte, a late answer, a refusal: any but
        bytes that form none) shows its line does not tear every byte."""
        for reply in replies:
            if isinstance(reply, JunkReply) and reply.reason in _FORMLESS:
                if not self.codec.harmless(reply.data):  # (a banner is of its form)
                    continue
            self._formed_t, self._torn = now, 0
            return

    def output(self) -> list[bytes]:
        """The frames written since the last call, in order: the worker puts them on the wire."""
        out, self._output = self._output, []
        return out

    # -- writing ----------------------------------------------------------------------------
    def write(self, frame: bytes, now: float) -> None:
        self._output.append(frame)
        if self._watches is not None:
            self._watches.frame_written(frame)
        self._fresh = False  # rule 13: its end ends any half frame in the box
        self._last_write_t = now
        self._last_axis = self._axis(frame)
        if self._reply_deadline is None and self.codec.awaiting_reply():
            self._reply_deadline = now + self.reply_wait_s
            self._given_up_t = -math.inf  # rule 12: its late answer is this one's now
            if self._asked_t <= self._heard_from():  # rule 2
                self._first_asked_t = now
            self._asked_t = now
            self._asked_bytes = 0  # rule 11
            self._hold_bytes, self._hold_until = 0, 0.0  # a poll sets its own (rule 7)
            self._hold_reads = 0
            self._garbled = self._repolled = False  # rule 11: a new exchange (poll sets its own)

    @property
    def quiet(self) -> bool:
        """Rule 4: no reply owed and nothing waiting to be written."""
        return self._reply_deadline is None and not self._outbox

    def write_setting(self, frame: bytes, now: float) -> None:
        """A setting (a GS-232's speed): written now; rule 4: no target before its refusal can
        have come."""
        self.write(frame, now)
        if self.spec.refusal_bytes:
            sent = len(frame) + self.spec.refusal_bytes + 1
            self.setting_until = now + sent * self._byte_s + self.late_s

    def want_stop(self) -> None:
        """A stop is due: written as soon as the line allows (``flush_stop``). Rule 6 (rule
        10: a stop's frames still waiting keep their time)."""
        self._keep_stop_frames()
        self._stop_due = True

    def stop_ready(self) -> bool:
        """A stop is due and the line takes it now (``flush_stop`` would write it)."""
        return self._stop_due and self.free(for_stop=True)

    def end_held(self, now: float) -> PositionReply | None:
        """Rule 9: a stop is about to be written and ends the held exchange: its reading if
        the reply is whole and nothing came after it; otherwise it is dropped and the
        controller asked again after the stop."""
        held, self._held = self._held, None
        if held is None:
            return None
        if not self.codec.awaiting_reply():  # its reply came: the stop's is owed now
            self._reply_deadline = None
        if self._held_after or self.codec.awaiting_reply():
            self._next_poll = now
            return None
        return held

    def flush_stop(self, now: float) -> bool:
        """Write the due stop if the line allows it now; True if it was written. During a slew
        the report now comes within one reply time, or the stop was lost, or the controller had
        already stopped (the session decides)."""
        if not self._stop_due or not self.free(for_stop=True):
            return False
        self._stop_due = False
        self.write_stop(now)
        return True

    def write_stop(self, now: float) -> None:
        """Write a stop now, whatever the line is doing (a stalled motor must not wait). A
        reading still held (rule 9) is settled now if ``end_held`` would take it (``settled``
        hands it over at once), dropped otherwise."""
        waiting = self._keep_stop_frames()
        held = self._held
        if held is not None and self.end_held(now) is held:
            self._held, self._held_until = held, now
        first_t = now
        if waiting:  # rule 10: a repeat: what waits keeps its time, the axes gone go after it
            frames = self._stop_frames(waiting)[len(waiting) :]
            self._queue(frames, self._outbox[-1][0] + self._gap_s, now, stop=True)
        else:
            frames = self._stop_frames(ready=self._ready_axes(now))
            first_t = max(now, self._paced_from(frames[0]))  # rule 10: the axis gap only
            if first_t > now:
                self._queue(frames, first_t, now, stop=True)
            else:
                self.write(frames[0], now)
                self._queue(frames[1:], now + self._gap_s, now, stop=True)
        if self._slew is not None:
            self._slew = replace(self._slew, stops=self._slew.stops + 1)
            self._reply_deadline = first_t + self.reply_timeout_s

    def _keep_stop_frames(self) -> bytes:
        """Rule 10: the outbox cleared but for a stop's frames still waiting; their axes, in
        the order they go (empty: none waits)."""
        kept = self.spec.axis_gap_s > 0  # (only frames the axis gap keeps apart wait so)
        self._outbox = deque(e for e in self._outbox if e[3] and kept)
        return b"".join(self._axis(e[1]) or b"" for e in self._outbox)

    def connect(self, frames: list[bytes], now: float) -> None:
        """Rule 13: the connect's frames, each written when the line takes it (a leading stop
        where the model's connect begins with one: followed by its report or written again)."""
        self._connecting = deque(frames)
        if self.spec.connect_stops and self._connecting:
            self._connecting.popleft()  # (the codec's stop, written as every stop is)
            self._connect_stop(now)
        self.flush_connect(now)

    @property
    def connecting(self) -> bool:
        """Rule 13: frames of the connect still to go (or its stop's report awaited)."""
        return bool(self._connecting) or self._connect_wait is not None

    def _connect_stop(self, now: float) -> None:
        """Rule 13: the connect's stop, its report awaited until it can be whole."""
        self.write_stop(now)
        self._connect_stops += 1
        whole_s = (1 + self.spec.reply_bytes + 1) * self._byte_s + self.late_s + self.overdue_s
        self._connect_wait = now + whole_s + self._settle_s + VERDICT_SLACK_S

    def _connect_quiet_t(self) -> float:
        """Rule 13: the rest of the connect goes no sooner (a stopped controller's report,
        or any bytes still coming, let finish first)."""
        return self._held_until if self._held is not None else self._read_t + JUNK_QUIET_S

    def flush_connect(self, now: float) -> None:
        """Rule 13: the connect's next frames, as far as the line takes them now."""
        if self._connect_wait is not None:
            if now < self._connect_wait:
                return
            if self._connect_stops < SLEW_STOP_TRIES:
                self._connect_stop(now)  # no report: lost on the line, or at rest
                return
            self._connect_wait = None  # (no report after its tries: at rest)
        if self._connecting and self.spec.connect_stops and now < self._connect_quiet_t():
            return
        while self._connecting and not self._stop_due and self._line_free():
            frame = self._connecting.popleft()
            if isinstance(self.codec, PacedConnect):
                self.codec.connect_written(frame)
            self.write(frame, now)

    def replied(self) -> None:
        """Rule 13: a reply that is no reading (a version) came: its exchange is over if the
        codec awaits no more."""
        if self._slew is None and not self.codec.awaiting_reply():
            self._reply_deadline = None

    def begin_slew(self, slew: Slew, travel_s: float) -> None:
        """The target just sent starts a slew expected to take ``travel_s``: its report is owed
        until twice that, plus SLEW_MARGIN_S."""
        self._slew = slew
        self._reply_deadline = slew.start_t + SLEW_TIME_FACTOR * travel_s + SLEW_MARGIN_S
        self._garbled = False  # rule 11: a slew's report is no poll's

    def send(self, frames: list[bytes], now: float) -> None:
        """The first frame now (rule 10: once the axis gap allows), the rest spaced by the
        model's inter-frame gap (all now if there is none: a stop that came between them would
        cancel the second alone)."""
        if self.spec.axis_gap_s:  # rule 10
            self._outbox = deque(e for e in self._outbox if not e[2])
            # (a stop's frames still waiting go first: a target's wait for them, rule 10)
            last = self._outbox[-1][1] if self._outbox else None
            last_axis = self._axis(last) if last is not None else self._last_axis
            first = [f for f in frames if self._axis(f) == last_axis and last_axis is not None]
            frames = first[:1] + [f for f in frames if f is not first[0]] if first else frames
        self._repoll_due = False  # rule 11: the target takes the re-poll's place
        first_t = max(now, self._paced_from(frames[0]))
        self._move_t = first_t + (len(frames) - 1) * self._gap_s  # rule 13
        if first_t > now:
            self._queue(frames, first_t, now)
            return
        self.write(frames[0], now)
        self._queue(frames[1:], now + self._gap_s, now)
        if self.spec.refusal_bytes:  # rule 4 (what is sent is a target: controller.py)
            sent = sum(map(len, frames)) + self.spec.refusal_bytes + 1
            self._refusal_until = now + sent * self._byte_s + self.late_s

    def _ready_axes(self, now: float) -> bytes | None:
        """Rule 10: the axes a stop's first frame could go to now, no axis gap to wait (None:
        no gap kept, every axis)."""
        if not self.spec.axis_gap_s:
            return None
        return b"".join(p for p in self.spec.axis_prefixes if self._paced_from(p) <= now)

    def _stop_frames(self, waiting: bytes = b"", ready: bytes | None = None) -> list[bytes]:
        """Rules 10 and 13: the stop's frames, as the line left off; ``waiting`` the axes
        whose stop frames still wait (a repeat's: those first, the others after them);
        ``ready`` the axes whose stop could go at once (``_ready_axes``)."""
        codec = self.codec
        if isinstance(codec, StopsOnTheLine):
            half = HalfLine.NONE
            if self._fresh:
                half = HalfLine.MOVE if self.cut_move else HalfLine.HARMLESS
            axes = None
            if waiting:
                gone = [p for p in self.spec.axis_prefixes if p not in waiting]
                axes = waiting + b"".join(gone)
            stop = codec.encode_stop_after(half, axes, ready)
        else:
            stop = codec.encode_stop()
        return stop if isinstance(stop, list) else [stop]

    @property
    def move_unsure(self) -> bool:
        """Rule 13: a target written on this connection may not have reached the box whole
        (no valid reply answered a question written after it); or, nothing written on it,
        what the connection before left (``cut_move``)."""
        return self._move_t >= self._whole_t or (self._fresh and self.cut_move)

    @property
    def _gap_s(self) -> float:
        return max(self.spec.inter_frame_gap_s, self.spec.axis_gap_s)

    def _axis(self, frame: bytes) -> bytes | None:
        """Rule 10: the axis ``frame`` is for, None if it names none."""
        return next((p for p in self.spec.axis_prefixes if frame.startswith(p)), None)

    def _paced_from(self, frame: bytes | None = None) -> float:
        """Rule 10: the earliest ``frame`` may go (any frame if None) that is no stop's first:
        after what waits, and the axis gap after a frame to another axis."""
        if not self.spec.axis_gap_s:
            return -math.inf
        last_t, last_axis = self._last_write_t, self._last_axis
        if self._outbox:
            last_t, last_axis = self._outbox[-1][0], self._axis(self._outbox[-1][1])
        axis = None if frame is None else self._axis(frame)
        same = axis is not None and axis == last_axis
        return last_t if same else last_t + self.spec.axis_gap_s

    def _queue(
        self,
        frames: list[bytes],
        first_t: float,
        now: float,
        poll: bool = False,
        stop: bool = False,
    ) -> None:
        for i, frame in enumerate(frames):
            self._outbox.append((first_t + i * self._gap_s, frame, poll, stop))
        self._flush_waiting(now)

    def flush_outbox(self, now: float) -> None:
        """The frames whose time came, then the connect's the line takes now (rule 14)."""
        self._flush_waiting(now)
        if self.connecting:
            self.flush_connect(now)

    def _flush_waiting(self, now: float) -> None:
        while self._outbox and self._outbox[0][0] <= now:
            self.write(self._outbox.popleft()[1], now)

    def free(self, for_stop: bool = False) -> bool:
        if not for_stop and self.connecting:  # rule 14: the connect's frames first
            return False
        return self._line_free(for_stop)

    def _line_free(self, for_stop: bool = False) -> bool:
        if self.spec.full_duplex or self._reply_deadline is None:
            return True
        if not for_stop:
            return False
        # rule 9: a whole reply held for the quiet time is no reply still coming
        return self.spec.stop_interrupts or self._reply_whole()

    def _reply_whole(self) -> bool:
        return self._held is not None and not self.codec.awaiting_reply()

    # -- replies ------------------------------------------------------------------------------
    def reply_overdue(self, now: float) -> bool:
        held = self._held is not None  # rule 9: the reply came
        due = self._overdue_t()
        return not held and due is not None and now >= due

    def _overdue_t(self) -> float | None:
        """Rule 12: when the owed reply is given up: at its deadline, or, if its bytes are
        arriving then, once the line has been quiet JUNK_QUIET_S (no later than the time its
        whole reply takes at the line rate after the deadline, and that quiet time)."""
        deadline = self._reply_deadline
        if deadline is None or self._slew is not None or self._garbled:
            return deadline
        if self._read_t < self._asked_t or not self.codec.awaiting_reply():
            return deadline
        most = deadline + (self.spec.reply_bytes + 1) * self._byte_s + JUNK_QUIET_S
        return min(most, max(deadline, self._read_t + JUNK_QUIET_S))

    def hold_reading(self, reply: PositionReply, now: float) -> bool:
        """Rule 9: a reading, taken once the line stays quiet after it; False when another is
        held (two readings in one exchange: neither is, the held one is dropped)."""
        if self._held is not None:
            self._held = None
            return False
        self._learn_late(now)
        self._held = reply
        self._held_until = now + self._settle_s
        self._held_cap = self._held_until + self.spec.reply_bytes * self._byte_s
        self._held_after = False
        return True

    def _learn_late(self, now: float) -> None:
        """Rule 7: how late the polled reply whose reading this is was whole."""
        reads, self._hold_reads = self._hold_reads, 0
        if not self._learns:
            return
        if reads == 1:  # whole at the hold's end: maybe held longer than it needed
            self.late_s -= self.late_s * LATE_EASE
            self._last_late = 0.0
        elif reads > 1:
            late = min(now, self._late_seen) + self._byte_s - self._hold_base
            both, self._last_late = min(late, self._last_late), late  # two in a row
            self.late_s = max(self.late_s, min(both, self.late_s + self._settle_s, LATE_MAX_S))

    def _unhealthy(self, junk: JunkReply) -> bool:
        """Rules 9 and 11: ``junk`` is bytes no healthy exchange has."""
        if junk.reason in (JunkReason.CHATTER, JunkReason.POWER_ON):
            return False
        return junk.reason is JunkReason.UNSOLICITED or not self.codec.harmless(junk.data)

    def spoils(self, junk: JunkReply) -> bool:
        """Rule 9: whether ``junk`` came in the same exchange as a held reading and spoils it
        (the reading is dropped then)."""
        if self._held is None or not self._unhealthy(junk):
            return False
        self._held = None
        return True

    def garbles(self, junk: JunkReply, now: float) -> None:
        """Rule 11: ``junk`` is the owed reply garbled, if it is bytes no healthy exchange has
        (the controller answered: not silent)."""
        if self._reply_deadline is None or self._slew is not None:
            return
        if junk.reason is JunkReason.REFUSED or not self._unhealthy(junk):
            return
        self._garbled, self._garbled_t = True, now

    def _ask_garbled(self, now: float) -> bool:
        """Rule 11: the exchange just closed came garbled: asked again at once, if its poll
        was not such a re-poll and a stop can go at any time. True if it is."""
        garbled, self._garbled = self._garbled, False
        self.poll_garbled = garbled and self._polled_t == self._asked_t  # (controller.py rule 9)
        if not garbled or self._slew is not None:
            return False
        if not (self.spec.full_duplex or self.spec.stop_interrupts):
            return False
        return self._repoll(now)

    def _repoll(self, now: float) -> bool:
        """Rule 11: the next poll at once, if the exchange's poll was no re-poll; True if so."""
        if self._repolled:
            return False
        self._next_poll, self._repoll_due = now, True
        return True

    def _garbled_over_t(self) -> float | None:
        """Rule 11: when the owed reply, garbled, is over if the codec awaits no more (None:
        not such a reply): JUNK_QUIET_S after the last byte read, and not while reads are held
        back (rule 7: the rest may be in the port)."""
        if not self._garbled or self._reply_deadline is None or self._held is not None:
            return None
        if self._slew is not None or self.codec.awaiting_reply():
            return None
        if any(e[2] for e in self._outbox):  # rule 10: its other axis to come
            return None
        return max(self._read_t + JUNK_QUIET_S, self._hold_until)

    def end_garbled(self, now: float) -> bool | None:
        """Rule 11: the owed reply is over if it came garbled, the codec awaits no more and
        the line has been quiet long enough: closed, and whether it is asked again at once
        (None: not over)."""
        over = self._garbled_over_t()
        if over is None or now < over:
            return None
        self._reply_deadline = None
        return self._ask_garbled(now)

    def settled(self, now: float) -> PositionReply | None:
        """Rule 9: the held reading, once the line has been quiet long enough after it."""
        held = self._held
        if held is None or now < self._held_until:
            return None
        self._held = None
        return held

    def give_up_reply(self, now: float) -> bool:
        """Stop waiting for the owed reply (and for a slew's report: the slew is over); True if
        it came garbled and is asked again at once (rule 11)."""
        self._tears(now)
        again = self._ask_garbled(now)
        self.codec.expire_query()
        self._reply_deadline = None
        if self._slew is None:  # rule 12: its answer may still come
            self._given_up_t = self._asked_t
            unread = self._read_t < self._asked_t and not again
            first = self._first_asked_t == self._asked_t  # (the first since a valid reply)
            polled = self._polled_t == self._asked_t and self._learns  # (one frame's poll)
            if unread and first and polled and self._owes_late():
                self._late_hold_until = self._asked_t + 2 * self.reply_timeout_s
        self.end_slew(now)
        return again

    def _tears(self, now: float) -> None:
        """Rule 11: the owed reply, given up now, came torn past any form (bytes read since
        it was asked, and none of them a reply of the controller's form: a line that garbles
        every byte, its line ends too), the second such in a row with no reply formed between:
        garbled (one per exchange, however many its bytes). The first alone may be an answer
        still arriving (one in parts, a late one): its rest forms a reply then, and ends the
        run."""
        if self._garbled or self._slew is not None:
            return
        torn = self._torn_so_far()
        least = 2 * TORN_SHARE * (self.spec.least_reply_bytes or self.spec.reply_bytes)
        if torn and self._torn and torn + self._torn >= least:  # (no stray byte; not
            self._garbled, self._torn_t = True, now  # _garbled_t: it yields no reading, and
        self._torn = torn  # keeps no controller online, controller.py rule 2)

    def _torn_so_far(self) -> int:
        """Rule 11: the bytes read since the question asked last, none of them forming a
        reply of the controller's (0: none read, or one formed)."""
        asked = self._asked_t
        torn = self._read_t >= asked and self._formed_t < asked
        return self._asked_bytes if torn else 0

    @property
    def torn_run(self) -> int:
        """Rule 11: a run of torn answers is open as the port closes: the exchange given up
        last came torn, or the one in flight had so far. The next connection's link goes on
        with it (``carry_torn``), as controller.py rule 9 counts first readings across a
        replug (review 118: begun anew, an adapter that reset every 2 s never had a torn
        answer counted, and a turn at the start ran past ``az_min_deg``)."""
        if self._torn or self._reply_deadline is None or self._slew is not None:
            return self._torn
        return self._torn_so_far()

    def carry_torn(self, count: int) -> None:
        """Rule 11: the connection before ended in a run of torn answers (``torn_run``: the
        bytes of its last)."""
        self._torn = count

    def _late_hold_t(self) -> float:
        """Rule 12: no poll before then: the late hold's end, or, if a late answer's bytes are
        arriving then, once the line has been quiet JUNK_QUIET_S (as ``_overdue_t``)."""
        hold = self._late_hold_until
        if hold == -math.inf or not self._owes_late():
            return hold
        most = hold + (self.spec.reply_bytes + 1) * self._byte_s + JUNK_QUIET_S
        return min(most, max(hold, self._read_t + JUNK_QUIET_S))

    def _owes_late(self) -> bool:
        """Rule 12: lines of an answer given up may still come (the codec's rule 7)."""
        return isinstance(self.codec, LateAnswers) and self.codec.owes_late

    @property
    def reply_wait_s(self) -> float:
        """Rule 12: how long an answer is waited for: the reply time and what was learned."""
        return self.reply_timeout_s + self.overdue_s

    def answered_late(self, now: float) -> None:
        """Rule 12: a line of the answer to the question given up last came now (the codec's
        late answer, protocols/base.py rule 7): the next questions wait for one as late, up to
        one reply time more."""
        if self._reply_deadline is not None or self._given_up_t == -math.inf:
            return
        after_s = now - self._given_up_t
        self._late_answer = now, after_s
        if not self._owes_late():  # (it came whole: the next question may go)
            self._late_hold_until = -math.inf
        past_s = after_s - self.reply_timeout_s
        wait_s = past_s + max(JUNK_QUIET_S, past_s * OVERDUE_SHARE)
        self.overdue_s = min(self.reply_timeout_s, max(self.overdue_s, wait_s))

    def late_since(self, t: float) -> float | None:
        """Rule 12: how long after its question the last late answer came, if one came after
        ``t`` (None: none did)."""
        late = self._late_answer
        return late[1] if late is not None and late[0] > t else None

    def end_slew(self, now: float) -> bool:
        """The slew (if any) is over without a reading: silence counts from now (rule 2).
        True if there was one."""
        if self._slew is None:
            return False
        self._slew = None
        self._quiet_from_t = self._answered_t = now
        return True

    def got_reading(self, now: float) -> None:
        """A valid position: the slew (if any) is over and the reply is no longer owed (the
        connect's stop's report: the controller stopped, rule 14)."""
        self._connect_wait = None
        if not self.codec.awaiting_reply():
            if self._reply_deadline is not None and now - self._asked_t <= self.reply_timeout_s:
                self.overdue_s -= self.overdue_s * OVERDUE_EASE  # rule 12: answered in time
            self._reply_deadline = None
            self._garbled = False  # rule 11: it ended with a reading, which gives a poll its
            self._repolled = False  # re-poll back (its last frame's: rule 10's two axes)
        self._answered(now)
        self._last_reply_t = now
        self._slew = None

    def heard(self, now: float) -> None:
        """A valid position not taken as a reading (controller.py rule 9: doubted): the reply
        is no longer owed and the controller is not silent, but nothing counts as a fresh
        reading (targets.py rule 7 waits for one)."""
        self._connect_wait = None  # (rule 14: the controller answered its connect's stop)
        if not self.codec.awaiting_reply():
            self._reply_deadline = None
            self._garbled = False  # rule 11: it ended with a valid reply, which gives a poll
            self._repolled = False  # its re-poll back
        self._answered(now)
        self._heard_t = now

    def _answered(self, now: float) -> None:
        """Rule 2: a valid reply came now: the question it answered went out then (a reply
        to no question since the last one answered, the controller's own, counts from now)."""
        if self.asked_since_heard:  # rule 13: what was written before that question is whole
            self._whole_t = self._asked_t
        self._answered_t = self._asked_t if self.asked_since_heard else now

    def ask_again(self, now: float, once: bool) -> None:
        """The reply was not usable: close it and poll at once (``once``: if its poll was no
        re-poll, else at the next poll as ever: rule 11)."""
        self.codec.expire_query()
        self._reply_deadline = None
        self._garbled = False  # (asked again, or left to the next poll)
        if once:
            self._repoll(now)
        else:
            self._next_poll = now

    def poll_now(self, now: float, interval_s: float | None = None) -> None:
        """Ask at the next chance (a target waits for a fresh reading); with ``interval_s``,
        after a re-poll that had no valid answer, on that interval's grid instead (rule 11)."""
        if interval_s is not None and self._repolled:
            self.poll_every(now, interval_s)
        else:
            self._next_poll = now

    def poll_by(self, t: float) -> None:
        """The next poll no later than ``t`` (a move just began: follow it closely)."""
        self._next_poll = min(self._next_poll, t)

    def poll_every(self, now: float, interval_s: float) -> None:
        """The next poll no later than the next instant of ``interval_s``'s grid (rule 8): a
        poll set on a slower grid (the idle one) is brought to it (a move first seen, a stop
        written: the readings that check them come at the moving rate from now on)."""
        self._next_poll = min(self._next_poll, _grid(now, interval_s))

    def poll(self, now: float, interval_s: float) -> bool:
        """Whether a query was written."""
        if self._reply_deadline is not None or self._stop_due or now < self._next_poll:
            return False
        if self.connecting:  # rule 14
            return False
        if now < self._refusal_until or now < self.setting_until:  # rule 4
            return False
        if now < self._late_hold_t() and not self._verdict:  # rule 12
            return False
        if now < self._paced_from() or (self.spec.axis_gap_s and self._outbox):  # rule 10
            return False
        asked = self.codec.encode_query()
        query = asked[0] if isinstance(asked, list) else asked
        if not query:
            return False
        self.write(query, now)
        if isinstance(asked, list):
            self._queue(asked[1:], now + self._gap_s, now, poll=True)
        if self._verdict and self._reply_deadline is not None:  # rule 2
            self._verdict = False
            last_t = now + (len(asked) - 1) * self._gap_s if isinstance(asked, list) else now
            whole_s = (len(query) + self.spec.reply_bytes + 1) * self._byte_s + self.late_s
            whole_s += self.overdue_s  # rule 12: a controller that answers late
            by = last_t + whole_s + self._settle_s + VERDICT_SLACK_S
            self._reply_deadline = min(self._reply_deadline, by)
        self._next_poll = _grid(now, interval_s)
        self._repolled, self._repoll_due = self._repoll_due, False  # rule 11
        self._hold_bytes, self._hold_reads = self.spec.reply_bytes, 0
        self._learns = not isinstance(asked, list) or len(asked) == 1
        self._polled_t = self._asked_t  # rule 12: the question is a poll's
        self._hold_base = now + (len(query) + self._hold_bytes + 1) * self._byte_s
        self._hold_until = self._hold_base + (self.late_s if self._learns else 0.0)
        return True

    def silent_for(self, now: float) -> float:
        """Rule 2: how long the controller has not answered, garbled answers counted."""
        return min(self.unread_for(now), now - self._garbled_t)

    @property
    def torn_since_heard(self) -> bool:
        """Rule 2's words: answers torn past any form (rule 11: garbled, but no silence's end)
        came since the last valid reply (or a slew's wait ended)."""
        return self._torn_t > self._heard_from()

    def unread_for(self, now: float) -> float:
        """Rule 2: how long since a valid reply (or a slew's wait ended)."""
        return now - self._heard_from()

    @property
    def asked_for_s(self) -> float:
        """Rule 2: how far the questions since the last valid reply (or a slew's wait ended)
        reach: from the question that reply answered to the last one (0: none since)."""
        return self._asked_t - self._answered_t if self.asked_since_heard else 0.0

    def ask_verdict(self, now: float) -> None:
        """Rule 2: the controller has given no valid reply for its silence's time, but the
        bridge asked nothing in its last part: a poll now, whose reply is owed only until it can
        be whole (rule 7's hold) and the quiet time of rule 9, plus VERDICT_SLACK_S."""
        self._next_poll, self._verdict = now, True

    def _heard_from(self) -> float:
        heard = self._last_reply_t if self._last_reply_t is not None else self._quiet_from_t
        return max(heard, self._quiet_from_t, self._heard_t)

    @property
    def asked_since_heard(self) -> bool:
        """Rule 2: a question went out since the last valid reply (or a slew's wait ended):
        only then can the controller be silent. Time the bridge did not ask in (its process
        held, a host that stalls) is no silence of the controller's (docs/architecture.md
        rule 15; review 102)."""
        return self._asked_t > self._heard_from()

    @property
    def first_asked_t(self) -> float:
        """Rule 2: when the first question since the last valid reply before it went out
        (-inf: none since the link came up): the earliest the reply read now can answer."""
        return self._first_asked_t

    @property
    def asking_since(self) -> float | None:
        """Rule 2: when the first question since the last valid reply went out, while nothing
        has come since the last one (a reply held, rule 9, or garbled, rule 11, is no
        silence); else None."""
        unanswered = self.asked_since_heard and self._read_t < self._asked_t
        return self._first_asked_t if unanswered else None

    # -- junk ---------------------------------------------------------------------------------
    def add_junk(self, data: bytes, now: float) -> None:
        if len(self._junk) < _JUNK_KEEP:
            self._junk += data[: _JUNK_KEEP - len(self._junk)]
        self._junk_t = now

    def quiet_junk(self, now: float) -> tuple[bytes, bool] | None:
        """Junk held back until the line went quiet, and whether the codec calls it harmless."""
        if not self._junk or now < self._junk_t + JUNK_QUIET_S:  # as wakeups() says
            return None
        data, self._junk = bytes(self._junk), bytearray()
        return data, self.codec.harmless(data)

    # -- scheduling ---------------------------------------------------------------------------
    def wakeups(self) -> list[float]:
        times: list[float] = []
        if self._outbox:
            times.append(self._outbox[0][0])
        if self._junk:
            times.append(self._junk_t + JUNK_QUIET_S)
        if self._held is not None:
            times.append(self._held_until)
        if self._connect_wait is not None:  # rule 14
            times.append(self._connect_wait)
        elif self._connecting and self.spec.connect_stops and self._reply_deadline is None:
            times.append(self._connect_quiet_t())
        if self.spec.can_report_position:
            deadline = self._reply_deadline
            if deadline is None and self.connecting:
                pass  # rule 14: no poll before the connect's frames are out
            elif deadline is None:
                hold = -math.inf if self._verdict else self._late_hold_t()  # rule 12
                refusal = max(self._refusal_until, self.setting_until)  # rule 4
                times.append(max(self._next_poll, self._paced_from(), refusal, hold))
            elif self._held is None:  # rule 9: not overdue while its reading is held
                due = self._overdue_t()  # (rule 12: an answer under way is let finish)
                times.append(deadline if due is None else due)
                over = self._garbled_over_t() if self._garbled else None
                if over is not None:  # rule 11
                    times.append(over)
        return times
