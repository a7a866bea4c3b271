"""Parking for a storm (``wind_topic``): the wind park owns the storm, the readings and when they
came. Pure: readings come in as inputs (``reading``, from the MQTT wind topic through the
mailbox); each step gets a read-only ``Scene`` (parts.py) and returns a ``Proposal`` (the park,
the end of tracking and following, a report) that the session applies.

Rules:
1. A reading above ``wind_park_above`` starts a storm: the rotator is sent to the wind park
   position (source ``wind``), tracking and following end, and every motion command (a target,
   a preset, a park, a nudge, a track or follow command) is refused with the reason
   ("wind 72 km/h above 60: parked for the storm"; "... motion refused for the storm (a stop
   or lock ON stopped its park)" once rule 3 stopped it short: a review, the refusal said the
   rotor was parked while it stood where the STOP left it; a stop after the rotor was seen at
   the park, rule 7's ``arrived``, stopped no park: still "parked for the storm") until the
   storm is over. A target taken before the storm and not sent yet is refused too: the
   session drops it when the storm begins (session.py ``_storm``; an attack pass: a storm
   known only from a replay, rule 6, put no park in its place, and a Rotor-EZ's target,
   waiting for the brake, went out 6 s into the storm); tracking's or following's ends with
   them, unsaid (their ``*_ended`` says why; a cold review: a WSJT-X target so dropped was
   refused on R/error as a 'target az ...' nobody sent), and so does auto-park's (it parks
   again after a quiet spell once the storm is over: autopark.py rule 1). A turn the
   controller has goes on (rule 6's storm sends nothing, not even a stop); a target whose
   frame did not move it (lost or garbled on the line: controller.py rule 11's try more) is not sent
   again in the storm, said on R/error (a cold review: a target lost just before a replayed
   storm went out again in it, the rotor turned while motion was refused); nor is a SatEL's
   slew's target whose report came late (slew.py rule 4): the slew is stopped and the
   controller asked where it is, as ever, but its target is not put back to go again, said
   once on R/error with how late the report was (a review: a storm known only from a replay
   began mid-slew, and the target went out again in it).
2. The storm is over once the readings have stayed below ``wind_release_below`` for
   ``wind_hold_min``: a reading at or above the release level starts the hold again. Only
   readings end a storm: nothing else does, not a restart of the wind station, not silence. So
   the hold ends with a reading that comes at least ``wind_hold_min`` after the calm began,
   never by the clock alone, and a gap of ``wind_silent_min`` between readings starts the calm
   again from the reading after it (a station that fell silent after one calm reading says
   nothing of the wind since). The gap is judged on the session's clock and on the wall clock,
   either one's a gap: the session's (monotonic) stands still while the machine sleeps, and a
   silence across a suspend is a silence all the same (review 106: a laptop asleep two hours
   after nine minutes of calm ended the storm at the first calm reading it heard awake). The
   wall clock only adds gaps, so it can only make a storm last longer (a clock stepped on by NTP
   starts the calm again; one stepped back hides no gap the session's clock sees), the one use
   docs/architecture.md rule 15 lets a clock have. The session is told the wall clock before
   every batch it is handed (runtime/worker.py ``tell_wall``; on a rotator of two boxes before
   either box's, runtime/composite.py rule 1: review 109). The end is judged at that reading,
   whether the controller answers or not (review 96: judged at this part's steps, which run
   only while it answers, a controller silent through a calm kept the storm it had, and the
   next storm was taken for it: a STOP of the old storm held the new park back, the new park
   took the old one's place). The session looks at the storm and the storms begun
   (``storms``) at every step, so a storm that ended and a next that began while it was
   silent are both seen.
3. STOP and the lock always work (docs/architecture.md rule 11): a stop or lock ON during a
   storm stops the park under way, and the park is not tried again until the next storm;
   motion stays refused meanwhile. That holds across a restart in the storm (the status's
   ``halted``, kept by runtime/kept.py rule 4) and a reset of this part (session.py rule 14):
   neither undoes the operator's STOP. A stop or lock ON in a storm known only from a replay
   (rule 6) stops no park and holds none back: that storm is not kept across a restart, and
   the STOP would hold the park back before one and not after it (a review). "During" is
   in the order put: a stop or lock ON put before the storm's first reading, though taken in
   one batch with it, is no stop in the storm (mailbox.py rule 9: the session applies the
   batch's readings put before the halt, the halt, then the rest; attack 14: applied reading
   first, a STOP sent at rest just before the storm cancelled its park for the whole storm).
4. A wind topic silent for ``wind_silent_min`` is reported once (kind ``wind``) and shown in
   the status; the state it had is kept (the report says which: a storm known only from a
   replay, rule 6, parked nothing; one whose park a stop or lock ON stopped short, rule 3, is
   not "parked"; nor is one begun while the rotator was locked, whose park waits for the lock OFF:
   a review, the rotor stood where the lock left it under a report that said it was parked).
   The next reading clears it.
5. The park is judged like any target (pointing.py); one the judge refuses is reported, and
   motion is refused all the same (a safeguard: the settings refuse such a park when they are
   read, settings/wind.py rule 1), said so: "wind 72 km/h above 60: motion refused for the
   storm (its park refused: ...)", the status's ``refused``, never "parked for the storm"
   (review 60: R/status, Home Assistant's "Parked for the storm" and every refusal in the
   storm said it parked while the antenna faced the storm where it stood; the settings'
   guard judges the park without a reading, so a park refused from where the rotor stands
   passes it). The bridge's turn under way then stops (``Proposal.halt``, a halt of the
   bridge's own, no STOP of rule 3): the park would have replaced it, and the rotor stands
   where the storm found it (review 63: it ran on 70 degrees to the operator's pre-storm
   target); a hand's turn on the panel is left alone (review 65). While the storm lasts with
   its park refused, a turn of the bridge's found later stops too (review 66: the turn a
   restart mid-turn finds is known for the bridge's only at the start's second reading, after
   the park was refused at the first, and it ran on 43 degrees). On a rotator of two boxes
   whose other box parked its own axis alone while this one did not answer (``RefusedHere``),
   this box's refusal is said so when the wind falls silent (rule 4): "refused on this axis
   ... the other parked for the storm", never "nothing parked" (review 65: the dish stood
   at its stow). A park owed
   again (rule 7) is judged again, and one it takes ends that. On a rotator of two boxes it
   is judged as the rotator's whole park first (``Scene.whole``, runtime/composite.py rule
   7): all axes or none, as autopark.py rule 5 has it (an attack
   pass: the azimuth box refused the storm's park and the elevation box lowered the dish
   alone), while both boxes answer. While the azimuth box does not answer, the elevation box
   judges and parks its own axis alone (the safe side, as a storm begun with the elevation
   box out parks the azimuth alone; review 63: it waited for the azimuth box, and the dish
   stayed raised for the whole storm), and the azimuth box's park stays owed (rule 7). While
   the azimuth box answers again but has taken no reading since, the whole park is not
   judged: it stays owed (``waiting``), neither taken nor refused (``Unjudged``), and tracking
   and following end as the park would have ended them; it is judged whole at that box's
   first reading (review 60: the elevation box judged the whole park from the azimuth box's
   bearing from before its offline, refused it for the whole storm, and once the azimuth box
   was back where the park is allowed, the antenna faced the storm at 100/40).
6. A reading the broker replayed (a retained one, sent again when the bridge subscribes anew:
   after a restart of the broker or of the bridge, a reconnect) is the last known wind, not a
   new reading: it may start a storm or start the hold again (the safe side), and it is the
   speed shown while no new reading has come; it never starts or continues a calm, so it never
   ends a storm, and it says nothing of silence (rule 4: the station may be long gone). A
   storm it starts refuses motion but sends no park (``replayed`` in the status): no retained
   or replayed message moves a rotor (an attack pass: a storm reading retained by a wind
   station dead for a week parked the rotor at every start of the bridge). It ends tracking
   and following all the same, as rule 1 says (an attack pass: the status said "tracking"
   through such a storm while the rotor stood still, and tracking turned it again by itself
   once live calm readings ended the storm). The first new
   reading above the park level parks it, as rule 1 says; one below the release level starts
   the calm; a storm known only from a replay is not kept across a restart (the replay comes
   again). Neither an offline of the controller (rule 7: it took no park from the rotator)
   nor a reset of this part (session.py rule 14) owes it a park (a review: either sent the
   park once the controller answered, and a replayed reading turned the rotor).
7. A park the line took from the rotator in a storm (the controller offline or its port gone:
   a turn under way stopped at the offline, session/controller.py rule 2, or a park waiting
   dropped) is owed again, proposed once the controller answers, unless a stop or lock ON
   halted it (rule 3): motion is refused in the storm, so nobody can send it again. (A review
   of d35d250: a GS-232B whose replies were lost for 4 s while it parked for the storm was
   stopped at the offline, and stood 140 degrees short of the park for the rest of the storm.)
   So is a park the box's known restart cut short (its power-on byte, controller.py rule 12;
   a SatEL's clock gone back, rule 14, keeps it waiting): no jam, its motor is free, and its
   error says the park goes again, never "send the target again" (review 80: it was never
   sent again, the antenna facing the storm 100 degrees off its park).
   A park the rotor was seen to reach (``arrived``) is no park the line took: an offline after
   it owes nothing (an attack pass: a rotor turned at its front panel after the storm's park,
   its line silent for 3 s, was turned back to the park by itself once it answered). That
   holds across a restart in the storm (the status's ``arrived``, kept by runtime/kept.py
   rule 4) and a reset of this part (session.py rule 14): neither parks again (a review of
   this rule: a bridge restarted in the storm turned a rotor moved by hand back to the park
   by itself), while a start in a storm whose park was not seen reached (the bridge died
   mid-park) parks again, as it did, at the place that park took (mailbox.py rule 10b,
   runtime/kept.py rule 4; review 96: a new place let a remote's STOP held against it go).
   A rotor that cannot report its position (a DCU-1) is never seen there: the end of its
   estimated move is no arrival, and an offline or a restart owes its park again (a review of
   3e4f0f4). A park owed so is judged (rule 5) from the first reading taken once the controller
   answers, never from the one kept from before the offline: it waits for that reading, owed
   (review 60: the first reading back, doubted, made the controller answer while the motion
   still held the bearing from before the offline; judged from it, a park from where the rotor
   had since been turned by hand was refused for the whole storm).
8. The park waits, like any target, under the hold of a STOP or lock ON that came before the
   storm (the stop lane's or the stop express's: session.py rule 13), and goes when the hold
   ends; a hold that ends by clearing (the main connection lost before its marker came back,
   the express ended before its word: stops.py rule 5) drops what an operator sent, who may
   send it again, but not the park, which goes then too: it is the bridge's own move, and
   nobody can send it again in the storm (rule 1; attack 14: the park dropped so, the rotor
   faced the storm 90 degrees off while the status said "parked for the storm"). Nothing is
   lost to the order either: a STOP of this storm (rule 3) halted the park already, and the
   waiting park would have gone at an ordinary release all the same. But only in the storm:
   the storm's end (rule 2) drops a park still waiting, unsaid (session.py ``_storm``): after
   the storm the rotator stays where it is (review 60: a calm reading ended the storm before
   the hold's marker came back, and the park went then, the rotor turned 90 degrees with no
   storm and nobody asking; a clearing then dropped it as an operator's target, "send it
   again").
9. A park owed and not sent (rules 4, 5 and 7: for the lock OFF, for the controller to answer,
   for its first reading since, for the azimuth box's) or taken and waiting under a STOP's
   hold (rule 8: the session says so, ``held_back``) is said waiting, never parked: the
   status's ``waiting`` (Home Assistant's "Parked for the storm" off), and the refusal "wind
   72 km/h above 60: motion refused for the storm (its park waits for the lock OFF)", with
   what it waits for; "parked for the storm" only once the park was sent (review 63: a park
   waiting for the azimuth box was refused to operators as "parked for the storm", and one
   under a STOP's hold showed ``waiting: false`` and "Parked for the storm" ON while the
   rotor faced the storm where it stood).
10. A park sent says "parked" only while the rotor is on its way to it or stands at it
   (within ``tolerance_deg + noise_deg`` of it as the controller holds it, the band a rotor
   at a bearing is judged by, braking or settling there too, ``_at``: the session tells this
   part where the rotor is before each status, ``seen``; review 80: within ``tolerance_deg``
   alone, a still rotor's noisy readings flipped it). A park whose turn ended short of it (a stall:
   ice, a caught cable; a pass, a turn back, a limit, the controller stopping its motor) says
   "its park not reached" and where the rotor stands, and one turned off it after it was
   reached (a hand at the front panel: rule 7 leaves it there) "turned off its park" and
   where: the status's ``off_park`` (Home Assistant's "Parked for the storm" off), and the
   refusal "wind 72 km/h above 60: motion refused for the storm (its park not reached: the
   rotor stands at 168°)", naming the elevation too where the park has one (review 80: an
   elevation stalled short was said to stand at the park's own azimuth). A rotor turned
   back to the park is parked again. A park seen
   reached before a restart in the storm, sent no more (rule 7), is judged so too, against
   the park as judged from the first reading since (review 80: judged against no park sent,
   a rotor turned 160 degrees off it was said parked). Motion stays
   refused, and the bridge does not send a park that ended short again in this storm: its
   motor drove for ``stall_timeout_s`` without moving it, and would drive on against the
   jam; nobody can send it in the storm either, so the stall's own error says so, never "send
   the target again" (session.py ``_heed``); nor does an offline after it owe it (rule 7: the
   line took no park; a restart in the storm still parks again, as rule 7 says of a park not
   seen reached). A rotor that cannot report its position (a DCU-1) is never judged so.
   (Attack 25: a park that stalled 78 degrees short, and one a hand turned 110 degrees off
   it, were said "parked for the storm" in R/status, Home Assistant and every refusal, and
   the stall said "send the target again", which the storm refused.)
"""

from __future__ import annotations

import logging

from bridge.core.errors import Refused
from bridge.core.model import ErrorKind, MotionState, Source, Target, WindInfo, kept_if_same
from bridge.session.actions import Report
from bridge.session.config import WindConfig, WorkerConfig
from bridge.session.motion import Motion, MotionConfig, angle_error
from bridge.session.parts import NOTHING, Proposal, RefusedHere, Scene, Unjudged

log = logging.getLogger(__name__)

# rule 9: what a park owed and not sent waits for
ANSWER = "the controller to answer"
LOCK_OFF = "the lock OFF"
READING = "the controller's first reading since it answers again"
AZIMUTH_READING = "the azimuth box's first reading since it answers again"
HOLD = "the hold of a STOP or lock ON sent before the storm"


def unread(scene: Scene) -> bool:
    """Rule 7: no reading taken since the controller answered again (the motion still the
    offline one: the first back doubted, controller.py rule 9): the park waits for one."""
    return scene.motion.state is MotionState.OFFLINE


def kept_start(*, halted: bool, arrived: bool, locked: bool) -> str:
    """What a start in a storm kept across a restart (runtime/kept.py rules 4 and 6) does with
    its park, in the words the log says it with: as ``WindPark`` takes ``halted`` and
    ``arrived`` (``arrived`` as the session hands it on: never a DCU-1's) and its step the
    lock kept with it (``locked``). A park seen reached first: a STOP after it stopped no park
    (rule 1: still "parked for the storm"), and the file holds both (review 109: such a start
    was said to have its park stopped). A park owed under the lock kept ON waits for the lock
    OFF (rules 4 and 9: said waiting, never parked; review 109: it was said "parking again"
    while the rotor stood where the lock held it); one owed with no lock kept goes once the
    controller answers, unless a lock ON comes first (the broker's, runtime/kept.py rule 10:
    that park is not tried again, rule 3)."""
    if arrived:  # rule 7
        return "its park was reached: not sent again"
    if halted:  # rule 3: the operator's STOP outlives the restart
        return "its park, stopped by a STOP or lock ON, is not sent again"
    if locked:  # rules 4 and 9: the step sends nothing while locked
        return f"its park (not seen reached) waits for {LOCK_OFF}: nothing turns until then"
    return (
        "parking again once the controller answers, unless a lock ON comes first (its park "
        "was not seen reached)"
    )


class WindPark:
    """Without a wind topic (``rig.wind`` None) it never does anything."""

    def __init__(
        self,
        rig: WorkerConfig,
        *,
        storm: bool = False,
        halted: bool = False,
        arrived: bool = False,
        replayed: bool = False,
        storms: int = 0,
    ) -> None:
        self._rig, self._cfg = rig, rig.wind or WindConfig(0.0, 0.0, 0.0, (0.0, None), 0.0)
        self.on = rig.wind is not None
        self.storm = storm
        # the storms begun so far (a storm kept across a restart counted as none): what names
        # this storm's park (session.py ``_own_turn``), one turn however often it is begun
        # (mailbox.py rule 10b); a reset keeps it
        self.storms = storms
        self._why = "wind above the park level"  # rule 1's reason, once a reading says it
        self._speed: float | None = None
        self._last_t: float | None = None  # when the last reading came
        self._last_wall: float | None = None  # ... on the wall clock (rule 2: a suspend)
        self._since_t: float | None = None  # silence counts from here before any reading
        self._calm_since: float | None = None
        self._silent = False
        # rules 3 and 7: a park stopped stays stopped, and one seen reached is done, across a
        # restart (kept.py rule 4) and a reset
        self._park_owed = storm and not halted and not arrived and not replayed  # (rule 6)
        self._halted = storm and halted
        self._arrived = storm and arrived  # rule 7: the rotor was seen at this storm's park
        self._replayed = storm and replayed  # rule 6: the storm known only from a replay
        self._end_owed = False  # rule 6: tracking and following to end, with no park to carry it
        self._refused: str | None = None  # rule 5: why the judge refused this storm's park
        self._here = False  # rule 5: refused on this box alone, the other's axis parked
        self._unjudged = False  # rule 5: the whole park waited, tracking's end proposed already
        self._waits: str | None = None  # rule 9: what the park owed waited for at a step
        self._offline = True  # rule 9: the controller does not answer (none has yet: no step)
        self._held_back = False  # rules 8 and 9: the park taken waits under a STOP's hold
        self._wire: tuple[float, float | None] | None = None  # rule 10: this storm's park, sent
        self._off: str | None = None  # rule 10: where the rotor stands off that park, in words
        self._wall_offset_s = 0.0
        self._info: WindInfo | None = None  # the last ``info``, kept while it says the same

    @property
    def info(self) -> WindInfo | None:
        """The status's ``wind``: the last one while it says the same (core/model.py
        ``kept_if_same``). The session asks at every status it makes, and one made anew at
        every reading made R/status's rest again at every one (payloads.py StatusText keeps it
        by its very objects: issue 39)."""
        if not self.on:
            return None
        calm = self._calm_since
        info = WindInfo(
            speed_kmh=None if self._speed is None else round(self._speed, 1),
            storm=self.storm,
            calm_since_unix=None if calm is None else calm + self._wall_offset_s,
            silent=self._silent,
            refusal=self.refusal(),
            replayed=self._replayed,
            halted=self._halted,
            arrived=self._arrived,
            waiting=self.waiting is not None,
            refused=self.storm and self._refused is not None,
            off_park=self._off is not None,
        )
        self._info = info = kept_if_same(info, self._info)
        return info

    def reading(
        self, kmh: float, now: float, *, wall_offset_s: float = 0.0, replayed: bool = False
    ) -> None:
        """Rules 1, 2, 4 and 6: a reading, in km/h (``replayed`` by the broker);
        ``wall_offset_s``: the wall clock (unix seconds) is ``now`` + this (rule 2's gap)."""
        cfg = self._cfg
        if not self.on:
            return
        if replayed:  # rule 6
            if self._last_t is None:
                self._speed = kmh
            if kmh > cfg.park_above_kmh:
                self._stormy(kmh, replayed=True)
            elif kmh >= cfg.release_below_kmh:
                self._calm_since = None
            return
        # rule 2: the gap on the session's clock, or on the wall clock (a suspend: the
        # session's stands still, review 106); either starts the calm again, the safe side
        wall = now + wall_offset_s
        gap = (
            self._last_t is None
            or now - self._last_t >= cfg.silent_s
            or self._last_wall is None
            or wall - self._last_wall >= cfg.silent_s
        )
        self._speed, self._last_t, self._last_wall, self._silent = kmh, now, wall, False
        if kmh > cfg.park_above_kmh:
            self._stormy(kmh)
        elif self.storm and kmh < cfg.release_below_kmh:
            if self._calm_since is None or gap:
                self._calm_since = now
            if now - self._calm_since >= cfg.hold_s:
                self._over()  # rule 2: at the reading, whether the controller answers or not
        else:
            self._calm_since = None  # rule 2: the hold starts again

    def _over(self) -> None:
        """Rule 2: the storm is over, judged at the reading that ends the hold, never at a
        step: a step runs only while the controller answers, and a controller silent through
        the calm kept the storm it had, the next storm taken for it (review 96: its STOP held
        the new storm's park back, or the new park took the old storm's place)."""
        self.storm, self._calm_since, self._park_owed = False, None, False
        self._halted = self._replayed = self._here = False
        self._refused, self._wire, self._off = None, None, None
        log.info("%s: the storm is over: motion allowed again", self._rig.rotator_id)

    def _stormy(self, kmh: float, *, replayed: bool = False) -> None:
        """Rule 1: a reading above the park level; rule 2: no calm since; rule 6: a replayed
        one parks nothing."""
        self._calm_since = None
        if self.storm and (replayed or not self._replayed):
            return  # (but a live reading in a storm known only from a replay: rule 6)
        if not self.storm:
            self.storms += 1  # (mailbox.py rule 10b: a new storm's park is a new turn)
            self.storm, self._halted, self._arrived = True, False, False
            self._refused, self._unjudged = None, False  # (rule 5: a new storm's park anew)
            self._here, self._wire, self._off = False, None, None  # (rule 10 likewise)
            self._end_owed = replayed  # rule 6: no park carries the end (rule 1)
        self._replayed, self._park_owed = replayed, not (replayed or self._halted)
        self._waits = None  # (rule 9: judged at the next step, if the controller answers)
        self._why = f"wind {kmh:.0f} km/h above {self._cfg.park_above_kmh:g}"
        if replayed:
            self._why += " (the last reading the broker kept)"
            log.warning(
                "%s: %s: motion refused, no park until a new reading",
                self._rig.rotator_id,
                self._why,
            )
        else:
            log.warning("%s: %s: parking for the storm", self._rig.rotator_id, self._why)

    @property
    def park_halted(self) -> bool:
        """Rule 3: a stop or lock ON came in this storm: its park is not tried again."""
        return self._halted

    def halted(self) -> None:
        """Rule 3: a stop or lock ON; the park is not tried again in this storm (rule 6: one
        known only from a replay has no park to stop, and the STOP holds none back)."""
        if self._replayed:
            return
        self._park_owed = False
        self._halted = self.storm

    @property
    def park_arrived(self) -> bool:
        """Rule 7: the rotor was seen at this storm's park: it is not sent again."""
        return self._arrived

    @property
    def parked(self) -> bool:
        """Rule 5: this storm's park was sent (or seen reached): not refused, owed, waiting,
        stopped short, nor a replay's (runtime/composite.py rule 7: a box's axis parked alone
        while the other box did not answer); and the rotor not off it (rule 10)."""
        return self._sent() and self._off is None

    def _sent(self) -> bool:
        """Rules 5 and 10: this storm's park was sent (or seen reached), wherever the rotor is."""
        if not self.storm or self._replayed or self._refused is not None or self._park_owed:
            return False
        return (self._arrived or not self._halted) and self.waiting is None

    @property
    def park_replayed(self) -> bool:
        """Rule 6: the storm is known only from a replayed reading: no park is owed."""
        return self._replayed

    @property
    def park_owed(self) -> bool:
        """Rule 7: this storm's park is owed, to be proposed again."""
        return self.storm and self._park_owed

    def lost(self) -> None:
        """Rule 7: the line took the rotator (offline, unplugged), or the box's known restart
        its park, in this storm (rule 6: one known only from a replay sent no park, and owes
        none; rule 10: nor one whose turn ended short of it before)."""
        if self.storm and not self._replayed and not self._halted and not self._arrived:
            if self._off is None:
                self._park_owed, self._waits = True, None  # (rule 9: ``answering``)

    def sent(self, wire: tuple[float, float | None]) -> None:
        """Rule 10: this storm's park went to the controller as ``wire`` (as it holds it), or
        was found there already (told by the session)."""
        if self.storm:
            self._wire = wire

    def seen(self, m: Motion, going: bool, where: str) -> None:
        """Rule 10: where the rotor stands against this storm's park, told by the session before
        each status: ``going``, the park waits to go out or its turn is under way (a target
        out, a slew); ``where``, the rotor's bearing in an error's words (Controller.where: its
        elevation too where the park names one). Offline, the last word is kept: where it
        stands is not known."""
        pos, offline = m.position_deg, m.state is MotionState.OFFLINE
        if self._wire is None and self._arrived and pos is not None and not offline:
            self._wire = self._kept_wire(pos)  # rule 7: reached before a restart, no park sent
        wire = self._wire  # in this run (review 80: judged against nothing, said parked)
        if wire is None or going or not self._sent() or not self._rig.spec.can_report_position:
            self._off = None
            return
        if offline or pos is None:
            return
        if _at(m, self._rig.motion, wire):  # (braking or settling there too: no flicker)
            self._off = None
        elif self._arrived:  # rule 7: reached, then turned (a hand at the front panel)
            self._off = f"turned off its park after reaching it: the rotor stands at {where}"
        else:
            self._off = f"its park not reached: the rotor stands at {where}"

    def _kept_wire(self, position_deg: float) -> tuple[float, float | None] | None:
        """Rule 10: this storm's park as the controller would hold it, judged from where the
        rotor stands, for a park seen reached before a restart (rule 7 sends it no more; review
        80: a rotor turned 160 degrees off it was said parked)."""
        cfg = self._cfg
        try:
            judged = self._rig.aim.judge(Target(cfg.park[0], cfg.park[1]), position_deg)
        except Refused:  # (the settings refuse such a park: settings/wind.py rule 1)
            return None
        return (judged.az_deg if judged.az_deg is not None else position_deg, judged.el_deg)

    def arrived(self) -> None:
        """Rule 7: the rotor was seen at rest at this storm's park: an offline owes it no more."""
        if self.storm and not self._park_owed:
            self._arrived = True

    @property
    def waiting(self) -> str | None:
        """Rule 9: what this storm's park, owed or taken and not sent, waits for (None: it
        does not wait: sent, parked, stopped, refused, or no storm)."""
        if not self.storm or self._replayed or self._halted or self._refused is not None:
            return None
        if self._park_owed:  # (None from a step's wait: judged at the next step, which
            return ANSWER if self._offline else self._waits  # runs while it answers)
        return HOLD if self._held_back else None

    def answering(self, answering: bool) -> None:
        """Rule 9: whether the controller answers (told by the session at each step): while
        it does not, no step runs, and a park owed waits for it."""
        self._offline = not answering

    def held_back(self, held: bool) -> None:
        """Rule 9: whether the park this part proposed waits, taken, under the hold of a STOP
        or lock ON sent before the storm (rule 8: session.py rule 13; told by the session
        before each status)."""
        self._held_back = held

    def refusal(self) -> str | None:
        """Why motion is refused now (rule 1), if it is."""
        if self._replayed:  # rule 6
            above = self._cfg.park_above_kmh
            return f"{self._why}: motion refused; the park waits for a new reading above {above:g}"
        if self.storm and self._refused is not None and self._here:  # rule 5: this axis
            return (  # alone: the other box's is parked (review 65)
                f"{self._why}: motion refused for the storm (its park refused on this axis: "
                f"{self._refused}; the other axis parked)"
            )
        if self.storm and self._refused is not None:  # rule 5: nothing parked (review 60)
            return f"{self._why}: motion refused for the storm (its park refused: {self._refused})"
        if self._halted and not self._arrived:  # rule 3: its park stopped short (a review)
            return f"{self._why}: motion refused for the storm (a stop or lock ON stopped its park)"
        waits = self.waiting
        if waits is not None:  # rule 9: owed and not sent (review 63)
            return f"{self._why}: motion refused for the storm (its park waits for {waits})"
        if self.storm and self._off is not None:  # rule 10: off the park sent (attack 25)
            return f"{self._why}: motion refused for the storm ({self._off})"
        return f"{self._why}: parked for the storm" if self.storm else None

    def wakeup(self, now: float) -> float | None:
        """When the silence is due, if it lies ahead (the hold ends with a reading: rule 2)."""
        times = []
        quiet_from = self._last_t if self._last_t is not None else self._since_t
        if quiet_from is not None and not self._silent and self.on:
            times.append(quiet_from + self._cfg.silent_s)
        ahead = [t for t in times if t > now]
        return min(ahead) if ahead else None

    def step(self, scene: Scene) -> Proposal:
        """Run by the session with its other rules, while the controller answers."""
        cfg, now = self._cfg, scene.now
        if not self.on:
            return NOTHING
        self._wall_offset_s = scene.wall_offset_s
        self._offline = False  # (rule 9: a step runs only while the controller answers)
        if self._since_t is None:
            self._since_t = now
        error = None
        quiet_from = self._last_t if self._last_t is not None else self._since_t
        if not self._silent and now - quiet_from >= cfg.silent_s:  # rule 4
            self._silent = True
            if self._replayed:  # rule 6: nothing was parked
                kept = (
                    "a storm known only from the reading the broker kept: motion refused, "
                    "nothing parked"
                )
            elif self._refused is not None and self.storm and self._here:  # rule 5: this
                kept = (  # box's axis alone (RefusedHere): the other box's is parked (review 65)
                    "a storm whose park was refused on this axis: motion refused, this axis "
                    "unparked, the other parked for the storm"
                )
            elif self._refused is not None and self.storm:  # rule 5: the park refused
                kept = "a storm whose park was refused: motion refused, nothing parked"
            elif self._halted and not self._arrived:  # rule 3: the park stopped short
                kept = "a storm whose park a stop or lock ON stopped: motion refused"
            elif self.waiting is not None:  # rules 4 and 9: owed (the lock ON...), not sent
                kept = (
                    f"a storm whose park waits for {self.waiting}: motion refused, nothing parked"
                )
            elif self.storm and self._off is not None:  # rule 10: off the park sent
                kept = f"a storm whose park was sent: motion refused, {self._off}"
            else:
                kept = "parked for the storm" if self.storm else "no storm"
            error = Report(
                ErrorKind.WIND,
                f"no wind reading on {cfg.topic} for {cfg.silent_s / 60:g} min: keeping the "
                f"state it had ({kept})",
            )
        if self._end_owed and not self._park_owed:  # rule 6: no park, the end all the same
            self._end_owed = False
            if self.storm:
                return Proposal(error=error, ended=self._why)
        if self.storm and self._refused is not None and not self._park_owed:
            if _turning(scene.motion):  # rule 5: a turn of the bridge's known only now (a
                # restart's carried turn, seen at its second reading: review 66) stops too
                return Proposal(error=error, halt=True)
        if not (self.storm and self._park_owed) or scene.locked or unread(scene):
            if self.storm and self._park_owed:  # rule 9: what it waits for
                self._waits = LOCK_OFF if scene.locked else READING
            return NOTHING if error is None else Proposal(error=error)
        self._park_owed = self._arrived = self._end_owed = False  # (the park ends them)
        self._wire = self._off = None  # (rule 10: told again once this park is sent)
        park = Target(cfg.park[0], cfg.park[1], Source.WIND, park=True)
        try:
            if scene.whole is not None:  # rule 5: a rotator of two boxes', all axes or none
                scene.whole(park)
            judged = self._rig.aim.judge(park, scene.motion.position_deg)
        except Unjudged:  # rule 5: the azimuth box without a fresh reading: owed, not refused
            self._park_owed, said, self._waits = True, self._unjudged, AZIMUTH_READING  # (9)
            self._unjudged = True  # (tracking and following end once, as the park would end them)
            return Proposal(error=error, ended=None if said else self._why)
        except Refused as exc:  # rule 5
            self._refused = exc.message  # (said so, not "parked": review 60)
            self._here = isinstance(exc, RefusedHere)  # (the other box's axis parked: 65)
            why = Report(ErrorKind.REFUSED, f"wind park refused: {exc.message}", "wind park")
            m = scene.motion  # (the turn under way stops, as the park would have replaced it)
            return Proposal(error=why, ended=self._why, busy=True, halt=_turning(m))
        self._refused, self._here = None, False
        return Proposal(target=judged, error=error, ended=self._why, busy=True)


def _at(m: Motion, cfg: MotionConfig, wire: tuple[float, float | None]) -> bool:
    """Rule 10: the rotor within ``tolerance_deg + noise_deg`` of ``wire`` on each axis it
    names (the band the controller judges a rotor at a bearing by: a still rotor's readings
    wander within ``noise_deg``, review 80: off_park flipped at every other reading), at rest
    or not: status.py's ``parked`` waits for rest, and a Rotor-EZ's brake window after its
    arrival, or a turn's settling, would say the rotor off its park for seconds."""
    pos, near = m.position_deg, cfg.tolerance_deg + cfg.noise_deg
    if pos is None or angle_error(pos, wire[0], cfg.az_wraps) > near:
        return False
    el = wire[1]
    return el is None or m.el_position_deg is None or abs(m.el_position_deg - el) <= near


def _turning(m: Motion) -> bool:
    """Rule 5: a turn of the bridge's under way (a target out, or the controller finishing one
    over a lost link: ``carried``, motion.py rule 4), with no stop of the bridge's sent for
    it; never a hand's on the panel (review 65: a park refused again after a line blip
    stopped the operator's own turn to 200 at 270, the one turn a storm leaves a person)."""
    aimed = m.target_deg is not None or m.el_target_deg is not None
    return m.stop_sent_t is None and (aimed or (m.state is MotionState.MOVING and m.carried))
