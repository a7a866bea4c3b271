"""The stop rules of one rotator: when a stop adds nothing, when one must be sent again, and
what a motion verdict (a stall, a rotor turned away, a refused bearing) asks of the line.
Pure: the session asks, with the motion and the time, and writes what these answer.

Rules:
1. A stop is written at once (on a half-duplex line right after the reply in flight) and
   cancels any frame still waiting in the outbox. One that comes within the brake window (at
   least STOP_MERGE_MIN_S) of another, with no target sent and no reading showing the rotor
   turning since, is merged into it: nothing more goes on the wire (a flood of stops to an idle
   Rotor-EZ had it answer each with its banner, crowding out the readings). A rotor the last
   stop found turning, no reading since saying whether it took, is another matter: that frame
   may have been lost on the line. There a stop merges only within STOP_REPEAT_GAP_S of the
   last one (two clients' bursts of STOPs had put over a hundred ``;`` on the wire, each
   answered with a banner once the first had stopped the rotor, queueing the readings for
   seconds: the controller taken for silent, the next target dropped), and one merged so is
   owed: it is sent when that gap ends, unless a reading has shown the rotor still by then
   (rule 2), or sooner if the controller is found silent meanwhile (a controller whose replies
   are lost may still hear; the readings that would show the rotor turning are gone). One such
   repeat is written after a stop, not more: later ones merge into it until a reading shows the
   rotor turning (a stop written restarts the motion machine's settle clock, so a stream of
   them would keep the rotor taken for moving and every one written). So a repeat after a lost
   stop frame is never more than the gap late, and a flood puts two stop frames on the wire,
   then one a brake window once the rotor is seen still. Should the line lose that repeat too,
   the next stop goes once a reading shows the rotor turning or the controller is found silent
   (meanwhile the stop express, where it runs, writes its own frame for a STOP 0.1 s or more
   after its last). A controller that reports no position while it turns (a SatEL's slew) is
   never merged then.
2. A stop is checked: if the rotor is still seen moving ``stop_resend_s`` later (a movement
   after the first reading after the stop and after the rotor's coast, less than ``settle_s``
   old: ``motion.stop_again``; a SPID running on a degree or two is not stopped twice),
   it is sent again, and after STOP_TRIES_BEFORE_ERROR tries an error says so (a repeat owed,
   rule 1, is written when its gap ends, before anything else of that step, and is no try). Lock
   ON always sends a stop, whatever the bridge believes the rotor is doing. An operator's STOP
   (or lock ON) to a rotor the bridge took for at rest is checked too, until the next target or
   until the move after it ended: that state may be a guess (the first reading of a connection,
   readings missed for a while, a stall whose motor may still be driving), and a stop lost then
   must not leave the rotor turning. The price: a move by hand long after such a stop is stopped
   once too; not after the lock is released (controller.py ``lock_released``: the lock's stop is
   checked while it holds, and its release says the tower work is over; a lock kept across a
   restart owes its stop on the first connect, session.py rule 11), nor after the stop the
   bridge sends first readings that never confirm (controller.py rule 9: nobody pressed STOP;
   let go as a released lock's once a reading shows the rotor still, review 107). Readings the
   doubt does not take (controller.py rule 9) show no turn to this check, and a replug or a
   silence rebuilds the motion without the lock's stop: rule 7 sends it again then.
3. A stop is never lost: one (or a lock ON) that comes while the port is closed or reopening,
   one still waiting for the line when the port failed, or one written less than
   STOP_UNSURE_S before it failed, is owed: the first frame written once it is open again
   (stopping is always safe). So is the last stop written when the port fails or the
   controller is found silent, unless a reading since showed the rotor at rest (``unseen_t``;
   a connection's first reading is a guess): found silent, the first frame after its first
   reading once it answers again, as a released lock's if it was one (rule 2). (An attack
   pass: a noise burst ate a GS-232B's STOP and the polls around it; taken for stopped for
   want of readings, then offline, and back online the rotor ran 26 s on to the target the
   operator had stopped. A review: the same with the adapter reset before the silence.)
   A target written after that stop leaves none owed once the second reading after it has
   come (the first may answer a poll written before it): the controller hears again, the best
   sign a reading gives that it had the target (none says which target it heads for: a burst
   that ate both and ended before a silence leaves the rotor on its way to the bearing before,
   motion.py rule 5 stops it where it passes the new one), and a stop would stop that move.
   Until then a silence or a failed port still owes the stop, and the error says so: the
   bridge drops the target then, so the stop cuts short no move the bridge still stands for,
   a heard one included (the safe side; a review: a deaf burst ate a STOP and the target
   after it, and the rotor ran on, back online, to the bearing before both).
4. A stall stops the rotor at once; a rotor turned away from its target (motion.py rule 5) is
   stopped once it comes to rest; one that turned on past it, turned back on its way or past
   a limit (motion.py rule 10), and a rotor still turning to the bearing before a new one the
   controller refused, are stopped at once. Each ends
   tracking. Such a stop is written at once, whatever the line is doing (link.py
   ``write_stop``: a motor driving a jammed rotor does not wait for a reply to end), and is
   owed as any (rule 3). The pass's and the refusal's, written while the rotor turns, are
   that turn's stop for rules 1, 2 and 3: checked and owed as an operator's (a pass comes of
   a line that lost a frame), but for the end: the pass's (the limit's too) is sent again
   STOP_TRIES_BEFORE_ERROR times at most, and with the error the rotor is left alone (a hand
   at the panel in the settle time after an arrival looks like a pass: stopped four times at
   most, not fought on, and owed to no silence after); a stop anew meanwhile, or one owed
   before the last try, is checked as any. The others go to a rotor
   at rest, and nothing is merged into them (an operator's STOP after a stall is written: no
   reading can show whether a jammed rotor's stop took). A turned-away rotor's is not
   checked (a later move by hand is
   left alone). A stall's is watched, once: its motor may have driven the jammed rotor all
   along, and when the rotor breaks free the readings show it turning on to its old bearing.
   The first turn seen after it, before a target, another stop or the port closing, gets one
   more stop frame at once, written and noted as the stall's was, and a ``stop`` error says so
   (unchecked: the operator freeing the rotor by hand at the control box has that move stopped
   once, then no more). A controller that said it restarted mid-turn (controller.py rule
   12) gets a stop as a refusal's mid-turn: written at once, checked as an operator's, its
   error the restart's (a ``serial`` one naming the target dropped), never a stall's. One
   that says it drives no motor, the rotor still short of its target (controller.py rule 12),
   gets the same stop, and a ``stalled`` error that says what it said, never a stall's (rotor
   health counts none). A
   composite's elevation box names its elevation where a stall, a turn away, a refusal or a
   rotor turning after its stall's stop is said (``standing``), never its own azimuth, which
   is none of the antenna's (a review: "rotor stalled at 0°", word for word the azimuth box's
   stall at north, and runtime/composite.py rule 9 said the two once).
5. The last word's fence (interfaces/mqtt/lastword.py): a stop or lock ON from the stop lane comes
   with a hold; no target goes out while one is held, until a release reaches its marker. A release
   that clears (the connection that would have caught up was lost) ends every hold, and what
   waited meanwhile is dropped: its place in line was lost (mailbox.py rule 6); but not the
   storm's park, the bridge's own, which goes then (wind.py rule 8; the storm's end drops it
   first). The stop
   express's hold (interfaces/mqtt/express.py rule 8) is a second one, with numbers of its own: a
   target waits while either is held; its release clears only when the express's connection
   (or the express) ended before its word came back, which no clock bounds: what waited is
   dropped then, said (EXPRESS_LOST), not sent late (an attack pass: a firewall that dropped
   the express's flow alone held a target sent after a STOP until the keepalive noticed, and
   the rotor turned 45 s after, unasked); the storm's park aside, as above: the storm asks it.
6. A controller that reports no position (a DCU-1) gets every stop twice, STOP_REPEAT_GAP_S
   apart: no reading can show one lost, and stopping is always safe (an attack pass: one bit
   flipped in a lock ON's ``AS1;`` and the rotor turned on 27 s). A target written in between
   leaves the second unwritten: it would stop that move. The second is all the check such a
   stop gets: none is owed to a port that fails later (rule 3's ``unseen_t``: no reading would
   ever clear it, and a turn by hand an hour after a released lock was stopped).
7. The lock fights a turn by itself, whatever the doubt (controller.py rule 9) believes: while
   it holds, any sign the rotor may be turning brings its stop again (``lock_sign``, checked at
   the step's stop check, ``lock_check``): a reading at rest doubted (further from where the
   rotor stands than ``noise_deg``: a hand at the panel, or a flipped bit, to which a stop
   costs nothing), and the controller answering again (a port opened, a controller back from
   a silence: the motion is rebuilt without the lock's stop, motion.py ``link_down``, and
   rule 2 would check none). Rule 2's check watches only readings taken; a turn by hand
   whose readings the doubt never takes (two garbled answers after its first reading, five in
   six, one flipped bit in the answer asked at once: review 40, attack 9) ran a locked rotor
   from 150 to 300 unfought, and after a replug the lock's stop was checked no more. Such a
   stop goes ``moving_poll_interval_s``, and STOP_MERGE_MIN_S at least, after the last stop
   (at most one a poll and one a second: no flood on a noisy line), whatever rule 1's brake
   window says, and is checked as any (rule 2). Merged as rule 1 merges (one a brake window),
   a turn by hand a second after the lock ON, its readings garbled, ran 26 degrees before it
   was fought (review 43), and letting only the first through that window let one flipped
   bit before such a turn spend it: 28 degrees (review 47); 8 now. The price on a line that
   flips every other reading: a stop a second, which a Rotor-EZ answers with its banner. A
   doubted reading's is said on R/error once an episode (``stop``: until a reading taken shows
   the rotor not turning, or the lock is released), and ``junk_report_interval_s`` apart at
   least (a line that flips every other reading), and only with a stop written (one a merge
   takes in is none: review 43); the controller answering again's is only logged. A reading
   away only on an axis the box never turns (a composite's elevation box's azimuth, axes.py
   rule 5) is no sign (review 43: a floating pot there had the lock's stop written a second).
   A stop frame to a still rotor is harmless on every controller the bridge drives (the lock
   ON sends one whatever the rotor does, rule 2): a SatEL's ``s`` also switches its automatic
   motion off, which its next report has switched on again (controller.py rule 4); a Rotor-EZ
   answers an idle ``;`` with its banner, which the merge keeps rare.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

from bridge.core.model import ErrorKind, MotionState
from bridge.session import motion as mo
from bridge.session.actions import Report
from bridge.session.mailbox import Batch

log = logging.getLogger(__name__)

STOP_TRIES_BEFORE_ERROR = 3
STOP_MERGE_MIN_S = 1.0  # rule 1: stops merge within the brake window, or at least this long
STOP_REPEAT_GAP_S = 0.1  # rule 1: a repeat this soon to a rotor maybe still turning is owed
STOP_UNSURE_S = 1.0  # rule 3: a stop written this recently when the port failed is sent again
# rule 4: how the errors of a turn a motion event dropped end (session.py ``_heed`` says
# otherwise for a storm's park, which nobody can send again: wind.py rule 10)
SEND_AGAIN = "send the target again"
EXPRESS_LOST = (
    "the stop express lost its connection while the target waited for it to confirm the stop "
    "before; send it again"
)
CLEARED = (
    "a stop or lock from the stop lane came before it, and the MQTT connection that would have "
    "told which was published first dropped; send it again"
)


def standing(m: mo.Motion, cfg: mo.MotionConfig, pos: float | None) -> str:
    """Rule 4: where a box says its rotor stands (``pos``: the bearing the user sees there); a
    composite's elevation box names its elevation, never its own azimuth, none of the antenna's."""
    if cfg.spec.turns_azimuth or m.el_position_deg is None or not cfg.spec.has_elevation:
        return f"{pos:g}°"
    return f"elevation {m.el_position_deg:g}°"


@dataclass(frozen=True)
class Verdict:
    """What the session does about one motion event (rule 4)."""

    stop: bool = False  # write a stop now
    error: Report | None = None
    ends_tracking: str | None = None


class Stops:
    def __init__(self) -> None:
        self.owed = False  # rule 3: a stop came while the port was closed
        self.unseen_t: float | None = None  # rule 3: the last stop, no reading at rest since
        self._tries = 0
        self._at_rest = False  # rule 4: turned away, a stop when it is still
        self._repeat_owed: float | None = None  # rule 1: the stop a merged repeat is owed to
        self._writing_repeat = False  # rule 1: the stop asked for now is that repeat
        self._repeat_sent: float | None = None  # rule 1: when the repeat went (the last stop)
        self._rest_stop_t: float | None = None  # rule 4: when one went to a rotor at rest
        self._after_target = 0  # rule 3: readings still to come before a target lets go unseen_t
        self._stall_stop_t: float | None = None  # rule 4: when a stall's went, while watched
        self.blind_at: float | None = None  # rule 6: when a blind controller's second stop goes
        self._blind_second = False  # rule 6: the stop asked for now is that second one
        self._lock_sign: tuple[float, str | None] | None = None  # rule 7: when, and the words
        self._lock_told = False  # rule 7: this episode's was said on R/error
        self._lock_told_t = -math.inf  # rule 7: when one was said last

    def merges(self, m: mo.Motion, cfg: mo.MotionConfig, now: float) -> bool:
        """Rule 1: a stop now adds nothing on the wire (one merged into a stop that may not
        have taken is owed: ``check``)."""
        if not cfg.can_report_position or m.stop_sent_t is None or m.target_deg is not None:
            return False  # a target went out after the last stop: this stop is needed
        moving = m.state is MotionState.MOVING  # (until a reading shows it still)
        if moving and not cfg.spec.reports_while_moving:
            return False  # no reading can show it turning (a SatEL's slew): always sent
        if m.last_move_t is not None and m.last_move_t > m.stop_sent_t:
            return False  # a reading since that stop showed the rotor turning
        if moving:  # that stop's frame may have been lost: one repeat, within the gap owed
            if self._repeat_sent == m.stop_sent_t:
                return True  # the last stop was that repeat: no more until a reading
            if now - m.stop_sent_t >= STOP_REPEAT_GAP_S:
                self._writing_repeat = True
                return False
            self._repeat_owed = m.stop_sent_t
            return True
        return now - m.stop_sent_t < max(cfg.brake_delay_s, STOP_MERGE_MIN_S)

    def repeat_at(self, m: mo.Motion) -> float | None:
        """Rule 1: when the repeat owed to the last stop goes out (None: none is owed)."""
        if self._repeat_owed is None or self._repeat_owed != m.stop_sent_t:
            return None  # none merged, or a newer stop went out since
        if m.state is not MotionState.MOVING or m.target_deg is not None:
            return None  # a reading showed the rotor still, or a target went out since
        return self._repeat_owed + STOP_REPEAT_GAP_S

    def repeat_due(self, m: mo.Motion, now: float) -> bool:
        """Rule 1: the repeat owed is to be written now (and is then owed no more)."""
        at = self.repeat_at(m)
        if at is None or now < at:
            return False
        self._repeat_owed = None
        self._writing_repeat = True
        return True

    def sent(self, at: float) -> None:
        """A stop frame was written at ``at`` (rule 1: the repeat, or one that starts anew)."""
        self.unseen_t, self._after_target = at, 0  # rule 3
        self._repeat_sent = at if self._writing_repeat else None
        self._writing_repeat = False
        self._stall_stop_t = None  # rule 4: rule 2 checks this one

    def blind_sent(self, at: float) -> None:
        """Rule 6: a blind controller's stop was written at ``at``: its second is owed, unless
        it was that second."""
        self.blind_at = None if self._blind_second else at + STOP_REPEAT_GAP_S
        self._blind_second = False
        self.unseen_t, self._after_target = None, 0  # (rule 3: no reading can ever show it;
        # its second is its check)

    def blind_due(self, now: float) -> bool:
        """Rule 6: the second stop is to be written now (and is then owed no more)."""
        if self.blind_at is None or now < self.blind_at:
            return False
        self.blind_at, self._blind_second = None, True
        return True

    def wrote_at_rest(self, at: float, stall: bool) -> None:
        """Rule 4: a stall's (``stall``) or a turned-away rotor's stop was written at ``at``:
        nothing to merge into, owed if the port fails right after it (rule 3), and a stall's
        watched (``broke_free``)."""
        self._rest_stop_t = at
        self._stall_stop_t = at if stall else None

    def let_go(self) -> None:
        """Rule 4: the pass's stops are given up (the error said so): none of them is owed."""
        self.unseen_t, self._after_target = None, 0

    def target_sent(self) -> None:
        """Rules 3 and 4: a target was written: no stop before it is checked any more, nor owed
        once two readings have come after it (rule 3)."""
        self._rest_stop_t = self._stall_stop_t = self.blind_at = None
        if self.unseen_t is not None:
            self._after_target = 2

    def reading(self, now: float, at_rest: bool) -> None:
        """Rule 3: a reading came at ``now`` (not a connection's first, nor an answering
        spell's: a guess), showing the rotor at rest (``at_rest``) or not: the last stop is
        owed no more if it shows that stop taken, or if it is the second after a target."""
        if self._after_target:
            self._after_target -= 1
            if not self._after_target:
                self.unseen_t = None
        if at_rest and self.unseen_t is not None and now > self.unseen_t:
            self.unseen_t = None

    @property
    def stall_watched(self) -> bool:
        """Rule 4: a stall's stop is watched (a reading showing the rotor turning may call for
        one more)."""
        return self._stall_stop_t is not None

    def broke_free(self, m: mo.Motion, target_going: bool) -> bool:
        """Rule 4: the rotor turns after a stall's stop (no stop nor target since): one more
        stop frame, once. (No wait: a jammed rotor does not coast, and one that broke free
        early may be taken for stopped again before a later look, between slow idle polls.)"""
        stall = self._stall_stop_t
        if stall is None or m.stop_sent_t is not None or m.state is not MotionState.MOVING:
            return False
        if target_going or m.last_move_t is None or m.last_move_t <= stall:
            return False
        self._stall_stop_t = None
        return True

    def port_closed(self, failed: bool, stop_due: bool, m: mo.Motion, now: float) -> None:
        """Rule 3: the port closed (``failed``: not on purpose); ``stop_due``: a stop waited
        for the line. A failed port owes a stop that waited, one written so recently (a
        failed write closes the port too) that the controller may never have had it, or one
        no reading has shown taking (``unseen_t``)."""
        written = [t for t in (m.stop_sent_t, self._rest_stop_t) if t is not None]
        self._rest_stop_t = self._stall_stop_t = None
        recent = bool(written) and now - max(written) < STOP_UNSURE_S
        if failed and (stop_due or recent or self.unseen_t is not None):
            self.owed = True

    def lock_sign(self, now: float, reading: str | None = None) -> None:
        """Rule 7: a sign at ``now`` that the rotor may be turning: a reading at rest doubted
        (``reading``: its words), or the controller answering again (None)."""
        sign = self._lock_sign
        if sign is None or sign[1] is None:  # (a doubted reading's words win: they are said)
            self._lock_sign = (now, reading)

    @property
    def lock_signed(self) -> bool:
        """Rule 7: a sign waits for ``lock_check``."""
        return self._lock_sign is not None

    def lock_calm(self) -> None:
        """Rule 7: a reading taken shows the rotor not turning: the episode is over."""
        self._lock_told = False

    def lock_check(
        self,
        locked: bool,
        m: mo.Motion,
        now: float,
        target_going: bool,
        gap_s: float,
        tell_every_s: float,
    ) -> tuple[bool, Report | None, str]:
        """Rule 7: whether the lock's stop goes again now (``locked``: the session's lock holds;
        ``gap_s``: the moving poll interval), the error to say with it (``tell_every_s`` apart
        at least), and its words for the log (none for a doubted reading's after the episode's
        first: logged at debug). A stop written since the sign, or within
        ``gap_s`` (STOP_MERGE_MIN_S at least) before now, is the one: nothing goes, nothing is
        said. The stop asked for is written unmerged (rule 1's brake window is not this one's:
        review 43 and 47)."""
        sign, self._lock_sign = self._lock_sign, None
        if not locked:
            self._lock_told = False
            return False, None, ""
        if sign is None or target_going:  # (a target stops the rotor by itself; never locked)
            return False, None, ""
        at, reading = sign
        last = m.stop_sent_t
        if last is not None and (last >= at or now - last < max(gap_s, STOP_MERGE_MIN_S)):
            return False, None, ""
        if reading is None:
            return True, None, "the controller answers again while the lock holds: its stop again"
        why = (
            f"a reading at rest of {reading} disagrees with where the locked rotor stands (a "
            "hand at the panel, or line noise): the lock's stop sent again, and at each such "
            "reading while the lock holds"
        )
        if self._lock_told or now - self._lock_told_t < tell_every_s:
            return True, None, ""  # (said once an episode, and logged so: a noisy line's is
            # a stop a second)
        self._lock_told, self._lock_told_t = True, now
        return True, Report(ErrorKind.STOP, why), why

    @property
    def counting(self) -> bool:
        """Rule 2: a series of stops to a rotor still turning is being counted (``check``
        starts the count again once no stop is out: it has something to do then)."""
        return self._tries != 0

    def check(
        self, m: mo.Motion, cfg: mo.MotionConfig, now: float, target_going: bool
    ) -> tuple[bool, Report | None]:
        """Rule 2: whether to stop again (and the error after the last try). A target about to
        go out stops the rotor by itself (motion.plan_target)."""
        if m.stop_sent_t is None:
            self._tries = 0
            return False, None
        if target_going or not mo.stop_again(m, cfg, now):
            return False, None
        self._tries += 1
        error = None
        if self._tries == STOP_TRIES_BEFORE_ERROR:
            error = Report(
                ErrorKind.STOP,
                f"rotor still turning after {self._tries} stop commands; stop it at the controller",
            )
        return True, error

    def verdict(
        self,
        event: mo.Event,
        m: mo.Motion,
        cfg: mo.MotionConfig,
        shown: float | None = None,
        aimed: float | None = None,
    ) -> Verdict:
        """Rule 4: what ``event`` (just reported by the motion machine, now at ``m``) asks;
        ``shown``: the bearing the user sees there (pointing.py: ``m``'s is the controller's
        own), in the error's words; ``aimed``: the target the event dropped, as the user sees
        it (a restart's)."""
        pos = m.position_deg if shown is None else shown
        where = f"{pos:g}°"  # (an elevation's pass is told with the elevation: an attack pass)
        if m.el_position_deg is not None and cfg.spec.has_elevation:
            el = f"elevation {m.el_position_deg:g}°"
            where = f"{where}, {el}" if cfg.spec.turns_azimuth else el
        own = standing(m, cfg, pos)  # (a composite's elevation box: its elevation)
        if event is mo.Event.PAST_LIMIT:
            beyond = "a limit"
            if m.past is not None:
                axis, at, limit, setting = m.past
                scale = " on the controller's scale" if axis == "azimuth" else ""
                beyond = f"its {axis} limit: {at:g}°{scale}, beyond {setting} {limit:g}°"
            why = (
                f"rotor turned past {beyond}, on its way to its target; now at {where} (a "
                "command garbled on the line, or a hand at the panel): target dropped and the "
                f"rotor stopped; {SEND_AGAIN}"
            )
            return Verdict(True, Report(ErrorKind.STALLED, why), "past a limit")
        if event is mo.Event.STALLED:
            stalled_axis, el_deg = m.stalled, m.el_position_deg  # (motion.py rule 3: its axis)
            both = cfg.spec.has_elevation and cfg.spec.turns_azimuth and el_deg is not None
            if el_deg is not None and both and stalled_axis == "elevation":  # the jammed axis
                own = f"elevation {el_deg:g}°, azimuth {pos:g}°"  # and its reading, first
            elif el_deg is not None and both:
                own = f"{pos:g}°, elevation {el_deg:g}°"
            progress = (
                f"its {stalled_axis} made no progress" if both and stalled_axis else "no progress"
            )
            why = (
                f"rotor stalled at {own} ({progress} for {cfg.stall_timeout_s:g} s): brake "
                "paddle pressed, rotor stuck, or the controller restarted (power cycled or "
                f"reset) and forgot its target; target dropped: {SEND_AGAIN}"
            )
            return Verdict(True, Report(ErrorKind.STALLED, why), "stalled")
        if event is mo.Event.RESTARTED:  # (controller.py rule 12: the controller's)
            turn = "its turn" if aimed is None else f"its turn to {aimed:g}°"
            why = (
                f"the controller restarted mid-turn (its power-on byte came) at {pos:g}°: {turn} "
                f"was not resumed: {SEND_AGAIN}"
            )
            return Verdict(True, Report(ErrorKind.SERIAL, why), "the controller restarted")
        if event is mo.Event.HALTED:  # (controller.py rule 12: the controller's word)
            turn = "its turn" if aimed is None else f"its turn to {aimed:g}°"
            why = (
                f"the controller stopped turning short of its target at {own} (it says its motor "
                "is off: power cycled or reset, stopped at its panel, or its own limit or "
                f"protection): {turn} was dropped, not resumed: {SEND_AGAIN}"
            )
            return Verdict(True, Report(ErrorKind.STALLED, why), "the controller stopped")
        if event is mo.Event.TURNED_AWAY:
            self._at_rest = True  # a controller driving the wrong way: stop it then
            why = (
                f"rotor turned away from its target at {own} (the front panel, or a "
                "controller driving the wrong way): target dropped, and a stop follows when it "
                "comes to rest"
            )
            return Verdict(False, Report(ErrorKind.STALLED, why), "turned by hand")
        if event is mo.Event.PASSED:
            why = (
                f"rotor turned on past its target, now at {where} (the target may never have "
                "reached the controller, or a hand at the panel): target dropped and the rotor "
                f"stopped; {SEND_AGAIN}"
            )
            return Verdict(True, Report(ErrorKind.STALLED, why), "passed its target")
        if event is mo.Event.TURNED_BACK:  # (stopped as a pass is: at once, a bounded series)
            why = (
                f"rotor turned back on its way to its target, now at {where} (a command "
                "garbled on the line, or a hand at the panel): target dropped and the rotor "
                f"stopped; {SEND_AGAIN}"
            )
            return Verdict(True, Report(ErrorKind.STALLED, why), "turned back")
        if event is mo.Event.REFUSED:
            why = (
                f"the controller refused the target (it answered with its refusal at {own}): "
                "outside the range the box is set to turn, or a bearing it cannot take"
            )
            turning = m.state is MotionState.MOVING  # still on its way to the bearing before
            if turning:
                why += "; the rotor was turning to the bearing before it: stopped"
            return Verdict(turning, Report(ErrorKind.REFUSED, why), "refused by the controller")
        if event is mo.Event.STOPPED and self._at_rest:
            self._at_rest = False
            return Verdict(stop=True)
        if event is mo.Event.ARRIVED:
            self._at_rest = False
        return Verdict()


class Fence:
    """Rule 5: the newest marker a hold waits for."""

    def __init__(self) -> None:
        self._hold: int | None = None
        self._express: int | None = None  # rule 5: the stop express's sync word waited for
        self.cleared_why = CLEARED  # rule 5: why what waited was dropped at the last clearing

    @property
    def held(self) -> bool:
        return self._hold is not None or self._express is not None

    def apply(self, batch: Batch) -> bool:
        """Take a batch's hold and release in; whether a held fence was cleared (what waited
        is then dropped: CLEARED says why)."""
        cleared = batch.release_clear and self._hold is not None  # (before the rest)
        self.cleared_why = CLEARED
        if cleared:
            self._hold = None
        if batch.hold is not None:
            self._hold = batch.hold if self._hold is None else max(self._hold, batch.hold)
        if batch.release is not None and self._hold is not None and self._hold <= batch.release:
            self._hold = None
            log.debug("hold ended")
        if batch.express_hold is not None:
            held = self._express
            self._express = batch.express_hold if held is None else max(held, batch.express_hold)
        done = batch.express_release
        if done is not None and self._express is not None and self._express <= done:
            self._express = None
            log.debug("the stop express's hold ended")
            if batch.express_lost and not cleared:  # rule 5: ended by its loss
                cleared, self.cleared_why = True, EXPRESS_LOST
        return cleared
