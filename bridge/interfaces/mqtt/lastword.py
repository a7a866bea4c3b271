"""The last word on stop and lock, across the MQTT connections. Pure: the clock is passed in;
the service (service.py rule 5) calls it under one lock, together with the mailbox put it
decides, so a decision and the command it lets through are one step.

Stop and lock come on two connections each: the main one, in order with the targets behind any
flood, and a lane (lane.py), behind no target: the stop lane for stops, the lock lane for lock
words (rule 16). The broker keeps each connection's order, but not the order between them. So
(each rule below that says "the lane" means the lane of the halt's kind):

1. The main connection is the order. Every stop and lock word it brings (ON and OFF) is carried
   out where it stands among the targets: a target before a stop is dropped by that stop, one
   after it is obeyed, and the lock ends on the last word published. Nothing is matched away
   or dropped as a duplicate on that side: a stop carried out twice stops twice (the session
   merges it on the wire), a lock ON twice is still ON.
2. The lane is the speed. A stop or a lock ON it brings is carried out at once, in full (the
   rotor stops, its target and tracking are dropped, the lock is set), and puts the rotator on
   **hold**: no target goes to the controller until the main connection has caught up with
   that word. To know when, the bridge publishes a **marker** of its own on the main connection
   (``B/bridge/fence``, this process's token and a number). The broker had the stop before the
   marker, and the main connection's own copy of the stop or lock comes before the marker
   too. The hold ends when the marker comes back (rule 13: the copy, counted, ends it only
   while no marker can come); then what is still pending goes out. A move the main
   connection reads while the hold lasts and before the copy (``held``) was published before
   the lane's word, or its copy was lost on the way (QoS 0: a broker that drops messages for a
   reader that fell behind, an ACL) and nothing tells whether it was published before the
   word or after: it is refused as older (halts.py), never held. (A review: held, it waited
   for the copy to drop it as rule 1 says; with the copy lost, the marker ended the hold and
   a target published before the STOP turned the rotor after it.) One read after the copy
   waits (rule 13). Nothing is decided by matching payloads, and no clock ends a hold (rule
   5).
3. A lock OFF from the lane is not carried out (it comes in order on the main connection,
   rule 1), except while the main connection is down: then the lane's word is the only one
   (but rule 12; and not while the lane has yet to read its copy of a lock ON the main
   connection carried out, rule 4's note, ``lane_behind``: the OFF was published before it).
4. The main connection may read a halt before the lane does (both are idle and race). The lane's
   copy, carried out late, would stop a target published after it and already on its way. So
   when the main connection carries out a halt the lane had no copy of waiting, the bridge
   publishes a **lane marker** (``B/bridge/fence/lane``, read by the lane only): the broker
   had the halt before it, so the lane's copy, if the lane has one, comes before the lane
   marker; a copy of that kind for that rotator read on the lane before then is the echo and
   is dropped, and the note ends when the lane marker comes back (within the lane's own round
   trip). A note is also forgotten when the lane reconnects (an older copy cannot come on the
   new connection), and none is made while the lane's subscription is not acknowledged, nor
   after, until the main connection has read past the marker its acknowledgement sent (rule
   9, asked the same way: the halt may have been published before the broker took the lane's
   SUBSCRIBE, so no copy comes on the lane, and the note would stand: the lane's next real
   stop of that kind, taken for the echo, then waited for the main connection's copy, behind
   whatever it is reading; two reviews: the main connection, behind a backlog when the lane
   alone reconnected, read a STOP from while the lane was down, and the operator's next STOP
   on the lane was dropped as its echo). A late copy is then carried out (an extra stop, its
   hold ended by its marker: the safe direction). No clock decides it. While the main
   connection cannot read its markers (rule 7) nothing tells when it is past, and the note
   is made as before.
5. A hold ends with clearing when the main connection drops (nothing older can come any more;
   a target or tracking that waited is dropped and reported: its place in line is lost) and
   when it connects again. While the main connection lives, no clock ends a hold: however
   long the main connection takes to read what was published before the word (a backlog of
   targets, a slow machine), the targets wait. A marker still out after RESEND_S (a broker
   that drops messages for a reader that fell behind) is sent again with a new number, the
   wait doubling up to RESEND_MAX_S, for as long as it is out; a later marker ends every hold
   before it. A hold longer than LONG_HOLD_S is reported (halts.py) while it lasts, and holds.
6. A retained stop or lock ON (a dashboard button set to retain by mistake) is carried out when
   it is published, like any, and reported; and once at most when the broker replays it: on a
   subscription, to either connection, at every reconnect. Under MQTT 5 the stop and lock
   topics are subscribed so that the broker replays nothing (retain handling 2) and a retained
   one is always live; under MQTT 3.1.1 a live one arrives without the flag, and one with it
   is a replay, known by its payload (a new payload on the topic is a new message; an empty
   retained message deletes it and is forgotten). A live one under MQTT 3.1.1 may have been
   published retained (the broker clears the flag on the way), so its payload is remembered
   as carried out too (``live_halt``): the broker's replay of it after its restart is not a
   second stop (an attack pass: a rotor turning to a later target was stopped mid-turn by
   the replay of a retained STOP it had obeyed when it was published, NATS and mosquitto
   keeping it across the restart). A replay of the same payload published while the bridge
   was away is then not carried out either, as under MQTT 5, which replays none.
7. Every marker of the main connection goes on two topics, the fence topic
   (``B/bridge/fence``) and the hello topic (``B/bridge/hello``, which the main connection
   reads back for its first look), the same payload (halts.py): whichever copy comes back first
   ends what the marker ends, the other nothing more; a copy read on either topic was published
   after its marker's halt, so it proves as much (rule 10). So an ACL that denies the fence
   topic costs no marker while the hello comes back (an attack pass: with the fence topic
   denied, rotctld's S fenced nothing, and a target published before it and read after it
   turned the rotor; and mosquitto reloads its ACL file on SIGHUP and keeps the connection,
   which no probe sees: after rotctld's S every MQTT target was refused as older for as long as
   the connection lasted, no marker coming back to end the fence). Whether the main connection
   can read its markers is learnt from the broker, never from a marker that is late, on every
   connect (client.py rule 16): the hello back, or the probe published on the fence topic right
   before it, says yes (``markers_allowed``); the fence topic denied (its SUBACK, MQTT 5's PUBACK
   of the probe, the hello back before the probe) and this connection's hello not back within
   the first look's time, no (``markers_denied``), until that hello comes back after all.
   Then no marker is sent, and a lane's halt holds until the main connection reads its own
   copy (rule 9), or drops: holding is the safe direction. (No marker can then tell when a
   new lane connection is in step, rule 9: its halts are taken as in step; a halt published
   while the lane was down could then stand for a newer one.)
8. A lock OFF the main connection reads while a lane lock ON for that rotator still waits for
   its main copy was published before that ON: it is not carried out (the ON is the last word,
   even if the main connection then drops before its copy comes), and R/error says so
   (halts.py: it may have been published after the ON, when rule 9 could not count the copy).
9. The main connection's copy of a lane halt is the oldest one the lane read of that rotator and
   kind still waiting (the broker keeps one order for both connections; at QoS 0 either may
   have lost a halt, so the count may be off: rule 13 says what it may decide), once the lane's
   connection is known to be in step: a halt published while the lane was not subscribed
   comes on the main connection only, and must not be taken for the copy of a newer one. So
   when the lane's subscription is acknowledged, a marker goes out on the main connection
   (``lane_subscribed``); until one at least as new comes back (or the main connection is new,
   subscribed after the lane; or the lane's own marker behind its SUBSCRIBE is back, rule
   17), a halt the main connection reads does not count as the copy of
   the lane's halts read on that connection: carried out all the same (rule 1), noting and
   ending nothing. A copy lets the moves of every hold up to its lane halt's number wait
   instead of being refused (rule 13).
10. A marker is this process's token, its number and its seal: a keyed hash of the number
   and of its kind (the main connection's or the lane's: counted apart, so a copy moved to
   the other topic could otherwise pass), whose key never leaves the process. A marker is
   published, so whoever reads the base topic learns the token and the numbers; one who may
   also publish on the fence topics could otherwise end every hold with a number of their own
   (targets published before a STOP then went out after it). A forged marker, or one torn or
   too long, is no marker; a copy of a real one republished on its own topic can come only
   after the real one, which ended the same holds already.
11. A stop or lock ON another interface carried out (the console, rotctld, GS-232, Easycomm,
   DCU-1, the loggers) comes on neither connection, so nothing above orders it against what
   the main connection has not read yet: a target, or a lock OFF, published before it and
   read after it was carried out (a backlog, a slow machine) turned the rotor again, or
   unlocked it (an attack pass: the console's lock ON, then an older MQTT lock OFF read
   late, left the rotator unlocked under a page that had said ON). So such a halt puts a
   **fence** on its rotator (``fence``) and a marker goes out on the main connection: until
   one at least as new comes back, the main connection's moves for that rotator, and its lock
   OFF after a lock ON, were published before the marker and are refused as stale
   (``fenced``); what it reads after the marker is taken. Like a hold, no clock ends a
   fence; the connection dropping does (rule 5: nothing older comes on the next one); one
   longer than LONG_HOLD_S is reported as a long hold is (its MQTT moves are refused). While
   the main connection cannot read its markers (rule 7) no fence is put: none could end. At
   most FENCE_MARKERS_OUT fence markers are out at once (an attack pass: a flood of stops on
   a logger port sent one each, 20,000 in 8 s, and every rotator's targets waited behind them
   on the main connection, seconds after the flood): a halt beyond them is fenced at once and
   its marker owed (``owed_fence``: one for every fence that waited, once one is back or a
   resend stood for them; a marker out then was published before the halt, so it ends no
   fence of it; the timer looks again while one is owed). A
   fence ends by a marker alone, never by the main copy of a lane halt (rule 9): the lane
   numbers a halt when it reads it, and one published before another interface's halt may
   be read after it (an attack pass: an MQTT STOP, a target, then rotctld's S; the lane read
   the MQTT STOP late, its copy ended the S's fence, and the target turned the rotor).
12. A fence orders the main connection alone; while the main connection is down the lane
   carries out lock OFFs (rule 3), and nothing orders one against another interface's lock
   ON: a lock ON carried out while the main connection was down (no fence: nothing reads a
   marker), or whose fence was still up when it dropped, may come after a lock OFF
   published before it and read by the lane after it (an attack pass: the console's lock ON,
   then an automation's older OFF read by the lane, unlocked the rotator under a page that
   said ON). Such a rotator's lane lock OFF is refused and said (``lane_lock_off_unordered``;
   so is one read while another interface's halt is under way, and it goes to the judge with
   the halt count read before that look, as the main connection's does), the lock staying
   ON, until a new main connection (whose fences order it again, and whose drop starts the
   count anew); a lock OFF from the console is carried out as ever.
13. The count decides what waits, never what goes (cold review 22). The lane may lose a halt
   (QoS 0) that the main connection reads: then the main connection's older halt is counted
   as the copy of the lane's newer one (or a group's stop, which a lane user may not read, as
   a member's). Had the copy ended the hold, a target or lock OFF published between the two
   would have gone out after the newer STOP or lock ON. So a copy, counted, ends no hold while
   markers can come: a move read before it is refused (``held``), a move read after it
   (``waits``) is put under the hold (a target in the mailbox, which the session holds) and
   goes out when the marker comes back. The broker had the lane's halt before the marker, so
   the halt's real copy, when the count was off, is read before it and drops what waits, as
   any stop or lock ON drops what was put before it. A lock OFF read under a hold with a lane
   lock ON among its halts (``off_waits``; under a STOP's alone it goes at once) is kept by
   halts.py, one per rotator, the lock staying ON meanwhile, and so is the newest move read
   after it (a group's target's part for that member too, in the same slot: cold review 29;
   one: a flood behind the OFF keeps nothing more, and the marker puts two commands, not
   thousands, under the lock a lane halt needs: an attack pass); at the marker
   the OFF goes, then that move, each judged against the halts put since the marker's look
   (a STOP read after the OFF drops the move, never the OFF: an attack pass). A lock ON
   carried out after the OFF was read, from anywhere, drops both, said on R/error (one read
   on the main connection is the later word; the lane's may be). A copy read while a hold
   is up sends a fresh marker at once, the back-off started anew (``Copy.marker``): a STOP
   then a target back to back end at the target within a broker round trip, and a hold after
   a flood lasts no longer than the main connection takes to read it (review 23: a marker
   lost in the flood, its resend 30 s away). What is left: a real copy lost on the main
   connection too (two losses) lets what waited go at the marker; while the markers cannot
   be read (rule 7) the count copy ends the hold as before, the gap open. A stamped move
   (service.py rule 9) that waits goes only while its expiry lasts: the session drops it
   past it (session.py rule 13; review 25: with every marker lost it went at a resend's
   return, long after it).
14. While neither connection can read its markers (rule 7, and rule 4's ``echoes`` off), the
   lane carries out nothing (halts.py ``_lane_blind``): its halt could not be told from the
   echo of one the main connection carried out first, and its hold would wait for a copy
   already read, for as long as the main connection lives (review 22 F3: every target after
   a STOP refused, for hours). The main connection carries out every halt in order (rule 1):
   stops lose the lane's speed, nothing else. A lane halt carried out before both were known
   denied holds as rule 7 says.
15. A marker sent again (rule 5) goes at QoS 1 (halts.py ``publish_confirmed``): an ACL that
   denies both marker topics, reloaded under a live connection (mosquitto's SIGHUP keeps the
   connections, and no probe sees it), is then told by the broker itself, under MQTT 5, in
   the PUBACK: 0x87, "not authorized", and no other code (delivery.py rule 11; an attack
   pass: a quota's 0x97 on the two resent markers was taken for the ACL, which reopened rule
   13's gap for the connection's life); both topics refused, the markers are known denied
   (rule 7), and a hold whose copy was counted ends (``markers_denied``). So known denied,
   on a live connection or by a new connection's look (its probe and its hello refused so:
   client.py rule 16), they are asked again every RESEND_MAX_S for as long as the connection
   lasts (a marker at QoS 1, ``probe``: logged once while they are refused, and not as a
   marker late, none being out: review 35), and one of those read back on the main connection
   turns them on again (``asked_back``). Refused on a live connection that read them before,
   a PUBACK that takes one turns them on too (review 31). Not so when a look said them lost:
   its hello never came back, so reading them was denied as well, and a publish taken says
   nothing of reading (review 35: an ACL mended to let the bridge publish its markers but not
   read them turned them on, and every lane STOP's hold then waited, for the connection's
   life, for a marker that could not come): while the broker takes them and none comes back,
   they stay off, said on ``B/bridge/info``. The clock only sends again; the broker's answer
   decides.
   Under MQTT 3.1.1 no answer says it, nor under MQTT 5 when the ACL denies reading the
   marker topics only (the broker takes the PUBACK and the SUBSCRIBE, and delivers nothing:
   review 25): such a hold lasts until the main connection drops, said on ``B/bridge/info``
   while it lasts (holding is the safe way), and what waits under it waits that long. Asking
   again by subscribing to the marker topics again answers nothing either: mosquitto 2.0
   never checks its ACL file on SUBSCRIBE, and grants it (QoS 1, under MQTT 5 and 3.1.1, on
   the live connection as on a new one) whatever the file says of reading (measured:
   tests/integration/test_review25_read_denied_markers.py, which keeps review 25's R25-1
   open, as tests/mqtt/test_review25_markers_unread.py does).
16. Each kind of halt has a lane of its own, and a lane carries nothing else that a
   neighbour can flood: the stop lane ``R/stop`` and ``G/stop``, the lock lane ``R/lock`` (and
   both the lane markers, ``B/bridge/fence/lane``, which only the bridge publishes). One
   connection delivers in order, and no reader is faster than every flood: with the lock
   words on the stop lane (attack 24), a client republishing ``R/lock OFF`` in a loop kept an
   operator's STOP behind the whole flood, 2.2 s at 10,000 a second, 9.9 s at 20,000, past the
   turn on a DCU-1; no judgement per message can help when the flood comes faster than it is
   read. So the rules above keep their per-lane books by kind: a lane's subscription in step
   (rule 9, ``_lane_sub``), its echo notes (rule 4: a lane marker read on a lane ends the notes
   of its own kind only; it proves that lane read every copy published before it, and nothing
   of the other lane's), its markers readable (rule 4's ``echoes``, ``lane_deaf``), a new
   connection (``lane_connected``). The holds and the copies were kept by kind already (rule 9:
   ``_lane_waiting``). A stop's hold and a lock ON's hold order the targets against the main
   connection as before, each by its marker; nothing orders a stop against a lock word between
   the two lanes, and nothing needs to: both only halt, and the lock OFF comes in order on the
   main connection (rule 3; while the main connection is down the lock lane's OFF is the only
   word, as the one lane's was). Called without a kind, the lane's methods act on both lanes,
   as the one lane that carried both did. What is left: a flood on a lane's own topic delays
   the words behind it on that lane, and costs what every stop or word costs. A flood of
   ``R/lock`` delays a lock ON behind it (30,000 OFFs: the lock ON about 2 s after it was
   published). A flood of ``R/stop`` junk is a flood of stops: its first message stops the
   rotor where it is, and every target is held or refused while it lasts; an operator's STOP
   behind it waits its turn, or is lost: measured as fast as one client can (a DCU-1), the
   stop lane read about 3,900 of them a second, mosquitto dropped messages for it ("Outgoing
   messages are being dropped"), and the operator's STOP was never read (not within 120 s
   after the flood ended), the rotor resting all along where the flood's first stop left it.
   The stop express's connection reads ``R/stop`` and ``R/lock`` both (express.py rule 2):
   behind a flood of lock OFFs its frame for a STOP went 6 ms to 0.7 s after it (Rotor-EZ),
   while the stop lane's went in 2 to 13 ms: speed, not a stop, is lost there.
17. Rule 9's marker goes out on the main connection once the lane's SUBACK is in, behind
   whatever the main connection is sending; a halt published after the broker took the lane's
   SUBSCRIBE and read before that marker is back counted for nothing, so a move read after it
   was refused (``held``) as published before the lane's copy of that very halt, and a lock
   ON read there first made no echo note, so the lane's copy, read after the OFF that
   followed, locked the rotator again, unsaid (attack 32: the lane back alone and the
   operator's STOP, or lock ON, right after its SUBACK, with the main connection's uplink
   busy). So each lane connection also publishes a marker of the main connection's kind
   itself (``lane_subscribing``, numbered as every marker, on the fence topic and the hello
   topic, rule 7), queued right behind its SUBSCRIBE on that connection: the broker takes a
   connection's packets in order, so it took the SUBSCRIBE before that marker, and a halt
   the main connection reads after it was published after the subscription, so it reaches
   the lane too. The main connection reading that very marker (its number, not one as high:
   a marker numbered after it may have been published on the main connection before the
   SUBSCRIBE reached the broker) puts that lane's connection in step as rule 9's marker
   does (``_in_step``), for its copies and its echo notes (rule 4), whichever of the two
   comes back first; it ends the holds and fences up to its number as any marker does (it
   was published after they were put). Nothing is timed: a marker lost, or one the broker
   does not let the lane publish, leaves rule 9's marker to do it, as before. What is left:
   a halt the broker takes between the lane's SUBSCRIBE and that marker (two packets of one
   connection, back to back) is read before the marker, and a move after it is refused as
   before (the safe direction: sent again, it goes). The rule leans on the broker taking a
   connection's SUBSCRIBE before the PUBLISH behind it (mosquitto does, one packet after the
   other); a broker that routed that marker before the subscription took effect would make a
   halt published in between count as the lane's (rule 13's count off: a move after it waits,
   and the lane's real copy drops it; an echo note made for it lasts until its lane marker
   is back, a lane round trip, and a lane halt read meanwhile waits for the main connection).
"""

from __future__ import annotations

import hashlib
import hmac
import secrets
import sys
from collections import deque
from dataclasses import dataclass, field

RESEND_S = 2.0  # rule 5: the first wait for a marker, doubled for each resend ...
RESEND_MAX_S = 30.0  # ... up to this; a marker is sent again for as long as it is out
LONG_HOLD_S = 5.0  # rule 5: a hold longer than this is reported while it lasts
NOT_YET = sys.maxsize  # rule 9: a lane connected, not yet subscribed: nothing of it in step
NUMBER_DIGITS = 18  # rule 10: a marker's number has at most this many (int() refuses 4,300)
FENCE_MARKERS_OUT = 4  # rule 11: fence markers out at once; a halt beyond them waits for room
OWED = sys.maxsize  # rule 11: a fence whose marker waits for room (no marker number reaches it)
LANES = ("stop", "lock")  # rule 16: the lanes, each named by the one kind of halt it carries


@dataclass(frozen=True)
class Copy:
    """What a halt read on the main connection means (rules 1, 4 and 9)."""

    echo: bool = False  # the copy of a halt the lane carried out first
    lane_marker: int | None = None  # rule 4: the lane marker to publish
    upto: int = 0  # rule 9: the holds up to this marker end ...
    released: tuple[str, ...] = ()  # ... these rotators' (only while no marker can come)
    marker: int | None = None  # rule 13: a fresh marker to publish (the holds wait for it)


@dataclass
class LastWord:
    token: str = field(default_factory=lambda: secrets.token_hex(4))
    _key: bytes = field(default_factory=lambda: secrets.token_bytes(16), repr=False)  # rule 10
    _next: int = 0
    _holds: dict[str, int] = field(default_factory=dict)  # rotator -> marker it waits for
    # rule 13: the held rotators whose hold's own lane halt has had its main copy counted: their
    # moves wait under the hold (for its marker) instead of being refused
    _copied: set[str] = field(default_factory=set)
    # rule 13: the held rotators whose hold has a lane lock ON among its halts: a lock OFF the
    # main connection reads under it waits for the marker (under a STOP's alone, it goes)
    _hold_locks: set[str] = field(default_factory=set)
    _held_since: dict[str, float] = field(default_factory=dict)  # rule 5: for the report
    _marker_sent_at: dict[int, float] = field(
        default_factory=dict
    )  # markers still out, by number (so by age)
    _resend_s: float = RESEND_S
    # rule 9: (rotator, kind) -> (number, the marker the main connection must have passed for
    # the main copy to count), oldest first
    # (rule 17: and the marker its lane's connection published behind its SUBSCRIBE, 0: none)
    _lane_waiting: dict[tuple[str, str], deque[tuple[int, int, int]]] = field(default_factory=dict)
    # rule 9: kind ("stop", "lock": rule 16, each its own lane) -> the marker sent when that
    # lane's subscription was acknowledged
    _lane_sub: dict[str, int] = field(default_factory=lambda: dict.fromkeys(LANES, 0))
    # rule 17: kind -> the marker the lane's present connection published right behind its
    # SUBSCRIBE (0: none yet on this connection), the newest one it published (any
    # connection), and the newest of them the main connection read back
    _lane_q: dict[str, int] = field(default_factory=lambda: dict.fromkeys(LANES, 0))
    _q_sent: dict[str, int] = field(default_factory=lambda: dict.fromkeys(LANES, 0))
    _q_past: dict[str, int] = field(default_factory=lambda: dict.fromkeys(LANES, 0))
    _main_past: int = 0  # rule 9: the newest marker the main connection has read past
    _echoes: dict[tuple[str, str], deque[int]] = field(default_factory=dict)  # rule 4
    _lane_next: int = 0
    # rule 4: the lanes (by kind, rule 16) that cannot read their markers (nothing noted there)
    _deaf: set[str] = field(default_factory=set)
    markers: bool = True  # False: the main connection cannot read its markers (rule 7)
    _retained: dict[str, bytes] = field(default_factory=dict)  # rule 6
    # rule 11: rotator -> (the marker its fence waits for, whether a lock ON is among its halts)
    _fences: dict[str, tuple[int, bool]] = field(default_factory=dict)
    _fenced_since: dict[str, float] = field(default_factory=dict)  # rule 11: for the report
    _fence_out: list[int] = field(default_factory=list)  # rule 11: the fence markers out
    # rule 12: the rotators another interface locked with no fence on the main connection
    _unfenced_locks: set[str] = field(default_factory=set)
    _denied_past: int = 0  # rule 15: the newest number when the markers were said denied

    # -- the lane (rule 2) -------------------------------------------------------------------
    def lane_halt(self, rotator_id: str, kind: str, now: float, hold: bool = True) -> int | None:
        """A stop or lock ON read on the lane: the number of the hold it puts the rotator on
        (0: carry it out without a hold, while the main connection is down), or None when it
        is the echo of one the main connection carried out (rule 4). Publish its marker while
        ``markers`` (rule 7)."""
        key = (rotator_id, kind)
        echoes = self._echoes.get(key)
        if echoes:
            echoes.popleft()
            return None
        if not hold:
            return 0
        self._next += 1
        n = self._next
        self._holds[rotator_id] = n
        self._copied.discard(rotator_id)  # rule 13: a new halt, its copy not read yet
        if kind == "lock":
            self._hold_locks.add(rotator_id)
        self._held_since.setdefault(rotator_id, now)
        if self.markers:
            self._marker_sent_at[n] = now
        entry = (n, self._lane_sub[kind], self._lane_q[kind])
        self._lane_waiting.setdefault(key, deque()).append(entry)
        return n

    def marker(self, n: int, lane: bool = False) -> str:
        """The payload of marker ``n`` (``lane``: a lane marker, rule 4): sealed (rule 10)."""
        return f"{self.token} {n} {self._seal(n, lane)}"

    def _seal(self, n: int, lane: bool) -> str:
        """Rule 10: the number and its kind (a lane marker's numbers are counted apart from
        the main connection's, so one copied to the other's topic must not pass as its)."""
        what = f"{'lane' if lane else 'main'} {n}".encode()
        return hmac.new(self._key, what, hashlib.sha256).hexdigest()[:16]

    @property
    def echoes(self) -> bool:
        """Rule 4: whether every lane can read its markers (set: all of them can, or none)."""
        return not self._deaf

    @echoes.setter
    def echoes(self, can: bool) -> None:
        self._deaf = set() if can else set(LANES)

    def lane_echoes(self, lane: str) -> bool:
        """Rule 4: whether the lane of this kind (rule 16) can read its markers."""
        return lane not in self._deaf

    def lane_deaf(self, lane: str) -> None:
        """Rule 4: the lane of this kind (rule 16) cannot read its markers: no echo noted."""
        self._deaf.add(lane)

    def lane_connected(self, lanes: tuple[str, ...] = LANES) -> None:
        """Rule 4: no copy of an older halt comes on the new connection; rule 9: nothing it
        reads is in step until its subscription is. ``lanes``: the kinds that connection
        carries (rule 16; both: the two lanes alike)."""
        for key in [key for key in self._echoes if key[1] in lanes]:
            del self._echoes[key]
        for lane in lanes:
            self._lane_sub[lane] = NOT_YET
            self._lane_q[lane] = 0

    def lane_subscribing(self, lanes: tuple[str, ...] = LANES) -> int | None:
        """Rule 17: the lane's SUBSCRIBE is queued on its new connection: the number of the
        marker that connection publishes right behind it (None while the main connection
        cannot read markers, rule 7: nothing would read it)."""
        if not self.markers:
            return None
        self._next += 1
        for lane in lanes:
            self._lane_q[lane] = self._q_sent[lane] = self._next
        return self._next

    def _in_step(self, kind: str, after: int, q: int) -> bool:
        """Rules 9 and 17: whether a halt the main connection reads now was published after
        the broker took the SUBSCRIBE of the lane connection that ``after`` (the marker its
        SUBACK sent) and ``q`` (the one it published behind its SUBSCRIBE) belong to."""
        return not self.markers or after <= self._main_past or 0 < q <= self._q_past[kind]

    def lane_subscribed(self, now: float, lanes: tuple[str, ...] = LANES) -> int | None:
        """Rule 9: the lane's subscription is acknowledged: the marker to publish on the main
        connection (None while the main connection cannot read markers, rule 7)."""
        self._next += 1
        for lane in lanes:
            self._lane_sub[lane] = self._next
        if not self.markers:
            return None
        self._marker_sent_at[self._next] = now
        return self._next

    def lane_marker_back(self, payload: bytes, lanes: tuple[str, ...] = LANES) -> None:
        """Rule 4: the lane has read every copy it will get of the halts noted up to it (a
        lane reads every lane marker, rule 16: it ends the notes of its own kind only)."""
        n = self._number(payload, lane=True)
        for key, echoes in self._echoes.items():
            while key[1] in lanes and echoes and echoes[0] <= n:
                echoes.popleft()

    # -- another interface's halt (rule 11) ----------------------------------------------------
    def fence(self, rotator_id: str, lock: bool, now: float) -> int | None:
        """Rule 11: a stop (``lock``: a lock ON) another interface carried out: the number of
        the marker to publish, the fence ending when one at least as new comes back; None
        while the main connection cannot read its markers (rule 7), and while
        FENCE_MARKERS_OUT are out (the fence then waits for ``owed_fence``)."""
        if not self.markers:
            return None
        old = self._fences.get(rotator_id)
        locks = lock or (old is not None and old[1])
        self._fenced_since.setdefault(rotator_id, now)
        if not self._fence_room():  # (no marker out now was published after this halt)
            self._fences[rotator_id] = (OWED, locks)
            return None
        n = self._fence_marker(now)
        self._fences[rotator_id] = (n, locks)
        return n

    def owed_fence(self, now: float) -> int | None:
        """Rule 11: the marker to publish for the fences that waited for room, once a fence
        marker is back (or void); None if none waits or there is no room yet."""
        owed = [rid for rid, (m, _) in self._fences.items() if m == OWED]
        if not owed or not self.markers or not self._fence_room():
            return None
        n = self._fence_marker(now)
        for rid in owed:
            self._fences[rid] = (n, self._fences[rid][1])
        return n

    def _fence_room(self) -> bool:
        """Rule 11: fewer than FENCE_MARKERS_OUT fence markers out (one that came back, or
        that a later one stands for, rule 5, is out no more)."""
        self._fence_out = [m for m in self._fence_out if m in self._marker_sent_at]
        return len(self._fence_out) < FENCE_MARKERS_OUT

    def _fence_marker(self, now: float) -> int:
        self._next += 1
        n = self._next
        self._marker_sent_at[n] = now
        self._fence_out.append(n)
        return n

    def unfenced_lock(self, rotator_id: str) -> None:
        """Rule 12: another interface's lock ON no fence orders (the main connection down)."""
        self._unfenced_locks.add(rotator_id)

    def lane_behind(self, rotator_id: str, kind: str) -> bool:
        """Rule 3: whether the lane has yet to read its copy of a halt of this ``kind`` the main
        connection carried out (rule 4's note): what it reads before that copy was published
        before that halt, so a lock OFF it reads now is older than the main connection's lock
        ON (an attack pass: the lane behind a flood of stops, the main connection carried OFF
        then ON and dropped; the lane's OFF, read then as the only word, unlocked the rotator
        under a climber, and its ON was dropped as the echo)."""
        return bool(self._echoes.get((rotator_id, kind)))

    def lane_lock_off_unordered(self, rotator_id: str) -> bool:
        """Rule 12: whether a lock OFF the lane would carry out (rule 3) may be older than
        another interface's lock ON that nothing orders it against."""
        return rotator_id in self._unfenced_locks

    def fenced(self, rotator_id: str, lock_off: bool = False) -> bool:
        """Rule 11: whether the main connection's move (``lock_off``: its lock OFF) for this
        rotator is refused: published before another interface's stop or lock ON."""
        fence = self._fences.get(rotator_id)
        return fence is not None and (fence[1] or not lock_off)

    # -- the main connection (rule 1) ----------------------------------------------------------
    def main_halt(self, rotator_id: str, kind: str, now: float = 0.0) -> Copy:
        """A stop or lock ON read on the main connection (it is carried out whatever this says):
        the copy of the lane's, if it came first (rule 9; rule 13: the holds whose moves wait
        from now on, and the fresh marker to publish; the holds it ends while no marker can
        come); if not, the lane marker to publish (rule 4)."""
        key = (rotator_id, kind)
        waiting = self._lane_waiting.get(key)
        if waiting:
            n, after, q = waiting[0]
            if not self._in_step(kind, after, q):
                return Copy()  # rule 9: maybe older than the lane's connection: nothing known
            waiting.popleft()
            if not self.markers:  # rule 13: no marker can come; the count copy ends the holds
                released = tuple(self._passed(n, fences=False))  # (rule 11: a marker alone)
                return Copy(echo=True, upto=n, released=released)
            self._copied.update(rid for rid, m in self._holds.items() if m <= n)
            self._next += 1  # rule 13: a fresh marker now, the back-off started anew
            self._marker_sent_at[self._next] = now
            self._resend_s = RESEND_S
            return Copy(echo=True, upto=n, marker=self._next)
        sub, q = self._lane_sub[kind], self._lane_q[kind]
        if not self.lane_echoes(kind):  # (rule 4: nothing to note against)
            return Copy()
        if sub == NOT_YET and not 0 < q <= self._q_past[kind]:  # (not subscribed: rule 4;
            return Copy()  # rule 17: its SUBSCRIBE taken before a marker read here)
        if not self._in_step(kind, sub, q):  # rule 4 as rule 9: this halt may be older than
            return Copy()  # the lane's subscription, which has no copy of it
        self._lane_next += 1
        self._echoes.setdefault(key, deque()).append(self._lane_next)
        return Copy(lane_marker=self._lane_next)

    def held(self, rotator_id: str) -> bool:
        """Rule 2: whether a move the main connection reads now for this rotator is refused:
        read while a lane halt holds it, before the main copy of that halt was counted (rule
        9), so published before that halt, or not known to be after it (its copy lost). Read
        after the count copy, it waits under the hold instead (rule 13: ``waits``)."""
        return rotator_id in self._holds and rotator_id not in self._copied

    def waits(self, rotator_id: str) -> bool:
        """Rule 13: whether a move the main connection reads now for this rotator waits under
        a hold for its marker, rather than going now."""
        return rotator_id in self._holds

    def off_waits(self, rotator_id: str) -> bool:
        """Rule 13: whether a lock OFF the main connection reads now for this rotator waits
        for the marker: under a hold with a lane lock ON among its halts (the lane may have
        lost an older ON that the main connection counted as this one's copy, and this OFF
        was published before the lane's ON). Under a STOP's hold alone it goes at once."""
        return self.waits(rotator_id) and rotator_id in self._hold_locks

    def main_lock_off(self, rotator_id: str) -> bool:
        """Rule 8: whether a lock OFF read on the main connection is carried out."""
        return not self._lane_waiting.get((rotator_id, "lock"))

    def marker_back(self, payload: bytes) -> tuple[int, list[str]]:
        """A marker read on the main connection: its number (0 if it is not this process's)
        and the rotators whose hold ends with it."""
        n = self._number(payload)
        if not n:
            return 0, []
        self._main_past = max(self._main_past, n)
        for lane in LANES:  # rule 17: a lane's own marker, behind its SUBSCRIBE, is back
            if n == self._q_sent[lane]:
                self._q_past[lane] = n
        return n, self._passed(n)

    def _passed(self, n: int, fences: bool = True) -> list[str]:
        """The main connection has read everything published before marker or lane halt
        ``n``: the holds up to it end, and what waited for it is done. Not ``fences``: ``n``
        is a lane halt's, numbered when the lane read it, which may be after another
        interface's halt that came later (rule 11): the fences stay, and so do the markers
        out that would end one."""
        sent_at = self._marker_sent_at  # (numbered in order: the oldest first)
        if fences:  # (from the front: a marker back costs what it ends, not all that are out)
            while sent_at and (oldest := next(iter(sent_at))) <= n:
                del sent_at[oldest]
        else:
            waited = [m for m, _ in self._fences.values()]
            for sent in [m for m in sent_at if m <= n]:
                if not any(f <= sent for f in waited):
                    del sent_at[sent]
        if not self._marker_sent_at:
            self._resend_s = RESEND_S
        for waiting in self._lane_waiting.values():
            while waiting and waiting[0][0] <= n:  # its main copy came before, or was
                waiting.popleft()  # lost: either way none is to come (rule 1)
        for rid in [rid for rid, (m, _) in self._fences.items() if fences and m <= n]:
            del self._fences[rid]  # rule 11
            self._fenced_since.pop(rid, None)
        released = [rid for rid, m in self._holds.items() if m <= n]
        for rid in released:
            del self._holds[rid]
            self._copied.discard(rid)
            self._hold_locks.discard(rid)
            self._held_since.pop(rid, None)
        return released

    def main_gone(self) -> list[str]:
        """Rule 5 (the main connection dropped or is new): the rotators whose hold ends with
        clearing; every marker out is void. Rule 9: the next main connection subscribes after
        the lane's present one did."""
        released = list(self._holds)
        self._copied.clear()
        self._hold_locks.clear()
        # rule 12: a lock fence the lane's lock OFFs are not ordered against from now on
        self._unfenced_locks = {rid for rid, (_, lock) in self._fences.items() if lock}
        self._holds.clear()
        self._held_since.clear()
        self._marker_sent_at.clear()
        self._lane_waiting.clear()
        self._fences.clear()  # rule 11: nothing older comes on the next connection
        self._fenced_since.clear()
        self._resend_s = RESEND_S
        if any(sub != NOT_YET for sub in self._lane_sub.values()):
            self._main_past = self._next
        return released

    def markers_denied(self) -> dict[str, int]:
        """Rule 7: the broker does not let the main connection read its markers: none goes out
        any more; the holds stay, each until its main copy. Rule 13: those whose copy was
        counted already end now (no marker will come for them): returned, with their marker."""
        self.markers = False
        self._denied_past = self._next  # (rule 15: one numbered after is asked)
        self._marker_sent_at.clear()
        self._fences.clear()  # rule 11: no marker could end them
        self._fenced_since.clear()
        ended = {rid: m for rid, m in self._holds.items() if rid in self._copied}
        for rid in ended:
            del self._holds[rid]
            self._hold_locks.discard(rid)
            self._held_since.pop(rid, None)
        self._copied.clear()
        return ended

    def markers_allowed(self, now: float) -> int | None:
        """Rule 7: the hello or the probe came back on a new connection: markers go out again,
        and one now (its number returned, to publish) when a hold is up or the lane's
        subscription waits for one (rule 9): a hold put while they were off had no marker,
        and its copy, not counted before the lane's marker, would never end it (an attack
        pass: every target refused for the connection's life)."""
        self.markers = True
        if not self._holds and not any(
            NOT_YET != sub > self._main_past for sub in self._lane_sub.values()
        ):
            return None
        self._next += 1
        self._marker_sent_at[self._next] = now
        return self._next

    def asked_back(self, n: int) -> bool:
        """Rule 15: whether marker ``n``, read back on the main connection (0: none of this
        process's), was published while the markers were known denied (none goes out then but
        the broker's asking, ``probe``): the main connection reads them again."""
        return not self.markers and n > self._denied_past

    def probe(self) -> int:
        """Rule 15: a marker's number to ask the broker with while it refuses them (none is
        out: its PUBACK, not its return, says whether the ACL changed back)."""
        self._next += 1
        return self._next

    def resend_due(self, now: float) -> int | None:
        """Rule 5: a new marker to publish when the oldest out has waited its turn (RESEND_S,
        doubling up to RESEND_MAX_S), else None. Never gives up, never ends a hold."""
        sent_at = self._marker_sent_at  # (the oldest first: numbered, and sent, in order)
        if not sent_at or now - next(iter(sent_at.values())) < self._resend_s:
            return None
        self._resend_s = min(2 * self._resend_s, RESEND_MAX_S)
        self._next += 1
        n = self._next
        self._marker_sent_at = {n: now}  # (a later marker ends every hold before it)
        return n

    def long_holds(self, now: float) -> dict[str, float]:
        """Rule 5: the rotators held for LONG_HOLD_S or more, and since when (to report)."""
        return {rid: since for rid, since in self._held_since.items() if now - since >= LONG_HOLD_S}

    def long_fences(self, now: float) -> dict[str, float]:
        """Rule 11: the rotators fenced for LONG_HOLD_S or more, and since when (to report, as
        a long hold is: their MQTT moves are refused while it lasts)."""
        since = self._fenced_since.items()
        return {rid: t for rid, t in since if now - t >= LONG_HOLD_S}

    @property
    def holding(self) -> bool:
        return bool(self._holds)

    @property
    def markers_out(self) -> bool:
        """A marker is out, or a fence's waits to go (the timer looks again: rule 5)."""
        return bool(self._marker_sent_at) or any(m == OWED for m, _ in self._fences.values())

    def _number(self, payload: bytes, lane: bool = False) -> int:
        """A marker's number; 0 for anything else: another process's, a forged one (rule 10).
        (Compared as bytes: any byte may come, and a text comparison of the seal raises on
        one outside ASCII.)"""
        words = payload.split(b" ")
        if len(words) != 3 or words[0] != self.token.encode():
            return 0
        number, seal = words[1], words[2]
        if not (number.isdigit() and len(number) <= NUMBER_DIGITS):
            return 0
        n = int(number)
        return n if hmac.compare_digest(seal, self._seal(n, lane).encode()) else 0

    # -- rule 6 ----------------------------------------------------------------------------------
    def live_halt(self, topic: str, payload: bytes) -> None:
        """Rule 6 under MQTT 3.1.1: a live stop or lock ON carried out, perhaps published
        retained: a replay of the same payload is not carried out again."""
        if payload:
            self._retained[topic] = payload

    def retained_halt(self, topic: str, payload: bytes, replayed: bool) -> bool:
        """Whether a retained stop or lock ON is carried out: a live one always, a replay once."""
        if not payload:
            self._retained.pop(topic, None)  # deleted: a new one is a new message
            return False
        if not replayed:
            return True
        if self._retained.get(topic) == payload:
            return False
        self._retained[topic] = payload
        return True
