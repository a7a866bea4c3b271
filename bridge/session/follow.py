"""Following the QSO partner (``R/follow``): the rotator turns to the great-circle bearing of
the station WSJT-X or JTDX names as its DX call and grid. Pure: the follower owns whether it
follows, what it last heard and the grid it last turned to; each step gets a read-only
``Scene`` (parts.py) and returns a ``Proposal`` the session applies. What WSJT-X says comes in
as ``Heard`` inputs (interfaces/wsjtx/server.py reads the datagrams on a thread of its own).

Rules:
1. Following is off until a Follow command switches it on, and ends on ``R/follow off``, a
   stop, the lock, a track command, any other target (a manual one, rotctld's P, a preset, a
   nudge, a park), the rotor turned by hand, a stall, the serial link going down or the
   controller falling silent: the rotor never turns by itself after any of these. The status
   says why (``following_ended``). Its own targets are put by the session, not through the
   mailbox, so they never end it. Turned by hand is as tracking has it (parts.py rule 8): the
   rotor turning with no target and no stop of the bridge's out, further than the tolerance
   from the bearing it last turned to, or at all before it has turned to one (nothing heard
   yet, no grid, a grid refused or off band): the operator took the antenna by hand, and the
   next grid must not turn it away from where the hand left it (a review: it did). Not the
   turn its start found carried over a lost link with no target (a replug mid-turn, the
   controller finishing its old turn by itself: parts.py rule 8; review 50): its first grid
   takes that turn's place. A hand already turning at the start is a hand (review 52).
2. While it follows, a grid not turned to before turns the rotor to its great-circle bearing
   from the station (the long path if asked). The same grid again moves nothing (the
   deadband), whatever else the program's status says; so does a status without a grid, or
   with one that is no Maidenhead locator. Its target is put at once, as any newest target
   (targets.py): a turn under way to an older one (the target before following started) is
   stopped first where the controller stops to re-target (a Rotor-EZ: then its brake delay),
   never waited for (tracking.py rule 3 has the same for a tracking start: review 46).
3. Hold while transmitting (``follow_hold_while_tx``, on by default): a new grid heard while
   the program transmits waits, shown as ``held``, until a status says the transmission has
   ended; then the newest grid is turned to (or, the dial off its bands, waits for them, no
   longer ``held``: rule 9). A transmission that begins while its own turn is
   under way (the usual case: the grid is named a second before the transmit period) stops
   the turn (``Proposal.halt``), and the grid is turned to again once it has ended. Its own
   turn is its target waiting or out with the rotor turning; a turn with none is not its own
   (rule 1: a hand ends following, never stopped and undone after the transmission).
4. Switching it on takes the newest status heard if it is at most FRESH_S old (WSJT-X sends one
   on every change and at least at every decoding period): the rotor turns to the partner of
   the QSO already under way. An older one is stale and moves nothing (docs/architecture.md
   rule 7). A rotator with ``bands`` (rule 9) takes the newest fresh status whose dial is on
   one of them when the newest of all is not (two radios: the QSO under way on its band, not
   a refusal for the other radio's band and a wait for the next status: a review), of a
   program whose own newest status it is: a program's status is what it says now, and one it
   sent on the band before its dial moved away (its later status on another band) is no QSO
   under way there (an attack pass: switched on 5 s after the only WSJT-X moved 20 m -> 40 m,
   the 20 m antenna turned to the partner it had named on 20 m). What it keeps of them is
   bounded (each program's newest, of the MINE_KEPT heard last on its bands).
5. Every target goes through the same judge as any other (pointing.py: limits, keep-out
   sectors). One it refuses is reported once for that grid and not tried again. A start whose
   first grid is refused (nothing turned to since it was switched on) holds the rotor where it
   is, as tracking's start does (tracking.py rule 5, parts.py rule 10): a turn under way to an
   older target is stopped (``Proposal.halt``), once, as that grid's own target would have
   stopped it (rule 2). Attack 19: a Rotor-EZ turning to an older target, told to follow a
   partner in a keep-out sector, said so on R/error and turned on 105 degrees. A turn carried
   over a lost link that no reading back has shown yet is halted at the step the next one
   shows it move, the grid not tried again (``StartHalt.owed``, parts.py rule 10; review 70:
   right after a replug mid-turn, the refusal was said while the rotor turned on 90 degrees;
   review 84: so a turn a bridge just started finds, right after a restart mid-turn).
6. Following is activity for auto-park (the rotor does not park while it follows a QSO).
7. Its targets carry an origin of interface ``wsjtx`` (the status's ``last_command_source``
   and ``last_operator``), with the operator who switched following on if they named
   themselves. Like tracking's, they are the bridge's own: the control lease judged who
   switched it on (rotator.py), not each grid WSJT-X names.
8. It follows one program: the instance (WSJT-X's Id) of the first status heard since it was
   switched on, the fresh one it started with included. Statuses of any other instance (a
   second WSJT-X on another band, another station's in the same multicast group) are ignored
   while it follows, or the rotor would swing between two partners at every decoding period.
   What it keeps of them is bounded (the IGNORED_KEPT heard last) and said at most once per
   IGNORED_LOG_S, with the count of others since: a flood of forged instance names costs
   neither memory nor the disk. A rotator with ``bands`` (rule 9) takes the first program
   whose dial is on one of its bands: with two radios (SO2R, one WSJT-X each) the 40 m
   antenna follows the program on 40 m, whichever spoke first (an attack pass: it took the
   one on 20 m, heard first, and ignored the 40 m radio's for as long as it followed). The
   program followed that leaves its bands (a dial moved to 20 m) is let go: another program
   heard on them in the last FRESH_S, and still on them by its own newest status (rule 4), is
   followed at once (its newest status: two radios that swap bands, their statuses in one
   batch), else the first heard on them again, it or another (a review: the 40 m antenna kept
   the radio gone to 20 m and ignored the one come to 40 m; an attack pass: it followed
   rig2's old 40 m status though rig2 had moved to 15 m since, and turned to its old partner).
9. A rotator with ``bands`` (settings/bands.py) follows only while the program's dial frequency
   is on one of them (core/bands.py): a grid heard on another band, on no amateur band, or with no
   dial frequency moves nothing, and is reported once (R/error) until the dial is on one of its
   bands again, whatever other band it goes to meanwhile (a review: said again at each change
   of the band it was off on, two radios on two other bands, an SO2R station's, had every
   status of each refused anew on R/error and in the log, and a status flood alternating two
   bands some 150 log lines a second); the grid is then turned to. With following on for
   each rotator of a station with one antenna per band, the one whose antenna is on the
   radio's band turns. A turn under way when the band changes is not stopped (it was for the
   partner heard on its band), nor by a transmission on another band (rule 3's hold is for
   this antenna's band: an attack pass, the 20 m antenna stopped half way when WSJT-X moved
   to 40 m and transmitted there, and nothing turned it on).
10. The DX call is shown (the status's ``following.call``, Home Assistant's sensor, the log,
   a refusal on R/error) only if it could be a call sign as WSJT-X writes one: at most MAX_CALL
   characters, printable ASCII (no control character, no Unicode line separator or
   right-to-left override, which a log viewer may honour: a review).
   Anything else is shown as none (``?`` in a refusal); the grid is followed all the same (it,
   not the call, is what the rotor turns to). Whoever reaches WSJT-X's port chooses the call
   (an attack pass: a line end in it forged lines in the bridge's log, and a call of 300
   characters made Home Assistant refuse the sensor's state at every status).
11. Each turn is logged, at INFO at most once per TURN_LOG_S (the line then says how many
   turns came since the last one), the rest at DEBUG: whoever reaches WSJT-X's port chooses
   how often the grid changes (an attack pass: a new grid every few milliseconds, within the
   sender's budget, was some 100 INFO lines a second). Every turn is proposed all the same.
"""

from __future__ import annotations

import logging
import math
from collections import OrderedDict
from dataclasses import dataclass, replace

from bridge.core import geo
from bridge.core.bands import band_of_hz, describe_hz
from bridge.core.errors import Refused
from bridge.core.model import ErrorKind, FollowingInfo, MotionState, Origin, Source, Target
from bridge.pointing import toward
from bridge.session.actions import Report
from bridge.session.config import WorkerConfig
from bridge.session.parts import NOTHING, Before, Proposal, Scene, StartHalt, turned_by_hand

log = logging.getLogger(__name__)

HAND = "turned by hand"  # rule 1: following_ended
FRESH_S = 30.0  # rule 4
IGNORED_KEPT = 32  # rule 8: the other instances remembered (so each is said once)
MINE_KEPT = 32  # rules 4 and 8: the programs on its bands whose newest status is kept
IGNORED_LOG_S = 60.0  # rule 8: at most one line this often about the others
NAME_SHOWN = 40  # characters of an instance name a log line quotes (WSJT-X's Id is short)
MAX_CALL = 32  # rule 10: WSJT-X's longest (a compound call in <>) is some 15 characters
TURN_LOG_S = 10.0  # rule 11: a turn's INFO line at most this often


@dataclass(frozen=True)
class Heard:
    """What the program says of the QSO under way (WSJT-X's Status message)."""

    call: str
    grid: str
    transmitting: bool
    instance: str = ""  # the program's Id (``WSJT-X``, ``JTDX``)
    dial_hz: int | None = None  # the radio's dial frequency (rule 9)


@dataclass(frozen=True)
class Follow:
    """Start following the partner WSJT-X names (``on``), or stop."""

    on: bool
    long_path: bool = False
    source: Source = Source.MQTT  # who asked
    described: str | None = None  # the command as the user gave it (a refusal names it)
    origin: Origin | None = None  # who asked (the status's last_operator)
    not_after_s: float | None = None  # a stamped start's expiry, as ``Track``'s (session.py
    # rule 13)


def call_of(text: str) -> str | None:
    """Rule 10: the DX call as shown, stripped, or None (none given, or no call sign)."""
    call = text.strip()
    if not call or len(call) > MAX_CALL or not (call.isascii() and call.isprintable()):
        return None  # (a call sign is ASCII: no line separator, no right-to-left override)
    return call


def grid_of(text: str) -> str | None:
    """A Maidenhead locator as WSJT-X writes it (``FN31``, ``fn31pr``), upper case, or None."""
    grid = text.strip().upper()
    return grid if grid and geo.is_locator(grid) else None


class Follower:
    def __init__(self, rig: WorkerConfig) -> None:
        self._rig = rig
        self.info: FollowingInfo | None = None  # None: not following
        self.ended: str | None = None
        self._heard: Heard | None = None
        self._heard_t = -math.inf
        self._aimed: str | None = None  # rule 2: the grid last turned to (or refused)
        self._bearing: float | None = None  # rule 1: the bearing last turned to (a hand's from)
        self._origin = Origin(Source.WSJTX)  # rule 7: what its targets carry
        self._turn_log_t = -math.inf  # rule 11: when a turn was last said at INFO
        self._turns_unsaid = 0  # rule 11: the turns since, said at DEBUG
        self._instance: str | None = None  # rule 8: the program followed
        self._ignored: OrderedDict[str, None] = OrderedDict()  # rule 8: the others heard last
        self._ignored_log_t = -math.inf  # rule 8: when the last line about them was logged
        self._ignored_since = 0  # rule 8: others first heard since then
        self._off_band: str | None = None  # rule 9: the band a grid was refused on, said
        # rules 4 and 8: each program's newest status, while it is on one of its bands (a
        # program's status on another band retires its own), newest last; bounded
        self._mine: OrderedDict[str, tuple[Heard, float]] = OrderedDict()
        self._before = Before()  # rule 1 (parts.py rule 8): the turn the start found
        self._halt = StartHalt()  # rule 5 (parts.py rule 10): the start's one halt

    @property
    def on(self) -> bool:
        return self.info is not None

    @property
    def owing(self) -> bool:
        """Following is on and its start's refusal owes a halt to a turn not yet seen (rule 5,
        parts.py rule 10): off, it owes nothing (feature_commands.py ``owing``)."""
        return self.info is not None and self._halt.owing

    def start(self, follow: Follow, now: float) -> None:
        """Rule 1; rule 4: only a fresh status turns the rotor at once."""
        self.info = FollowingInfo(Source.WSJTX.value, "long" if follow.long_path else "short")
        self.ended, self._aimed, self._bearing, self._off_band = None, None, None, None
        starter = follow.origin.operator if follow.origin is not None else None
        self._origin = Origin(Source.WSJTX, operator=starter)  # rule 7
        fresh = self._heard if now - self._heard_t <= FRESH_S else None
        mine = self._newest_mine(now)
        if (fresh is None or not self._for_me(fresh)) and mine is not None:
            fresh, self._heard_t = mine  # rule 4: the QSO on its band
        self._heard = fresh
        self._listen(fresh.instance if fresh is not None and self._for_me(fresh) else None)
        self._ignored.clear()
        self._before.start()
        self._halt.start()
        log.info("%s: following the QSO partner WSJT-X names", self._rig.rotator_id)

    def end(self, why: str) -> bool:
        """Stop following (``why`` shows as ``following_ended``); whether it was on."""
        if self.info is None:
            return False
        log.info("%s: following ended: %s", self._rig.rotator_id, why)
        self.info, self.ended, self._aimed, self._bearing = None, why, None, None
        return True

    def heard(self, heard: Heard, now: float) -> None:
        """The newest status (kept while off too: rule 4), of the program followed (rule 8)."""
        if self._rig.follow.bands:  # rule 4: each program's newest on its bands
            self._keep_mine(heard, now)
        if self.info is not None:
            if self._instance is None:
                if self._for_me(heard):  # rule 8: the first program on this antenna's band
                    self._listen(heard.instance)
            elif heard.instance != self._instance:
                self._ignore(heard.instance, now)
                return
            elif not self._for_me(heard):  # rule 8: it left this antenna's bands
                self._ignored.clear()
                mine = self._newest_mine(now)  # another program still on its bands, heard
                if mine is not None:  # (its own, retired by this status: _keep_mine)
                    self._listen(mine[0].instance)
                    self._heard, self._heard_t = mine
                    return
                self._listen(None)
        self._heard, self._heard_t = heard, now

    def _keep_mine(self, heard: Heard, now: float) -> None:
        """Rules 4 and 8: ``heard`` as its program's newest status: kept while on one of this
        antenna's bands, and retiring that program's older one when on another (what a program
        says now is where its dial is: a status it sent before its dial left the band is no
        QSO under way there)."""
        mine = self._mine
        if not self._for_me(heard):
            mine.pop(heard.instance, None)
            return
        mine[heard.instance] = (heard, now)
        mine.move_to_end(heard.instance)
        if len(mine) > MINE_KEPT:
            mine.popitem(last=False)

    def _newest_mine(self, now: float) -> tuple[Heard, float] | None:
        """Rules 4 and 8: the newest status of a program still on one of this antenna's
        bands, if at most FRESH_S old (None: none)."""
        if not self._mine:
            return None
        heard, t = next(reversed(self._mine.values()))
        return (heard, t) if now - t <= FRESH_S else None

    def _listen(self, instance: str | None) -> None:
        """Rule 8: the program followed (None: the first heard), shown in the status's info
        (not published: interfaces/wsjtx/server.py rule 5 keeps room for its statuses)."""
        self._instance = instance
        if self.info is not None and self.info.instance != instance:
            self.info = replace(self.info, instance=instance)

    def _ignore(self, instance: str, now: float) -> None:
        """Rule 8: another program's status; remembered (bounded) and said rarely."""
        ignored = self._ignored
        if instance in ignored:
            ignored.move_to_end(instance)
            return
        ignored[instance] = None
        if len(ignored) > IGNORED_KEPT:
            ignored.popitem(last=False)
        self._ignored_since += 1
        if now - self._ignored_log_t < IGNORED_LOG_S:
            return
        others = self._ignored_since - 1
        self._ignored_log_t, self._ignored_since = now, 0
        log.warning(
            "%s: following %r: the status of %r is ignored%s (switch following off and on to "
            "follow the program heard first then)",
            self._rig.rotator_id,
            (self._instance or "")[:NAME_SHOWN],
            instance[:NAME_SHOWN],
            f", and of {others} other program(s) since the last such line" if others else "",
        )

    def _turning(self, scene: Scene) -> bool:
        """Rule 3: its own turn is under way: its target waiting, or one out with the rotor
        turning (while it follows, any other target has ended it: rule 1)."""
        m = scene.motion
        own = scene.pending is not None and scene.pending.source is Source.WSJTX
        out = m.state is MotionState.MOVING and m.target_deg is not None
        return self._aimed is not None and (own or out)

    def _turned_by_hand(self, scene: Scene) -> bool:
        """Rule 1: turned away from the bearing it last turned to, by no target of the bridge's
        (before its first bearing: any such turn but the one its start found under way)."""
        before = self._before.look(scene)
        aim, tolerance = self._rig.aim, self._rig.motion.tolerance_deg
        return turned_by_hand(scene, aim, self._bearing, tolerance, before)

    def _for_me(self, heard: Heard) -> bool:
        """Rules 8 and 9: ``heard`` may choose the program followed: any, for a rotator
        without bands; one whose dial is on one of its bands, for a rotator with bands."""
        bands = self._rig.follow.bands
        return not bands or (heard.dial_hz is not None and band_of_hz(heard.dial_hz) in bands)

    def _on_my_band(self, heard: Heard) -> bool:
        """Rule 9: ``heard``'s dial is on one of this antenna's bands, or could be (no bands,
        no dial given)."""
        bands = self._rig.follow.bands
        return not bands or heard.dial_hz is None or band_of_hz(heard.dial_hz) in bands

    def _off_band_why(self, heard: Heard) -> tuple[str, str] | None:
        """Rule 9: the band ``heard`` is on and why it is not for this rotator's antenna, or
        None (it is)."""
        bands = self._rig.follow.bands
        if not bands:
            return None
        mine = ", ".join(bands)
        if heard.dial_hz is None:
            return "", f"following: WSJT-X gave no dial frequency, and this antenna is for {mine}"
        band = band_of_hz(heard.dial_hz)
        if band in bands:
            return None
        on = f"on {band}" if band is not None else "on no amateur band"
        dial = describe_hz(heard.dial_hz)
        why = f"following: WSJT-X's dial {dial} is {on}, and this antenna is for {mine}"
        return band or "?", why

    def step(self, scene: Scene) -> Proposal:
        """Run by the session with its other rules, while the controller answers."""
        info, heard = self.info, self._heard
        if info is None:
            return NOTHING
        if self._turned_by_hand(scene):  # rule 1: the session ends it (its targets dropped)
            return Proposal(ended=HAND, busy=True)
        if self._halt.owed(scene, self._bearing is None):  # rule 5: the first grid refused,
            return Proposal(halt=True, busy=True)  # the carried turn seen only now
        if heard is None:  # rule 6: following waits for WSJT-X, the rotor is not idle
            return Proposal(busy=True)
        grid = grid_of(heard.grid)
        if self._for_me(heard):  # rule 9: the dial is on one of its bands (again)
            self._off_band = None
        # rule 9: a transmission on another band goes out on another antenna: this one's turn
        # under way is not stopped for it (nor is it a turn this one waits for)
        holding = heard.transmitting and self._rig.follow.hold_while_tx and self._on_my_band(heard)
        if holding and self._turning(scene):  # rule 3: the turn under way stops
            self._aimed = None  # turned to again after the transmission
            self.info = replace(info, held=True)
            return Proposal(halt=True, busy=True)
        if grid is None or grid == self._aimed:  # rule 2
            if info.held:  # the grid held for is gone: nothing waits any more
                self.info = replace(info, held=False)
            return Proposal(busy=True)  # rule 6
        if holding:  # rule 3
            self.info = replace(info, held=True)
            return Proposal(busy=True)
        off_band = self._off_band_why(heard)
        if off_band is not None:  # rule 9: reported once, until the dial comes back
            if info.held:  # rule 3: the transmission ended; the grid waits for the band now
                self.info = replace(info, held=False)
            band, why = off_band
            said, self._off_band = self._off_band is not None, band
            if said:
                return Proposal(busy=True)
            what = f"follow {call_of(heard.call) or '?'} {grid}"
            return Proposal(error=Report(ErrorKind.REFUSED, why, what), busy=True)
        self._off_band = None
        self._aimed = grid
        call = call_of(heard.call)  # rule 10
        try:
            lat, lon = geo.parse_locator(grid)
            az, place = toward(
                self._rig.follow.station, lat, lon, long_path=info.path == "long", locator=grid
            )
            judged = self._rig.aim.judge(
                Target(az, None, Source.WSJTX, info=place, origin=self._origin),
                scene.motion.position_deg,
            )
        except (Refused, ValueError) as exc:  # rule 5
            why = exc.message if isinstance(exc, Refused) else str(exc)
            self.info = replace(info, call=call, grid=grid, bearing_deg=None, held=False)
            what = f"follow {call or '?'} {grid}"
            # (the start's first grid: the turn under way to an older target stopped, once,
            # as its own target would have stopped it: rule 2, parts.py rule 10)
            halt = self._halt.wanted(scene, self._bearing is None)
            error = Report(ErrorKind.REFUSED, f"following: {why}", what)
            return Proposal(error=error, busy=True, halt=halt)
        self._bearing = az
        self.info = replace(
            info, call=call, grid=grid, bearing_deg=az, distance_km=place.distance_km, held=False
        )
        self._say_turn(scene.now, call or "?", grid, az)
        return Proposal(target=judged, busy=True)

    def _say_turn(self, now: float, call: str, grid: str, az: float) -> None:
        """Rule 11: at INFO at most once per TURN_LOG_S, with the turns unsaid since."""
        if now - self._turn_log_t < TURN_LOG_S:
            self._turns_unsaid += 1
            log.debug("%s: following %s in %s: %.1f deg", self._rig.rotator_id, call, grid, az)
            return
        unsaid, self._turn_log_t, self._turns_unsaid = self._turns_unsaid, now, 0
        more = f" ({unsaid} more turn(s) since the last such line)" if unsaid else ""
        log.info("%s: following %s in %s: %.1f deg%s", self._rig.rotator_id, call, grid, az, more)
