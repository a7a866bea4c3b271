"""One controller as the bridge knows it through its line: the link (link.py, the line
discipline), the motion machine fed by its readings (motion.py), whether it answers, what it is
owed (a stop, options, an enable: stops.py, options.py) and its polls. Sans-IO like the session
that owns it: the session calls it with the time, and it hands back, as ``notes``, what the
session must act on (an error event, tracking to end, the pending target to drop or to put
back); it never touches the session's targets, tracking or auto-park.

Rules:
1. The link's state belongs to ``Link`` and the motion machine's to ``motion``; this class
   keeps the controller's: answering or not, options owed, motion to re-enable, the bearings
   shown (status.py rule 1).
2. A controller that reports positions is "available" only after a valid reading, and stops
   being available after ``silence_timeout_s`` without one (tracking ends, a waiting target is
   dropped), counted only once a question went out since that reply and its time passed
   unanswered (link.py ``asked_since_heard``): time in which the bridge asked nothing (its
   process held, a host that stalls) is no silence of the controller's, nor a stall's
   (docs/architecture.md rule 15; review 102: held 12 s mid-turn, the session called it
   silent and stalled at its first step after, and stopped it short); and only once the
   questions since reach the silence's end: where they do not (the last went out a reply time
   before it, lost), one asked then decides (link.py rule 2), unless a stall could be called
   by then (``_stall_check_t``: that offline cannot wait; a review: a line that lost 2.6 s of
   every 3.6 s took a GS-232B offline and stopped its turn, although it answered every time
   the line let it).
   A DCU-1 is available while its port is open (it never answers). A garbled answer (link.py rule
   11) counts as answering, but for GARBLED_SILENCE_FACTOR silence timeouts without a valid reply at
   most, and offline before the motion machine could call a turn fed no reading stalled
   (``stall_timeout_s`` from the last movement it saw, less a moving poll and a reply time: how late
   the check may come), never less than one timeout: a line that gives only garbage goes offline
   then, with its own words; one that gives nothing at all still after ``silence_timeout_s``, and so
   does one whose answers are torn past any form (link.py rule 11: no reading can come from them;
   review 118: kept online as garbled, a turn ran 3 s longer unwatched), told as garbled. While a
   target is out, either is offline before the turn could be called stalled however long
   ``silence_timeout_s`` is, where that leaves it TURN_SILENCE_SHARE of ``stall_timeout_s``, and
   TURN_SILENCE_LEAST_S at least, without a valid reply (without a byte, for one that gives nothing:
   lost replies are ridden out). A turn under way that goes offline so, whichever came first, is
   stopped then, in case the controller still hears (its replies lost or garbled on their way), and
   the stop is owed again when it answers (stops.py rule 3); the error says so. The bridge watches a
   turn's stall and its limits only through readings, and a turn no reading watches does not go on:
   a jammed rotor's motor would drive on against the jam; a free one is cut short, its target
   dropped as any waiting one, to be sent
   again once the controller answers (the price of safety; a stop to a rotor at rest is
   harmless). (A review: the stop went only where that offline came before silence or garbage
   alone would have made it so, where the stall's would have gone; at the defaults, 3 s of
   silence or 6 s of garbage came first, the error said the rotor may still be turning, and a
   jammed Rotor-EZ, GS-232B, Easycomm, RC2800, Prosistel or RT-21 drove on against its jam 60 s
   later; a free one ran on unwatched to its target, 26 s.) The error still says the rotor may be
   turning where the stop could not be written yet. A rotor whose last reading put it at its
   target is no turn under way (motion.py rule 3: no stall can come, only the reading that finds
   it still is missing): offline as with no target out, and the error says nothing of a turn
   (nor does it get a stop; one owed goes as ever). A stall needs readings
   that show none (a Rot2Prog at its 600 baud, idle-polled every 9.3 s, waits 19.4 s of silence:
   one that went silent mid-turn was called stalled at 10 s, an error that blamed the brake, and
   rotor health counted a stall; a review: offline with no stop, a jammed one's motor drove on,
   and an attack pass: the same for a jammed GS-232B whose replies went to garbage; an attack
   pass: at half a 3 s stall timeout, two lost replies took a GS-232B offline). One that never
   gave a valid reply but garbled ones is said to (the wrong baud rate looks so), not to give
   none. A controller whose answers came, later than the bridge waits for one (link.py rule
   12), since the last valid reply is offline all the same, and the error says it answers, how
   late, and how long the bridge waits ('stopped answering' or 'does not answer' alone was
   false). (Reviews: with silence_timeout_s 6, a GS-232B turning when its replies went to garbage
   stayed online 12 s and was called stalled at 10 s, an error that blamed the brake; a slow one
   whose last movement was seconds before its last valid reply, at 5.4 s of the default 3.)
3. Polling is idle work: slow when idle, fast while moving or while a target waits, never for a
   controller that cannot report. A query is never sent while another is open. A move first
   seen by an idle poll, and a stop written, bring the next poll to the moving rate's grid at
   once (an attack pass: a SPID, idle-polled every 9.3 s, was taken for stopped for want of
   readings within its settle time, and a STOP the line lost after a reconnect mid-turn was
   never sent again: the rotor ran on to its old target).
4. A silent controller's slew (SatEL) feeds the motion machine nothing until its report; a
   report that says automatic motion is off gets it switched on again (slew.py has the
   rules for a report that does not come).
5. Bytes that complete no reply change nothing: the codec keeps them (``feed`` says so, and
   whether all they did was to hold a reading: session.py rule 16). A reading is taken when
   its exchange is over (link.py rule 9): one that other bytes spoil, or one the codec does not
   trust, is no reading, and the controller is asked again at once, once (link.py rule 11:
   the answer to that is asked for at the next poll). A stop written while a
   reading is held ends its exchange: the reading is taken just before the stop is written
   (the motion machine sees the reading, then the stop), or dropped if bytes came after it.
6. Junk that is no reply is logged; a user is told at most every ``junk_report_interval_s``.
   A reply the codec calls a MISFIT (protocols/base.py: the box set up otherwise than
   configured, a GS-232 at P45 configured as a 360-degree model) is told in the codec's own
   words, which say what to configure, once MISFITS_TOLD come in a row (no reading settled
   between them), and not as bytes that are no valid reply (attack 12: a box whose every
   reply is such was told only as bytes that are no valid reply, or not at all). A lone one
   is doubted as rule 9 doubts a reading: asked again at once, and if the reading that comes
   then is taken, told as line noise (review 49: one flipped bit, ``AZ=030`` read as
   ``AZ=430``, was told at once as a box set to P45, and a failing sensor's wander past 360
   as a model to change before its own words); a box really set otherwise says so again at
   once.
7. ``cfg`` is the rotator's configuration with its speeds as the settings in effect make them
   (options.py rule 3: a GS-232 at X2 turns at half its speed), and the settle time they need
   (motion.py rule 2: from the slower axis it turns, a composite's elevation box's own);
   ``base_cfg`` as configured. Its speeds are the one source of the rotor's speeds: the
   session's parts see them in their scene (parts.py rule 9).
8. A codec that keeps what its controller said of itself (protocols/base.TakesReadings: a
   composite's elevation box) is told each reading taken, and only those (rule 5).
9. A reading that puts a rotor not turning (no move seen, no target out: idle, braking, stalled,
   also after a stop) further from where it stands than ``noise_deg`` on either axis (what the
   motion machine would take for a move: motion.py rule 1) is believed when the next says so too,
   within ``doubt_deg``: the controller is asked again at once, and a reading back where the rotor
   stood shows the first was line noise (logged, and told on R/error as junk is: rule 6, saying how
   far off it was on the axis that was off, both when both were: attack 12, the azimuth's alone
   told an elevation glitch as 0 degrees off). One flipped bit in an ASCII reply makes a
   well-formed bearing (``AZ=150`` read as ``AZ=350``): it was published and taken as a move, and a
   nudge made from that bearing turned the rotor 200 degrees. A rotor not turning changes its
   bearing only by a hand at the controller's panel, which the reading asked a moment later
   confirms (a move by hand is seen one exchange later; a stop that did not take is checked one
   exchange later, within stops.py rule 2's resend time).
   A turning rotor's readings change at every poll: one is doubted only
   if it is further from the last taken than the rotor can have turned since (motion.py
   ``reach_deg``: three times its nominal speed, and the tolerance, noise and margin of a pass),
   once: the reading asked for then is taken, and one not back within reach ends the doubt for
   that turn (``_doubts_turning``; a flipped digit mid-turn was published for one poll on seven
   models); a silent controller's report after its slew is not doubted, and only that one
   (review 105: a SatEL's answers after it, polled at the moving rate while it settles, were
   all taken unchecked, and one flipped bit, 200 read 280, was published past ``az_max_deg``
   and fed to the motion as a move; now they are doubted as a turning rotor's). A
   connection's first reading (the bridge started, a port replugged, a controller answering
   again after a silence) with nothing to doubt it against (no reading before, or the rotor
   turning or with a target out when its readings were lost) is believed only when the next
   agrees with it, within ``doubt_deg`` alone, however far apart in time (``_doubts_first``:
   asked again at once, DOUBTS_TOLD in a row at most, then at the moving rate; where the
   second disagrees, a third that agrees with either is taken, and the odd one is told as line
   noise); the reading taken is the first of the two, which answered the question the motion
   machine times it by (within ``doubt_deg`` of the other: a pot's jitter shows its first
   phase). Two further apart than ``doubt_deg`` may be a turn, or a garble and the true
   reading in either order, which two readings cannot tell: review 105, an allowance of what
   the rotor can turn between them at its top speed (motion.py ``top_speed_deg_s``) let the
   true reading confirm a flipped one before it whenever the two came far enough apart (an
   RC2800 az/el's two axes asked 200 ms apart, a K3NG box answering 400 ms late, a reply lost,
   the moving rate's ask compared with the one two back): the garble was the bearing and a
   nudge turned the rotor the wrong way; taking the newer of the two would only have turned it
   round (the true reading, then a garble within reach), and a pot's jitter, 10 then 11, into
   its second phase. A turn is told by its line instead: FIRST_TURN_READINGS (four: review
   103, a true one and two garbles at 150, 160, 170 made three) in a row that disagree but lie
   on one steady turn, each axis the same way at one rate within ``doubt_deg``,
   FIRST_TURN_MAX_DEG_S at most (or the top speed, if faster), are a turn: the last is taken,
   and the next reading that goes on with it too, the turn's readings trusted till it rests,
   ``_steady`` (review 100: a Rot2Prog at 30 deg/s replugged mid-turn was offline for 24 s,
   till it rested, and R/error blamed the line; and at the usual polls within ``doubt_deg``
   alone, a rotor turning at its nominal speed never had two agree, and a turn nobody asked
   for ran past ``az_min_deg`` unjudged: asked at once or at the moving rate, its readings
   agree, or lie on its line). Until
   then the controller is not answering: the user sees it
   offline, with no bearing, one reply time longer than before, as before any answer; nothing
   relative to the bearing is made from that reading (a nudge is refused as before the first
   answer, "no bearing to nudge from", rather than waited for: the judge makes it from the
   status it sees, runtime/rotator.py, and the wait is one reply time; no target's side or end
   is picked from it, pointing.py rule 2; no move, limit, stall or turn nobody asked for,
   rules 10 and 13, is judged from it; no bearing is published). Attack 30: one byte lost or
   flipped in the first answer after a start (``AZ150.0`` read ``AZ10.0`` on an Easycomm box,
   ``AZ=150`` read ``AZ=110`` on a GS-232B) was the bearing, and a nudge of +10 from it turned
   a rotor at rest at 150 down to 20; after a replug mid-turn, the same byte showed the rotor
   at 110 (attack 16 had closed only a reply torn by a line end). The first back where the
   rotor stood still when its readings were lost (a port replugged, a controller answering
   again after a silence) is doubted against where it stood (an attack pass: believed
   unchecked, one flipped bit was shown as the bearing
   at rest, and a nudge from it turned the rotor 190 degrees), a stop sent to it or not (a stop
   leaves a rotor at rest as still as it was; attack 9: a STOP at rest, the port replugged
   before a reading showed it taken, and 150 read as 350 was published and taken as a turn).
   A doubted reading is no reading for anything: not the motion's, not a target's fresh one
   (targets.py rule 7: a target waits for the answer), not one a stop cuts short (rule 5); but
   the controller answered (no
   silence), and the first back after a loss makes it answering again as a reading would (its
   options, its connect guard, a stop owed written at once), shown at the bearing it stood at
   (a review: a line that went on disagreeing after a replug kept the rotator offline, where
   the same inside a session leaves it online); but a connection's first with nothing to doubt
   it against makes it answering only once it is taken (there is no bearing to show: a line
   that goes on disagreeing then keeps it offline, told from the DOUBTS_TOLD-th in a row on),
   and a stop owed is written at once all the same.
   First readings that go on disagreeing leave a rotor the bridge cannot watch: no limit,
   stall or turn nobody asked for is judged, and a turn under way runs on unseen (review 100:
   a line that garbled every answer differently, 0, +60, -60 in turn, kept an Easycomm turning
   at the start unwatched, and it ran from 150 past ``az_min_deg`` 60 to its end). So
   FIRST_UNWATCHED_READINGS of them in a row that confirmed none (eight: more than any healthy
   start needs, two for a rotor at rest or turning less than ``doubt_deg`` between two
   readings, four for a steady turn, eight with one garble among those; a poll answered
   garbled past parsing counts as one, ``_garbled_first``: review 107, a line that tore every
   answer had none counted, and a turn at the start ran past ``az_min_deg`` to its end; so
   does one torn past any form, its line ends too, link.py rule 11: review 113, such a line was
   silence and the stop came 22 s late, 45 degrees past the limit; a
   controller that answers nothing at all is rule 2's silence, and one that reports no
   position never has first readings; counted across a replug until a reading is taken:
   review 107, a flaky adapter's connections of seven readings each never reached eight) get a
   stop
   (``_unwatched_stop``: a stop as any, the line's discipline and the stop rules as ever;
   always safe; but checked only until a reading a resend time after it shows the rotor still,
   then let go as a released lock's stop, ``_release_check``, unless it came over another stop
   still checked, an operator's or the lock's: review 107, checked until the next target, a
   hand at the panel ten minutes after the line came right was stopped, unsaid; its copy owed
   across a drop, stops.py rule 3, is let go so too, ``_let_go``: review 113, written on the
   reconnect it was checked as an operator's, for good), and so do each
   as many more
   while they go on (a hand at the panel after the first such stop, review 103); a ``stop``
   error says the readings do not agree (the last in true bearings, pointing.py: review 107
   found it raw) and the rotor was stopped for it (at most every
   ``junk_report_interval_s``, a connection's first always: review 107, a port replugged
   within the interval had its stops written every 1.6 s, unsaid, R/error's last word "port
   unplugged"). They stay unconfirmed: nothing is made from them. (A stop for
   one unconfirmed reading past a limit, e9e2e51a, was taken back: it stopped every healthy
   start of a rotor resting outside a limit with a false error, cut a turn back inside the
   limit short, and one garble at rest spent it for the connection: review 103.)
   Readings at rest that go on disagreeing (a line gone bad, a failing position sensor) are
   asked for at the moving rate, not at once, until the first unwatched stop below, then at
   the usual polls (review 103's follow-up: eight at a Rot2Prog's idle rate, 9.3 s, took 74 s;
   not for good, the polling load review 105 found), with one more asked as a turn at the
   rotor's nominal speed would have gone UNWATCHED_TURN_DEG since the last unwatched stop,
   which brings the next (review 116: eight idle polls more, 49 s, let a hand after the first
   stop run 19 degrees past ``az_min_deg``), and at the usual polls while the
   controller is not answering (review 40); told from the DOUBTS_TOLD-th in a row on; the
   bearing shown is the last two readings agreed on. A reading asked again at once agrees
   with the doubted one within ``doubt_deg`` plus twice what the rotor turns at its speed
   between them (DOUBT_TURN_MAX_DEG at most): a rotor turning while taken for still is
   believed on its second reading, also when a stop cut the first short and the second is
   asked once the stop is out; readings at a poll's distance agree within ``doubt_deg`` alone
   (polls half a minute apart would let any two agree). A turn is told by its line as at the
   start: FIRST_TURN_READINGS of them in a row on one steady line (``_steady``) are a turn,
   the last taken and the turn's readings trusted till it rests, so rule 10 judges it (review
   111: one flipped bit in a hand turn's first answer broke the pair, an Easycomm stepping 6
   degrees a poll never had two agree, and it ran shown idle at 150 past ``az_min_deg`` 60 to
   5; review 111 too: a fast turn confirmed at the start, garbled right after its line, shown
   idle for the rest of it). And FIRST_UNWATCHED_READINGS of them in a row that confirmed none
   (a garble and a line, one garble among a fast turn's, fit well within) leave a rotor the
   bridge cannot watch, and get the first readings' unwatched stop (``_unwatched_stop``, each
   as many more while they go on, or sooner by the clock as above; said on R/error as readings
   at rest, as rarely; never merged away: one within STOP_MERGE_MIN_S of the last stop
   written, the lock's own (stops.py rule 7), goes once that second is over unless a stop
   went since; review 116: merged as stops.py rule 1 merges, into any stop a brake window
   before, no reading ever showing the rotor turning, a STOP before a hand's turn, and under
   a long ``brake_delay_s`` every other unwatched stop, were dropped, and the hand ran past
   ``az_min_deg``): the maintainers' decision on review 103's follow-up, the limits hold over
   a rotor the bridge cannot watch (a line gone bad at rest, every answer off by 0, +60 or
   -60, hid a hand turn, and an Easycomm ran from 150 past ``az_min_deg`` 60 to 5
   unstopped); a stop to a still rotor costs nothing, and a failing sensor must be told.
   (Before, such readings got no stop without the lock: review 40's "the same noise without
   the lock writes no stop", superseded.) A poll answered garbled past parsing at rest counts
   as one of them, as a first reading's does (``_garbled_at_rest``; review 116: a line that
   tore every answer at rest, each '.' read '?', had none counted, and a hand turn ran from
   150 past ``az_min_deg`` 60 to 5 unstopped); one now and then is never eight in a row.
   (A composite box's axis that is never turned is kept so too: axes.py rule 5.)
   Whatever the doubt decides, a reading at rest it doubts is a sign the rotor may be turning,
   handed to the stop rules (``Stops.lock_sign``): while the lock holds, its stop goes again
   (stops.py rule 7; review 40: a turn by hand whose readings the doubt never took, two garbled
   answers or one flipped one after its first, ran a locked rotor from 150 to 300 unfought).
   The doubt and the bearing it shows are left as they are (a fix that bent them was taken
   back for three regressions it made, review 40). So is the controller answering again (a
   port opened, the end of a silence; a blind controller at its connect): the lock's stop,
   which the motion rebuilt then forgets, goes again.
10. A turn nobody asked for: a rotor seen turning from a settled rest (``at_rest``), or from the
   first readings back (a port opened, a controller answering again; still or braking, before
   the motion settled) where the rotor was still with no target out when the readings were
   lost, or where this session never had any and every such turn is stopped (its ``stop``
   error then names a restart mid-turn first; an attack pass: a poll garbled into a jog in
   those first seconds ran an Easycomm to its end stop past ``az_min_deg``, and a Rotor-EZ
   replugged after a STOP on to the target it was stopped short of; a review: the same for
   a controller answering again after a silence), but not where it was turning or had a
   target out (a review: a reconnect mid-turn stopped the user's own move), with no target
   out is stopped, once a reading
   puts it more than UNASKED_MOVE_DEG from where it rested on either axis (never a pot's jitter,
   which the doubt of rule 9 lets through when two readings agree), by a stop checked as an
   operator's but sent again three times at most, as a pass's (stops.py rule 4: a hand holding a
   button is let be), and a ``stop`` error says why (in true bearings), where
   - ``unasked_moves`` is "stop" (an Easycomm box's default, whose poll is one flipped bit
     from a jog, ``EL`` read as ``ML``, and its space from a ``0``, ``AZ0EL``, which a lenient
     parser reads as a move to 0: an attack soak ran a rotor to its end stop that way; the
     SatEL's, whose frames are each one flipped bit from a jog; the RC2800's, whose poll, ``A``
     CR, is one stray digit from a target, ``A5`` CR: an attack pass ran it from 150 to 5, past
     ``az_min_deg`` 30, followed and unsaid, the limits on the way being held only for the
     bridge's own targets, motion.py rule 10): every such turn, a hand at the panel's too;
   - it is "after-stop" (the Rotor-EZ's and RotorCard's: the controller keeps the bearing of its
     last target, and one flipped bit makes a poll the command to turn to it, ``AI1;`` read as
     ``AM1;``, a probe: stopped at 60 on the way to 300, the rotor went on to 300, nothing said
     why): the first such turn since the last target written, if the rotor rested further than
     ``tolerance_deg + noise_deg`` from that target (stopped short of it: a STOP or a lock mid-turn,
     a pass, rule 9's unwatched stop). That first turn ends the guard, stopped or not (not a turn
     the first readings back find going on across a reconnect: nobody's new turn; review 107, a
     replug mid-turn forgot the guard of the turn a stop then cut short), and so does the lock's
     release (a move by hand after it is the operator's: ``lock_released``): a hand at the panel
     after a STOP is stopped once, then followed; a poll garbled after a move by hand is not caught
     (writing the rest bearing to the board, ``AP1xxx;``, was tried and taken back: a review found
     it cut a hand at the panel short and turned a rotor at 360 a full circle). The target it rested
     short of is in the status (``short_of_deg``) and outlives a restart (runtime/kept.py rule 9):
     the next session starts guarded, its first readings too (``keep_short_of``).
   While such a turn would be stopped, a poll left unanswered or answered in part at rest (what
   a garbled one gets) is followed by polls at the moving rate for ``settle_s`` (a review: with
   polls 10 s apart at rest, a jog ran 60°). A stop already out when such a turn is seen (the
   lock's, an operator's) stays checked as any: the lock's is not let go after four, and goes
   again at each reading at rest doubted while the lock holds (stops.py rule 7).
11. A target gets one try more where the controller takes a new bearing at any time
   (``RetargetPolicy.DIRECT``: the same bearing again changes nothing of a turn under way) and
   reports while it turns: if a reading ``settle_s`` + ``brake_delay_s`` + BRAKE_GUARD_S and a
   moving poll after it went out (longer for a slow axis: ``noise_deg`` and a reading's step at
   its speed) shows an axis that had to turn (further than ``tolerance_deg``, and by at least
   ``noise_deg`` and a reading's step) not moved since (not beyond ``noise_deg``: the frame lost
   or garbled on the line, one of an RC2800's two; an Easycomm box ignores a bearing it cannot
   read), or if the controller refuses it before it moved the rotor (motion.py rule 8: a flipped
   bit made a frame it refuses). An axis that was turning when it went (mid-turn, more than
   ``noise_deg`` from where that turn was going; or with no turn under way within
   ``tolerance_deg`` of the last azimuth written, where a slow rotor called arrived may creep
   on; not after a stop: it moves whether the frame came or not) is judged by where it rests
   instead: a reading at that time or later that shows that axis come to rest (no movement of
   its own for ``settle_s``, as motion.py rule 3 judges its stall, the other axis turning on or
   not) off its target, where the turn before was going (within ``tolerance_deg`` +
   ``noise_deg``), shows the frame lost (a probe: turning to 100, sent 200 at 60, lost: it rested
   at 100, and a "stalled" error 16 s later blamed the brake; and a rotor that jammed mid-turn,
   not moved since, was sent its new target twice). Each axis on its own: an RC2800's elevation
   frame lost under a new azimuth, or its azimuth's under a new elevation; and a target sent at
   97 on the way to 100, lost, judged by whether it moved, was a stall that blamed the brake.
   (Review 78: judged once the whole rotor rested, an azimuth whose frame was lost mid-turn
   rested at the old target while the elevation climbed on, was called stalled on its own 10 s
   later and the elevation's healthy turn stopped; now the try goes once that axis rests, and
   its stall counts from that try.) It
   goes again, try 2, with the raw bearing its first try resolved (an axis it left out
   included), if the bridge still stands for it (``Again``: targets.py rule 8, no newer target,
   stop or end of its feature since, no storm refusing motion: session/wind.py rule 1; if
   not, a refusal is reported as ever, but for one whose sender the lease refuses by then,
   session.py rule 23, whose drop is said alone, as a storm's; that one, or one the end of its
   feature took, with
   nothing newer waiting, targets.py ``forsaken`` (its try more waiting: ``forgo_owed``), is
   given up: ``forgo``, at rest, its turn never began, no stall called), with a warning in
   the log (a refusal some codecs read as junk is still told as junk); the time is judged at the
   reading by the settings then in effect (rule 7: a speed set in the same batch as the target
   slows it); a second refusal is reported, and a turn that does not start then is a stall as
   ever (``stall_timeout_s`` from the try that went). A stop ends the tries. Not on the Rotor-
   EZ, RotorCard or DCU-1: a bearing while their motor runs (a jammed rotor's) stops it, against
   the controller's rule (docs/architecture.md rule 7).
12. A controller that says it restarted (a power-on byte: the Rotor-EZ's and RotorCard's
   0xE0) while a turn of the bridge's is out has forgotten that turn, and the rotor stands: the
   turn is abandoned (motion.py rule 11), never resumed by the bridge (no move the user did
   not send again), tracking ends, and a ``serial`` error says so with the target it dropped
   (the status's ``last_error`` with it; the target no longer shown). A stop goes as for a
   refusal mid-turn (stops.py rule 4), checked: harmless to a controller at rest, and should
   the byte have been line noise, the rotor the bridge no longer stands a turn for is stopped.
   ``restarts`` counts such turns: a composite's other box abandons its own (runtime/
   composite.py rule 8).
   No stall is called then (an earlier pass: 10 s after such a restart the rotor was said
   stalled, "brake paddle pressed or rotor stuck", and rotor health counted a stall: a climb
   to a rotor that is not stuck). A controller whose readings say whether it drives a motor
   (protocols/base.py rule 8: Prosistel's ``B``, an RC2800's ``ST``) tells it too: a reading
   that says it drives none, the reading before it too (HALT_READINGS: Prosistel's ``R`` is one
   flipped bit from ``B``; a review: one such reading of a jammed rotor said the box had
   stopped, and rotor health counted no stall), seen driving since the target went out (a
   reading that said so later than that; not a turn about to start) and no try more of rule
   11 open, that finds
   the rotor still for ``settle_s`` further than ``tolerance_deg`` from its target, ends the
   turn (motion.py rule 12): the target dropped, tracking ended, a stop as for a restart,
   ``restarts`` counted, and a ``stalled`` error that says the controller stopped short and
   why it may have (a restart, its panel, its own limit or protection), never a stall
   (``stall_timeout_s`` later, and counted by rotor health: an attack pass, a Prosistel and an
   RC2800 power-cycled mid-turn). A jammed rotor whose motor the box still drives is a stall
   as ever, and so is one the box was seen driving while it stood still for ``settle_s``
   before it said its motor is off (its own stall protection cutting the motor out: an
   attack pass, such a jam was said 'stopped turning short' and rotor health counted no
   stall): rule 3's stall tells it, ``stall_timeout_s`` after its last movement. A
   controller that says nothing when it restarts (RT-21, GS-232, SPID, Easycomm: their
   readings of a rotor stopped by a restart are those of a stall) is called stalled as
   before, and that error names a restart too. A stall's error or a stop short owes the
   settings the controller forgets again (options.py rule 1: a GS-232 back at X4).
13. A port lost (an adapter unplugged, a write the port refused, a bug in the worker) while a
   turn of the bridge's is out (``turn_out``: a target written, no stop sent for it, the rotor
   not at it by the last reading) drops that turn with the link (motion.py ``link_down``): it
   is never resumed, and a controller that keeps its power (a Rotor-EZ whose USB adapter was
   pulled) carries it out by itself. The replug does not stop it while its readings show it
   turning: the first readings back follow it as a turn (motion.py rule 4), and it is the
   user's own move (rule 10: a review found a stop then cut it short); a STOP sent while the
   port is out is its first frame (stops.py rule 3), and nothing sent on a replug moves the
   rotor. But with its target dropped no stall is judged, and a motor driving a rotor jammed
   meanwhile drove on for good under an ``idle`` status (an attack pass: a GS-232B, an
   Easycomm and a Rotor-EZ, unplugged mid-turn, jammed, replugged: two minutes on, still
   driving, nothing said). So the dropped target is kept (``_lost_aim``, raw) until the first
   rest the readings show after the port is back (``_lost_rest``): a rest further than
   ``tolerance_deg`` + ``noise_deg`` from it on either axis (jammed, stopped at the panel, a
   power cut meanwhile: the readings cannot tell which) gets a stop, checked as an operator's
   (harmless to a rotor at rest), and a ``stop`` error that says why; a rest at it, a target or
   a stop written meanwhile (an owed one at the connect, a composite box's) end it unsaid. An
   axis the readings back decide still (motion.py rule 4: ``still_axes`` when they decide the
   lost turn over, ``lost_still``) is judged by where it stood then (``_lost_decided``): at its
   aim, it is left out at the rest, and a hand at it after that is a turn begun since, not the
   lost one (found fixing review 95: a hand at a GS-232B's azimuth after its lost elevation
   turn ended at its aim was stopped at its rest at 182, R/error "short of its turn ...
   jammed, stopped at the panel, or its power cut"); with no axis left, it ends unsaid.
   Where no reading judges it (the controller does not answer once the port is back, or goes
   silent before the rotor rests) it is a turn no reading watches, stopped as rule 2 stops
   one, in case the controller still hears, and the offline's error says so (a cold review:
   'does not answer' said, the motor drove a rotor jammed meanwhile on for good). A
   single controller's port error says what became of the turn (``lost_turn``): dropped, its
   target in true bearings, that the controller may finish it by itself (followed, and stopped
   if it rests short; a DCU-1's never seen), that a STOP sent meanwhile goes first, and to
   send the target again to have it watched ("serial link ... lost (adapter unplugged?)" alone
   left the user waiting for a turn the bridge had given up); so does each failed try to open
   it again until it is back (session.py rule 12). A composite's box says its
   port's words alone: there the rotator's turn is not left to the box (runtime/composite.py
   rule 8: the other box is stopped at once, and the box whose port went owes its stop), and
   keeps no target to judge at its rest (its owed stop is its first frame back). A controller
   whose connect begins with its stop (``ModelSpec.connect_stops``: a SatEL, protocols/satel.py
   rule 2) has its turn stopped by the replug: its error says so, and it keeps no target to
   judge either (a cold review: the error promised the turn finished and followed, and the
   rest the connect's stop made got a second stop and an error blaming a jam). A port lost
   at rest, at a target or after a stop (one still waiting for a half-duplex line too: owed,
   the first frame back; a cold review, a Rot2Prog's error said the turn was left to the
   controller under the operator's STOP) says nothing of a turn, and nothing of this rule is
   sent at the replug.
14. A silent controller (SatEL) restarted mid-slew sends no report, as one whose report was lost
   on the line; nothing it may be sent during the slew can tell them apart, so slew.py rule 4
   waits, stops it, asks where it is and puts its target back (``Retry``; not in a storm:
   wind.py rule 1); a newer target (a second user's: tracking steps a SatEL only at rest) stops
   the slew at once, and that stop's report is as lost (slew.py rule 6: asked after the last
   stop). The first reading after any lost report of a slew tells them (a review: the stopped
   slew's was not judged, and a SatEL restarted before a second user's target was sent it): a
   clock (set from the host at
   connect) that reads earlier than at the last reading before the slew has gone back to its
   power-on reading (Hamlib's example: ``2001/00/00 00:00:07``, unverified on a real unit):
   the controller restarted and forgot its point. Its turn is abandoned as rule 12's: any target
   waiting is dropped (``Forgot``: the one put back, or a newer one named as the error's command;
   none after a stop or the lock cleared it, and then nothing is said; a storm's park waiting goes
   on, named as no command of the error's: a cold review, the park that went on was named as the
   target dropped), a ``serial`` error says so with where it stands and the slew's target, tracking
   ends, ``restarts`` is counted (a composite's other box abandons its own turn: a cold review, the
   azimuth box turned on alone), no stall (the motion machine had no target out). Its motion flag
   cannot tell (the stop switched it off too), nor its position (a rotor slower than set stands
   short of the point as well). A clock that ran on is a lost report, and the target goes again (a
   review: a SatEL power-cycled mid-slew was sent its point again 70 s later, the rotor turned on
   unasked, against rule 12). A clock not read (garbled in either reading) cannot tell: the target
   goes again, as for a lost report; so would it on a unit whose clock outlives a power cut. A
   flipped digit in the clock that makes it read earlier abandons the turn of a controller that did
   not restart: said, and safe (no move).
"""

from __future__ import annotations

import logging
import math
import re
from collections.abc import Callable
from dataclasses import dataclass, replace
from enum import Enum
from functools import partial
from typing import NamedTuple, cast

from bridge.core.model import ErrorKind, RotatorStatus, SettingValue, Target
from bridge.protocols.base import (
    JunkReason,
    JunkReply,
    NotReady,
    PositionReply,
    TakesReadings,
    VersionReply,
)
from bridge.session import motion as mo
from bridge.session import status as st
from bridge.session.actions import Report
from bridge.session.config import WorkerConfig
from bridge.session.link import Link
from bridge.session.options import Options
from bridge.session.slew import Slew, overdue, travel_s
from bridge.session.stops import SEND_AGAIN, STOP_MERGE_MIN_S, Stops, Verdict, standing
from bridge.session.targets import Sending, resolve

log = logging.getLogger(__name__)
# rule 12: readings in a row that must say no motor runs (Prosistel's R is one bit from B)
HALT_READINGS = 2

ONLY_POLL_MARGIN_S = 1e-3  # _only_poll_until's: the whole step a little early (rounding)
DOUBT_MIN_DEG = 5.0  # rule 9: two readings this close (or twice the noise) agree
DOUBTS_TOLD = 3  # rule 9: this many doubted readings in a row are reported
MISFITS_TOLD = 2  # rule 6: this many MISFIT replies in a row are told in the codec's words
DOUBT_TURN_MAX_DEG = 90.0  # rule 9: what a rotor may have turned between two doubted, at most
FIRST_TURN_READINGS = 4  # rule 9: first readings in a row on one line taken for a turn
FIRST_TURN_MAX_DEG_S = 60.0  # rule 9: no rotor turns faster (a circle in 6 s): a steady turn
# rule 9: first readings in a row that did not confirm: the rotor cannot be watched, stopped (a
# healthy start confirms within FIRST_TURN_READINGS, with one garble among them within twice)
FIRST_UNWATCHED_READINGS = 2 * FIRST_TURN_READINGS
# rule 9: after the first unwatched stop at rest, the next comes before a turn at nominal speed
# has gone this far (``_unwatched_at_rest_due``)
UNWATCHED_TURN_DEG = 20.0
GARBLED_SILENCE_FACTOR = 2  # rule 2: garbled answers keep a controller online this long at most
TURN_SILENCE_SHARE = 0.5  # rule 2: mid-turn, no valid reply for this share of stall_timeout_s
TURN_SILENCE_LEAST_S = 3.0  # ... and this long at least (the default silence_timeout_s)
ASKED_MARGIN_S = 1e-6  # rule 2: the questions reach the silence's end (rounding)
UNASKED_MOVE_DEG = 5.0  # rule 10: a turn nobody asked for is stopped this far from its rest
_RESTS = (mo.IDLE, mo.BRAKING, mo.STALLED)  # rule 10: where ``_short_of`` judges
_DROPS_TURN = frozenset(  # ``dropped_turns``: the events whose error says the target dropped
    {
        mo.Event.STALLED,
        mo.Event.PAST_LIMIT,
        mo.Event.TURNED_AWAY,
        mo.Event.PASSED,
        mo.Event.TURNED_BACK,
        mo.Event.REFUSED,
    }
)
# rule 12: the events whose error names a restart the controller did not tell: the settings it
# forgets are owed again (options.py rule 1)
_MAY_HAVE_RESTARTED = frozenset({mo.Event.STALLED, mo.Event.HALTED})
#: stops.py rule 4: a bounded stop series
_PASSING = (mo.Event.PASSED, mo.Event.TURNED_BACK, mo.Event.PAST_LIMIT)


def _turned(
    rested: tuple[float, float | None], az_deg: float, el_deg: float | None, az_stayed: bool
) -> str:
    """Rule 10's words for a turn: the azimuth's, the elevation's alone where the azimuth
    stayed (a composite's elevation box: its own azimuth is none of the antenna's), or both."""
    az0, el0 = rested
    if el0 is None or el_deg is None:
        return f"from {az0:g}° to {az_deg:g}°"
    if az_stayed:
        return f"its elevation from {el0:g}° to {el_deg:g}°"
    return f"from {az0:g}°/{el0:g}° to {az_deg:g}°/{el_deg:g}°"


def doubt_deg(cfg: mo.MotionConfig) -> float:
    """Rule 9: how close two readings of a rotor not turning agree."""
    return max(DOUBT_MIN_DEG, 2 * cfg.noise_deg)


@dataclass(frozen=True)
class Ends:
    """Tracking ends for ``reason``, and a target of its own still waiting is dropped."""

    reason: str


@dataclass(frozen=True)
class Drop:
    """The waiting target is dropped, with an error that says ``why``."""

    why: str


@dataclass(frozen=True)
class Retry:
    """Put ``target`` back as the waiting one, try ``attempt`` (slew.py rule 4), said with
    ``error``; in a storm that refuses it (wind.py rule 1) it is not, and ``late`` (how late
    the report was) is said with the storm instead."""

    target: Target
    attempt: int
    error: Report | None = None
    late: str = ""
    of: Target | None = None  # the target sent, which ``target`` stands for (slew.py rule 4)


@dataclass(frozen=True)
class Forgot:
    """Rule 14: the controller restarted during the slew to ``target`` whose report never
    came: a target still waiting (that one, put back by ``Retry``, or a newer one) is dropped,
    with ``error`` said, and tracking ends."""

    target: Target
    error: Report


@dataclass(frozen=True)
class Again:
    """Rule 11: ``target``, the one sent last, goes once more as its first try resolved it
    (``az_deg``, ``el_deg``: raw) if the bridge still stands for it (targets.py ``again``);
    if not, ``refused`` (its refusal's error) is reported and ``ends`` ends tracking."""

    target: Target
    az_deg: float
    el_deg: float | None
    refused: Report | None = None
    ends: str | None = None


Note = Report | Ends | Drop | Retry | Forgot | Again


class Fed(Enum):
    """What bytes from the port did (``feed``)."""

    NOTHING = "nothing"  # no reply completed: nothing changed (rule 5)
    HELD = "held"  # one reading completed, now held for its quiet time and nothing else
    REPLY = "reply"  # anything else: a reading taken or dropped, junk, a version


def _apart(
    reply: PositionReply,
    az_deg: float,
    el_deg: float | None,
    limit: float,
    wraps: bool,
    azimuth: bool = True,
) -> bool:
    """Rule 9: whether ``reply`` is more than ``limit`` from ``az_deg``/``el_deg`` on either
    axis (``azimuth`` False: the elevation alone, a composite's elevation box's, which never
    turns its azimuth: protocols/axes.py rules 2 and 5)."""
    if azimuth and mo.angle_error(reply.az_deg, az_deg, wraps) > limit:
        return True
    return reply.el_deg is not None and el_deg is not None and abs(reply.el_deg - el_deg) > limit


def _to_turn(
    m: mo.Motion, cfg: WorkerConfig, az: float, el: float | None
) -> tuple[float | None, float | None]:
    """Rule 11: where each axis stands that has to turn to ``az``/``el`` (further than
    ``tolerance_deg``, and at least ``noise_deg`` and a reading's step, so that its turn shows
    as a movement: attack passes, a 2-degree turn with tolerance 1 never did, and a 5-degree
    one lost at the defaults was left out at tolerance plus noise), None for one that has
    not, is not known, or is not this box's (a composite's elevation box turns no azimuth)."""
    mc, spec = cfg.motion, cfg.spec
    step = spec.reading_step_deg

    def turns(err: float) -> bool:
        return err > mc.tolerance_deg and err >= mc.noise_deg + step

    az_from = m.position_deg if spec.turns_azimuth else None
    if az_from is not None and not turns(mo.angle_error(az_from, az, mc.az_wraps)):
        az_from = None
    el_from = m.el_position_deg if el is not None and spec.has_elevation else None
    if el_from is not None and el is not None and not turns(abs(el_from - el)):
        el_from = None
    return az_from, el_from


def _turn_least_s(cfg: mo.MotionConfig) -> float:
    """Rule 2: the least time mid-turn without a valid reply that makes the controller
    offline: TURN_SILENCE_SHARE of ``stall_timeout_s``, and TURN_SILENCE_LEAST_S at least."""
    return max(cfg.stall_timeout_s * TURN_SILENCE_SHARE, TURN_SILENCE_LEAST_S)


def _turning_to(
    m: mo.Motion, cfg: mo.MotionConfig, sent_az: float | None
) -> tuple[float | None, float | None]:
    """Rule 11: the bearing each axis may still be turning to when a target goes now (it then
    moves whether the frame came or not): the turn's under way, or, with none (the rotor
    called arrived, or a turn whose target was dropped), the last azimuth written
    (``sent_az``) if the rotor is within ``tolerance_deg`` of it (a slow rotor called arrived
    may creep on to it); None for an axis within ``noise_deg`` of it (it cannot move more than
    that: whether it moved tells), with none, or after a stop (then whether it moved tells:
    a target lost while the rotor coasts after a STOP is a stall, as before). An attack pass:
    with the tolerance here, a target sent at 97 on the way to 100, lost, ended as a stall
    that blamed the brake."""
    if m.stop_sent_t is not None:
        return None, None
    az, el = m.position_deg, m.el_position_deg
    to_az: float | None
    if m.state is mo.MOVING and m.target_deg is not None:
        to_az, to_el = m.target_deg, m.el_target_deg
    elif sent_az is not None and az is not None:
        if mo.angle_error(az, sent_az, cfg.az_wraps) > cfg.tolerance_deg:
            return None, None  # (stopped short of it, or turned away since: still)
        to_az, to_el = sent_az, None
    else:
        return None, None
    if az is not None and to_az is not None:
        if mo.angle_error(az, to_az, cfg.az_wraps) <= cfg.noise_deg:
            to_az = None
    if to_el is not None and (el is None or abs(el - to_el) <= cfg.noise_deg):
        to_el = None
    return to_az, to_el


def _left_behind(
    start: tuple[float | None, float | None],
    before: tuple[float | None, float | None],
    m: mo.Motion,
    cfg: mo.MotionConfig,
    now: float,
) -> tuple[bool, bool]:
    """Rule 11: whether an axis that had to turn (``_to_turn``: where it stood) may yet be
    found left behind by the target's frame, and whether one is now. One that was still when
    the target went is left behind while it has not moved more than ``noise_deg`` from where it
    stood; one that was turning (``_turning_to``: ``before``, mid-turn, moves whether the frame
    came or not) once that axis has come to rest (no movement of its own for ``settle_s``, as
    motion.py rule 3 judges its stall: ``axis_progress_t``) off its target, where that turn was
    going, within ``tolerance_deg`` + ``noise_deg`` (an attack pass: judged on both axes
    together, an RC2800's lost elevation frame under a new azimuth went unseen; review 78:
    waiting for the whole rotor to rest, the axis whose frame was lost was called stalled while
    the other still turned)."""
    open_ = lost = False
    near = cfg.tolerance_deg + cfg.noise_deg
    axes = (
        ("azimuth", m.position_deg, m.target_deg, start[0], before[0], cfg.az_wraps),
        ("elevation", m.el_position_deg, m.el_target_deg, start[1], before[1], False),
    )
    for axis, pos, aim, stood, was, wraps in axes:
        if stood is None:
            continue  # (no turn of its own to make)
        if was is None:  # still when the target went: moved since, or not
            if pos is None or mo.angle_error(pos, stood, wraps) <= cfg.noise_deg:
                open_ = lost = True
        else:  # turning: left where the turn before was going, or not (yet)
            open_ = True
            if lost or pos is None or mo.angle_error(pos, was, wraps) > near:
                continue
            if aim is not None and mo.angle_error(pos, aim, wraps) <= cfg.tolerance_deg:
                continue  # (at its target: the frame came, or was not needed)
            moved_t = mo.axis_progress_t(m, cfg, axis)
            lost = moved_t is not None and now >= moved_t + cfg.settle_s
    return open_, lost


def _how_far(
    reply: PositionReply,
    az_deg: float,
    el_deg: float | None,
    noise_deg: float,
    wraps: bool,
    turns_az: bool = True,
) -> str:
    """Rule 9: how far ``reply`` is from ``az_deg``/``el_deg``, in an error's words: on the
    axis that is off (more than ``noise_deg``), both when both are (attack 12: the azimuth's
    alone told an elevation glitch, 45 read as 145, as 0 degrees off); a bearing alone as a
    number of degrees. A box that never turns its azimuth (``turns_az``: a composite's
    elevation box) names that channel as its own, none of the rotator's (review 48: "160° off
    in azimuth" while the antenna's azimuth, the other box's, never moved)."""
    az_off = mo.angle_error(reply.az_deg, az_deg, wraps)
    if reply.el_deg is None or el_deg is None:
        return f"{az_off:g}°"
    el_off = abs(reply.el_deg - el_deg)
    azimuth = "azimuth" if turns_az else "the box's own azimuth channel (none of the antenna's)"
    parts = [(off, axis) for off, axis in ((az_off, azimuth), (el_off, "elevation"))]
    off_axes = [(off, axis) for off, axis in parts if off > noise_deg] or parts
    return " and ".join(f"{off:g}° off in {axis}" for off, axis in off_axes)


def _signed(a_deg: float, b_deg: float, wraps: bool) -> float:
    """Rule 9: ``b_deg`` less ``a_deg``, the short way round where ``wraps``."""
    d = b_deg - a_deg
    return (d + 180.0) % 360.0 - 180.0 if wraps else d


def _steady(
    readings: tuple[tuple[PositionReply, float], ...], cfg: mo.MotionConfig, limit_deg: float
) -> bool:
    """Rule 9: whether three readings in a row (each with its time) are one turn: each axis
    moving the same way at a steady rate, the third within ``limit_deg`` of where the first
    two put it at its time, at FIRST_TURN_MAX_DEG_S at most (or the model's top speed, if
    faster). One byte off in one of them breaks the line; one flipped at a rate no rotor
    turns (347, 247, 147 a reply time apart) is no turn. More than three: every three in a
    row so."""
    if len(readings) > 3:
        return all(_steady(readings[i : i + 3], cfg, limit_deg) for i in range(len(readings) - 2))
    (r1, t1), (r2, t2), (r3, t3) = readings
    if not t1 < t2 < t3:
        return False
    most = max(FIRST_TURN_MAX_DEG_S, mo.top_speed_deg_s(cfg))
    axes = [(r1.az_deg, r2.az_deg, r3.az_deg, cfg.az_wraps)]
    if r1.el_deg is not None and r2.el_deg is not None and r3.el_deg is not None:
        axes.append((r1.el_deg, r2.el_deg, r3.el_deg, False))
    for a, b, c, wraps in axes:
        rate = _signed(a, b, wraps) / (t2 - t1)
        if abs(rate) > most or abs(_signed(b, c, wraps) / (t3 - t2)) > most:
            return False
        if abs(_signed(b + rate * (t3 - t2), c, wraps)) > limit_deg:
            return False
    return True


def _where(reply: PositionReply) -> str:
    return f"{reply.az_deg:g}" if reply.el_deg is None else f"{reply.az_deg:g}/{reply.el_deg:g}"


def _clock(text: str) -> tuple[int, ...]:
    """Rule 14: a controller's clock as it prints it (``2001/00/00 00:01:09``: its power-on
    reading has month and day 0), in an order that compares."""
    return tuple(int(part) for part in re.findall(r"\d+", text))


class _Doubted(NamedTuple):
    """Rule 9: the reading asked again, when it came, whether it was asked again at once, and
    whether the rotor was turning (its next reading is taken)."""

    reply: PositionReply | None
    t: float
    at_once: bool
    turning: bool = False
    first: bool = False  # a connection's first, nothing to doubt it against: no answer yet


NOT_DOUBTED = _Doubted(None, -math.inf, False)


class Doubt(Enum):
    """Rule 9: what becomes of a reading."""

    TAKEN = "taken"  # believed
    ASK = "ask"  # not yet: asked again at once
    WAIT = "wait"  # not yet: asked at the next poll (the readings go on disagreeing)


class Controller:
    def __init__(self, cfg: WorkerConfig, options: dict[str, SettingValue] | None) -> None:
        self.cfg = self.base_cfg = cfg  # rule 7
        # rule 2: ``_turn_least_s`` of the motion in effect, and the least silence, or the least
        # time without a valid reply, that can make the controller offline (the cheap look
        # before ``_silent_offline_t`` and ``_garbled_offline_t``): set with ``cfg``
        self._least_s = self._least_silence_s = 0.0
        self._limits_of(cfg)
        self.link: Link | None = None
        self.motion = mo.Motion()
        self.answering = False
        self.options = Options(options, cfg.spec.settings)
        self.target_last = False  # the last command written was a target (motion.py rule 8)
        self.stops = Stops()
        self.az_shown, self.el_shown = st.Hysteresis(), st.Hysteresis()
        self.version: str | None = None
        self.controller_time: str | None = None  # its own clock (SatEL)
        self.restarts = 0  # rule 12: turns a restart abandoned (runtime/composite.py rule 8)
        # turns a motion event dropped, said (a stall, a limit, a turn away or back, a pass, a
        # refusal): a composite's other box abandons its own (runtime/composite.py rule 8)
        self.dropped_turns = 0
        # rule 14: a silent controller's slew target put back after its report did not come, and
        # its clock as last read before that slew, until the first reading after it judges it
        self._slew_retry: tuple[Target, str | None] | None = None
        self._drove_t: float | None = None  # rule 12: the last reading that said a motor runs
        self._said_off = 0  # rule 12: readings in a row that said no motor runs
        self._silence_reported = False
        self._afresh = False  # status.py rule 1: the next first reading is shown as it is
        self._junk_reported_t = -1e18
        self._port_error: str | None = None
        self._takes_readings = False  # rule 8: the link's codec does (set on connect)
        self._doubted = NOT_DOUBTED  # rule 9: a reading of a rotor not turning asked again
        self._doubts_in_row = 0  # rule 9: readings at rest doubted since one was believed
        self._misfits = 0  # rule 6: MISFIT replies since the last reading settled
        self._misfit_said = ""  # ... the last one's bytes, for the words of a lone one
        self._turn_trusted = False  # rule 9: a turning rotor's readings not doubted till rest
        self._first_unread = False  # rule 9: answering by a doubted reading, none taken yet
        self._first_said: tuple[_Doubted, ...] = ()  # rule 9: the last three first, doubted
        self._rest_said: tuple[_Doubted, ...] = ()  # rule 9: the last three at rest, doubted
        self._first_agreed: PositionReply | None = None  # ... the one the next confirmed
        self._first_unconfirmed = 0  # ... in a row (FIRST_UNWATCHED_READINGS: a stop each)
        self._first_garbled = False  # ... some of them answers garbled past parsing
        self._torn_run = 0  # ... the connection before ended in torn answers (link.py 11)
        self._unwatched_due = False  # ... the stop that many call for, due after the reading
        self._unwatched_said_t = -math.inf  # ... when such a stop was last said on R/error
        # ... one at rest that came within STOP_MERGE_MIN_S of the last stop written: when it
        # was due, and its reading (written once that second is over, never merged away)
        self._unwatched_owed: tuple[float, PositionReply | None] | None = None
        # ... the count and time of the last at rest (the next comes sooner: review 116)
        self._unwatched_last: tuple[int, float] | None = None
        self._unwatched_ask_t: float | None = None  # ... when the reading for the next is asked
        # ... the last two of three taken as a turn: the next reading may go on with it
        self._steady_from: tuple[tuple[PositionReply, float], ...] | None = None
        self._released_stop_t: float | None = None  # ``lock_released``: the stop let go
        self._unwatched_stopping = False  # rule 9: the stop being written is the unwatched one
        self._released_owed = False  # ... one owed when the lock was released (rule 3)
        self._cut_move = True  # link.py rule 13: a target the last connection wrote may be cut
        self._released_unseen_t: float | None = None  # ... its stop no reading showed taking
        self._passing = False  # stops.py rule 4: the stops checked now are a pass's (or rule 10's)
        self._pass_ends = False  # ... and the stop due now its last try: given up once written
        self._rested: tuple[float, float | None] | None = None  # rule 10: where it rested
        self._sent_az: float | None = None  # rule 10: the last target's azimuth written
        self._short_latched: float | None = None  # rule 10: ``_short_of`` said it (latched)
        self._guarded = False  # rule 10: the first turn nobody asked for since it is judged
        self._still_at_close: bool | None = None  # rule 10: still, no target out, when the
        # readings were last lost (the port closed, the controller silent; None: never had any)
        self._rest_at_close = False  # rule 9: ... not turning, a stop sent or not (its first
        # reading back is doubted against where it stood)
        self._connect_guard = False  # rule 10: a turn from the first readings back is judged
        self.pending_unshown = False  # ``seen``: the status built last shows no target waiting
        self._guard_at_start = False  # rule 10: ... and they are this session's first
        self._known_since_loss = False  # rule 10: a turn or a settled rest seen since then
        self._rested_at_start = False  # rule 10: ``_rested`` is from those
        self._watch_until = -math.inf  # rule 10: polled at the moving rate until then
        self._retry: Target | None = None  # rule 11: the target sent once, until judged
        # rule 13: the raw target of a turn a failed port dropped, judged at the first rest after
        self._lost_aim: tuple[float | None, float | None] | None = None
        self._lost_at_aim: frozenset[str] = frozenset()  # rule 13: axes decided at it
        self._retry_t = math.inf  # rule 11: when it was sent
        self._retry_raw: tuple[float, float | None] = (0.0, None)  # ... as it was resolved
        self._retry_from: tuple[float | None, float | None] = (None, None)  # ... axes to turn
        self._retry_before: tuple[float | None, float | None] = (None, None)  # ... each axis's
        # bearing it was turning to when the target went (mid-turn), None for a still one
        self.notes: list[Note] = []  # for the session, in order (``take_notes``)
        # the motion (and its configuration) whose next deadline ``wakeups`` found, and that
        # deadline: ``tick`` changes nothing before it (motion.py rule 9)
        self._deadline: tuple[mo.Motion | None, mo.MotionConfig | None, float] = (
            None,
            None,
            -math.inf,
        )

    @property
    def name(self) -> str:
        return self.cfg.rotator_id

    def seen(
        self,
        previous: RotatorStatus,
        view: st.View,
        pending: Target | None,
        locked: bool,
        wall_offset_s: float,
        features: st.Features,
    ) -> st.Seen:
        """What the status view needs (status.py), the controller's part from here."""
        link, wire, motion = self.link, None, self.motion
        if pending is not None and link is not None:
            spec = self.cfg.spec
            az, el = resolve(
                pending, motion, self.cfg.aim, link.codec, (spec.el_min_deg, spec.el_max_deg)
            )
            try:
                wire = link.codec.wire_target(az, el) if az is not None else None
            except NotReady:  # (protocols/base.py: it goes once the codec can count it)
                wire = None
        # a target waiting that this status cannot show (session.py ``newest_applied``)
        self.pending_unshown = pending is not None and wire is None
        if link is not None and link.stop_due and motion.target_deg is not None:
            # a stop waits for a half-duplex line (link.py rule 3): the target is dropped, as
            # once it is written (a nudge is then made from the bearing: runtime/rotator.py)
            motion = replace(motion, target_deg=None, el_target_deg=None)
        return st.Seen(  # (by position: a third of the cost by name, at every reading)
            previous,
            view,
            self.version,  # version
            self.controller_time,  # controller_time
            motion,  # motion
            link is not None,  # connected
            link is not None and self.answering,  # answering
            locked,
            self.options.values,  # options
            self.az_shown.value,  # bearing_deg
            self.el_shown.value,  # elevation_deg
            link.slew if link is not None else None,  # slew
            pending,
            wire,  # pending_wire
            wall_offset_s,
            features,
            self.stops.owed,  # stop_owed
            self._short_of(motion),  # short_of_deg
        )

    def _short_of(self, m: mo.Motion) -> float | None:
        """Rule 10: the last target written, while the guard is on and the rotor, not turning,
        rests short of it (kept across a restart: ``keep_short_of``); None otherwise."""
        sent = self._sent_az
        if not self._guarded or sent is None or m.state is mo.MOVING:
            self._short_latched = None
            return None
        if self._short_latched == sent:  # (until a turn, another target or the guard's end: a
            return sent  # review, a rest at the tolerance's edge flipped it at every poll)
        # (readings lost mid-turn are no rest, nor the first one back, a guess: no move seen
        # by these readings; reviews, a restart then stopped the user's own turn)
        if m.state not in _RESTS or m.position_deg is None or m.last_move_t is None:
            return None
        if self._short_of_target(m.position_deg, self.cfg.motion):
            self._short_latched = sent
            return sent
        return None

    @property
    def short_of_deg(self) -> float | None:
        """Rule 10's ``_short_of`` now (the first status's, before any step)."""
        return self._short_of(self.motion)

    def keep_turn(self) -> None:
        """motion.py rule 6, at the start: the state file keeps a turn the run before may have
        left in flight (runtime/kept.py rule 13): on a box with no feedback, taken at the first
        connect as one lost with the port (``lost_turning``); readings tell the others'."""
        if not self.cfg.spec.can_report_position:
            self.motion = replace(self.motion, lost_turning=True)

    def keep_short_of(self, raw_az: float) -> None:
        """Rule 10, at the start: the target the rotor rested short of when the bridge last ran
        (runtime/kept.py rule 9): its guard as if written in this session."""
        if self.cfg.unasked_moves == "after-stop":  # (latched: before any reading, as kept;
            # an attack pass, a start whose controller did not answer yet forgot it)
            self._sent_az, self._guarded, self._short_latched = raw_az, True, raw_az

    def take_notes(self) -> list[Note]:
        """What happened since the last call that the session must act on, in order."""
        notes, self.notes = self.notes, []
        return notes

    # -- the port ----------------------------------------------------------------------------
    def open_failed(self, reason: str) -> None:
        if reason != self._port_error:  # once per reason
            self._port_error = reason
            self.notes.append(Report(ErrorKind.SERIAL, reason))

    def connect(self, now: float, wall_s: float) -> None:
        spec = self.cfg.spec
        self._port_error = None
        self.link = link = Link(spec.codec_factory(), spec, now, self.cfg.baud)
        link.cut_move = self._cut_move  # link.py rule 13: what the last connection may have cut
        if self._torn_run:  # link.py rule 11: a run of torn answers goes on across a replug
            link.carry_torn(
                self._torn_run
            )  # (rule 9: counted until a reading is taken; review 118)
        # (a runtime Protocol check costs tens of microseconds: once per link, not per reading)
        self._takes_readings = isinstance(link.codec, TakesReadings)
        self._first_unread = self._unwatched_due = False
        self._unwatched_owed = None  # (rule 9: the port's fall owed the last stop, stops.py 3)
        self._rest_said = ()  # (rule 9: a line at rest is one connection's)
        self._steady_from = None  # (rule 9: the unconfirmed count goes on until a reading
        # is taken, ``_reading``; review 107: a flaky adapter's connections of seven readings
        # each never reached FIRST_UNWATCHED_READINGS, and a turn at the start ran to its end)
        self._unwatched_said_t = -math.inf  # rule 9: a new connection's first such stop said
        self._doubted, self._doubts_in_row = NOT_DOUBTED, 0  # rule 9: a new connection's
        # first reading is believed once the next agrees (``_doubts_first``)
        self._misfits = 0  # rule 6: counted anew
        self.motion = mo.link_up(self.motion, self.cfg.motion, now)
        self.answering = not spec.can_report_position
        if self.answering:  # (stops.py rule 7: a blind controller answers from its connect)
            self.stops.lock_sign(now)
        self._silence_reported = False
        self.options.connected(self.answering)
        self._retune()
        if self.stops.owed:  # stops.py rule 3: before anything else the controller gets
            log.info("%s: sending the stop that came while the port was closed", self.name)
            self._send_owed(link, now)
        link.connect(link.codec.encode_connect(wall_s), now)  # link.py rule 14

    def _send_owed(self, link: Link, now: float) -> None:
        """stops.py rule 3: the stop owed, written now (checked as any: rule 4)."""
        self._passing = self._pass_ends = False
        self.stops.owed = False
        released, self._released_owed = self._released_owed, False
        link.write_stop(now)
        self._stop_written(link, now)
        if released:  # (a lock released before the port opened: its stop as released)
            self._released_stop_t = self._released_unseen_t = now

    def disconnect(self, failed: bool, now: float) -> None:
        """The port is closed (``failed``: not on purpose)."""
        stop_due = self.link is not None and self.link.stop_due
        if self.link is not None:  # link.py rule 13: a target of it may be cut in the box
            self._cut_move = self.link.move_unsure
            self._torn_run = self.link.torn_run  # (link.py rule 11: for the next connection)
        unseen = self.stops.unseen_t
        self.stops.port_closed(failed, stop_due, self.motion, now)
        if self.stops.owed and self._let_go(unseen):
            self._released_owed = True  # (the released lock's, or rule 9's unwatched one)
        spec = self.cfg.spec  # rule 13: judged at its rest (not where the replug stops it)
        if failed and not self.cfg.box and not spec.connect_stops and self.turn_out():
            self._lost_aim = (self.motion.target_deg, self.motion.el_target_deg)
            self._lost_at_aim = frozenset()
        self.link = None
        self._slew_retry = None  # rule 14: (its target waits no more: session.py)
        self.answering = self._first_unread = False
        self._lose_motion(mo.link_down)
        self._pass_ends = False  # (a last try not written: owed, checked as any)

    def turn_out(self) -> bool:
        """Rule 13: a turn of the bridge's the controller may be driving: a target written, no
        stop sent for it nor due on the line (link.py rule 3: owed once the port is lost), the
        rotor not at it by the last reading."""
        m, link = self.motion, self.link
        return (
            (m.target_deg is not None or m.el_target_deg is not None)
            and m.stop_sent_t is None
            and not (link is not None and link.stop_due)
            and not mo.at_target(m, self.cfg.motion)
        )

    def lost_turn(self) -> str:
        """Rule 13, before ``disconnect``: what becomes of a single controller's turn out when
        its port is lost, as the words its error ends with ("" where none is out, and on a
        composite's box)."""
        if self.cfg.box or not self.turn_out():
            return ""
        m, spec = self.motion, self.cfg.spec
        turn = f"its turn{self._turn_to(m.target_deg, m.el_target_deg)}"
        if spec.connect_stops:  # (a SatEL's: protocols/satel.py rule 2)
            return (
                f": {turn} was dropped, and the replug stops it (the controller's connect "
                "begins with a stop); send the target again"
            )
        seen = (
            "followed by its readings once the port is back, and stopped if it comes to rest "
            "short of it"
            if spec.can_report_position
            else "unseen, not stopped"
        )
        return (
            f": {turn} was dropped, and the controller may finish it by itself ({seen}); "
            "a STOP sent meanwhile goes first when the port is back; send the target again "
            "to have the turn watched"
        )

    # -- stops ---------------------------------------------------------------------------------
    def turning(self) -> bool:
        """Rule 2: a turn to a target under way, no stop sent for it (at its target by the last
        reading: no turn under way, only the reading that finds it still is missing, motion.py
        rule 2)."""
        m = self.motion
        return (
            m.state is mo.MOVING
            and m.target_deg is not None
            and m.stop_sent_t is None
            and not mo.at_target(m, self.cfg.motion)
        )

    def halt_owed(self, owed: bool) -> None:
        """parts.py rule 10: a refused start's halt is owed to the turn its readings are still
        judging (``owed``), or no longer: motion.py rule 4 then confirms a move only on axes
        decided still by a later reading before it takes it for a hand's."""
        self.motion = mo.halt_owed(self.motion, owed)

    def cut_mid_turn(self) -> bool:
        """The port is closed and the rotor was turning, or had a target out, when it went
        (rule 10's ``_still_at_close``): a turn that goes on when the port is back unless a
        stop is owed (runtime/composite.py rule 8)."""
        return self.link is None and self._still_at_close is False

    def stop(
        self, now: float, merge: bool = False, ends_pass: bool = False, unwatched: bool = False
    ) -> None:
        """A stop now (``merge``: unless it adds nothing, stops.py rule 1), or, while the port
        is closed, as the first frame it gets (stops.py rule 3); ``ends_pass``: a pass's last
        try (stops.py rule 4); ``unwatched``: rule 9's, let go once readings show it had."""
        self._passing, self._pass_ends = False, ends_pass  # (else a stop anew: checked as any)
        self._unwatched_stopping = unwatched  # (any other: checked as an operator's)
        if not unwatched:  # (stops.py rule 2: somebody's, merged or waiting for the line, is
            self._released_stop_t = self._released_unseen_t = None  # not let go: review 118)
        self._retry = None  # rule 11: a stop ends the target's tries
        if self.link is None:
            self.stops.owed = True
            self._released_owed = False  # (a stop owed now is checked as any: stops.py rule 2)
        elif not merge or not self.stops.merges(self.motion, self.cfg.motion, now):
            self._released_owed = False  # (a new stop: checked as any, stops.py rule 2)
            self.link.want_stop()
            self.flush_stop(now)

    def flush_stop(self, now: float) -> None:
        """Write a due stop now, or as soon as a half-duplex line is free (one reply time)."""
        link = self.link
        if link is None or not link.stop_ready():
            return
        reply = link.end_held(now)  # rule 5: the reading the stop cuts short, before the stop
        if reply is not None:
            if self._doubts(reply, now) is Doubt.TAKEN:
                self._reading(link, self._confirmed(reply), now)
            else:  # rule 9: asked again as soon as the stop is out (a review: asked a moving
                link.heard(now)  # poll later, the rotor turning on disagreed again, and the
                link.poll_now(now)  # stop the line lost was never checked)
                self._unwatched_due = False  # (the stop an unwatched rotor is owed: this one)
                first = self._doubted.first and self._doubts_in_row < DOUBTS_TOLD
                self._doubted = self._doubted._replace(at_once=self._doubts_in_row == 1 or first)
        if link.flush_stop(now):
            self._stop_written(link, now)

    def _stop_written(self, link: Link, now: float) -> None:
        """A stop frame (an operator's, a repeat, one owed) was written now: the motion, the
        stop rules and the next poll learn it alike (a review found the owed stop's own copy
        of these lines had lost two of them)."""
        self.motion = mo.stop_sent(self.motion, self.cfg.motion, now)
        if self._unwatched_stopping:  # rule 9: the unwatched stop, let go as a released
            self._unwatched_stopping = False  # lock's once a reading shows it had (review 107)
            self._released_stop_t = self.motion.stop_sent_t
        self._connect_guard = False  # (rule 10: a stop's own checks watch it from now)
        self._lost_aim = None  # (rule 13: a stop is all its rest would get)
        self.stops.sent(now)  # (stops.py rule 1: the repeat, or a stop anew)
        if not self.cfg.spec.can_report_position:
            self.stops.blind_sent(now)  # stops.py rule 6: nothing can check it
        link.poll_every(now, self.cfg.moving_poll_interval_s)  # rule 3: it is checked
        if self._pass_ends:  # stops.py rule 4: a pass's last try, written (on a half-duplex
            self._pass_ends = False  # line maybe after the check that asked for it): given up
            self.motion = mo.stop_checked(self.motion)  # (a hand has it: left alone, and
            self.stops.let_go()  # owed to no silence nor port failure after)

    def owe_stop(self) -> None:
        """stops.py rule 3: a stop is owed: the first frame once the port is open (a lock kept
        from before a restart: session.py rule 11)."""
        self.stops.owed = True
        self._released_owed = False

    def lock_released(self) -> None:
        """stops.py rule 2: the lock's stop to a rotor at rest is checked while the lock holds;
        its release is the operator's word that the tower work is over (a move by hand after
        it is theirs: a review found one stopped an hour after a locked start). The check
        still has its chance (``_release_check``): a stop out when the lock was released is
        let go once a reading a resend time after it shows the rotor still (a review: released
        at once after a locked start, the stop the line lost was never checked)."""
        self._released_stop_t = self.motion.stop_sent_t
        self._released_owed = self.stops.owed  # (the port out: the stop it writes on connect)
        self._guarded = False  # (rule 10's guard too)
        self._released_unseen_t = self.stops.unseen_t  # (owed if found silent: rule 2 too)

    def _let_go(self, unseen: float | None) -> bool:
        """Whether the stop written at ``unseen`` (the last, no reading at rest since) is one
        let go once a reading shows it had: the released lock's (``lock_released``), or rule 9's
        unwatched stop (``_unwatched_stop``). Owed across a drop (stops.py rule 3), its copy
        written on the reconnect is let go so too (review 113: checked as an operator's, for
        good, a hand at the panel ten minutes later was stopped, unsaid). Somebody's stop since
        (an operator's, the lock's: merged into it, or waiting for a half-duplex line when the
        port failed) forgets both (``stop``): checked as any (review 118)."""
        return unseen is not None and unseen in (self._released_unseen_t, self._released_stop_t)

    def _release_check(self, now: float) -> None:
        """``lock_released``'s stop let go, after a reading (the motion just updated)."""
        m = self.motion
        if m.stop_sent_t is None or m.stop_sent_t != self._released_stop_t:
            self._released_stop_t = None  # (a newer stop, or none: rule 2 as ever)
            return
        if m.state is not mo.IDLE or m.idle_not_before_t is not None or m.target_deg is not None:
            return  # (turning, braking, settling: a connection's first reading is a guess)
        if now >= m.stop_sent_t + self.cfg.motion.stop_resend_s:
            self.motion = mo.stop_checked(m)
            self._released_stop_t = None

    def check_stop(self, now: float, target_going: bool, locked: bool = False) -> None:
        """stops.py rule 2: a stop that did not take is sent again (rule 4: a stall's too,
        once, if the rotor broke free); rule 7: the lock's (``locked``: the session's lock
        holds) at a sign the rotor may be turning."""
        link = self.link
        if link is not None and self.stops.broke_free(self.motion, target_going):
            link.write_stop(now)
            self.stops.wrote_at_rest(now, False)
            why = (
                f"rotor turning at {self.where()} after the stop its stall was "
                "given (freed, turned by hand, or that stop lost on the line): stopped once "
                "more; if it still turns, stop it at the controller"
            )
            self.notes.append(Report(ErrorKind.STOP, why))
            return
        again, error = self.stops.check(self.motion, self.cfg.motion, now, target_going)
        if error is not None:
            self.notes.append(error)
        if again:
            log.warning("%s: still turning after a stop; stopping again", self.name)
            passing = self._passing
            last = passing and error is not None  # stops.py rule 4: a pass's last try
            self.stop(now, ends_pass=last)
            self._passing = passing and not last  # (the same series)
        self._owed_unwatched(now)
        cfg = self.cfg
        lock, said, why = self.stops.lock_check(
            locked,
            self.motion,
            now,
            target_going,
            cfg.moving_poll_interval_s,
            cfg.junk_report_interval_s,
        )
        if said is not None:
            self.notes.append(said)
        if lock:
            if why:
                log.warning("%s: %s", self.name, why)
            else:
                log.debug("%s: the lock's stop again (a reading at rest doubted)", self.name)
            self.stop(now)  # (stops.py rule 7: lock_check keeps them a second apart at least)

    # -- what comes in ---------------------------------------------------------------------------
    def feed(self, data: bytes, now: float) -> Fed:
        """Bytes from the port: whether they completed a reply, and if so whether all they did
        was to hold a reading (rules 5 and 9)."""
        link = self.link
        if link is None:
            return Fed.NOTHING
        if log.isEnabledFor(logging.DEBUG):  # (one call, not two, at every read)
            log.debug("%s: <- %r", self.cfg.rotator_id, data)
        link.got_bytes(len(data), now)
        replies = link.codec.feed(data)
        link.parsed(replies, now)  # link.py rule 11: a reply of the controller's form, or none
        if not replies:
            return Fed.NOTHING
        held = len(replies) == 1 and isinstance(replies[0], PositionReply)
        for reply in replies:
            if isinstance(reply, PositionReply):
                if not link.hold_reading(reply, now):  # rule 5: taken once the exchange is over
                    held = False
                    self._ask_again(link, now, once=True)
            elif isinstance(reply, VersionReply):
                if reply.version != self.version:
                    log.info("%s: controller version %s", self.name, reply.version)
                self.version = reply.version
                link.replied()  # link.py rule 14: its exchange over
            elif isinstance(reply, JunkReply):
                if reply.reason is JunkReason.POWER_ON:
                    log.info("%s: power-on byte seen; options will be re-applied", self.name)
                    self.options.all_due()
                    self._retune()
                    self._restarted(now)  # rule 12
                if reply.reason is JunkReason.REFUSED and self.target_last:  # motion.py rule 8
                    self.target_last = False
                    self.motion, events = mo.refused(self.motion, self.cfg.motion, now)
                    self._motion_events(events, now)
                    if events:
                        continue  # the answer to the target, reported as such: no junk
                if reply.axis is not None:  # motion.py rule 3: that axis's frame refused
                    self.motion = mo.undriven(self.motion, reply.axis)
                if reply.late:  # link.py rule 12: it answers, late
                    link.answered_late(now)
                if reply.reason is JunkReason.MISFIT:  # rule 6: in the codec's words, if
                    self._misfit(link, reply, now)  # it persists
                else:  # (told, and logged, once the line is quiet)
                    link.add_junk(reply.data, now)
                link.garbles(reply, now)  # link.py rule 11: the controller answered, garbled
                if link.spoils(reply) or reply.reason is JunkReason.UNTRUSTED:
                    self._ask_again(link, now, once=True)
        if self._settled(link, now):
            held = False
        return Fed.HELD if held else Fed.REPLY

    def _ask_again(self, link: Link, now: float, *, once: bool) -> None:
        """Rule 5: the exchange gave no reading it can trust (``once``: asked again at once if
        its poll was no re-poll, link.py rule 11; rule 9's doubt has its own bound)."""
        log.debug("%s: reply not trusted; asking again", self.name)
        link.ask_again(now, once)
        if link.end_slew(now):  # the slew is over; where it ended, unseen
            self.motion = mo.slew_ended(self.motion, now)
            self._unseen()

    def _unseen(self) -> None:
        """A slew ended where no reading shows (a spoiled or lost report): the bearing is
        unknown until the next reading (status.py rule 3's "never more than it knows"), not
        the last one read, from before the slew, nor the slew's estimate."""
        self.az_shown, self.el_shown = st.Hysteresis(), st.Hysteresis()

    def _settled(self, link: Link, now: float) -> bool:
        """Rule 5: a reading whose exchange is over is taken; True if one was."""
        reply = link.settled(now)
        if reply is None:
            return False
        doubt = self._doubts(reply, now)
        if self._misfits == 1 and doubt is Doubt.TAKEN:  # rule 6: a lone misfit, line noise
            self._say(
                f"a reply of {self._misfit_said}, outside the scale the controller is "
                "configured for, was not said again: ignored (line noise?)",
                now,
                logged=True,
            )
        self._misfits = 0
        if doubt is not Doubt.TAKEN:
            link.heard(now)  # (the controller answers: its value is what is doubted)
            if doubt is Doubt.ASK:  # (the first time only: a line gone bad is polled as ever)
                self._ask_again(link, now, once=False)
            if not self.answering:  # rule 9: the first back, doubted, is an answer all the same
                if not self._doubted.first:  # (where it stood is shown; a connection's first
                    self._answers_again(now)  # has nothing to show: not answering yet)
                    self._first_unread = True  # (the first taken is still the connection's)
                if self.stops.owed:  # stops.py rule 3: the stop it went silent with, at once
                    log.info(
                        "%s: sending again the stop it went silent before confirming", self.name
                    )
                    self._send_owed(link, now)
            if self._unwatched_due:  # rule 9: readings that never confirm
                self._unwatched_stop(reply, now, self._doubted.first)
            return False
        self._reading(link, self._confirmed(reply), now)
        return True

    def _confirmed(self, reply: PositionReply) -> PositionReply:
        """Rule 9: the reading taken for ``reply``: the first reading it confirmed (a
        connection's first, ``_doubts_first``: the value that answered the question the motion
        machine times it by, link.py ``first_asked_t``), else itself."""
        first, self._first_agreed = self._first_agreed, None
        return reply if first is None else first

    def _misfit(self, link: Link, reply: JunkReply, now: float) -> None:
        """Rule 6: a MISFIT reply is told in the codec's words from the MISFITS_TOLD-th in a
        row on (no reading settled between); the first is asked again at once, as a reading
        rule 9 doubts."""
        self._misfits += 1
        self._misfit_said = reply.data.strip(b"\r\n ").decode("ascii", "replace")
        if self._misfits >= MISFITS_TOLD:
            self._say(reply.detail, now, logged=False)
            return
        log.info("%s: %s; asking again", self.name, reply.detail)
        self._ask_again(link, now, once=True)

    def _doubts(self, reply: PositionReply, now: float) -> Doubt:
        """Rule 9: whether ``reply`` is believed (TAKEN), or asked again (at once: ASK; at the
        next poll: WAIT, the readings having disagreed more than once in a row)."""
        m, cfg, doubted = self.motion, self.cfg.motion, self._doubted
        self._doubted = NOT_DOUBTED
        steady, self._steady_from = self._steady_from, None  # (one reading's chance)
        stands = m.anchor_deg  # (where the motion machine last saw it move: None at first)
        el_stands = m.el_anchor_deg
        if stands is None and self._rest_at_close and m.state is not mo.MOVING:
            stands, el_stands = m.position_deg, m.el_position_deg  # (the first back: where it
            # stood still when the readings were lost, an attack pass)
        if stands is None and not self.answering:  # a connection's first: two must agree
            return self._doubts_first(reply, doubted, now)
        if m.state is mo.MOVING or m.target_deg is not None or stands is None:
            self._doubts_in_row = 0  # (turning, a target out, or a slew's report)
            report = self.link is not None and self.link.slew is not None  # (a silent one's
            if stands is not None and not report:  # after its slew; only that one: review 105,
                return self._doubts_turning(reply, doubted, now)  # a SatEL's answers after
            return Doubt.TAKEN  # it, while it settles, were taken unchecked)
        if steady is not None and _steady((*steady, (reply, now)), cfg, doubt_deg(cfg)):
            return Doubt.TAKEN  # (the turn a connection's first readings showed goes on)
        self._turn_trusted = False  # (at rest: _doubts_turning's next turn is doubted anew)
        limit, wraps = doubt_deg(cfg), cfg.az_wraps
        # no move for the motion machine (within noise_deg of where it stands): taken; a move
        # is what is doubted, however small (a review: a flip of 2 degrees, taken, turned the
        # motion to MOVING, and a second glitch in its settle time was published as a move)
        if not _apart(reply, stands, el_stands, cfg.noise_deg, wraps):
            if doubted.reply is not None:  # back where it stood: the one before was noise
                away = _how_far(
                    doubted.reply, stands, el_stands, cfg.noise_deg, wraps, cfg.spec.turns_azimuth
                )
                self._say(
                    f"a reading at rest of {_where(doubted.reply)}, {away} from where the "
                    "rotor stands, was not said again: ignored (line noise?)",
                    now,
                    logged=True,
                )
            self._doubts_in_row = 0
            return Doubt.TAKEN
        # said twice: the rotor is there (moved by hand, recalibrated); asked again at once,
        # as far on as it can have turned since (taken for still while it turned, a stop cut
        # the doubted one short: its next came a moving poll later); at the idle rate, not
        # (two readings of a noisy line half a minute apart would agree: a review)
        turned = 0.0
        if doubted.at_once:
            turned = min(2 * cfg.nominal_speed_deg_s * (now - doubted.t), DOUBT_TURN_MAX_DEG)
        if doubted.reply is not None and not _apart(
            reply, doubted.reply.az_deg, doubted.reply.el_deg, limit + turned, wraps
        ):
            self._doubts_in_row = 0
            return Doubt.TAKEN
        # FIRST_TURN_READINGS in a row on one steady line: a turn, as at the start (review 111:
        # one garble broke the pair, and a hand turn stepping 6 degrees a poll never agreed)
        said = self._rest_said
        line = (*((d.reply, d.t) for d in said if d.reply is not None), (reply, now))
        if len(line) >= FIRST_TURN_READINGS and _steady(line, cfg, limit):
            log.info("%s: readings at rest of a turn, the last %s", self.name, _where(reply))
            self._doubts_in_row, self._rest_said = 0, ()
            self._turn_trusted = True  # (its next readings as a turn's)
            self._steady_from = (line[-2], line[-1])
            return Doubt.TAKEN  # (the last of them: where it is now)
        self._doubts_in_row += 1
        self._first_unconfirmed += 1  # (a stop each FIRST_UNWATCHED_READINGS: review 103;
        self._unwatched_due = self._unwatched_at_rest_due(now)  # then sooner, review 116)
        self._doubted = _Doubted(reply, now, self._doubts_in_row == 1)  # (ASK: at once)
        self._rest_said = (*said[-(FIRST_TURN_READINGS - 2) :], self._doubted)
        turns_az = cfg.spec.turns_azimuth  # (stops.py rule 7: the lock's stop again; not for
        if _apart(reply, stands, el_stands, cfg.noise_deg, wraps, turns_az):  # an axis the box
            self.stops.lock_sign(now, _where(reply))  # never turns: review 43)
        log.info("%s: a reading at rest of %s; asking again", self.name, _where(reply))
        if self._doubts_in_row >= DOUBTS_TOLD:  # (every junk interval while it goes on)
            self._say(
                f"{self._doubts_in_row} readings in a row at rest disagree, the last "
                f"{_where(reply)}: a noisy line or a failing position sensor; the bearing shown "
                "is the last two readings agreed on",
                now,
                logged=False,
            )
        return Doubt.ASK if self._doubts_in_row == 1 else Doubt.WAIT

    def _doubts_first(self, reply: PositionReply, doubted: _Doubted, now: float) -> Doubt:
        """Rule 9: a connection's first reading, or the first back after readings were lost
        while the rotor turned (nothing it stood at to doubt it against), is believed when the
        next agrees, or the one after it (the one between then line noise), within
        ``doubt_deg`` alone, the first of the two taken, however they were asked: at once,
        DOUBTS_TOLD in a row at most, then at the moving rate (``poll``; review 100: after
        three, at the usual polls, a rotor turning at its nominal speed never had two readings
        agree, and its turn nobody asked for ran past ``az_min_deg`` unjudged). Further apart
        they may be a turn, told by FIRST_TURN_READINGS on its line (``_steady``), never by two
        (review 105: an allowance of the top speed between them let a true reading confirm the
        garble before it, taken for the bearing). Until then it is no reading for anything,
        and the controller is not answering yet (no bearing, offline, as before its first
        answer). Attack 30: one byte lost or flipped in
        the first answer (``AZ150.0`` read ``AZ10.0``) was the bearing, and a nudge of +10
        turned the rotor from 150 down to 20."""
        cfg = self.cfg.motion
        said = self._first_said if doubted.first else ()
        chain = said[-2:]  # (the older one kept only for a turn's line: FIRST_TURN_READINGS)
        # the last one doubted, or the one before it (one glitch between: 150, 10, 150), within
        # doubt_deg alone however far apart in time: two readings further apart than that may
        # be a turn or a garble and the true reading (in either order), which two cannot tell
        # (review 105); a turn is told by its line, below
        for back, first in enumerate(reversed(chain)):
            one = first.reply
            if one is None or _apart(reply, one.az_deg, one.el_deg, doubt_deg(cfg), cfg.az_wraps):
                continue
            noise = None  # (the odd one: the one between, or the one before the pair)
            if back == 1:
                noise = chain[-1].reply
            elif len(chain) > 1:
                noise = chain[-2].reply
            if noise is not None:
                self._say(
                    f"a first reading of {_where(noise)}, not said again (two others "
                    f"agree on {_where(reply)}): ignored (line noise?)",
                    now,
                    logged=True,
                )
            self._doubts_in_row, self._first_said, self._first_unconfirmed = 0, (), 0
            self._first_agreed = one  # (taken for this one: ``_confirmed``)
            return Doubt.TAKEN
        # FIRST_TURN_READINGS in a row on one steady line: a turn stepping further than
        # doubt_deg (review 103: three were not enough, a true one and two garbles on one line)
        line = (*((d.reply, d.t) for d in said if d.reply is not None), (reply, now))
        on_line = len(line) >= 3 and _steady(line[-3:], cfg, doubt_deg(cfg))
        if len(line) == FIRST_TURN_READINGS and _steady(line, cfg, doubt_deg(cfg)):
            log.info("%s: first readings of a turn, the last %s", self.name, _where(reply))
            self._doubts_in_row, self._first_said, self._first_unconfirmed = 0, (), 0
            self._turn_trusted = True  # (its next readings as a turn's, ``_doubts``)
            self._steady_from = (line[-2], line[-1])
            return Doubt.TAKEN  # (the last of them: where it is now)
        if not said:  # (the count goes on: answers garbled past parsing, ``_garbled_first``)
            self._doubts_in_row = 0
        self._doubts_in_row += 1
        self._first_unconfirmed += 1  # (a stop each FIRST_UNWATCHED_READINGS: _unwatched_stop)
        self._unwatched_due = self._first_unconfirmed % FIRST_UNWATCHED_READINGS == 0
        at_once = self._doubts_in_row < DOUBTS_TOLD
        self._doubted = _Doubted(reply, now, at_once, first=True)
        self._first_said = (*said[-(FIRST_TURN_READINGS - 2) :], self._doubted)
        log.info("%s: a first reading of %s; asking again", self.name, _where(reply))
        if self._doubts_in_row >= DOUBTS_TOLD and not on_line:  # (on a line: a turn's, maybe)
            self._say(
                f"{self._doubts_in_row} first readings in a row disagree, the last "
                f"{_where(reply)}: a noisy line or a failing position sensor; no bearing is "
                "shown, nor a target taken, until two agree",
                now,
                logged=False,
            )
        return Doubt.ASK if at_once else Doubt.WAIT

    def _unwatched_at_rest_due(self, now: float) -> bool:
        """Rule 9: whether the readings at rest that confirmed none in a row so far call for
        the unwatched stop: the FIRST_UNWATCHED_READINGS-th, then each as many more, or sooner
        once a turn at the rotor's nominal speed would have gone UNWATCHED_TURN_DEG since the
        last such stop, asked at the usual polls (review 116: eight more at a Rot2Prog's 9.3 s
        idle rate let a hand after the first stop run 49 s, 19 degrees past ``az_min_deg``;
        asked at the moving rate instead, a failing sensor's load for good: review 105). By
        the clock, not a count: the stop's own check asks at the moving rate."""
        count, last = self._first_unconfirmed, self._unwatched_last
        if last is None:
            return count % FIRST_UNWATCHED_READINGS == 0
        last_count, last_t = last
        if count - last_count >= FIRST_UNWATCHED_READINGS:
            return True
        return count > last_count and now - last_t >= self._unwatched_after_s()

    def _unwatched_after_s(self) -> float:
        """Rule 9: how long a turn at the rotor's nominal speed takes to go UNWATCHED_TURN_DEG:
        the next unwatched stop at rest comes with the first reading after it."""
        motion = self.cfg.motion
        speed = max(motion.nominal_speed_deg_s, motion.el_speed_deg_s or 0.0)
        return max(STOP_MERGE_MIN_S, UNWATCHED_TURN_DEG / speed)

    def _unwatched_stop(self, reply: PositionReply | None, now: float, first: bool = True) -> None:
        """Rule 9: FIRST_UNWATCHED_READINGS first readings in a row (and each as many more
        while they go on) that confirmed none: no limit, stall or turn nobody asked for can be
        judged from them, so the rotor is stopped (a stop is always safe; the line's and the
        stop rules' as any stop's), and R/error says why, at most every
        ``junk_report_interval_s`` (review 100: a line that garbled every answer differently
        left a turn at the start unwatched, and it ran past ``az_min_deg`` to its end; review
        103: a stop for one unconfirmed reading past a limit, tried before, stopped healthy
        starts of a rotor resting outside a limit, and one garble spent it). So do readings at
        rest (``first`` False: a session's, after a reading was taken) that go on disagreeing
        (review 103's follow-up: a line gone bad at rest hid a hand turn, which ran past
        ``az_min_deg`` unstopped; the maintainers' decision: the limit holds over a rotor the
        bridge cannot watch, and a still rotor's stop costs nothing)."""
        self._unwatched_due = False
        count = self._first_unconfirmed
        if not first:  # (the next at rest by the clock too: ``_unwatched_at_rest_due``)
            self._unwatched_last = (count, now)
            self._unwatched_ask_t = now + self._unwatched_after_s()
        readings = "first readings in a row" if first else "readings in a row at rest"
        m = self.motion  # (let go once readings confirm, ``_release_check``: not where it
        # stands for another stop still checked, an operator's or the lock's; review 107: kept
        # checked until the next target, a hand at the panel minutes later was stopped, unsaid)
        last_t = m.stop_sent_t
        if not first and last_t is not None and now - last_t < STOP_MERGE_MIN_S:
            # at rest, never merged away (review 116: merged as stops.py rule 1 merges, into any
            # stop a brake window before, a STOP before a hand's turn and every other unwatched
            # stop under a 10 s brake_delay_s were dropped, and the hand ran past az_min_deg):
            # within a second of the last (the lock's own, stops.py rule 7), written once that
            # second is over, unless a stop went since (``_owed_unwatched``): a second apart
            self._unwatched_owed = (now, reply)
            return
        self._unwatched_owed = None
        unwatched = last_t is None or last_t == self._released_stop_t
        self.stop(now, unwatched=unwatched)
        if now - self._unwatched_said_t < self.cfg.junk_report_interval_s:
            log.info("%s: %d %s disagree: stopped again", self.name, count, readings)
            return
        self._unwatched_said_t = now  # (its own clock: the doubt's words keep rule 6's)
        last = "garbled past reading"  # (``_garbled_first``)
        if reply is not None:  # (in true bearings, as every bearing shown: review 107)
            az = self.cfg.aim.true_of(reply.az_deg)
            last = f"{az:g}" if reply.el_deg is None else f"{az:g}/{reply.el_deg:g}"
        why = (
            f"{count} {readings} do not agree (the last {last}): the "
            "bridge cannot watch the rotor (its limits, a stall, a turn nobody asked for), so "
            "it was stopped, and is stopped again while they go on disagreeing: a noisy line "
            "or a failing position sensor?"
        )
        log.warning("%s: %s", self.name, why)
        self.notes.append(Report(ErrorKind.STOP, why))

    def _unwatched_owed_at(self) -> float | None:
        """Rule 9: when the unwatched stop at rest held back a second goes (None: none owed,
        or a stop went since it was due, which is that stop)."""
        owed, last_t = self._unwatched_owed, self.motion.stop_sent_t
        if owed is None or self.link is None:
            return None
        if not self.answering:  # (offline: the last stop is owed as any, stops.py rule 3)
            self._unwatched_owed = None
            return None
        if last_t is None or last_t >= owed[0]:
            self._unwatched_owed = None
            return None
        return last_t + STOP_MERGE_MIN_S

    def _owed_unwatched(self, now: float) -> None:
        """Rule 9: the unwatched stop at rest held back a second, written now if due."""
        at = self._unwatched_owed_at()
        if at is None or now < at:
            return
        owed = self._unwatched_owed
        assert owed is not None
        self._unwatched_stop(owed[1], now, first=False)

    def _doubts_turning(self, reply: PositionReply, doubted: _Doubted, now: float) -> Doubt:
        """Rule 9 while the rotor turns (or a target is out; not a silent controller's report
        after its slew): a reading further from the last taken than the rotor can have
        turned since (motion.py ``reach_deg``, from that reading's time) is asked again at
        once, once. The next is taken: if it is within reach of that last reading, the doubted
        one is told as line noise; if not, the rotor turns faster than its nominal speed (or
        the line garbled twice in a row), and no reading is doubted again until it rests (an
        integration test: a SPID turning ten times its nominal speed had every reading doubted
        in turn, none taken, and was called stalled and stopped)."""
        if self._turn_trusted:
            return Doubt.TAKEN
        m, cfg, link = self.motion, self.cfg.motion, self.link
        pos = m.position_deg  # (the last reading taken: one that changed nothing left it)
        since = link.last_reply_t if link is not None else None  # (that reading's time: an
        if pos is None or since is None:  # attack pass, from the last that changed, a rotor
            return Doubt.TAKEN  # standing with a target out let any reading through)
        if m.target_t is not None and m.back_from_t is None:  # a target sent at rest: it
            since = max(since, m.target_t)  # stood there until then (idle polls are slow)
        wraps, el = cfg.az_wraps, m.el_position_deg
        far = cfg.away_deg  # (reach's least: the cheap look first)
        near = not _apart(reply, pos, el, far, wraps) or not _apart(
            reply, pos, el, mo.reach_deg(m, cfg, now, since), wraps
        )
        prior = doubted.reply if doubted.turning else None
        if prior is not None:
            if near:
                self._say(
                    f"a reading of {_where(prior)} while the rotor turned, further from the one "
                    f"before than it can have turned, was not said again ({_where(reply)} "
                    "now): ignored (line noise?)",
                    now,
                    logged=True,
                )
            else:
                self._turn_trusted = True
            return Doubt.TAKEN
        if near:
            return Doubt.TAKEN
        self._doubted = _Doubted(reply, now, True, turning=True)
        log.info("%s: a reading while turning of %s; asking again", self.name, _where(reply))
        return Doubt.ASK

    def _reading(self, link: Link, reply: PositionReply, now: float) -> None:
        link.got_reading(now)
        self._first_unconfirmed, self._first_garbled = 0, False  # rule 9: a reading taken
        self._unwatched_owed = self._unwatched_last = None  # (the rotor is watched again)
        self._unwatched_ask_t = None
        self._rest_said = ()
        if self._takes_readings:  # rule 8
            cast(TakesReadings, link.codec).taken(reply)
        if reply.motion_enabled is False:
            self.options.enable_due = True  # rule 4
        if self.options.unanswered:
            self.options.answered()  # (options.py rule 1)
        if self._slew_retry is not None:  # rule 14: the first reading after the lost report
            self._slew_restart(reply)
        if reply.controller_time is not None:
            self.controller_time = reply.controller_time
        owed = first = False
        if not self.answering:
            owed, first = self.stops.owed, True
            self._answers_again(now)
        elif self._first_unread:  # rule 9: a doubted one made it answering; this is the first
            first = True  # taken, a guess as any first is (stops.py rule 3; a review: it showed
        self._first_unread = False  # a stop lost at the reconnect taken, and it was owed no more)
        cfg, was = self.cfg, self.motion
        before = was.state
        asked = link.first_asked_t  # (the question it answers, the first since the last reading)
        self.motion, events = mo.reading(
            self.motion, cfg.motion, reply.az_deg, now, reply.el_deg, asked
        )
        if self._lost_aim is not None and self.motion.lost_still and not was.lost_still:
            self._lost_decided(was)  # rule 13: axes the readings showed still, judged now
        if self.motion.state is mo.MOVING and mo.stall_due(self.motion, cfg.motion, now):
            link.poll_now(now)  # (motion.py rule 3: asked before the stall's time, it decided
            # nothing; the answer to a question asked now does, a reply time later, review 36)
        if mo.found_unjudged(self.motion):  # (motion.py rule 4: a restart's first readings
            link.poll_every(now, cfg.moving_poll_interval_s)  # tell a turn found at once)
        if self.motion.state is not mo.MOVING:  # (stops.py rule 7: an episode's end)
            self.stops.lock_calm()
        if self.motion.state is mo.MOVING or mo.at_rest(self.motion):
            self._known_since_loss = True  # (rule 10: what a loss of readings then finds)
        if self._watching() or self._rested is not None:  # rule 10
            self._unasked(was, now)
        if owed:  # stops.py rule 3: the stop it went silent with, before anything else
            log.info("%s: sending again the stop it went silent before confirming", self.name)
            self._send_owed(link, now)
        elif not first and self.stops.unseen_t is not None:  # stops.py rule 3 (a connection's
            self.stops.reading(now, self.motion.state is not mo.MOVING)  # first is a guess)
        if self.motion.state is mo.MOVING and before is not mo.MOVING:  # rule 3: a move seen
            link.poll_every(now, cfg.moving_poll_interval_s)  # (by an idle poll) is followed
        # a reading's motion is one its clock leaves as it is now (motion.py rule 9): the
        # step's tick at this time has nothing to do
        self._deadline = self.motion, cfg.motion, math.nextafter(now, math.inf)
        if events:
            self._motion_events(events, now)
        if reply.driving is False:  # rule 12: the controller says it drives no motor
            self._said_off += 1
            if self._said_off >= HALT_READINGS and self._retry is None:  # (rule 11's first)
                self._halted(now)
        else:
            self._said_off = 0
            if reply.driving:
                self._drove_t = now
        if self._retry is not None:  # rule 11
            self._retry_check(link, now)
        if self._released_stop_t is not None:
            self._release_check(now)
        if self._lost_aim is not None and before is mo.MOVING and self.motion.state in _RESTS:
            self._lost_rest(now)  # rule 13
        m = self.motion  # the bearing shown (status.py rule 1): a turn's last degrees too
        if mo.held_back(m, now):  # (motion.py rule 4: a move a later reading is to confirm,
            return  # shown then if one does: a garbled reading never)
        if was.anchor_deg is None and self._afresh:  # (``_lose_motion``)
            self.az_shown, self.el_shown = st.Hysteresis(), st.Hysteresis()
            self._afresh = False
        moving = m.state is mo.MOVING
        coasting = not moving and (before is mo.MOVING or m.state is mo.BRAKING)
        az_shown, deadband_deg = self.az_shown, cfg.deadband_deg
        spec = cfg.motion.spec  # (a travel that ends at north turns along the scale)
        toward = m.target_deg if spec.az_ends_at_north else None
        az_shown.feed(reply.az_deg, moving, deadband_deg, spec.az_wraps, coasting, toward)
        if reply.el_deg is not None:
            self.el_shown.feed(reply.el_deg, moving, deadband_deg, False, coasting)

    def _turn_to(self, az: float | None, el: float | None) -> str:
        """Rule 13: where a turn went (raw targets), in words: " to 300°, elevation 20°"."""
        spec, where = self.cfg.spec, []
        if spec.turns_azimuth and az is not None:
            where.append(f"{round(self.cfg.aim.true_of(az), 1):g}°")
        if spec.has_elevation and el is not None:
            where.append(f"elevation {el:g}°")
        return f" to {', '.join(where)}" if where else ""

    def _lost_decided(self, was: mo.Motion) -> None:
        """Rule 13: the readings back decided the lost turn over (motion.py rule 4,
        ``lost_still``) on the axes they showed still for their own time (``still_axes``): one
        of them that stood at its aim (``was``: the reading before, which a turn begun since
        has not moved from there) is left out of the judgement at the rest (``_lost_at_aim``),
        whoever turns it after; with none left, the turn ended at its aim, unsaid."""
        az, el = cast(tuple[float | None, float | None], self._lost_aim)
        m, cfg = self.motion, self.cfg.motion
        within = cfg.tolerance_deg + cfg.noise_deg
        stood, el_stood = was.position_deg, was.el_position_deg
        at_aim = set(self._lost_at_aim)
        if az is None or (
            stood is not None
            and "azimuth" in m.still_axes
            and mo.angle_error(stood, az, cfg.az_wraps) <= within
        ):
            at_aim.add("azimuth")
        if el is None or (
            el_stood is not None and "elevation" in m.still_axes and abs(el_stood - el) <= within
        ):
            at_aim.add("elevation")
        if at_aim >= {"azimuth", "elevation"}:
            self._lost_aim = None
        else:
            self._lost_at_aim = frozenset(at_aim)

    def _lost_rest(self, now: float) -> None:
        """Rule 13: the rotor followed since its port came back is at rest: short of the turn
        the port dropped, it gets a stop (its motor may still drive a jammed rotor)."""
        (az, el), self._lost_aim = cast(tuple[float | None, float | None], self._lost_aim), None
        m, cfg = self.motion, self.cfg.motion
        if m.position_deg is None:
            return
        within = cfg.tolerance_deg + cfg.noise_deg
        judged = self._lost_at_aim  # (not the axes decided at their aim: ``_lost_decided``)
        short = (
            az is not None
            and "azimuth" not in judged
            and mo.angle_error(m.position_deg, az, cfg.az_wraps) > within
        )
        el_at = m.el_position_deg
        el_short = (
            el is not None
            and "elevation" not in judged
            and el_at is not None
            and abs(el_at - el) > within
        )
        if not (short or el_short):
            return
        at = self.where()  # (an azimuth's: the elevation too where it is the one short, a
        if el_short and self.cfg.spec.turns_azimuth:  # cold review: "at rest at 10°, short of
            at += f", elevation {el_at:g}°"  # its turn to 10°, elevation 80°")
        message = (
            f"rotor at rest at {at} since its port came back, short of its turn"
            f"{self._turn_to(az, el)} dropped with the port (jammed, stopped at the panel, or "
            "its power cut meanwhile): stopped, in case its motor still drives; send the "
            "target again"
        )
        self.notes.append(Report(ErrorKind.STOP, message))
        self.stop(now)

    def _answers_again(self, now: float) -> None:
        """The controller answers (again): its first reading taken, or doubted (rule 9)."""
        self.answering = True
        self.stops.lock_sign(now)  # (stops.py rule 7: the lock's stop, lost with the readings)
        still = self._still_at_close  # rule 10: a turn from these first readings judged?
        guard = still if still is not None else self._watching()  # (a kept short_of)
        self._connect_guard = guard and self.motion.stop_sent_t is None
        self._guard_at_start = still is None
        self.options.all_due()
        self._retune()
        log.info("%s: controller answering", self.name)

    def _lose_motion(self, lose: Callable[[mo.Motion], mo.Motion]) -> None:
        """The readings are lost (the port closed, the controller offline, a SatEL's report):
        the motion is rebuilt by ``lose``. A rotor that was turning, or had a target out, may
        be anywhere near when they come back: the first reading then is shown as it is
        (status.py rule 1; a last read: the 2 degrees it turned on from the 58 shown were
        inside the deadband). One at rest keeps the bearing shown, and forgets the way of its
        last turn: a first reading of jitter, or one a noisy line made, would move it (attack
        passes: 12 changes in 20 replugs; a still rotor whose last turn went up showed its
        jitter up for good)."""
        m = self.motion
        turning = m.state is mo.MOVING or m.target_deg is not None or m.el_target_deg is not None
        if turning or self._known_since_loss:  # rule 10: what the motion knows; lost again
            self._still_at_close = not turning and m.stop_sent_t is None  # before it knew (a
            # port that flaps, a silence then the port lost), what the loss before found (an
            # attack pass: the rebuilt motion read as still, the user's turn was stopped; a
            # review: one braking after a turn seen is known, its stillness too)
            self._rest_at_close = not turning  # rule 9: a stop to a rotor at rest leaves it as
            # still as it was (an attack pass: after a STOP at rest and a replug before a
            # reading showed it taken, 150 read as 350 was published and taken as a turn)
        self._known_since_loss = False
        self._connect_guard = False  # (armed again by the first reading back)
        if turning:
            self._afresh = True
        else:  # (the way of its last turn, however long ago, is no way it turns after)
            self.az_shown.direction = self.el_shown.direction = 0
        self.motion = lose(m)

    def _unasked(self, was: mo.Motion, now: float) -> None:
        """Rule 10: ``was`` the motion before this reading."""
        m = self.motion
        if mo.at_rest(m):
            self._connect_guard = False  # (settled: at_rest judges from now on)
        if m.state is not mo.MOVING or m.target_deg is not None or m.el_target_deg is not None:
            self._rested = None
            return
        cfg = self.cfg.motion
        if was.state is not mo.MOVING and was.position_deg is not None:  # a turn begins
            self._rested = None
            # from a settled rest (not after a stall: stops.py rule 4), or from the first
            # readings back (a port opened, a controller answering again) where it was still
            # when they were lost (or, where every such turn is stopped, this session's first):
            # not where it was turning, or had a target out (a turn under way across a
            # reconnect)
            first = self._connect_guard and (was.state is mo.IDLE or was.state is mo.BRAKING)
            self._connect_guard = False
            if (mo.at_rest(was) or first) and (
                self.cfg.unasked_moves == "stop" or self._short_of_target(was.position_deg, cfg)
            ):
                self._rested = (was.position_deg, was.el_position_deg)
                self._rested_at_start = first and self._guard_at_start
            if was.state is not mo.OFFLINE:  # (the first turn ends the guard, stopped or not;
                self._guarded = False  # not one the first readings back find going on across
                # a reconnect, nobody's new turn: review 107, a turn the unwatched stop, or a
                # STOP owed to the reconnect, cut short lost its guard, and a poll garbled into
                # AM1; later ran the Rotor-EZ on to its old target)
        rested = self._rested
        if rested is None or m.position_deg is None:
            return
        az_away = mo.angle_error(m.position_deg, rested[0], cfg.az_wraps)
        away = az_away
        if rested[1] is not None and m.el_position_deg is not None:
            away = max(away, abs(m.el_position_deg - rested[1]))
        if away <= UNASKED_MOVE_DEG:
            return
        self._rested = None
        true = self.cfg.aim.true_of  # (the bearings the user sees, not the controller's)
        if self._rested_at_start and self.cfg.unasked_moves == "stop":  # (a review: a restart
            # mid-turn was blamed on the line; after-stop's guard at the start is a kept one)
            why = (
                "it was turning when the bridge started (a restart mid-turn?), or a poll a noisy "
                "line made a command, or a hand at the panel"
            )
            then = 'send the target again; set unasked_moves = "follow" to let such turns be'
        elif self.cfg.unasked_moves == "stop" or self._sent_az is None:
            why = "a poll a noisy line made a command, or a hand at the panel"
            then = 'set unasked_moves = "follow" to let such turns be'
        else:
            why = (
                f"the controller keeps the bearing {true(self._sent_az):g}° it was stopped "
                "short of, and a poll a noisy line garbled turns it there; or a hand at the panel"
            )
            then = "turn it again at the panel to go on"
        stayed = az_away <= cfg.noise_deg
        turned = _turned(
            (true(rested[0]), rested[1]), true(m.position_deg), m.el_position_deg, stayed
        )
        message = (
            f"the rotor turned with no command from the bridge, {turned} ({why}): stopped; {then}"
        )
        log.warning("%s: %s", self.name, message)
        self.notes.append(Report(ErrorKind.STOP, message))
        anew = m.stop_sent_t is None  # (a stop out, the lock's, an operator's: checked as any)
        self.stop(now)
        self._passing = anew  # (a series of its own bounded as a pass's: a held button is let be)

    def _watching(self) -> bool:
        """Rule 10: a turn nobody asked for would be stopped now."""
        return self.cfg.unasked_moves == "stop" or self._guarded

    def _short_of_target(self, rest_deg: float, cfg: mo.MotionConfig) -> bool:
        """Rule 10: the guard is on and the rotor rested short of the last target written."""
        if not self._guarded or self._sent_az is None:
            return False
        return mo.angle_error(rest_deg, self._sent_az, cfg.az_wraps) > (
            cfg.tolerance_deg + cfg.noise_deg
        )

    def _retry_check(self, link: Link, now: float) -> None:
        """Rule 11, at a reading: the target sent once is sent again if this reading, from
        its time on, shows an axis that had to turn left behind by its frame (``_left_behind``:
        a still one not moved since it went out, one turning at rest where the turn before was
        going; an attack pass: the elevation frame of an RC2800's two lost, the azimuth came,
        and the stall told blamed the brake); the tries end once no axis can be found left
        behind any more, or the target came or was dropped."""
        m, target, cfg = self.motion, self._retry, self.cfg
        assert target is not None
        mc = cfg.motion  # (as the settings in effect now make it: rule 7, a speed set since)
        wait = mc.settle_s + mc.brake_delay_s
        step = cfg.spec.reading_step_deg
        speeds = cfg.az_speed_deg_s, cfg.el_speed_deg_s
        for start, speed in zip(self._retry_from, speeds, strict=True):
            if start is not None and speed > 0:  # (a slow axis: noise and a step at its speed)
                wait = max(wait, (mc.noise_deg + step) / speed)
        due = self._retry_t + wait + mo.BRAKE_GUARD_S + cfg.moving_poll_interval_s
        if m.target_deg is None or m.state is not mo.MOVING:  # (a stop drops the target)
            self._retry = None
            return
        open_, lost = _left_behind(self._retry_from, self._retry_before, m, mc, now)
        if not open_:
            self._retry = None
        elif lost and now >= due and link.free() and not link.stop_due:
            self._retry = None
            self.notes.append(Again(target, *self._retry_raw))

    def forgo(self, now: float) -> None:
        """Rule 11: the session sends the target that did not move the rotor no more (its
        ``Again`` declined: session.py rule 23, targets.py rule 8): its turn, which never
        began, is over, at rest (motion.py rule 8), not a stall ``stall_timeout_s`` later."""
        self._retry = None
        self.motion = mo.forgone(self.motion, self.cfg.motion, now)

    def _restarted(self, now: float) -> None:
        """Rule 12: the controller restarted; a turn it had is abandoned."""
        aimed = self.motion.target_deg
        self.motion, events = mo.restarted(self.motion, self.cfg.motion)
        self.restarts += bool(events)  # (a composite's other box abandons its turn too)
        shown = None if aimed is None else self.cfg.aim.true_of(aimed)
        self._motion_events(events, now, shown)

    def _slew_restart(self, reply: PositionReply) -> None:
        """Rule 14: the first reading after a slew whose report never came; a clock gone back
        (to its power-on reading) shows the controller restarted: the target put back is
        forgotten, not sent again."""
        (target, before), self._slew_retry = self._slew_retry or (None, None), None
        after = reply.controller_time
        if target is None or before is None or after is None:
            return  # (a clock not read, before or now: a lost report, as far as it can tell)
        if _clock(after) >= _clock(before):
            return  # (its clock ran on: the report was lost on the line, the target goes again)
        shown = self.cfg.aim.true_of(reply.az_deg)
        where = f"{shown:g}°" + ("" if reply.el_deg is None else f", elevation {reply.el_deg:g}°")
        aim = self.cfg.aim.true_of(target.az_deg) if target.az_deg is not None else None
        turn = "its turn" if aim is None else f"its turn to {aim:g}°"
        if aim is not None and target.el_deg is not None:
            turn += f", elevation {target.el_deg:g}°"
        why = (
            f"the controller restarted mid-turn (its clock went back, to {after}) at {where}: "
            f"{turn} was not resumed: {SEND_AGAIN}"
        )
        log.warning("%s: clock %s, then %s after the slew: restarted", self.name, before, after)
        self.notes.append(Forgot(target, Report(ErrorKind.SERIAL, why)))

    def _halted(self, now: float) -> None:
        """Rule 12: the controller says it drives no motor; a turn it was seen driving since
        its target went out, now still short of it, is over."""
        m = self.motion
        if m.target_t is None or self._drove_t is None or self._drove_t <= m.target_t:
            return  # (not seen driving this target: a turn about to start, or never begun)
        if self._drove_t >= mo.still_from(m, self.cfg.motion):
            return  # (seen driving a rotor still: a jam its box gave up on, rule 3's stall)
        aimed = m.target_deg
        self.motion, events = mo.halted(m, self.cfg.motion, now)
        self.restarts += bool(events)  # (a composite's other box abandons its turn too)
        shown = None if aimed is None else self.cfg.aim.true_of(aimed)
        self._motion_events(events, now, shown)

    def _motion_events(
        self, events: list[mo.Event], now: float, aimed: float | None = None
    ) -> None:
        """What each motion event asks (stops.py rule 4); ``aimed``: the target it dropped,
        in true bearings (a restart's)."""
        for event in events:
            verdict = self.stops.verdict(
                event, self.motion, self.cfg.motion, self._shown_az(), aimed
            )
            if event is mo.Event.REFUSED and self._refused_once(verdict):
                continue
            if verdict.error is not None and event in _DROPS_TURN:
                self.dropped_turns += 1
            if verdict.error is not None and event in _MAY_HAVE_RESTARTED:  # rule 12
                self.options.all_due()  # (the box may be back at its own speed: an attack
                self._retune()  # pass, a GS-232 set to X1 turned at X4 after a power cycle)
            if verdict.ends_tracking is not None:
                self.notes.append(Ends(verdict.ends_tracking))
            if verdict.error is not None:
                self.notes.append(verdict.error)
            else:
                log.info("%s: %s at %s", self.name, event.value, self.motion.position_deg)
            if not verdict.stop:
                continue
            if self.link is None:  # (never: a verdict comes from a link's reading or clock;
                self.stops.owed = True  # were it otherwise, the stop is owed, not dropped)
            else:  # stops.py rule 4
                self.link.write_stop(now)  # at once, also on a half-duplex line's reply
                if self.motion.state is mo.MOVING:  # a refusal's, a pass's: this turn's stop
                    self.motion = mo.stop_sent(self.motion, self.cfg.motion, now)
                    self.stops.sent(now)
                    self._passing = event in _PASSING
                else:  # a stall's, a turned-away rotor's: to a rotor at rest
                    self.stops.wrote_at_rest(now, event is mo.Event.STALLED)

    def _refused_once(self, verdict: Verdict) -> bool:
        """Rule 11: the controller refused the target sent once, which had not moved the rotor
        (motion.py rule 8, at rest): sent again, its refusal (``verdict``) reported only if the
        bridge no longer stands for it (a frame a flipped bit made one the controller
        refuses); True if so. A second refusal is reported."""
        target, self._retry = self._retry, None
        if target is None or self.motion.state is mo.MOVING or verdict.stop:
            return False
        self.notes.append(Again(target, *self._retry_raw, verdict.error, verdict.ends_tracking))
        return True

    def where(self, *, both: bool = False) -> str:
        """Where the rotor stands, in an error's words (stops.py ``standing``: a composite's
        elevation box names its elevation); ``both``: a box that turns both axes names its
        elevation too, where it has a reading (wind.py rule 10, review 80: an elevation short
        of the storm's park was said to stand at the park's own azimuth)."""
        m, spec = self.motion, self.cfg.spec
        at = standing(m, self.cfg.motion, self._shown_az())
        if both and spec.turns_azimuth and spec.has_elevation and m.el_position_deg is not None:
            at += f", elevation {m.el_position_deg:g}°"
        return at

    def _shown_az(self) -> float | None:
        """The bearing the user sees where the motion machine has the rotor (pointing.py)."""
        pos = self.motion.position_deg
        return None if pos is None else self.cfg.aim.true_of(pos)

    # -- the line's own work, run by the session's step ------------------------------------------
    def line_work(self, now: float) -> None:
        """An overdue reply (slew.py), a due stop, the outbox, junk gone quiet."""
        link = self.link
        if link is None:
            return
        if self.stops.repeat_due(self.motion, now) or self.stops.blind_due(now):  # stops.py
            log.debug("%s: a stop repeated right after the last one, written now", self.name)
            self.stop(now)  # rules 1 and 6: before anything else
        self._settled(link, now)
        if link.reply_overdue(now):
            todo = overdue(self.cfg, link.slew, link.reply_timeout_s, now)
            if todo.retry is not None:  # (its error with it: the session words it)
                retry = Retry(todo.retry, todo.attempt, todo.error, todo.late, todo.retry_of)
                self.notes.append(retry)
                self._slew_retry = (todo.retry, self.controller_time)  # rule 14
            elif todo.error is not None:
                self.notes.append(todo.error)
            if todo.stop:
                self.stop(now)
            else:
                if link.slew is not None:  # its report never came: where it ended, unseen
                    if self._slew_retry is None:  # rule 14: a stopped slew's lost report too
                        slew = link.slew
                        aim = Target(
                            slew.to_az_deg, slew.to_el_deg, slew.source, origin=slew.origin
                        )
                        self._slew_retry = (aim, self.controller_time)
                    self._unseen()
                if self.options.values and link.asking_since is not None:  # options.py
                    self.options.unanswered = True  # rule 1: nothing came: was it off?
                self._given_up(link.give_up_reply(now), now)
                if self._watching() and mo.at_rest(self.motion):  # rule 10: a poll left
                    self._watch_until = now + self.cfg.motion.settle_s  # unanswered may have
                    link.poll_every(now, self.cfg.moving_poll_interval_s)  # been a command
                if todo.track_lost:
                    self._lose_motion(partial(mo.track_lost, cfg=self.cfg.motion))
        self.flush_stop(now)
        link.flush_outbox(now)
        junk = link.quiet_junk(now)
        if junk is not None:
            self._junk(*junk, now)
        again = link.end_garbled(now)  # link.py rule 11: a garbled reply the codec ended
        if again is not None:
            self._given_up(again, now)

    def _given_up(self, again: bool, now: float) -> None:
        """The owed reply is given up, and asked again at once if ``again`` (link.py rule 11:
        it came garbled): a reading doubted keeps its window as asked at once then, not at
        the next poll (rule 9: a review found the ask's answer lost, a reading at the next idle
        poll had the widened window; an attack pass, the re-poll's answer taken as one at the
        idle rate: readings of a rotor turned by hand disagreed, the bearing stale for 10 s)."""
        if not again:
            self._doubted = self._doubted._replace(at_once=False)
        link = self.link
        if link is not None and link.poll_garbled:
            if self._first_phase():
                self._garbled_first(now)
            elif self._rest_phase():
                self._garbled_at_rest(now)

    def _first_phase(self) -> bool:
        """Rule 9: a reading now would be a connection's first (``_doubts_first``)."""
        m = self.motion
        stands = m.anchor_deg
        if stands is None and self._rest_at_close and m.state is not mo.MOVING:
            stands = m.position_deg
        return stands is None and not self.answering

    def _rest_phase(self) -> bool:
        """Rule 9: a reading now would be one at rest (``_doubts``' own, doubted against where
        the rotor stands): answering, no turn, no target, no slew."""
        m, link = self.motion, self.link
        if not self.answering or link is None or link.slew is not None:
            return False
        return m.anchor_deg is not None and m.state is not mo.MOVING and m.target_deg is None

    def _garbled_at_rest(self, now: float) -> None:
        """Rule 9: a poll answered garbled past parsing at rest is a reading at rest that
        confirmed none, counted toward the unwatched stop as a first reading's is (review 116:
        a line that tore every answer at rest, every '.' read '?', had none counted, and a hand
        turn ran from 150 past ``az_min_deg`` 60 to 5, no stop written). One now and then is
        never eight in a row: a reading taken starts the count again (``_reading``)."""
        self._first_unconfirmed += 1
        self._first_garbled = True
        if self._unwatched_at_rest_due(now):
            self._unwatched_stop(None, now, first=False)

    def _garbled_first(self, now: float) -> None:
        """Rule 9: a poll answered garbled past parsing where a connection's first reading is
        awaited is a first reading that confirmed none, counted toward the unwatched stop
        (review 107: a line that tore every answer had none counted, and a turn at the start
        ran past ``az_min_deg`` to its end)."""
        self._first_unconfirmed += 1
        self._first_garbled = True
        if self._first_unconfirmed % FIRST_UNWATCHED_READINGS == 0:
            self._unwatched_stop(None, now)

    def tick(self, now: float) -> None:
        """The motion machine's clock (rule 4: not during a slew), and an enable owed. Not
        before the motion's next deadline (``wakeups`` keeps it): until then its clock
        changes nothing (motion.py rule 9)."""
        link = self.link
        seen, cfg, deadline = self._deadline
        if (link is None or link.slew is None) and (
            self.motion is not seen or self.cfg.motion is not cfg or now >= deadline
        ):
            asking = -math.inf if link is None else link.asking_since  # (rule 2: a stall too)
            self.motion, events = mo.tick(self.motion, self.cfg.motion, now, asking_since=asking)
            if events:
                self._motion_events(events, now)
            if (  # rule 2: a stall's deadline with nothing asked: the reading that decides,
                link is not None  # asked now, not a moving poll later (a reply under way
                and asking is None  # is that reading)
                and not link.reply_owed
                and mo.stall_due(self.motion, self.cfg.motion, now)
            ):
                link.poll_now(now)
        if link is None or not self.answering:
            return
        if self.options.enable_due and link.slew is None and link.free() and not link.stop_due:
            enable = link.codec.encode_enable()
            if enable:
                link.write(enable, now)
                self.target_last = False
            self.options.enable_due = False

    def _only_poll_until(
        self, now: float, link: Link, times: list[float], deadline: float
    ) -> float:
        """Until when a step has nothing of the controller's to do but its poll, if nothing
        but time passes from ``now``, the end of a step (session.py rule 20; -inf: not even
        now): ``line_work``, ``tick``, ``check_stop`` and ``send_options`` change nothing,
        and the poll finds the controller answering. Only when: the link is up and answering
        on a line that reports positions, no slew, no stop due or owed a repeat (none sent
        since the rotor came to rest and no count of stops left to start again: ``check_stop``
        has nothing to do), nothing owed on the line but its next poll (no reply, no reading
        held, no frame waiting, no junk: the line's wake-ups, ``times``, name the poll alone),
        no enable and no note owed; then until the motion's next deadline (``deadline``, that
        ``wakeups`` just found and kept for ``tick``), silence's timeout (the poll's check) or
        options owed, whichever comes first, ONLY_POLL_MARGIN_S early."""
        m = self.motion
        if not self.answering or self.notes or m.stop_sent_t is not None:
            return -math.inf
        if self.stops.counting:  # check_stop has its count of stops to start again
            return -math.inf
        if self.stops.lock_signed:  # or the lock's stop to write again (stops.py rule 7)
            return -math.inf
        if self.stops.stall_watched and m.state is mo.MOVING:  # or a stall's stop to watch
            return -math.inf
        if link.slew is not None or link.stop_due or link.reply_owed or self.options.enable_due:
            return -math.inf
        if not self.cfg.spec.can_report_position or len(times) != 1:
            return -math.inf
        silent_at = min(self._silent_offline_t(link, now), self._garbled_offline_t(link, now))
        until = min(deadline, silent_at, self.options.owed_from(mo.at_rest(m)))
        return until - ONLY_POLL_MARGIN_S

    def send_options(self, now: float, target_waits: bool) -> None:
        """options.py rule 1: each setting by its declaration's encoder (the codec's)."""
        link = self.link
        if link is None or not self.answering:
            return
        idle = mo.at_rest(self.motion)
        if not self.options.owes(idle, now):
            return  # (the step of nearly every reading: the line not looked at)
        free = link.free()
        line_free = free and link.slew is None and not link.stop_due
        if link.spec.refusal_bytes and not link.quiet:  # link.py rule 4: its refusal, if any,
            line_free = free = False  # within a known time after it
        taken = self.options.take(idle, not target_waits and free, now, line_free=line_free)
        for name, value in taken:
            setting = self.cfg.spec.setting(name)
            try:
                if setting is None:
                    raise ValueError(name)
                frame = setting.encode(setting.read(value))
            except (KeyError, ValueError):
                log.warning("%s: option %r not supported; skipped", self.name, name)
                continue
            if self.options.news(name, value):  # (options.py rule 5: a refresh is no news)
                log.info("%s: setting %s sent (%r)", self.name, name, frame)
            else:
                log.debug("%s: setting %s sent again (%r)", self.name, name, frame)
            link.write_setting(frame, now)
            self.target_last = False  # a refusal now may be the setting's
        if taken:
            self._retune()

    def _retune(self) -> None:
        """Rule 7: the speeds the settings in effect give the rotor."""
        factor, base = self.options.speed_factor(), self.base_cfg
        if factor == 1.0:
            self.cfg = base
            self._limits_of(base)
            return
        az, el = base.az_speed_deg_s * factor, base.el_speed_deg_s * factor
        spec, was = base.spec, base.motion
        step = spec.reading_step_deg
        slowest = (min(az, el) if spec.turns_azimuth else el) if spec.has_elevation else az
        motion = replace(
            was,
            nominal_speed_deg_s=was.nominal_speed_deg_s * factor,
            el_speed_deg_s=el,
            settle_s=mo.settle_for(  # motion.py rule 2: slower, longer (never below the base's)
                was.settle_s, was.noise_deg, step, slowest, base.moving_poll_interval_s
            ),
        )
        self.cfg = replace(base, motion=motion, az_speed_deg_s=az, el_speed_deg_s=el)
        self._limits_of(self.cfg)

    def _limits_of(self, cfg: WorkerConfig) -> None:
        """Rule 2's least silences, of the configuration in effect (``cfg``, set with it): read at
        every poll and every step's wake-up, they change only with it."""
        self._least_s = _turn_least_s(cfg.motion)
        self._least_silence_s = min(cfg.silence_timeout_s, self._least_s)

    def send(self, todo: Sending, target: Target, attempt: int, now: float) -> None:
        """Write ``target`` as ``todo`` says (targets.py), try ``attempt``."""
        link, m, cfg = self.link, self.motion, self.cfg
        assert link is not None
        link.send(link.codec.encode_target(todo.az_deg, todo.el_deg), now)
        self.target_last = True
        az, el = todo.wire
        sent_az = self._sent_az  # (rule 11: the target written before this one)
        self._sent_az, self._guarded = az, self.cfg.unasked_moves == "after-stop"  # rule 10
        self._connect_guard = False  # (rule 10: a turn now is asked for)
        self._lost_aim = None  # (rule 13: a new turn, the bridge's own)
        self._retry = None  # rule 11: one try more, where the controller takes one at any time
        if attempt == 1 and cfg.motion.direct_retarget and cfg.spec.reports_while_moving:
            self._retry, self._retry_t = target, now
            self._retry_raw = todo.az_deg, todo.el_deg
            self._retry_from = _to_turn(m, cfg, az, el)
            self._retry_before = _turning_to(m, cfg.motion, sent_az)
        if not cfg.spec.reports_while_moving:
            slew = Slew(
                now,
                m.position_deg,
                m.el_position_deg,
                az,
                el,
                target.source,
                0,
                attempt,
                target.origin,  # (slew.py rule 4: put back as its sender's, who may add an axis)
                target,  # (slew.py rule 4: what is put back stands for it)
            )
            link.begin_slew(slew, travel_s(cfg, slew))
        self.motion = mo.commanded(m, cfg.motion, az, now, el)
        self.stops.target_sent()  # (stops.py rule 3: a stop owed now would stop this move)
        link.poll_by(now + cfg.moving_poll_interval_s)

    def poll(self, now: float, busy: bool) -> None:
        """Rules 2 and 3 (``busy``: a target waits)."""
        link, cfg = self.link, self.cfg
        if link is None or not cfg.spec.can_report_position:
            return
        timeout_s = cfg.silence_timeout_s
        unread_s = link.unread_for(now)
        silent = by_silence = False
        # (the cheap look first, at every step of every rotor; then no silence in time
        # nothing was asked in: rule 2)
        if unread_s >= self._least_silence_s and link.asked_since_heard:
            silent_at = self._silent_offline_t(link, now)
            garbled_at = self._garbled_offline_t(link, now)  # (garbage only)
            by_silence, unread = now >= silent_at, now >= garbled_at
            silent = not link.reply_owed and (  # (a slew's report takes the whole slew: a
                by_silence or unread  # reply owed may still come)
            )
            # rule 2: the questions must reach the silence's end, or one asked now decides
            # (not once a stall could be called: that offline cannot wait)
            heard_t = now - link.silent_for(now) if by_silence else now - unread_s
            asked_s = (silent_at if by_silence else garbled_at) - heard_t - ASKED_MARGIN_S
            if silent and link.asked_for_s < asked_s and now < self._stall_check_t(link):
                link.ask_verdict(now)
                silent = by_silence = False
        # (never answered: no valid reply for one timeout, as ever)
        never = (
            link.last_reply_t is None
            and not link.reply_owed
            and unread_s >= timeout_s
            and link.asked_since_heard
        )
        if silent and self.answering:
            # (link.py rule 11: answers torn past any form are silence's time, told garbled)
            torn = by_silence and link.torn_since_heard
            if by_silence and not torn:
                quiet_s = round(min(unread_s, timeout_s), 1)  # (less, mid-turn)
                why = (
                    f"controller on {cfg.shown_port} stopped answering (no valid reply for "
                    f"{quiet_s:g} s)"
                )
            else:  # rule 2: garbled answers only (its limit: before a stop moves the stall's)
                offline_t = now if torn else self._garbled_offline_t(link, now)
                quiet_s = min(offline_t - (now - unread_s), unread_s)
                why = (
                    f"controller on {cfg.shown_port} answers only garbled replies (no valid "
                    f"reply for {quiet_s:.3g} s)"
                )
            m = self.motion
            turning = self.turning() or self._lost_aim is not None  # (rule 13's, followed)
            if turning:  # rule 2: a turn no reading watches any more is stopped, in case it
                self.stop(now)  # still hears (its stall and limits unseen); owed just below
            elif self.stops.repeat_at(m) is not None:  # stops.py rule 1: owed, it goes now
                self.stops.repeat_due(m, math.inf)  # (a silent controller may still hear: its
                again = self._let_go(self.stops.unseen_t)  # motion is lost with the readings
                self.stop(now, unwatched=again)  # just below; nobody's repeat is let go too)
            self.answering = busy = self._first_unread = False  # (the waiting target is dropped)
            unseen = self.stops.unseen_t
            if unseen is not None:  # stops.py rule 3: a stop no reading showed taking is owed
                self.stops.owed = True  # when it answers again, as released if it was the
                self._released_owed = self._let_go(unseen)  # released lock's (or rule 9's)
            stopped = turning and self.motion.stop_sent_t is not None
            if turning and not stopped:  # (rule 2: its stop waits for the line: a turn not
                why += " while the rotor turned to its target (it may still be turning)"  # seen
            elif stopped:  # to its end, not a stall)
                why += " while the rotor turned to its target"
            told_garbled = not by_silence or torn
            why += ": a noisy line?" if told_garbled else ""
            why += self._late_words(link, now - unread_s)
            self._lose_motion(mo.link_down)
            said = None
            if stopped:
                said = "a stop sent, in case it still hears, and again when it answers"
            elif unseen is not None:  # (said: the stop may cut short a move that was heard)
                said = "the last stop, no reading showed taking, goes again when it answers"
            if said is not None:
                why += f" {said[0].upper()}{said[1:]}" if told_garbled else f"; {said}"
            # the drop before tracking's end: a target of tracking's own is reported dropped
            # too (Ends would drop it silently first)
            self.notes += [Report(ErrorKind.SERIAL, why), Drop("controller not answering")]
            self.notes.append(Ends("controller not answering"))
        elif never and not self._silence_reported:
            self._silence_reported = True
            why = f"controller on {cfg.shown_port} does not answer"
            if (
                link.silent_for(now) < timeout_s or link.torn_since_heard
            ):  # rule 2: garbled, or torn
                why = (
                    f"controller on {cfg.shown_port} answers only garbled replies: the wrong baud "
                    "rate or model, or a noisy line?"
                )
            if self._lost_aim is not None:  # rule 13: the turn the port dropped, which no
                self.stop(now)  # reading watches (rule 2), stopped in case it still hears
                why += (
                    ": the turn dropped with the port, not seen since, a stop sent, in case it "
                    "still hears"
                )
            why += self._late_words(link, now - unread_s)
            self.notes.append(Report(ErrorKind.SERIAL, why))
        m = self.motion  # (motion.py rule 4: a restart's found turn judged at the moving rate;
        # rule 9: a connection's first readings that go on disagreeing too: it may be turning)
        busy = busy or m.state is mo.MOVING or now < self._watch_until or mo.found_unjudged(m)
        garbled = self._first_garbled and self._first_phase()  # (answers garbled past reading)
        doubted = self._doubted
        # rule 9: readings at rest that go on disagreeing, at the moving rate until the first
        # unwatched stop (review 103's follow-up: a Rot2Prog's eight at its idle rate took 74 s;
        # not for good, the load review 105 found), while it answers (review 40: offline, idle)
        at_rest = doubted.reply is not None and not (doubted.first or doubted.turning)
        at_rest = at_rest and self.answering and not doubted.at_once
        count = self._first_unconfirmed  # (review 116: answers torn at rest too, from the
        torn = self._first_garbled and count >= DOUBTS_TOLD and self._rest_phase()  # third on:
        unwatched = at_rest or torn  # one or two garbled are asked again as ever, link.py 11)
        at_rest = unwatched and count < FIRST_UNWATCHED_READINGS
        if garbled or at_rest or (doubted.first and not doubted.at_once):  # (review 103: the
            busy = True  # poll after the DOUBTS_TOLD-th was set on the idle grid when asked)
            link.poll_every(now, cfg.moving_poll_interval_s)
        ask_t = self._unwatched_ask_t  # rule 9: the reading that the next at rest is due
        if ask_t is not None and unwatched:  # with, asked then (review 116: not an idle poll
            link.poll_by(ask_t)  # on), once (a reply lost: the usual polls)
        if link.poll(now, cfg.moving_poll_interval_s if busy else cfg.idle_poll_interval_s):
            self.target_last = False  # a refusal now may be the query's (motion.py rule 8)
            if ask_t is not None and now >= ask_t:
                self._unwatched_ask_t = None

    def _late_words(self, link: Link, heard_t: float) -> str:
        """Rule 2: what an offline's error adds where the controller answered since ``heard_t``,
        but later than the bridge waits (link.py rule 12)."""
        after_s = link.late_since(heard_t)
        if after_s is None:
            return ""
        reply_s, most_s = link.reply_timeout_s, 2 * link.reply_timeout_s
        return (
            f"; it answers, late: {after_s:.2g} s after a poll, and the bridge waits "
            f"{reply_s:.2g} s for the {self.cfg.spec.display_name} (up to {most_s:.2g} s for one "
            "that answers late every time): a slow USB adapter or a serial server on the "
            "network?"
        )

    def _silent_offline_t(self, link: Link, now: float) -> float:
        """Rule 2: when a controller that gives nothing at all is offline: ``silence_timeout_s``
        after its last byte, or sooner while a target is out (``_turn_offline_t``)."""
        heard_t = now - link.silent_for(now)
        until = heard_t + self.cfg.silence_timeout_s
        return min(until, self._turn_offline_t(link, heard_t))

    def _garbled_offline_t(self, link: Link, now: float) -> float:
        """Rule 2: when garbled answers alone no longer keep the controller online: at most
        GARBLED_SILENCE_FACTOR timeouts after the last valid reply, and, while a target is out,
        at the motion machine's stall check (``_stall_check_t``), but not sooner than one timeout
        after that reply; or sooner while a target is out (``_turn_offline_t``)."""
        timeout_s = self.cfg.silence_timeout_s
        valid_t = now - link.unread_for(now)
        until = valid_t + GARBLED_SILENCE_FACTOR * timeout_s
        until = max(valid_t + timeout_s, min(until, self._stall_check_t(link)))
        return min(until, self._turn_offline_t(link, valid_t))

    def _turn_offline_t(self, link: Link, heard_t: float) -> float:
        """Rule 2: while a target is out, when a line that gives no valid reply since
        ``heard_t`` is offline however long ``silence_timeout_s`` is: at the motion machine's
        stall check (``_stall_check_t``), but never sooner than ``_turn_least_s`` after
        ``heard_t`` (lost replies on a noisy line are ridden out: an attack pass, at half a 3 s
        stall timeout two lost GS-232 replies went offline); inf with no target out."""
        return max(self._stall_check_t(link), heard_t + self._least_s)

    def _stall_check_t(self, link: Link) -> float:
        """Rule 2: the last check before the motion machine could call the turn under way
        stalled: ``stall_timeout_s`` from the last movement it saw of the axis judged first
        (motion.py rule 3, ``stall_from``: each axis off its target on its own), less a moving
        poll and a reply time, how late the check may come; inf with none, or with the rotor
        at its target (motion.py rule 3: no stall then)."""
        cfg = self.cfg
        progress_t = mo.stall_from(self.motion, cfg.motion)  # (None at it: no stall)
        if progress_t is None:
            return math.inf
        late_s = cfg.moving_poll_interval_s + link.reply_wait_s
        return progress_t + cfg.motion.stall_timeout_s - late_s

    def _junk(self, data: bytes, harmless: bool, now: float) -> None:
        """Rule 6."""
        if harmless:  # a banner after a stop, a blank line: nothing a user acts on
            log.debug("%s: ignored %d harmless bytes: %r", self.name, len(data), data[:64])
            return
        log.warning("%s: ignored %d bytes that are no reply: %r", self.name, len(data), data[:64])
        self._tell(f"controller sent {len(data)} bytes that are no valid reply; ignored", now)

    def _say(self, why: str, now: float, *, logged: bool) -> None:
        """Rule 9: ``why`` told as rule 6 tells of junk, and logged (``logged``: every time;
        else only when told: a reading after reading that goes on disagreeing)."""
        told = self._tell(why, now)
        if logged or told:
            log.warning("%s: %s", self.name, why)

    def _tell(self, why: str, now: float) -> bool:
        """Rules 6 and 9: ``why`` on R/error, at most every ``junk_report_interval_s``."""
        if now - self._junk_reported_t < self.cfg.junk_report_interval_s:
            return False
        self._junk_reported_t = now
        self.notes.append(Report(ErrorKind.PROTOCOL, why))
        return True

    def wakeups(self, now: float, latest: float, alone: bool) -> tuple[float, float]:
        """When the line or the motion machine needs the session next, ``latest`` at the
        latest; and until when a step has nothing of the controller's to do but its poll
        (``_only_poll_until``) if ``alone`` (the session's own part of rule 20 holds), -inf if
        not: the end of a whole step asks both, and the line's wake-ups once for both."""
        link = self.link
        times = None
        if link is not None:
            times = link.wakeups()
            for t in times:
                if t < latest:
                    latest = t
            if link.slew is not None:  # refresh the estimate
                latest = min(latest, now + self.cfg.moving_poll_interval_s)
            if now < link.setting_until < latest:  # link.py rule 4: a target may wait for it
                latest = link.setting_until
        m, cfg = self.motion, self.cfg.motion
        repeat = self.stops.repeat_at(m)  # stops.py rule 1: a stop repeat owed (line_work's)
        if repeat is not None and now < repeat < latest and link is not None:
            latest = repeat
        owed = self._unwatched_owed_at()  # rule 9: the unwatched stop held back a second
        if owed is not None and owed < latest:
            latest = max(now, owed)
        blind = self.stops.blind_at  # stops.py rule 6
        if blind is not None and blind < latest and link is not None:
            latest = max(now, blind)
        deadline = mo.next_deadline(m, cfg, now)
        kept = math.inf if deadline is None else deadline
        self._deadline = m, cfg, kept  # (tick's)
        wakeup = latest if deadline is None or deadline >= latest else deadline
        if not alone or link is None or times is None:
            return wakeup, -math.inf
        return wakeup, self._only_poll_until(now, link, times, kept)
