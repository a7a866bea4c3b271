"""Following the sun, the moon or a satellite (``R/track``). Pure: the session gives the time;
positions and passes are answers of the sky worker (skywork.py, rule 8).

Rules:
1. Tracking starts on a Track command and ends on ``R/track off``, a stop, the lock, any
   other target (a manual one, rotctld's P, a preset, a nudge, a park), the rotor turned by
   hand, a stall, the serial link going down or the controller falling silent: the rotor never
   turns by itself after any of these. The status says why (``tracking_ended``). Tracking's
   own targets are put here, not in the mailbox, so they never end it. It goes on from pass
   to pass until it is ended. A step is measured from the last target and, once the rotor
   has got there (arrived, not still on its way), from where it really is: a rotor that fell
   short or was turned gets the step again; one turned away while still holding the last step
   is left to the motion machine's verdict (a stall ends tracking), never pulled back.
2. Passes: while the body is below ``min_el_deg`` the rotator waits at the azimuth where the
   next pass rises (at the minimum elevation): at once when tracking starts, and after a pass
   when the rotor, at its real speeds, would just make it in time plus PREPOSITION_MARGIN_S.
   At the end of a pass it parks (``at_los = "park"``, if a park position is configured) or
   stays where it is.
3. During a pass a new target goes out when the body has moved ``step_deg`` on either axis
   from the last one, and only when the controller may take one: any time on a controller that
   re-targets while turning (SPID); when the rotor is idle on the others (a Rotor-EZ stops to
   re-target, a SatEL takes no input while slewing). The target leads the body by half a
   step, so the rotor straddles it: within half a step either side, plus what the rotor lags.
4. Flip: an az/el rotor whose elevation reaches 180 minus the minimum elevation flies a
   satellite's pass with elevation 180 - el and azimuth + 180 when that saves turning time
   during the pass: both axes at their real speeds, each raw azimuth picked as the judge would
   (the first from where the rotor is); the saving must exceed FLIP_SAVING_DEG at the azimuth
   speed. A pass across a
   stop (the north on a 0..360 rotor) then stays clear of it. Decided once per pass.
5. Every target goes through the same judge as any other (pointing.py: limits, keep-out
   sectors). One it refuses is skipped, reported once per pass, and the rotor holds until the
   body is back where it may go.
6. Azimuth-only rotors follow the azimuth; the body's elevation only decides the passes.
7. Tracking is activity for auto-park: a rotor that is tracking never parks by itself.
8. Nothing of the sky is computed here (ARCHITECTURE.md rule 12): pass searches, windows of
   the body's track, a pass's samples for the flip and TLE file look-ups are questions
   (skywork.py) the session hands to the sky worker, and their answers come back as inputs.
   Until an answer is in, tracking waits: no target from it, the status's block as it was.
   Each start or end of tracking is a new generation: an answer asked for before it is
   dropped (a stop or ``off`` meanwhile is never undone by a late answer). An answer that says
   the sky cannot be computed (an orbit decayed, a date beyond the ephemeris) ends tracking
   with that reason. A look-up leaves what is tracked alone until its answer names a body.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

from bridge.engine.skywork import Answer, LookupQuestion, PassQuestion, PositionsQuestion, Question
from bridge.errors import Refused
from bridge.model import ErrorKind, MotionState, Source, Target, TrackingInfo
from bridge.pointing import angle_between
from bridge.sky import Body, Pass, Sky

if TYPE_CHECKING:
    from bridge.engine.session import RotatorSession

log = logging.getLogger(__name__)

# the body's track is computed at this spacing (a satellite's; the sun's and the moon's ten
# times wider) and interpolated, WINDOW samples in one call, a few windows kept
SAMPLE_S = 1.0
SLOW_SAMPLE_S = 10.0
WINDOW = 120
WINDOWS_KEPT = 8  # more than one step needs: now, +10 s, +60 s, + a lead of 300 s, the next
PASS_RETRY_S = 60.0  # no pass in sight: look again this often
PREPOSITION_MARGIN_S = 20.0
INFO_EVERY_S = 5.0  # the status's tracking block is refreshed this often (and on a target)
NEXT_S = 60.0  # the status's "next" position: this far ahead
MAX_LEAD_S = 300.0
FLIP_SAVING_DEG = 30.0
FLIP_SAMPLE_S = 10.0
FLIP_SAMPLES = 120  # at most, over a pass


@dataclass(frozen=True)
class Track:
    """Start following ``body``; or look the satellite ``lookup`` up in the TLE file first (the
    file is read by the sky worker: rule 8); or stop (neither)."""

    body: Body | None
    source: Source = Source.MQTT
    lookup: LookupQuestion | None = None
    described: str | None = None  # the command as the user gave it (a refusal names it)


@dataclass(frozen=True)
class TrackConfig:
    sky: Sky | None = None  # None: no station configured, nothing can be tracked
    min_el_deg: float = 0.0
    step_deg: float = 3.0
    at_los: str = "stay"  # or "park"


class Tracker:
    def __init__(self, cfg: TrackConfig) -> None:
        self.cfg = cfg
        self.body: Body | None = None
        self.ended: str | None = None
        self.info: TrackingInfo | None = None
        self.generation = 0  # rule 8: an answer asked for before a start or an end is stale
        self.asks: list[Question] = []  # rule 8: questions for the sky worker, not yet sent
        self.lookup: Track | None = None  # a look-up under way (the body tracked goes on)
        self._reset()

    def _reset(self) -> None:
        self.generation += 1
        self.lookup = None
        self._asked: set[Question] = set()  # sent, no answer yet
        self._pass: Pass | None = None
        self._pass_checked = -math.inf
        self._flip = False
        self._flip_for: float | None = None  # the AOS the flip was decided for
        self._flip_track: dict[PositionsQuestion, list[tuple[float, float]]] = {}
        self._windows: dict[int, list[tuple[float, float]]] = {}
        self._last: tuple[float, float | None] | None = None  # last target put (true, flipped)
        self._waited_for: float | None = None  # AOS of the pass the rotor went to wait for
        self._parked_after: float | None = None  # LOS of the pass parked (or stayed) after
        self._after_pass = False
        self._refused_for: float | None = None
        self._info_t = -math.inf
        self._away: float | None = None  # how far the rotor was from the last target, turning

    # -- rule 1 ----------------------------------------------------------------------------
    def start(self, body: Body) -> None:
        self._reset()
        self.body, self.ended, self.info = body, None, TrackingInfo(body.name, "waiting")

    def end(self, why: str) -> bool:
        """Stop following (``why`` shows as ``tracking_ended``); whether anything was tracked.
        A look-up under way is dropped too (its answer comes too late)."""
        if self.body is None:
            self.lookup = None
            self.generation += 1
            return False
        log.info("tracking %s ended: %s", self.body.name, why)
        self.body, self.ended, self.info = None, why, None
        self._reset()
        return True

    def look_up(self, track: Track) -> None:
        """Rule 8: ask the sky worker for the satellite by name; whatever is tracked goes on
        until the answer (an unknown name changes nothing)."""
        assert track.lookup is not None
        self.lookup = track
        self.asks.append(track.lookup)

    def wakeup(self, now: float) -> float | None:
        """Tracking looks at the sky at least once a second."""
        return now + SAMPLE_S if self.body is not None else None

    # -- rule 8: questions and answers -------------------------------------------------------
    def _ask(self, question: Question) -> None:
        if question not in self._asked:
            self._asked.add(question)
            self.asks.append(question)

    def answered(self, answer: Answer) -> str | None:
        """Take an answer of this generation in; why tracking must end, if it must."""
        q = answer.question
        self._asked.discard(q)
        if isinstance(q, LookupQuestion) or self.body is None:
            return None
        if answer.failure is not None:
            return answer.failure
        if isinstance(q, PassQuestion):
            self._pass_checked = q.utc
            self._pass = answer.value if isinstance(answer.value, Pass) else None
        elif isinstance(q, PositionsQuestion) and isinstance(answer.value, list):
            index = self._window_index(q)
            if index is not None:
                if len(self._windows) >= WINDOWS_KEPT:
                    self._windows.pop(min(self._windows))  # the oldest
                self._windows[index] = answer.value
            else:
                self._flip_track = {q: answer.value}
        return None

    # -- the body's track ------------------------------------------------------------------
    def _step_s(self) -> float:
        assert self.body is not None
        return SAMPLE_S if self.body.kind == "satellite" else SLOW_SAMPLE_S

    def _window(self, index: int) -> PositionsQuestion:
        assert self.body is not None and self.cfg.sky is not None
        step = self._step_s()
        times = tuple(index * step * WINDOW + i * step for i in range(WINDOW + 1))
        return PositionsQuestion(self.cfg.sky, self.body, times)

    def _window_index(self, q: PositionsQuestion) -> int | None:
        span = self._step_s() * WINDOW
        index = math.floor(q.times[0] / span)
        return index if q == self._window(index) else None

    def at(self, utc: float) -> tuple[float, float] | None:
        """The body's (azimuth, elevation) at ``utc``, interpolated in a window of its track;
        None while the window is being computed (asked for here, with the one after it)."""
        step = self._step_s()
        span = step * WINDOW
        index = math.floor(utc / span)
        track = self._windows.get(index)
        if index + 1 not in self._windows:
            self._ask(self._window(index + 1))  # ready before it is needed
        if track is None:
            self._ask(self._window(index))
            return None
        x = (utc - index * span) / step
        i = min(int(x), WINDOW - 1)
        f = x - i
        (az0, el0), (az1, el1) = track[i], track[i + 1]
        daz = (az1 - az0 + 180.0) % 360.0 - 180.0
        return (az0 + f * daz) % 360.0, el0 + f * (el1 - el0)

    def searching(self, utc: float) -> bool:
        """Whether the pass now or next must be found first (asked for here, rule 8): tracking
        waits for the answer. Afterwards ``pass_now`` is it (None: none in sight)."""
        p = self._pass
        if p is not None and utc > p.los_s:
            self._after_pass, self._pass = True, None
        if self._pass is not None or utc - self._pass_checked < PASS_RETRY_S:
            return False
        if not any(isinstance(q, PassQuestion) for q in self._asked):
            assert self.body is not None and self.cfg.sky is not None
            self._ask(PassQuestion(self.cfg.sky, self.body, utc, self.cfg.min_el_deg))
        return True

    @property
    def pass_now(self) -> Pass | None:
        return self._pass

    def flip_track(self, p: Pass) -> list[tuple[float, float]] | None:
        """The body's track over the pass, sampled for the flip decision (rule 4); None while
        it is being computed."""
        assert self.body is not None and self.cfg.sky is not None
        n = min(FLIP_SAMPLES, max(2, int((p.los_s - p.aos_s) / FLIP_SAMPLE_S) + 1))
        times = tuple(p.aos_s + (p.los_s - p.aos_s) * i / (n - 1) for i in range(n))
        q = PositionsQuestion(self.cfg.sky, self.body, times)
        track = self._flip_track.get(q)
        if track is None:
            self._ask(q)
        return track


def step(session: RotatorSession, now: float) -> None:
    """Run by the session with its other rules, while the controller answers."""
    tr = session.tracker
    if tr.body is None or tr.cfg.sky is None:
        return
    session.autopark.activity(now)  # rule 7
    if session.link is None or not session.answering or session.locked:
        return
    if _turned_by_hand(session):
        tr.end("turned by hand")  # rule 1: the front panel is a command too
        session.drop_tracking_target()
        return
    utc = now + session.wall_offset_s
    if tr.searching(utc):
        return  # rule 8: searched on the sky worker; the answer comes as an input
    p = tr.pass_now
    if p is None:
        _inform(tr, utc, None, "no pass", now)
        return
    if tr._flip_for != p.aos_s:
        flip = _flip_saves(session, p)
        if flip is None:
            return  # rule 8: the pass's track is being computed
        tr._flip_for, tr._flip = p.aos_s, flip
    if utc < p.aos_s:  # current_pass has moved on past a LOS: utc <= p.los_s
        _inform(tr, utc, p, "waiting", now)
        _wait_for(session, p, utc, now)
    else:
        _inform(tr, utc, p, "tracking", now)
        _follow(session, p, utc, now)


def _flipped(tr: Tracker, az: float, el: float) -> tuple[float, float]:
    return ((az + 180.0) % 360.0, 180.0 - el) if tr._flip else (az, el)


def _aim(session: RotatorSession, az: float, el: float) -> tuple[float, float | None]:
    """Rules 4 and 6: what the rotor is sent for a body at (az, el)."""
    tr = session.tracker
    az, el = _flipped(tr, az, el)
    aim = session.cfg.aim
    if not aim.has_elevation:
        return az, None
    lo = max(aim.el_min_deg, tr.cfg.min_el_deg if not tr._flip else -math.inf)
    hi = min(aim.el_max_deg, 180.0 - tr.cfg.min_el_deg if tr._flip else math.inf)
    return az, min(max(el, lo), hi)


def _put(session: RotatorSession, target: Target, now: float) -> bool:
    """Rule 5: judged like any target; a refusal is reported once per pass."""
    tr = session.tracker
    try:
        judged = session.cfg.aim.judge(target, session.motion.position_deg)
    except Refused as exc:
        aos = tr._pass.aos_s if tr._pass is not None else None
        if tr._refused_for != aos or aos is None:
            tr._refused_for = aos
            assert tr.body is not None
            session.error(ErrorKind.REFUSED, f"tracking {tr.body.name}: {exc.message}; holding")
        return False
    session.targets.put(judged, now)
    return True


def _wait_for(session: RotatorSession, p: Pass, utc: float, now: float) -> None:
    """Rule 2: after a pass park or stay, then go and wait where the next one rises."""
    tr = session.tracker
    if tr._after_pass and tr._parked_after != p.aos_s:
        tr._parked_after = p.aos_s
        if tr.cfg.at_los == "park" and session.cfg.aim.park is not None:
            az, el = session.cfg.aim.park
            if _put(session, Target(az, el, Source.TRACKING, park=True), now):
                log.info("%s: pass over; parking until the next one", session.name)
            return
    if tr._waited_for == p.aos_s or session.targets.pending is not None:
        return
    aos_el = tr.cfg.min_el_deg
    az, el = _aim(session, p.aos_az_deg, aos_el)
    if tr._after_pass and utc < p.aos_s - _travel_s(session, az, el) - PREPOSITION_MARGIN_S:
        return
    if tr._after_pass and session.motion.state in (MotionState.MOVING, MotionState.BRAKING):
        return  # a park still on its way: the wait target follows it
    tr._waited_for = p.aos_s
    _put(session, Target(az, el, Source.TRACKING), now)
    tr._last = (az, el)


def _follow(session: RotatorSession, p: Pass, utc: float, now: float) -> None:
    """Rule 3."""
    tr = session.tracker
    link = session.link
    assert link is not None
    direct = session.cfg.motion.direct_retarget
    m = session.motion
    if session.targets.pending is not None or link.slew is not None:
        return
    if not direct and m.state is not MotionState.IDLE:
        return
    if m.state in (MotionState.BRAKING, MotionState.STALLED):
        return
    lead = _half_step_s(tr, utc)
    body = tr.at(min(utc + lead, p.los_s)) if lead is not None else None
    if body is None:
        return  # rule 8: that part of the track is being computed
    az, el = _aim(session, *body)
    step = tr.cfg.step_deg
    if tr._last is not None and _apart(tr._last, (az, el)) < step:
        if m.target_deg is not None or _near(session, az, el):
            return  # on its way to the last step (its verdict, arrival or stall, decides)
    if _put(session, Target(az, el, Source.TRACKING), now):
        tr._last = (az, el)


def _turned_by_hand(session: RotatorSession) -> bool:
    """Turning with no target and no stop of ours, and already further from the last tracking
    target than a step and the tolerance: a hand on the front panel, not jitter, coasting or
    a late start on a small step."""
    m, tr = session.motion, session.tracker
    if m.state is not MotionState.MOVING or m.target_deg is not None or m.stop_sent_t is not None:
        return False
    if tr._last is None or m.position_deg is None:
        return True
    at = session.cfg.aim.true_of(m.position_deg)
    return (
        _apart((at, None), (tr._last[0], None)) > tr.cfg.step_deg + session.cfg.motion.tolerance_deg
    )


def _near(session: RotatorSession, az: float, el: float | None) -> bool:
    """The rotor really is within a step (and its tolerance) of (az, el): the last target is
    not enough, the rotor may have been turned since or have fallen short."""
    m, aim = session.motion, session.cfg.aim
    if m.position_deg is None:
        return True  # nothing to judge by: the last target stands
    at = (aim.true_of(m.position_deg), m.el_position_deg if el is not None else None)
    return _apart(at, (az, el)) < session.tracker.cfg.step_deg + session.cfg.motion.tolerance_deg


def _apart(a: tuple[float, float | None], b: tuple[float, float | None]) -> float:
    daz = angle_between(a[0], b[0])
    if a[1] is None or b[1] is None:
        return daz
    return max(daz, abs(a[1] - b[1]))


def _half_step_s(tr: Tracker, utc: float) -> float | None:
    """How long the body takes to move half a step (rule 3), from its rate over 10 s; None
    while its track is being computed."""
    a, b = tr.at(utc), tr.at(utc + 10.0)
    if a is None or b is None:
        return None
    rate = _apart(a, b) / 10.0
    if rate <= 0.0:
        return MAX_LEAD_S
    return min(tr.cfg.step_deg / 2.0 / rate, MAX_LEAD_S)


def _travel_s(session: RotatorSession, az: float, el: float | None) -> float:
    """How long the rotor takes from where it is to (az, el) at its real speeds (rule 2)."""
    cfg, m = session.cfg, session.motion
    try:
        raw = cfg.aim.raw_for(az, m.position_deg)
    except Refused:
        return 0.0
    t = 0.0 if m.position_deg is None else abs(raw - m.position_deg) / cfg.az_speed_deg_s
    if el is not None and m.el_position_deg is not None:
        t = max(t, abs(el - m.el_position_deg) / cfg.el_speed_deg_s)
    return t + cfg.spec.brake_delay_s


def _flip_saves(session: RotatorSession, p: Pass) -> bool | None:
    """Rule 4: whether this pass is flown flipped (None: its track is being computed, rule 8).
    Satellites only: the sun and the moon move too slowly across a "pass" of half a day for a
    flip to be worth its elevation travel."""
    tr, aim, cfg = session.tracker, session.cfg.aim, session.cfg
    if not aim.has_elevation or aim.el_max_deg < 180.0 - tr.cfg.min_el_deg:
        return False
    assert tr.body is not None
    if tr.body.kind != "satellite":
        return False
    track = tr.flip_track(p)
    if track is None:
        return None

    def travel_s(flip: bool) -> float:
        """The time the rotor spends turning during the pass, on its slower axis at each step
        (both axes at their real speeds): an unwind through a stop shows as a long step. The
        move to where the pass rises is left out: it is made while waiting for it."""
        raw: float | None = session.motion.position_deg
        el: float | None = None
        total = 0.0
        for az_b, el_b in track:
            az_want, el_want = ((az_b + 180.0) % 360.0, 180.0 - el_b) if flip else (az_b, el_b)
            try:
                nxt = aim.raw_for(az_want, raw)
            except Refused:
                return math.inf
            if el is not None and raw is not None:
                total += max(
                    abs(nxt - raw) / cfg.az_speed_deg_s, abs(el_want - el) / cfg.el_speed_deg_s
                )
            raw, el = nxt, el_want
        return total

    return travel_s(True) + FLIP_SAVING_DEG / cfg.az_speed_deg_s < travel_s(False)


def _inform(tr: Tracker, utc: float, p: Pass | None, phase: str, now: float) -> None:
    """The status's tracking block, refreshed every INFO_EVERY_S or when the phase changes."""
    assert tr.body is not None
    old = tr.info
    if old is not None and old.phase == phase and now - tr._info_t < INFO_EVERY_S:
        return
    here, then = tr.at(utc), tr.at(utc + NEXT_S)
    if here is None or then is None:
        return  # rule 8: shown once its track is computed
    tr._info_t = now
    (az, el), (naz, nel) = here, then
    info = TrackingInfo(
        tr.body.name,
        phase,
        round(az, 1),
        round(el, 1),
        round(naz, 1),
        round(nel, 1),
        flip=tr._flip,
    )
    if p is not None:
        info = replace(
            info,
            aos_unix=round(p.aos_s, 1),
            los_unix=round(p.los_s, 1),
            max_elevation_deg=round(p.max_el_deg, 1),
            aos_azimuth_deg=round(p.aos_az_deg, 1),
        )
    tr.info = info
