"""Where the antenna points, in the user's terms: every way of naming a target becomes a true
bearing, is judged once and converted once to the controller's raw value; readings come back
through the same transform. Pure: no clock, no I/O.

Rules:
1. A target's azimuth is a true bearing, 0..360 clockwise from true north. The controller's
   raw value is the bearing minus ``offset_deg`` (a south-centred scale, a rotor mounted off
   north); a reading's true bearing is raw + offset, mod 360. Elevation has no offset.
2. On a rotor that can pass 360 (SPID, mechanically -180..540) every raw value r + k*360
   inside the limits points the same way: the one nearest the rotor's raw position when the
   target is sent is taken (least travel; a move inside the mechanical range never crosses a
   stop), and without a reading the one nearest the middle of the range. The judge checks
   that one exists and marks the target (Target.true_az_deg); the engine picks the side when
   it sends, from the position it has then (a target that waited, e.g. for a brake, is not
   sent to the side that was nearest when it came; a nudge's side is its own: rule 6). A
   target outside 0..360 on such a rotor names the side itself: 400 is "40, past north
   clockwise" (raw = value - offset), and a
   client that named it reads the rotor the same way (``unfolded``: raw + offset, the offset
   read from the true bearing beside the raw value, so the remote, whose pointing has none,
   reads it too). A
   controller whose scale wraps gets the value in 0..360 as the target names it: 360 named is
   360 (the end of a GS-232's or an Easycomm box's travel clockwise of 350, as Hamlib sends
   ``P 360``; 0 is the other end, a whole turn back: a rotor at 350 asked for 360 was sent
   ``W000``, and turned 350 degrees the long way round). A bearing the offset brings to north
   (true 180 with offset 180; true 350 with offset -10) names neither end, and a target that
   names neither end (``Target.az_either_end``: a group member's bearing after its group
   offset, interfaces/mqtt/groups.py rule 2) goes,
   where both ends are legal (after its arc, rule 9) and 0 and 360 are the ends of the travel,
   to the end nearer the rotor's reading (equals, or no reading: 0; a cold review: true 350
   with offset -10 went out as 360, and a GS-232 at true 0 turned 350 degrees the long way
   round; attack 10: the group's 180 was north for a member with offset 180, and a GS-232 at
   355 was sent ``M000``, as was the rotator's own target of 180 with that offset); where a
   limit leaves only one end, that one. So does a value the controller is sent as north after
   its rounding (rule 4: 0.4 on a GS-232, 356 on a SatEL; ``_north_step``, not inside a
   group's arc; review 42: a member's 0.4 from 355 went out as ``M000``). The nearer end is
   picked again from where the rotor is when the target is sent (``_end_free``: a target that
   waited, a SatEL that stops before it takes one; review 44; a group member's too, review
   45), but where a group's arc that leaves part of the circle out decided it: judged once.
3. Keep-out sectors are true bearings, clockwise from the first edge to the second, edges
   included. A target in one is refused however it was named (number, preset, locator,
   rotctld). The rotor may sweep through a sector on its way; it never stops there.
4. Limits are mechanical: checked on the raw value, after rounding on controllers that take
   whole degrees or tenths (never rounded past a limit, nor into a keep-out sector: rule 3 holds
   for what the controller is sent). Where the travel runs through the scale's 0 and 360 (a
   Hy-Gain rotor's stop is at south, north mid-travel) limits that leave part of the scale out
   are held along the turn as a group's arc is (rule 9), from the rotor's reading: a helper,
   limits 20..340 on a Rotor-EZ at 30 sent 330 swept through north, 27 readings outside them.
   With no reading (a DCU-1, which never answers) the way is not known: its end is checked.
   Only where the stop is known to be at south (``stop_at_south``: not an RT-21's, which may
   turn a Yaesu through south; a review: with limits 2..358 it could no longer leave its half).
   A target at the stop itself (raw 180) is refused under such limits, named or with no
   reading: there no reading tells which end the rotor is at, and from one of them every turn
   passes north (a review: parked at 180, every target after was refused).
5. A refusal raises Refused with a message naming the true and the raw value when they differ;
   a value past a limit is quoted with the digits that keep it past it (core/text.py
   ``shown_past``: attack 28, 360.00001 was refused as "azimuth 360 outside 0..360").
6. The other ways of naming a target become a true bearing here, before the judge: a preset,
   the park position, a place (locator or coordinates: the great-circle bearing from the
   station, short path unless the long one is asked for; core/geo.py) and a nudge (relative to the
   target while one is being approached, turning or braking, else to the bearing; never to a
   target a stop put before it dropped, though the status it is made from predates that stop:
   runtime/rotator.py ``_seen``). On a controller of steps (rule 4: a SatEL's ten degrees) a
   nudge, in azimuth or elevation, goes to the nearest step of the value it names and at
   least the first step past where it starts its own way (``_stepped``): -5 at 120 is 110 as
   +5 is 130 (rounded alone, 115 went out as 120 and nothing turned), and a second press
   counts from the step the status shows as the target, so two of +5 end at 140; one of less
   than half a step is refused (it names far less than the least the controller turns). A nudge
   turns the short way it names. Where the controller's
   0 and 360 are the ends of the travel (``az_ends_at_north``: the stop at north, a GS-232's,
   an Easycomm's, a SatEL's), it is taken on the controller's own scale: +10 at 350 is 360,
   10 degrees on (``Target.az_end_deg``; folded to 0 it went out as the other end, ``M000``,
   and the rotor turned 350 degrees back through south), and a nudge past an end (+10 at 360,
   -10 at 0) is refused, never taken the whole way round, as past a SPID's stop. On a scale
   that does not wrap (a SPID, a 450-degree Yaesu) a nudge is a move along the travel: its raw
   value is the one it counts from plus the step, refused past a limit and sent as it is
   (``Target.az_end_deg``), never taken as a bearing (attack 10: a 450-degree GS-232B with
   limits 20..440 at 30, nudged -15, named 15, whose one raw value inside them is 375: it was
   sent ``W375`` and turned 345 degrees clockwise), nor its side left to the engine (rule 2:
   a SPID turning from 100 to 300, nudged +10, went to -50, 150 degrees back). Where north
   is the middle of the travel (a Hy-Gain rotor's stop is at south: a Rotor-EZ, a DCU-1) or
   the controller is never sent 360 and turns its own way (an RT-21), it is folded as before:
   +10 at 355 goes out as 5 (``AP1005``), the turn across north the controller makes; but a
   nudge across raw 180 is refused, and any nudge from raw 180 itself (a Hy-Gain rotor cannot
   pass its stop there: +10 at 175 went out as ``AP1185``, a turn of 350 degrees through
   north, and at the stop no reading says which end the rotor is at; an RT-21 may turn a
   Hy-Gain rotor too). A
   nudge is less than a turn each way: a step of 360 degrees or more is refused (an attack
   pass: ``1e308`` turned a rotor to its remainder, 296, and ``720`` was taken as no step at
   all).
7. A place without a direction from the station is refused: the station's own position (no
   bearing at all) and its antipode, where every direction is a great circle of the same
   length (a locator's centre has one: JO62qm's is AD67ql). Anything short of these has a
   bearing and is taken, even close to the antipode, where the bearing swings with the
   station's exact position: that is the great circle from the position configured.
8. A target already in raw values (one a session part made: a feature's, judged by its own
   code) is checked again by ``check_raw`` against the limits and the keep-out sectors, with
   the messages of rules 3-5: the session sends nothing those refuse, whoever judged it.
9. A target may carry an arc its turn must stay inside (``Target.within_deg``, true bearings:
   a group member's limits, interfaces/mqtt/groups.py rule 2). Of the raw values that point
   its way (rule 2), the judge takes one whose turn from where the rotor is stays inside, and
   refuses the target if there is none; from outside the arc, the one that turns least
   outside it. Its side is then fixed: the session sends that value, not the side nearest
   when it sends. With no reading to judge from (a DCU-1, which never answers), the target is
   refused unless no turn can leave the arc (a scale of true bearings that wraps, no offset,
   and an arc clear of north, where its stop is), since the way it turns depends on where the
   rotor is. A review: a group's
   ``upper = [20, 340]`` on a 450-degree rotor at 300, sent 30, went to 390, through the
   340..20 the group keeps it out of; an attack pass: a south-centred DCU-1 at true 300, sent
   the group's 30, turned through north on its scale (120 to 210). A scale that wraps with
   its ends not known to be at its 0 and 360 (``az_ends_at_north`` False: a Rotor-EZ's or
   DCU-1's Hy-Gain rotor has its stop at south, raw 180, north mid-travel; an RT-21 turns its
   own way) is judged both ways round, the turn taken only if it stays inside either way, and
   with no reading an arc must be clear of south too (an attack pass: a Rotor-EZ at 300 in a
   group with ``[20, 340]`` was sent the group's 30 as ``AP1030``, judged as a turn through
   south, which its rotor cannot pass: it turns through north, out of the group's limits).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, field, replace

from bridge.core import geo
from bridge.core.errors import RefusalCode, Refused
from bridge.core.model import MotionState, RotatorStatus, Target, TargetInfo
from bridge.core.text import shown_past
from bridge.protocols.base import ModelSpec, half_up, half_up_step

MAX_NUDGE_DEG = 360.0  # rule 6: a nudge is less than a turn either way
WITHIN_SLACK_DEG = 0.5  # rule 9: a reading's step at an edge is not a turn outside
UNFOLD_TIE_DEG = 1e-6  # rule 2: an offset read this near -180 is 180 (``unfolded``)


def norm360(deg: float) -> float:
    """``deg`` folded into [0, 360) (never 360, never -0.0)."""
    out = deg % 360.0
    return 0.0 if out >= 360.0 or out == 0.0 else out


def unfolded(bearing_deg: float | None, raw_deg: float | None) -> float | None:
    """Rule 2: a reading as a target that names its side says it (400, not 40): raw + offset,
    the offset read from the true bearing beside the raw value (the settings keep it in
    (-180, 180]), so that a far client's reading needs no offset (the remote's pointing has
    none: its ranges are true bearings already); None without both values. (A review: the
    remote added its own offset, none, to the station's raw value: AZ=390 for 400 on a rotor
    mounted 10 degrees off north, AZ=220 on a south-centred one.)"""
    if bearing_deg is None or raw_deg is None:
        return None
    offset = 180.0 - (180.0 - (bearing_deg - raw_deg)) % 360.0
    if offset < UNFOLD_TIE_DEG - 180.0:  # (180 that rounding put a hair past -180)
        offset += 360.0
    return raw_deg + offset


def raw_reading(status: RotatorStatus) -> float | None:
    """Rule 1: the raw value of ``status``'s reading: its raw bearing, else its bearing (a
    status read from the station's ``R/status``, which leaves the raw bearing out where it
    tells nothing more: no offset and a scale that wraps, ``shows_raw``), else None. North's
    nearer end is picked by it (``Pointing.least_turn``; review 64: the remote had no raw
    bearing, and a DCU-1's north through it went to the far end; a logger's too)."""
    raw = status.raw_bearing_deg
    return status.bearing_deg if raw is None else raw


def at_south_stop(raw_deg: float) -> bool:
    """Whether ``raw_deg`` is a Hy-Gain rotor's stop, raw 180, where no reading tells which end
    of its travel it is at (rules 4 and 6)."""
    return raw_deg % 360.0 == 180.0


def angle_between(a_deg: float, b_deg: float) -> float:
    """The smaller angle between two bearings, 0..180, whatever turns either names."""
    return abs((a_deg - b_deg + 180.0) % 360.0 - 180.0)


def in_sector(bearing_deg: float, sector: tuple[float, float]) -> bool:
    """``bearing_deg`` lies in the sector clockwise from its first edge to its second (rule 3)."""
    start, end = norm360(sector[0]), norm360(sector[1])
    b = norm360(bearing_deg)
    if start <= end:
        return start <= b <= end
    return b >= start or b <= end


@dataclass(frozen=True)
class Pointing:
    """One rotator's transform and judge (app.py builds it from the settings)."""

    model_name: str = "rotator"
    az_min_deg: float = 0.0  # mechanical (raw) limits
    az_max_deg: float = 360.0
    el_min_deg: float = 0.0
    el_max_deg: float = 0.0
    has_elevation: bool = False
    az_wraps: bool = True  # the controller's 0 and 360 are the same direction
    az_ends_at_north: bool = True  # and the two ends of the travel (rule 6)
    stop_at_south: bool = False  # a Hy-Gain rotor's: north mid-travel, known (rule 4)
    whole_degrees: bool = False
    steps_deg: int = 1  # (whole degrees in steps of this many: a SatEL's ten)
    tenths: bool = False
    cuts_down: bool = False
    el_rounding: tuple[bool, bool, bool, int] | None = None  # a composite's elevation box's
    offset_deg: float = 0.0
    keep_out: tuple[tuple[float, float], ...] = ()
    presets: dict[str, tuple[float, float | None]] = field(default_factory=dict)
    park: tuple[float, float | None] | None = None  # true bearing (and elevation)

    @classmethod
    def of(
        cls,
        spec: ModelSpec,
        az_limits: tuple[float, float] | None = None,
        el_limits: tuple[float, float] | None = None,
        *,
        offset_deg: float = 0.0,
        keep_out: tuple[tuple[float, float], ...] = (),
        presets: dict[str, tuple[float, float | None]] | None = None,
        park: tuple[float, float | None] | None = None,
    ) -> Pointing:
        """The model's facts and limits (its whole range unless given), and the user's terms."""
        az_lo, az_hi = az_limits or (spec.az_min_deg, spec.az_max_deg)
        el_lo, el_hi = el_limits or (spec.el_min_deg, spec.el_max_deg)
        return cls(
            model_name=spec.display_name,
            az_min_deg=az_lo,
            az_max_deg=az_hi,
            el_min_deg=el_lo,
            el_max_deg=el_hi,
            has_elevation=spec.has_elevation,
            az_wraps=spec.az_wraps,
            az_ends_at_north=spec.az_ends_at_north,
            stop_at_south=spec.stop_at_south,
            whole_degrees=spec.whole_degrees,
            steps_deg=spec.steps_deg,
            tenths=spec.tenths,
            cuts_down=spec.cuts_down,
            el_rounding=spec.el_rounding,
            offset_deg=offset_deg,
            keep_out=keep_out,
            presets=dict(presets or {}),
            park=park,
        )

    # -- readings (rule 1) ---------------------------------------------------------------------
    @property
    def shows_raw(self) -> bool:
        """Whether the raw value tells the user more than the bearing does."""
        return self.offset_deg != 0.0 or not self.az_wraps

    def true_of(self, raw_deg: float) -> float:
        return norm360(raw_deg + self.offset_deg)

    def at_360(self, raw_deg: float | None) -> bool:
        """Whether a reading of ``raw_deg`` is the true bearing 360 that a target of 360 sends
        the rotor to on a scale that wraps (rule 2: raw + offset is 360, the clockwise end,
        not 0), so that a client that reads it back as its target names the same end."""
        return self.az_wraps and raw_deg is not None and raw_deg + self.offset_deg == 360.0

    def overlap(self, raw_deg: float | None) -> str | None:
        """Which way past the scale a rotor that can pass 360 is: "cw" above 360, "ccw" below 0."""
        if raw_deg is None or self.az_wraps:
            return None
        if raw_deg > 360.0:
            return "cw"
        if raw_deg < 0.0:
            return "ccw"
        return None

    # -- targets (rules 2-5) -------------------------------------------------------------------
    def target_range(self) -> tuple[float, float]:
        """The azimuth targets a user may name, in true bearings (rules 1, 2): the limits as
        they are without an offset; with one, 0..360 on a scale that wraps, else 0..360 and
        the limits shifted by the offset (a SPID's or a 450-degree rotor's overlap names the
        side itself; a review: a 450-degree GS-232 with offset 180 said 180..630, and
        Hamlib's ``rotctl -m 2``, which takes \\dump_state's range, refused ``P 90`` itself);
        0..360 only where every bearing has a raw value inside the limits (limits narrowed
        under a turn, 0..300 with offset 30: 30..330, not 0..360, whose ends the judge refuses)."""
        lo, hi = self.az_min_deg, self.az_max_deg
        if not self.offset_deg:
            return lo, hi
        if self.az_wraps:
            return 0.0, 360.0
        if hi - lo < 360.0:
            return lo + self.offset_deg, hi + self.offset_deg
        return min(0.0, lo + self.offset_deg), max(360.0, hi + self.offset_deg)

    def keep_out_of(self, bearing_deg: float) -> tuple[float, float] | None:
        return next((s for s in self.keep_out if in_sector(bearing_deg, s)), None)

    def turn_deg(self, az_deg: float, current_raw_deg: float) -> float:
        """How far the rotor at ``current_raw_deg`` turns for a target of ``az_deg`` (the raw
        value the judge takes), along its travel (core/geo.py ``travel_deg``); inf if the judge
        refuses it (a limit, a keep-out sector: an attack pass, N1MM's heading in a sector was
        chosen for the shorter turn and refused, where its reciprocal was free)."""
        try:
            raw = self.judge(Target(az_deg), current_raw_deg).az_deg
        except Refused:
            return math.inf
        if raw is None:
            return math.inf
        return geo.travel_deg(current_raw_deg, raw, self.az_wraps, self.az_ends_at_north)

    def least_turn(self, named: Iterable[float], status: RotatorStatus) -> float:
        """Of the azimuths ``named``, each folded into 0..360, the one the rotor turns least to
        (``turn_deg``) from ``status``'s reading (``raw_reading``); north, 0 or 360, names
        both ends of the travel (0 first), as a logger's north does (it names a direction:
        interfaces/loggers/commands.py rule 3) and a DCU-1's 000 (rule 2, ``az_either_end``).
        The first of equals; without a reading, the first as named. One choice for the
        loggers' ``heading`` and the remote's ``_end_named`` (remote/rotator.py rule 3): a
        status read from the station's ``R/status`` has no raw bearing where it equals the
        bearing, and the loggers' north through the remote, picked by the raw bearing alone,
        went out as 0, the counter-clockwise end: a Yaesu at 355 turned back through south."""
        ways = [n for w in named for n in ((0.0, 360.0) if norm360(w) == 0.0 else (norm360(w),))]
        raw = raw_reading(status)
        if raw is None:
            return ways[0]
        return min(ways, key=lambda a: self.turn_deg(a, raw))

    def _north_step(self, raw_deg: float, current_raw_deg: float | None) -> float | None:
        """Rule 2 on a controller that rounds (a SatEL's ten degrees, a GS-232's whole degrees,
        tenths: rule 4) whose 0 and 360 are the ends: a value that goes out as north, named as
        neither end (356 goes out as 360 on a SatEL, 4 as 0; 0.4 as 0 on a GS-232), is the end
        nearer the rotor (an attack pass: at 10, 356 went out as 360 and the rotor turned 350
        degrees to the north it stood 10 from; review 42: a group member's 0.4 from 355 went
        out as M000, the same on a GS-232). None where it is not."""
        if not self.az_ends_at_north or current_raw_deg is None:
            return None
        if raw_deg in (0.0, 360.0) or self._sent(raw_deg)[0] not in (0.0, 360.0):
            return None
        end = 360.0 if current_raw_deg > 180.0 else 0.0
        return end if self._sent_within(end, self.az_min_deg, self.az_max_deg) else None

    def el_sendable(self) -> tuple[float, float]:
        """The elevation limits, each moved in to the nearest value the controller is sent as
        itself (rule 4): a SatEL's 75 goes out as 80, so its highest is 70; the limits as they
        are where none is between them. What tracking holds an elevation to (an attack pass:
        held to 75, every target was refused and the rotor never moved)."""
        lo, hi = self.el_min_deg, self.el_max_deg
        whole, tenths, _cuts, steps = self._rounds(True)
        q = float(steps) if whole else 0.1 if tenths else None
        if q is None:
            return lo, hi
        top = hi if self._sent_within(hi, lo, hi, True) else math.floor(hi / q + 1e-9) * q
        bottom = lo if self._sent_within(lo, lo, hi, True) else math.ceil(lo / q - 1e-9) * q
        if bottom > top or not self._sent_within(top, lo, hi, True):
            return lo, hi
        return bottom, top

    def raw_for(
        self,
        az_deg: float,
        current_raw_deg: float | None,
        within: tuple[float, float] | None = None,
        end: float | None = None,
        either_end: bool = False,
    ) -> float:
        """The raw azimuth for a target of ``az_deg`` (rules 1, 2, 4); Refused if none is legal,
        or if ``within`` (rule 9) is given and every legal one turns outside it. ``end``: the
        end of a scale that wraps a nudge turns to (rule 6), taken where it is legal; on a
        scale that does not wrap, the raw value a nudge turns to, checked and taken as it is;
        ``either_end``: ``az_deg`` names no end of it (rule 2: a group member's bearing)."""
        lo, hi = self.az_min_deg, self.az_max_deg
        if not math.isfinite(az_deg):
            raise Refused(RefusalCode.LIMITS, "azimuth must be a finite number")
        if not self.az_wraps and end is not None:  # rule 6: where a nudge turns to, as it is
            raw = self._checked(az_deg, end)
            if within is not None:
                self._within(az_deg, current_raw_deg, [raw], within)
            return raw
        if not 0.0 <= az_deg <= 360.0:
            if self.az_wraps:
                raise Refused(
                    RefusalCode.LIMITS, f"azimuth {shown_past(az_deg, 0.0, 360.0)} outside 0..360"
                )
            raw = self._checked(az_deg, az_deg - self.offset_deg)
            if within is not None:
                self._within(az_deg, current_raw_deg, [raw], within)
            return raw
        base = norm360(az_deg - self.offset_deg)
        legal = [
            base + k * 360.0
            for k in range(math.floor((lo - base) / 360.0), math.ceil((hi - base) / 360.0) + 1)
            if self._sent_within(base + k * 360.0, lo, hi)
        ]
        if not legal:
            return self._checked(az_deg, base)  # raises, naming the raw value
        if within is not None:
            legal = self._within(az_deg, current_raw_deg, legal, within)
        self._at_the_stop(az_deg, legal)
        limits = self._limits_arc(current_raw_deg)
        if limits is not None:  # rule 4: the turn, not its end alone, on a travel through north
            try:
                legal = self._within(az_deg, current_raw_deg, legal, limits, self._limits_text())
            except Refused:
                if current_raw_deg is not None and at_south_stop(current_raw_deg):
                    raise Refused(
                        RefusalCode.LIMITS,
                        f"azimuth {az_deg:g}: the {self.model_name} is at its stop (controller "
                        "180), where no reading tells which end of its travel it is at; from "
                        f"one of them the turn leaves {self._limits_text()}: turn it off the "
                        "stop at the controller",
                    ) from None
                raise
        if self.az_wraps:  # rule 2: 360 named is 360 (no offset); else 0 rather than 360
            if end is not None:  # rule 6: the end a nudge turns to, never the other one
                if end in legal:
                    return end
                self._checked(az_deg, end)  # raises, naming the limits
                arc = f"{within[0]:g}..{within[1]:g}" if within else "its limits"
                raise Refused(
                    RefusalCode.LIMITS,
                    f"azimuth {az_deg:g} (controller {end:g}) is not reached without turning "
                    f"outside {arc}",
                )
            # (rule 2: a bearing the offset brings to north names neither end either)
            either_end = either_end or (bool(self.offset_deg) and base == 0.0)
            if either_end and self.az_ends_at_north and current_raw_deg is not None:
                at, ends = current_raw_deg, [r for r in legal if r in (0.0, 360.0)]
                if len(ends) == 2:  # rule 2: named as neither end, the nearer (equals: 0)
                    return min(ends, key=lambda r: abs(r - at))
            if az_deg == 360.0 and not self.offset_deg and az_deg in legal:
                return az_deg
            north = None if within is not None else self._north_step(base, current_raw_deg)
            if north is not None:  # (not for an arc: rule 9 judged the value named)
                return north
            raw = base if base in legal else legal[-1]
            if not lo <= raw <= hi and self._rounds(False)[3] > 1:
                raw = self._sent(raw)[0]  # a SatEL's -4 goes out as 0: check_raw's terms too
            return raw
        anchor = (lo + hi) / 2 if current_raw_deg is None else current_raw_deg
        return min(legal, key=lambda r: (abs(r - anchor), r))

    def _limits_arc(self, current_raw: float | None) -> tuple[float, float] | None:
        """Rule 4: the limits as an arc of true bearings a turn must stay inside, where the
        travel runs through the scale's 0 and 360 (a Hy-Gain rotor's stop at south: a turn from
        30 to 330 sweeps through north) and the limits leave some of it out; None elsewhere (a
        turn between two values inside limits stays inside them) and with no reading (which way
        a turn goes is not known: its end is checked, as on every scale)."""
        if current_raw is None or not self._narrowed_through_north():
            return None
        return self.az_min_deg + self.offset_deg, self.az_max_deg + self.offset_deg

    def _narrowed_through_north(self) -> bool:
        """Rule 4: a Hy-Gain rotor's travel (its stop at south, north mid-travel) whose limits
        leave part of the scale out."""
        whole = self.az_min_deg <= 0.0 and self.az_max_deg >= 360.0
        return self.stop_at_south and self.az_wraps and not whole

    def _at_the_stop(self, az_deg: float, legal: list[float]) -> None:
        """Rule 4: Refused for a target that leaves a Hy-Gain rotor at its stop under narrowed
        limits: there no reading tells which end of its travel it is at, and from one of them
        any turn passes north (a review: at 180, every target was refused)."""
        if not self._narrowed_through_north():
            return
        if any(at_south_stop(sent) for r in legal for sent in self._sent(r)):  # (as sent:
            # an attack pass, 179.6 went out as AP1180 and the rotor was left at its stop)
            east, west = self.true_of(179.0), self.true_of(181.0)
            raise Refused(
                RefusalCode.LIMITS,
                f"azimuth {az_deg:g} is sent to the {self.model_name} as its stop (controller "
                "180): there no reading tells which end of its travel the rotor is at, and the "
                f"limits {self.az_min_deg:g}..{self.az_max_deg:g} need it to judge a turn from "
                f"there; send {east:g} or {west:g}",
            )

    def _limits_text(self) -> str:
        text = f"the limits {self.az_min_deg:g}..{self.az_max_deg:g}"
        return text + (" (controller)" if self.offset_deg else "")

    def _outside_deg(self, from_raw: float, to_raw: float, within: tuple[float, float]) -> float:
        """Rule 9: how many degrees of the turn from ``from_raw`` to ``to_raw`` lie outside
        ``within`` (true bearings, lower first): on the raw scale, and on a scale that wraps
        with its ends not known to be at its 0 and 360 (``az_ends_at_north`` False: a Hy-Gain
        rotor's stop is at its south, raw 180; an RT-21 turns its own way) the other way round
        too, the more of the two."""
        if within[1] - within[0] >= 360.0:
            return 0.0
        outside = self._swept_outside(min(from_raw, to_raw), max(from_raw, to_raw), within)
        if not self.az_wraps or self.az_ends_at_north:
            return outside
        for u0 in geo.on_south_travel(from_raw):  # (at the stop: either end)
            u1 = min(geo.on_south_travel(to_raw), key=lambda u: abs(u - u0))  # (the end nearer)
            outside = max(outside, self._swept_outside(min(u0, u1), max(u0, u1), within))
        return outside

    def _swept_outside(self, r0: float, r1: float, within: tuple[float, float]) -> float:
        """Rule 9: the degrees of a sweep over raw ``r0``..``r1`` outside ``within``."""
        lo, hi = within
        t0, t1 = r0 + self.offset_deg, r1 + self.offset_deg
        inside = 0.0
        for k in range(math.floor((t0 - hi) / 360.0), math.ceil((t1 - lo) / 360.0) + 1):
            inside += max(0.0, min(t1, hi + 360.0 * k) - max(t0, lo + 360.0 * k))
        return (t1 - t0) - inside

    def _within(
        self,
        az_deg: float,
        current_raw: float | None,
        legal: list[float],
        within: tuple[float, float],
        arc: str | None = None,
    ) -> list[float]:
        """Rule 9: the legal raw values whose turn from ``current_raw`` stays inside ``within``
        (from a rotor outside it: those that turn least outside it); Refused if none, and
        where no reading shows the way (``current_raw`` None) unless no turn can leave it. The
        turn is judged to the value the controller is sent (rule 4: a SatEL's 335 goes out as
        340, outside a group's 20..335). ``arc``: what the refusal calls ``within``."""
        lo, hi = within
        arc = arc or f"{lo:g}..{hi:g}"
        if current_raw is None:
            # a scale of true bearings that wraps (no offset) turns between two bearings of an
            # arc clear of its stop without leaving it; an arc that ends at north (0..90,
            # 300..360) has the stop at its end, where north is raw 0 or 360 (the DCU-1 gets
            # 360 as 000: at true 330, the group's 0 turned it 330 -> 0 the long way round,
            # and from there the next 310 went round again); elsewhere the way depends on
            # where the rotor is
            clear = 0.0 < lo and hi < 360.0
            if not self.az_ends_at_north:  # (nor its south: a Hy-Gain's stop, raw 180)
                clear = clear and not lo < 180.0 < hi
            if hi - lo >= 360.0 or (clear and self.az_wraps and self.offset_deg % 360.0 == 0.0):
                return legal
            raise Refused(
                RefusalCode.LIMITS,
                f"azimuth {az_deg:g}: the {self.model_name} has no reading of where it points, "
                f"so a turn that stays inside {lo:g}..{hi:g} cannot be chosen",
            )
        outside = [
            max(self._outside_deg(current_raw, sent, within) for sent in self._sent(r))
            for r in legal
        ]
        least = min(outside)
        at = self.true_of(current_raw)
        if any(lo <= at + k <= hi for k in (-360.0, 0.0, 360.0)) and least > WITHIN_SLACK_DEG:
            raise Refused(
                RefusalCode.LIMITS,
                f"azimuth {az_deg:g} is not reached from {self.true_of(current_raw):g} without "
                f"turning outside {arc}",
            )
        return [r for r, out in zip(legal, outside, strict=True) if out <= least]

    def judge(self, target: Target, current_raw_deg: float | None) -> Target:
        """``target`` (true bearings) checked and converted to the controller's raw values."""
        if target.az_deg is None and target.el_deg is None:
            raise Refused(RefusalCode.INVALID, "target without azimuth or elevation")
        raw_az: float | None = None
        if target.az_deg is not None:
            sector = self.keep_out_of(target.az_deg) if math.isfinite(target.az_deg) else None
            if sector is not None:
                raise Refused(
                    RefusalCode.KEEP_OUT,
                    f"azimuth {target.az_deg:g}{self._folded(target.az_deg)} is in the "
                    "keep-out sector "
                    f"{sector[0]:g}..{sector[1]:g}: refused",
                )
            raw_az = self.raw_for(
                target.az_deg,
                current_raw_deg,
                target.within_deg,
                target.az_end_deg,
                target.az_either_end,
            )
            self._check_sent_keep_out(target.az_deg, raw_az)
        if target.el_deg is not None:
            if not self.has_elevation:
                raise Refused(RefusalCode.UNSUPPORTED, f"{self.model_name} has no elevation axis")
            el, lo, hi = target.el_deg, self.el_min_deg, self.el_max_deg
            if not math.isfinite(el) or not lo <= el <= hi:
                raise Refused(
                    RefusalCode.LIMITS,
                    f"elevation {shown_past(el, lo, hi)} outside the limits {lo:g}..{hi:g}",
                )
            if not self._sent_within(el, lo, hi, el=True):
                why = self._rounding(f"elevation {el:g}", el, lo, hi, el=True)
                raise Refused(RefusalCode.LIMITS, why)
        arc = target.within_deg
        fixed = arc is not None and current_raw_deg is not None and arc[1] - arc[0] < 360.0
        fixed = fixed or target.az_end_deg is not None  # (rule 9: an arc; rule 6: a nudge's)
        side_free = None if fixed else self._side_free(target.az_deg)
        either = False
        if side_free is None and not fixed and self._end_free(target, raw_az):
            side_free = target.az_deg  # rule 2: its end picked again when it is sent
            either = target.az_either_end  # (as named: neither end)
        # (rule 9: its side; rule 6: the raw value a nudge turns to is in ``raw_az`` now)
        return replace(
            target, az_deg=raw_az, true_az_deg=side_free, az_end_deg=None, az_either_end=either
        )

    def check_raw(self, target: Target) -> None:
        """Rule 8: Refused if the controller may not be sent ``target`` (raw values)."""
        if target.az_deg is not None:
            raw = target.az_deg
            if not math.isfinite(raw):
                raise Refused(RefusalCode.LIMITS, "azimuth must be a finite number")
            true = raw + self.offset_deg
            sector = self.keep_out_of(true)
            if sector is not None:
                raise Refused(
                    RefusalCode.KEEP_OUT,
                    f"azimuth {norm360(true):g} is in the keep-out sector "
                    f"{sector[0]:g}..{sector[1]:g}: refused",
                )
            self._checked(true, raw)
            self._check_sent_keep_out(true, raw)
        if target.el_deg is not None:
            el, lo, hi = target.el_deg, self.el_min_deg, self.el_max_deg
            if not self.has_elevation:
                raise Refused(RefusalCode.UNSUPPORTED, f"{self.model_name} has no elevation axis")
            sent = math.isfinite(el) and self._sent_within(el, lo, hi, el=True)
            if not math.isfinite(el) or not lo <= el <= hi or not sent:
                raise Refused(
                    RefusalCode.LIMITS,
                    f"elevation {shown_past(el, lo, hi)} outside the limits {lo:g}..{hi:g}",
                )

    def _end_free(self, target: Target, raw_az: float | None) -> bool:
        """Rule 2: ``target`` was sent to an end (``raw_az``) it does not name, the nearer one,
        so the end is picked again from where the rotor is when it is sent (a bearing the
        offset or the rounding brings to north; review 44: a south-centred SatEL asked for
        true 180 mid-slew was judged by its slew's estimate, 199, sent ``360`` and turned 212
        degrees through its south from 148); a group member's ``az_either_end`` too, where no
        arc that leaves part of the circle out decides it (review 45: the same swing for a
        stack's member with no limits of its own), its flag kept for ``resolve``."""
        az = target.az_deg
        if az is None or raw_az not in (0.0, 360.0):
            return False
        if not (self.az_wraps and self.az_ends_at_north):
            return False
        if target.az_either_end:
            return True
        return not (az in (0.0, 360.0) and not self.offset_deg)  # (an end named: that end)

    def _side_free(self, az_deg: float | None) -> float | None:
        """``az_deg`` if the rotor may take it on either side (rule 2), else None."""
        if az_deg is None or self.az_wraps or not 0.0 <= az_deg <= 360.0:
            return None
        return az_deg

    # -- naming a target (rule 6) ------------------------------------------------------------
    def preset(self, name: str) -> tuple[float, float | None]:
        if name not in self.presets:
            have = ", ".join(self.presets) or "none configured"
            raise Refused(RefusalCode.INVALID, f"no preset {name!r} (presets: {have})")
        return self.presets[name]

    def parking(self) -> tuple[float, float | None]:
        if self.park is None:
            raise Refused(RefusalCode.UNSUPPORTED, "no park position configured (park_az_deg)")
        return self.park

    def _clear_of_south(self, raw: float, d_az: float) -> None:
        """Rule 6: a nudge of ``d_az`` from ``raw`` on a scale whose stop may be at raw 180 (a
        Hy-Gain rotor's) stays on its side of it, or is refused."""
        past = (raw - 180.0) % 360.0  # clockwise from the stop
        if past != 0.0 and 0.0 <= past + d_az <= 360.0:
            return
        where = "starts at" if past == 0.0 else "crosses"
        raise Refused(
            RefusalCode.LIMITS,
            f"a nudge of {d_az:+.10g} degrees {where} south on the {self.model_name}'s scale "
            f"(controller {raw:g}), where a Hy-Gain rotor has its stop: it would turn the whole "
            "way round; send a target",
        )

    def nudge(
        self, status: RotatorStatus, d_az: float, d_el: float | None, halted: bool = False
    ) -> Target:
        """Rule 6's nudge from ``status`` as a target to judge: true bearings, and the end of
        the travel it turns to where 0 and 360 are ends; ``halted`` as in ``nudged``."""
        az, el, end = self._nudge(status, d_az, d_el, halted)
        return Target(az, el, az_end_deg=end, nudge=True)

    def nudged(
        self, status: RotatorStatus, d_az: float, d_el: float | None, halted: bool = False
    ) -> tuple[float | None, float | None]:
        """Rule 6's nudge from ``status``; ``halted``: a stop came after that status was made
        (its target dropped: the nudge is from the bearing)."""
        az, el, _end = self._nudge(status, d_az, d_el, halted)
        return az, el

    def _nudge(
        self, status: RotatorStatus, d_az: float, d_el: float | None, halted: bool
    ) -> tuple[float | None, float | None, float | None]:
        """``nudged``, and the raw end of the travel it turns to (rule 6), if it turns to one."""
        if not d_az and not d_el:
            raise Refused(RefusalCode.INVALID, "a nudge of 0 degrees moves nothing")
        for step, axis in ((d_az, "azimuth"), (d_el or 0.0, "elevation")):
            if not -MAX_NUDGE_DEG < step < MAX_NUDGE_DEG:
                raise Refused(
                    RefusalCode.INVALID,
                    f"a nudge of {step:.10g} degrees in {axis} is a turn or more: a nudge is less "
                    f"than {MAX_NUDGE_DEG:g} degrees either way",
                )
        # from the target while the rotor is on its way (turning, braking before it turns, or
        # idle with a target still waiting to go out, as a rotor with no brake is while it
        # settles: a second press of a nudge button adds to the first), else from the bearing
        going = not halted and status.state in (
            MotionState.MOVING,
            MotionState.BRAKING,
            MotionState.IDLE,
        )
        moving = going and status.target_az_deg is not None
        az = status.target_az_deg if moving else status.bearing_deg
        if az is None:
            raise Refused(
                RefusalCode.OFFLINE, f"no bearing to nudge from (the {self.model_name} has none)"
            )
        new_az: float | None = None
        end: float | None = None
        raw = status.raw_target_az_deg if moving else status.raw_bearing_deg
        named = d_az
        if d_az and raw is not None:  # a controller of steps: the turn to the step it takes
            d_az = self._stepped(raw, d_az, el=False) - raw
        if d_az and self.az_wraps and self.az_ends_at_north and raw is not None:
            # on the controller's own scale, whose ends are 0 and 360: +10 at 350 is 360, 10
            # on (folded to 0, it went out as the other end), +10 at 360 is past that end
            # (the value named: -10 at 5 is refused though a SatEL's step of -5 is 0)
            to_raw = raw + d_az
            new_az = norm360(to_raw + self.offset_deg)
            past = next((r for r in (raw + named, to_raw) if not 0.0 <= r <= 360.0), None)
            if past is not None:
                at = norm360(past + self.offset_deg)
                shown = f"{at:g}" + ("" if past == at else f" (controller {past:g})")
                raise Refused(
                    RefusalCode.LIMITS,
                    f"a nudge of {named:+.10g} degrees turns to azimuth {shown}, past the end of "
                    f"the {self.model_name}'s travel: a nudge is not taken the other way round",
                )
            if self._sent(to_raw)[0] in (0.0, 360.0):  # (one sent as an end after its
                end = to_raw  # rounding too: its own end, not the nearer; review 44)
        elif d_az and not self.az_wraps and raw is not None:
            # a move along the travel from where the rotor is (or is going): its raw value is
            # that one plus the step, judged against the limits and sent as it is (``end``),
            # never taken as a bearing whose other raw value lies inside them: +10 at raw 535
            # is refused at the 540 stop, -15 at raw 30 under limits 20..440 at the limit 20
            # (as a bearing, 15 was the 375 inside them: 345 degrees the other way round)
            end = raw + d_az
            new_az = end + self.offset_deg
            if 0.0 <= new_az <= 360.0:  # (the true bearing it shows: 400 names its side)
                new_az = norm360(new_az)
            if not self.az_min_deg <= end <= self.az_max_deg:
                at = norm360(end + self.offset_deg)
                shown = f"{at:g}" + ("" if end == at else f" (controller {end:g})")
                raise Refused(
                    RefusalCode.LIMITS,
                    f"a nudge of {named:+.10g} degrees turns to azimuth {shown}, past "
                    f"{self._limits_text()} of the {self.model_name}'s travel: a nudge is not "
                    "taken the other way round",
                )
        elif d_az:
            if self.az_wraps and raw is not None:  # (not az_ends_at_north: its stop at raw 180?)
                self._clear_of_south(raw, d_az)
            new_az = norm360(az + d_az)
        el: float | None = None
        if d_el is not None and d_el != 0.0:
            base = status.target_el_deg if moving else status.elevation_deg
            if base is None:
                raise Refused(RefusalCode.UNSUPPORTED, f"{self.model_name} has no elevation axis")
            el = self._stepped(base, d_el, el=True)
        return new_az, el, end

    def _stepped(self, start: float, d: float, el: bool) -> float:
        """Rule 6 on a controller of steps (rule 4: a SatEL's ten degrees): where a nudge of
        ``d`` from ``start`` (the axis's raw value) goes, the nearest step of ``start + d``
        and at least the first step past ``start`` its own way (-5 at 120 is 110 as +5 is
        130; rounded half up alone, 115 went out as 120 and nothing turned); ``start + d``
        on any other controller. Refused for a nudge of less than half a step, which names a
        turn far shorter than the least the controller makes (a review: 0.001 turned it 10)."""
        whole, _tenths, _cuts, steps = self._rounds(el)
        if not whole or steps == 1:
            return start + d
        if abs(d) < steps / 2:
            raise Refused(
                RefusalCode.INVALID,
                f"a nudge of {d:+.10g} degrees is less than half of the {self.model_name}'s "
                f"{steps}-degree step, the least it turns: nudge by {steps / 2:g} or more",
            )
        nearest = float(half_up_step(start + d, steps))
        at = half_up_step(start, steps) // steps  # (the step it stands on: a reading of 121 is
        # the rotor at 120, and -5 went to 120, nothing: an attack pass)
        if d > 0:
            return max(nearest, float((at + 1) * steps))
        return min(nearest, float((at - 1) * steps))

    def _checked(self, az_deg: float, raw_deg: float) -> float:
        lo, hi = self.az_min_deg, self.az_max_deg
        # (rule 5: the value past the limits quoted with the digits that keep it past them)
        shown = "azimuth " + (shown_past(az_deg, lo, hi) if raw_deg == az_deg else f"{az_deg:g}")
        if raw_deg != az_deg:
            shown += f" (controller {shown_past(raw_deg, lo, hi)})"
        if not lo <= raw_deg <= hi:
            raise Refused(RefusalCode.LIMITS, f"{shown} outside the limits {lo:g}..{hi:g}")
        if not self._sent_within(raw_deg, lo, hi):
            raise Refused(RefusalCode.LIMITS, self._rounding(shown, raw_deg, lo, hi))
        return raw_deg

    def _rounds(self, el: bool) -> tuple[bool, bool, bool, int]:
        """(whole degrees, tenths, cut down, steps) of the box that turns the axis (rule 4)."""
        if el and self.el_rounding is not None:
            return self.el_rounding
        return self.whole_degrees, self.tenths, self.cuts_down, self.steps_deg

    def _sent(self, value: float, el: bool = False) -> tuple[float, float]:
        """The lowest and highest value the controller can be sent for ``value`` (rule 4): the
        Rotor-EZ family rounds half up to whole degrees, the SatEL to its rotors' ten-degree
        steps, the Easycomm family, the RC2800, the RT-21 and the Combi-Track to tenths; the
        SPID family cuts down to its resolution, learned only from its replies: one pulse per
        degree at the coarsest. A
        composite's azimuth by its azimuth box, its elevation (``el``) by the other (an attack
        pass: judged by both boxes' ways, a SPID's cut was lost beside a box of tenths, and a
        box of tenths refused what only the other box would have rounded)."""
        whole, tenths, cuts, steps = self._rounds(el)
        if whole:  # (the codecs' own rounding: ``half_up``)
            r = float(half_up_step(value, steps))
            return r, r
        if tenths:
            r = half_up(value, 10) / 10
            return r, r
        if cuts:  # the codec's cut at one pulse per degree, floor(360 + v) - 360
            return float(math.floor(360.0 + value)) - 360.0, value
        return value, value

    def _resolution(self, el: bool = False) -> str:
        """Why ``_sent`` moved a value, for the refusal's message."""
        whole, tenths, _cuts, steps = self._rounds(el)
        if whole:
            return "it takes whole degrees" if steps == 1 else f"it turns in {steps}-degree steps"
        if tenths:
            return "it takes tenths of a degree"
        return "it may cut to whole degrees, its coarsest resolution"

    def _sent_within(self, value: float, lo: float, hi: float, el: bool = False) -> bool:
        low, high = self._sent(value, el)
        return lo <= low and high <= hi

    def _rounding(self, shown: str, value: float, lo: float, hi: float, el: bool = False) -> str:
        low, high = self._sent(value, el)
        sent = f"{low:g}" if low == high else f"as low as {low:g}"
        return (
            f"{shown} becomes {sent} on the {self.model_name} ({self._resolution(el)}), "
            f"outside the limits {lo:g}..{hi:g}"
        )

    @staticmethod
    def _folded(az_deg: float) -> str:
        """ " (5)" for 365: a target that names a side, as the compass reads it."""
        return "" if 0.0 <= az_deg <= 360.0 else f" ({norm360(az_deg):g})"

    def _check_sent_keep_out(self, az_deg: float, raw_deg: float) -> None:
        """Rule 3 for what the controller is really sent: 199.5 goes out as 200 on a Rotor-EZ,
        10.9 as 10 on a Rot1Prog, which may be a sector's edge."""
        low, high = self._sent(raw_deg)
        t1, t2 = low + self.offset_deg, high + self.offset_deg
        for sector in self.keep_out:
            start_inside = norm360(sector[0] - t1) <= t2 - t1
            if in_sector(t1, sector) or in_sector(t2, sector) or start_inside:
                raise Refused(
                    RefusalCode.KEEP_OUT,
                    f"azimuth {az_deg:g} is sent to the {self.model_name} as "
                    f"{norm360(t1):g}{'' if t1 == t2 else f'..{norm360(t2):g}'} "
                    f"({self._resolution()}), "
                    f"in the keep-out sector {sector[0]:g}..{sector[1]:g}: refused",
                )


def toward(
    station: tuple[float, float] | None,
    latitude_deg: float,
    longitude_deg: float,
    *,
    long_path: bool = False,
    locator: str | None = None,
) -> tuple[float, TargetInfo]:
    """The true bearing from ``station`` to a place, and what the status says about it."""
    if station is None:
        raise Refused(
            RefusalCode.UNSUPPORTED,
            "a target by locator or coordinates needs the station's position ([station] locator)",
        )
    try:
        path = geo.great_circle(station[0], station[1], latitude_deg, longitude_deg)
    except ValueError as exc:
        raise Refused(RefusalCode.INVALID, str(exc)) from None
    if not path.has_direction:  # rule 7
        place = locator or f"{latitude_deg:g}, {longitude_deg:g}"
        if path.distance_km < path.long_distance_km:
            why = "the station's own position: it has no bearing (distance 0)"
        else:
            why = (
                "the station's antipode: every bearing is a great circle to it, "
                f"{path.distance_km:.0f} km either way; name a bearing instead"
            )
        raise Refused(RefusalCode.INVALID, f"{place} is {why}")
    info = TargetInfo(
        latitude_deg=latitude_deg,
        longitude_deg=longitude_deg,
        distance_km=path.long_distance_km if long_path else path.distance_km,
        short_path_deg=path.short_path_deg,
        long_path_deg=path.long_path_deg,
        path="long" if long_path else "short",
        locator=locator,
    )
    return (path.long_path_deg if long_path else path.short_path_deg), info


@dataclass(frozen=True)
class Limits:
    """The mechanical limits (the controller's raw values), as rotctld's ``dump_state`` gives
    them; here rather than beside the engine's Rotator so that the remote, which has no serial
    line, needs nothing of the engine."""

    az_min_deg: float
    az_max_deg: float
    el_min_deg: float = 0.0
    el_max_deg: float = 0.0

    @classmethod
    def of(cls, p: Pointing) -> Limits:
        """The mechanical limits of a rotator's terms."""
        return cls(p.az_min_deg, p.az_max_deg, p.el_min_deg, p.el_max_deg)
